/* dyn_kernels.cu — the dynamic model's kernels (docs/cuda.md "The dynamic model"): the
 * strand and warp variants of one frame, the bend rest lengths and the observables. The
 * per-strand math is cuda/dyn_model.cuh; this file maps threads to strands and points.
 *
 * Feature dispatch (docs/model.md §3.9): a table of kernel pointers indexed by the run's
 * feature mask. A mask for which specialised_mask() (cuda/dyn_kernels.cuh) is true has
 * kernels of its own, compiled with the mask as a constant (StaticF), so an undeclared
 * feature leaves no code; any other valid mask runs the generic kernel (DynF), which tests
 * the same bits at run time: uniform branches around the same expressions, so the bits are
 * the same either way (the host check runs both). Building all 96 valid masks as kernels
 * of their own (-DHB_DYN_SPECIALISE_ALL) multiplies the build time (docs/cuda.md gives the
 * numbers), so the default build specialises the listed sets only. The solver is a
 * run-time branch once per substep in both, outside the inner loops.
 */
#include <utility>

#include "dyn_kernels.cuh"

namespace hb {
namespace dyn {

/* the kernel's feature policy from the run's mask (outside the anonymous namespace: with
 * every mask specialised the generic one is never referenced) */
template <class Feat> struct MakeFeat;
template <unsigned F> struct MakeFeat<StaticF<F>> {
    __device__ static StaticF<F> make(unsigned) { return StaticF<F>(); }
};
template <> struct MakeFeat<DynF> {
    __device__ static DynF make(unsigned f) { return DynF{f}; }
};

namespace {

constexpr int kMaxThreads = 1024;


/* A loop over a warp's lanes: iteration k runs on lane (k − b)/step mod 32; the warp
 * synchronises after the loop, so the next group sees every write (shared memory). */
struct Lanes {
    int lane;
    template <class Fn> __device__ __forceinline__ void each(int64_t b, int64_t e, int64_t step, Fn f) const
    {
        for (int64_t k = b + (int64_t)lane * step; k < e; k += 32 * step) f(k);
        __syncwarp();
    }
    template <class Fn> __device__ __forceinline__ void one(Fn f) const
    {
        if (lane == 0) f();
        __syncwarp();
    }
};

/* ---- the strand variant: one thread per strand ---- */
template <typename T, class Feat>
__global__ void __launch_bounds__(kMaxThreads)
    k_strand(DModel<T> m, const T *__restrict__ q, const T *__restrict__ ph, T *x, T *v, const T *rest,
             const T *bend_rest, T *scratch, int64_t N)
{
    const Feat has = MakeFeat<Feat>::make(m.features);
    const int64_t nt = (int64_t)gridDim.x * blockDim.x;
    const int64_t t = (int64_t)blockIdx.x * blockDim.x + threadIdx.x;
    const int64_t P = m.points, NP = N * P;
    Strand<T> s;
    s.p = Arr<T>{scratch + t, nt, P * nt};
    s.lam = Arr1<T>{scratch + 3 * P * nt + t, nt};
    s.d = Arr<T>{scratch + 6 * P * nt + t, nt, P * nt};
    for (int64_t i = t; i < N; i += nt) {
        s.x = Arr<T>{x + i, N, NP};
        s.v = Arr<T>{v + i, N, NP};
        s.rest = Arr<const T>{rest + i, N, NP};
        s.bend_rest = Arr1<const T>{bend_rest + i, N};
        frame_body(m, q, ph, s, Seq(), has);
    }
}

/* ---- the warp variant: one warp per strand, a lane per point ---- */
template <typename T> __host__ __device__ constexpr int64_t warp_reals(int64_t P)
{
    return 15 * P;
} /* x, v, p, d [3][P]; λ [3P] */

template <typename T, class Feat>
__global__ void __launch_bounds__(kMaxThreads) k_warp(DModel<T> m, const T *__restrict__ q, const T *__restrict__ ph,
                                                      T *x, T *v, const T *rest, const T *bend_rest, int64_t N)
{
    extern __shared__ __align__(16) unsigned char hb_dyn_smem[];
    const Feat has = MakeFeat<Feat>::make(m.features);
    const int lane = (int)(threadIdx.x & 31u), w = (int)(threadIdx.x >> 5), wpb = (int)(blockDim.x >> 5);
    const int64_t P = m.points, P3 = 3 * P;
    T *base = (T *)hb_dyn_smem + (int64_t)w * warp_reals<T>(P);
    Strand<T> s;
    s.x = Arr<T>{base, 1, P};
    s.v = Arr<T>{base + 3 * P, 1, P};
    s.p = Arr<T>{base + 6 * P, 1, P};
    s.d = Arr<T>{base + 9 * P, 1, P};
    s.lam = Arr1<T>{base + 12 * P, 1};
    const Lanes ex{lane};
    /* the loop bound is the same for every lane of a warp: whole warps take each strand */
    for (int64_t i = (int64_t)blockIdx.x * wpb + w; i < N; i += (int64_t)gridDim.x * wpb) {
        T *gx = x + i * P3, *gv = v + i * P3;
        for (int64_t e = lane; e < P3; e += 32) { /* coalesced: the strand's 3P reals in a row */
            base[(e % 3) * P + e / 3] = gx[e];
            base[3 * P + (e % 3) * P + e / 3] = gv[e];
        }
        __syncwarp();
        s.rest = Arr<const T>{rest + i * P3, 3, 1};
        s.bend_rest = Arr1<const T>{bend_rest + i * (P - 2), 1};
        frame_body(m, q, ph, s, ex, has);
        for (int64_t e = lane; e < P3; e += 32) {
            gx[e] = base[(e % 3) * P + e / 3];
            gv[e] = base[3 * P + (e % 3) * P + e / 3];
        }
        __syncwarp();
    }
}

/* ---- the dispatch tables ---- */
template <typename T>
using StrandFn = void (*)(DModel<T>, const T *, const T *, T *, T *, const T *, const T *, T *, int64_t);
template <typename T> using WarpFn = void (*)(DModel<T>, const T *, const T *, T *, T *, const T *, const T *, int64_t);

template <typename T, unsigned F> constexpr StrandFn<T> strand_entry()
{
    if constexpr (!valid_mask(F)) return nullptr;
    else if constexpr (specialised_mask(F)) return &k_strand<T, StaticF<F>>;
    else return &k_strand<T, DynF>;
}
template <typename T, unsigned F> constexpr WarpFn<T> warp_entry()
{
    if constexpr (!valid_mask(F)) return nullptr;
    else if constexpr (specialised_mask(F)) return &k_warp<T, StaticF<F>>;
    else return &k_warp<T, DynF>;
}

template <typename T, unsigned... Fs> struct Tables {
    static constexpr StrandFn<T> strand[sizeof...(Fs)] = {strand_entry<T, Fs>()...};
    static constexpr WarpFn<T> warp[sizeof...(Fs)] = {warp_entry<T, Fs>()...};
};
template <typename T, unsigned... Fs> Tables<T, Fs...> tables_of(std::integer_sequence<unsigned, Fs...>);
template <typename T> using TablesT = decltype(tables_of<T>(std::make_integer_sequence<unsigned, HB_F_COUNT>()));

template <typename T> __global__ void k_bend_rest(const T *rest, Layout rl, T *out, Layout1 bl, int64_t N, int64_t P)
{
    for (int64_t i = (int64_t)blockIdx.x * blockDim.x + threadIdx.x; i < N; i += (int64_t)gridDim.x * blockDim.x)
        bend_rest(P, Arr<const T>{rest + i * rl.is, rl.ks, rl.cs}, Arr1<T>{out + i * bl.is, bl.s});
}

constexpr int kObsThreads = 256;

template <typename T>
__global__ void __launch_bounds__(kObsThreads)
    k_observe(ObsScene sc, const T *x, const T *v, Layout lay, int64_t N, ObsPartial *out)
{
    __shared__ ObsPartial part[kObsChunk];
    const int64_t i0 = (int64_t)blockIdx.x * kObsChunk;
    const int64_t n = N - i0 < kObsChunk ? N - i0 : kObsChunk;
    for (int64_t j = threadIdx.x; j < n; j += blockDim.x) {
        const int64_t i = i0 + j;
        observe_strand(sc, Arr<const T>{x + i * lay.is, lay.ks, lay.cs}, Arr<const T>{v + i * lay.is, lay.ks, lay.cs},
                       &part[j]);
    }
    __syncthreads();
    if (threadIdx.x == 0) { /* strand order, as the CPU's chunks */
        ObsPartial acc = {0.0, 0.0, 0.0, 0};
        for (int64_t j = 0; j < n; j++) reduce_into(&acc, &part[j]);
        out[blockIdx.x] = acc;
    }
}

int grid_for(int64_t items, int per_block)
{
    const int64_t g = (items + per_block - 1) / per_block;
    return (int)(g < 1 ? 1 : g > 2147483647 ? 2147483647 : g);
}

} /* namespace */

template <typename T>
cudaError_t launch_frame_strand(const DModel<T> &m, const T *q, const T *phase, T *x, T *v, const T *rest,
                                const T *bend_rest, T *scratch, int64_t N, int grid, int block, cudaStream_t stream)
{
    if (!valid_mask(m.features)) return cudaErrorInvalidValue;
    const StrandFn<T> fn = TablesT<T>::strand[m.features];
    fn<<<grid, block, 0, stream>>>(m, q, phase, x, v, rest, bend_rest, scratch, N);
    return cudaGetLastError();
}

template <typename T> size_t warp_smem_bytes(int64_t P)
{
    return (size_t)warp_reals<T>(P) * sizeof(T);
}

template <typename T> cudaError_t prepare_warp(unsigned features, size_t bytes)
{
    if (!valid_mask(features)) return cudaErrorInvalidValue;
    return cudaFuncSetAttribute(TablesT<T>::warp[features], cudaFuncAttributeMaxDynamicSharedMemorySize, (int)bytes);
}

template <typename T>
cudaError_t launch_frame_warp(const DModel<T> &m, const T *q, const T *phase, T *x, T *v, const T *rest,
                              const T *bend_rest, int64_t N, int grid, int block, cudaStream_t stream)
{
    if (!valid_mask(m.features)) return cudaErrorInvalidValue;
    const WarpFn<T> fn = TablesT<T>::warp[m.features];
    const size_t smem = warp_smem_bytes<T>(m.points) * (size_t)(block / 32);
    fn<<<grid, block, smem, stream>>>(m, q, phase, x, v, rest, bend_rest, N);
    return cudaGetLastError();
}

template <typename T>
cudaError_t launch_bend_rest(const T *rest, Layout rl, T *out, Layout1 bl, int64_t N, int64_t P, cudaStream_t stream)
{
    k_bend_rest<T><<<grid_for(N, 256), 256, 0, stream>>>(rest, rl, out, bl, N, P);
    return cudaGetLastError();
}

template <typename T>
cudaError_t launch_observe(const ObsScene &sc, const T *x, const T *v, Layout lay, int64_t N, ObsPartial *out,
                           cudaStream_t stream)
{
    k_observe<T><<<grid_for(N, (int)kObsChunk), kObsThreads, 0, stream>>>(sc, x, v, lay, N, out);
    return cudaGetLastError();
}

#define HB_DYN_INSTANTIATE(T)                                                                                          \
    template cudaError_t launch_frame_strand<T>(const DModel<T> &, const T *, const T *, T *, T *, const T *,          \
                                                const T *, T *, int64_t, int, int, cudaStream_t);                      \
    template cudaError_t launch_frame_warp<T>(const DModel<T> &, const T *, const T *, T *, T *, const T *, const T *, \
                                              int64_t, int, int, cudaStream_t);                                        \
    template size_t warp_smem_bytes<T>(int64_t);                                                                       \
    template cudaError_t prepare_warp<T>(unsigned, size_t);                                                            \
    template cudaError_t launch_bend_rest<T>(const T *, Layout, T *, Layout1, int64_t, int64_t, cudaStream_t);         \
    template cudaError_t launch_observe<T>(const ObsScene &, const T *, const T *, Layout, int64_t, ObsPartial *,      \
                                           cudaStream_t);
HB_DYN_INSTANTIATE(float)
HB_DYN_INSTANTIATE(double)
#undef HB_DYN_INSTANTIATE

} /* namespace dyn */
} /* namespace hb */
