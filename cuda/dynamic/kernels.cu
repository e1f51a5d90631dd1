/* cuda/dynamic/kernels.cu — the dynamic model's kernels (docs/cuda.md "The dynamic model"): the
 * strand and warp variants of one frame, the bend rest lengths and the observables. The
 * per-strand math is cuda/dynamic/model.cuh; this file maps threads to strands and points.
 *
 * Feature dispatch (docs/model.md §3.9): a table of kernel pointers indexed by the run's
 * feature mask. A mask for which specialised_mask() (cuda/dynamic/kernels.cuh) is true has
 * kernels of its own, compiled with the mask as a constant (StaticF), so an undeclared
 * feature leaves no code; any other valid mask runs the generic kernel (DynF), which tests
 * the same bits at run time: uniform branches around the same expressions, so the bits are
 * the same either way (the host check runs both). Building all 96 valid masks as kernels
 * of their own (-DHB_DYN_SPECIALISE_ALL) multiplies the build time (docs/cuda.md gives the
 * numbers), so the default build specialises the listed sets only. The solver is a
 * run-time branch once per substep in both, outside the inner loops.
 */
#include <utility>

#include "dynamic/kernels.cuh"

namespace hb {
namespace dyn {

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
             const T *bend_rest, T *scratch, int64_t N, const int64_t *map, int64_t n_run)
{
    const Feat has = MakeFeat<Feat>::make(m.features);
    const int64_t nt = (int64_t)gridDim.x * blockDim.x;
    const int64_t t = (int64_t)blockIdx.x * blockDim.x + threadIdx.x;
    const int64_t P = m.points, NP = N * P;
    Strand<T> s;
    s.p = Arr<T>{scratch + t, nt, P * nt};
    s.lam = Arr1<T>{scratch + 3 * P * nt + t, nt};
    s.d = Arr<T>{scratch + 6 * P * nt + t, nt, P * nt};
    for (int64_t j = t; j < n_run; j += nt) {
        const int64_t i = map ? map[j] : j; /* §3.14: only the guides, when guided */
        s.x = Arr<T>{x + i, N, NP};
        s.v = Arr<T>{v + i, N, NP};
        s.rest = Arr<const T>{rest + i, N, NP};
        s.bend_rest = Arr1<const T>{bend_rest + i, N};
        if (m.seg_rest) s.seg_rest = Arr1<const T>{m.seg_rest + i * m.seg_is, m.seg_s}; /* §3.15 */
        frame_body(m, q, ph, s, Seq(), has);
    }
}

/* ---- the warp variant: one warp per strand, a lane per point ---- */

template <typename T, class Feat>
__global__ void __launch_bounds__(kMaxThreads)
    k_warp(DModel<T> m, const T *__restrict__ q, const T *__restrict__ ph, T *x, T *v, const T *rest,
           const T *bend_rest, int64_t N, const int64_t *map, int64_t n_run)
{
    extern __shared__ __align__(16) unsigned char hb_dyn_smem[];
    const Feat has = MakeFeat<Feat>::make(m.features);
    const int lane = (int)(threadIdx.x & 31u), w = (int)(threadIdx.x >> 5), wpb = (int)(blockDim.x >> 5);
    const int64_t P = m.points, P3 = 3 * P;
    T *base = (T *)hb_dyn_smem + (int64_t)w * warp_reals<T>(P);
    Strand<T> s = warp_strand(base, P);
    const Lanes ex{lane};
    /* the loop bound is the same for every lane of a warp: whole warps take each strand */
    (void)N;
    for (int64_t j = (int64_t)blockIdx.x * wpb + w; j < n_run; j += (int64_t)gridDim.x * wpb) {
        const int64_t i = map ? map[j] : j; /* §3.14: only the guides, when guided */
        T *gx = x + i * P3, *gv = v + i * P3;
        for (int64_t e = lane; e < P3; e += 32) { /* coalesced: the strand's 3P reals in a row */
            base[(e % 3) * P + e / 3] = gx[e];
            base[3 * P + (e % 3) * P + e / 3] = gv[e];
        }
        __syncwarp();
        s.rest = Arr<const T>{rest + i * P3, 3, 1};
        s.bend_rest = Arr1<const T>{bend_rest + i * (P - 2), 1};
        if (m.seg_rest) s.seg_rest = Arr1<const T>{m.seg_rest + i * m.seg_is, m.seg_s}; /* §3.15 */
        frame_body(m, q, ph, s, ex, has);
        for (int64_t e = lane; e < P3; e += 32) {
            gx[e] = base[(e % 3) * P + e / 3];
            gv[e] = base[3 * P + (e % 3) * P + e / 3];
        }
        __syncwarp();
    }
}

/* ---- the warpreg variant: one warp per strand, lane k holds point k (P ≤ 32) in registers ----
 * The same per-point math as frame_body (cuda/dynamic/model.cuh's scalar helpers), in the same
 * order; a constraint between neighbouring points runs on the lane of its higher point,
 * which reads the other end with a shuffle and sends it the step (dl, n) back, so the
 * moved point computes its own p − dl·n exactly as the reference does. Within a group of
 * §3.6 no two constraints share a point, so each lane takes at most one step per group. */
constexpr unsigned kFull = 0xffffffffu;
template <typename T> __device__ __forceinline__ T from_prev(T v)
{
    return __shfl_up_sync(kFull, v, 1);
}
template <typename T> __device__ __forceinline__ T from_next(T v)
{
    return __shfl_down_sync(kFull, v, 1);
}

/* A distance step of one lane, to be sent to a neighbour. */
template <typename T> struct Step {
    int on;
    T dl, n0, n1, n2;
};
template <typename T> __device__ __forceinline__ Step<T> step_from_prev(const Step<T> &s)
{
    return Step<T>{from_prev(s.on), from_prev(s.dl), from_prev(s.n0), from_prev(s.n1), from_prev(s.n2)};
}
template <typename T> __device__ __forceinline__ Step<T> step_from_next(const Step<T> &s)
{
    return Step<T>{from_next(s.on), from_next(s.dl), from_next(s.n0), from_next(s.n1), from_next(s.n2)};
}
template <typename T> __device__ __forceinline__ void move_minus(const Step<T> &s, T &p0, T &p1, T &p2)
{
    p0 = p0 - s.dl * s.n0;
    p1 = p1 - s.dl * s.n1;
    p2 = p2 - s.dl * s.n2;
}
template <typename T> __device__ __forceinline__ void move_plus(const Step<T> &s, T &p0, T &p1, T &p2)
{
    p0 = p0 + s.dl * s.n0;
    p1 = p1 + s.dl * s.n1;
    p2 = p2 + s.dl * s.n2;
}

template <typename T, class Feat>
__global__ void __launch_bounds__(kMaxThreads)
    k_warpreg(DModel<T> m, const T *__restrict__ qtab, const T *__restrict__ phtab, T *x, T *v,
              const T *__restrict__ rest, const T *__restrict__ bend_rest, int64_t N, const int64_t *map, int64_t n_run)
{
    const Feat has = MakeFeat<Feat>::make(m.features);
    const int k = (int)(threadIdx.x & 31u), w = (int)(threadIdx.x >> 5), wpb = (int)(blockDim.x >> 5);
    const int P = (int)m.points, K = (int)m.shape_count;
    const bool on = k < P, inner = on && k >= 1;
    const bool shaped = has(HB_F_SHAPE) && k >= 1 && k <= K;
    const bool need_rest = (has(HB_F_MOTION) && k == 0) || shaped;
    const bool bends = has(HB_F_BEND) && k >= 1 && k + 1 < P;
    const bool xpbd = m.solver == HB_SOLVER_XPBD;
    const T h = m.h;
    /* the loop bound is the same for every lane of a warp: whole warps take each strand */
    (void)N;
    for (int64_t j = (int64_t)blockIdx.x * wpb + w; j < n_run; j += (int64_t)gridDim.x * wpb) {
        const int64_t i = map ? map[j] : j; /* §3.14: only the guides, when guided */
        const int64_t at = i * 3 * (int64_t)P + 3 * k;
        T x0 = 0, x1 = 0, x2 = 0, v0 = 0, v1 = 0, v2 = 0, r0 = 0, r1 = 0, r2 = 0, br = 0;
        if (on) {
            x0 = x[at];
            x1 = x[at + 1];
            x2 = x[at + 2];
            v0 = v[at];
            v1 = v[at + 1];
            v2 = v[at + 2];
        }
        if (need_rest) {
            r0 = rest[at];
            r1 = rest[at + 1];
            r2 = rest[at + 2];
        }
        if (bends) br = bend_rest[i * (int64_t)(P - 2) + (k - 1)];
        /* §3.15 lane k's stretch rest length ℓ_k (a groom's, else ℓ) */
        const T ell = (m.seg_rest && inner) ? m.seg_rest[i * m.seg_is + (int64_t)(k - 1) * m.seg_s] : m.seg_len;
        T p0 = x0, p1 = x1, p2 = x2, d0 = 0, d1 = 0, d2 = 0;
        for (int64_t j = 0; j < m.substeps; j++) {
            const T *q = qtab + 9 * j;
            /* 1. root on the head, then p0 = x0 */
            if (k == 0) {
                if (has(HB_F_MOTION)) root_step(q, r0, r1, r2, h, x0, x1, x2, v0, v1, v2);
                p0 = x0;
                p1 = x1;
                p2 = x2;
            }
            /* 2. velocities and the prediction */
            if (inner) velocity_predict(m, has, has(HB_F_GUST) ? phtab[j] : (T)0, x0, x1, x2, v0, v1, v2, p0, p1, p2);
            /* 3. constraints; the multipliers of this lane's stretch (k−1, k), bend (k−1, k+1)
             * and shape k start the substep at 0 */
            T ls = 0, lb = 0, lg = 0;
            auto stretch = [&](int parity) { /* stretch (k−1, k) with k ≡ parity (mod 2) */
                                             const T a0 = from_prev(p0), a1 = from_prev(p1), a2 = from_prev(p2);
                                             Step<T> s{0, 0, 0, 0, 0};
                                             if (inner && (k & 1) == parity) {
                                                 s.on = distance_step(a0, a1, a2, p0, p1, p2, k - 1 != 0, ell,
                                                                      m.stretch_at, ls, s.dl, s.n0, s.n1, s.n2);
                                                 if (s.on) move_plus(s, p0, p1, p2);
                                             }
                                             const Step<T> r =
                                                 step_from_next(s); /* this lane is the lower end of lane k+1's */
                                             if (r.on && k >= 1 && k < 31) move_minus(r, p0, p1, p2);
            };
            auto bend = [&](int parity) { /* bend (k−1, k+1) with ⌊(k−1)/2⌋ ≡ parity (mod 2) */
                                          const T a0 = from_prev(p0), a1 = from_prev(p1), a2 = from_prev(p2);
                                          const T b0 = from_next(p0), b1 = from_next(p1), b2 = from_next(p2);
                                          Step<T> s{0, 0, 0, 0, 0};
                                          if (bends && (((k - 1) >> 1) & 1) == parity)
                                              s.on = distance_step(a0, a1, a2, b0, b1, b2, k - 1 != 0, br, m.bend_at,
                                                                   lb, s.dl, s.n0, s.n1, s.n2);
                                          const Step<T> lo =
                                              step_from_next(s); /* lane k+1's constraint: this lane is its lower end */
                                          const Step<T> hi =
                                              step_from_prev(s); /* lane k−1's constraint: this lane is its upper end */
                                          if (lo.on && k >= 1 && k < 31) move_minus(lo, p0, p1, p2);
                                          if (hi.on && k >= 1) move_plus(hi, p0, p1, p2);
            };
            auto shape = [&]() {
                if (!shaped) return;
                T t[3];
                if (has(HB_F_MOTION)) rotate(q, r0, r1, r2, t);
                else {
                    t[0] = r0;
                    t[1] = r1;
                    t[2] = r2;
                }
                shape_pull(p0, p1, p2, t, m.shape_at, lg);
            };
            auto lra = [&]() { /* §3.14: every lane reads the root's p from lane 0 */
                               const T a0 = __shfl_sync(kFull, p0, 0), a1 = __shfl_sync(kFull, p1, 0),
                                       a2 = __shfl_sync(kFull, p2, 0);
                               if (inner) lra_point(a0, a1, a2, p0, p1, p2, m.lra_len, (int64_t)k);
            };
            if (xpbd) {
                for (int64_t it = 0; it < m.iterations; it++) {
                    stretch(1);
                    stretch(0);
                    if (has(HB_F_BEND)) {
                        bend(0);
                        bend(1);
                    }
                    if (has(HB_F_SHAPE)) shape();
                    if (m.lra) lra();
                    if (has(HB_F_COLLIDE) && inner) collide_sphere(p0, p1, p2, m.collide_r);
                }
            } else {
                for (int64_t it = 0; it < m.iterations; it++) {
                    if (has(HB_F_BEND)) {
                        bend(0);
                        bend(1);
                    }
                    if (has(HB_F_SHAPE)) shape();
                    if (m.lra) lra();
                }
                /* §3.7 follow the leader, k ascending: lane kk follows lane kk−1's corrected point */
                for (int kk = 1; kk < P; kk++) {
                    const T a0 = __shfl_sync(kFull, p0, kk - 1), a1 = __shfl_sync(kFull, p1, kk - 1),
                            a2 = __shfl_sync(kFull, p2, kk - 1);
                    if (k == kk) follow(a0, a1, a2, p0, p1, p2, ell, has(HB_F_COLLIDE), m.collide_r, d0, d1, d2);
                }
            }
            /* 4. velocities from the motion (ftl: less s·d(k+1)/h), then the positions */
            T e0 = 0, e1 = 0, e2 = 0;
            if (!xpbd) {
                e0 = from_next(d0);
                e1 = from_next(d1);
                e2 = from_next(d2);
            }
            if (inner) {
                const bool corr = !xpbd && k + 1 < P;
                v0 = update_velocity(p0, x0, h, corr, m.ftl_s, e0);
                v1 = update_velocity(p1, x1, h, corr, m.ftl_s, e1);
                v2 = update_velocity(p2, x2, h, corr, m.ftl_s, e2);
                x0 = p0;
                x1 = p1;
                x2 = p2;
            }
        }
        if (on) {
            x[at] = x0;
            x[at + 1] = x1;
            x[at + 2] = x2;
            v[at] = v0;
            v[at + 1] = v1;
            v[at + 2] = v2;
        }
    }
}

/* ---- the dispatch tables ---- */
template <typename T>
using StrandFn = void (*)(DModel<T>, const T *, const T *, T *, T *, const T *, const T *, T *, int64_t,
                          const int64_t *, int64_t);
template <typename T>
using WarpFn = void (*)(DModel<T>, const T *, const T *, T *, T *, const T *, const T *, int64_t, const int64_t *,
                        int64_t);
/* k_warp and k_warpreg share a signature */

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

template <typename T, unsigned F> constexpr WarpFn<T> warpreg_entry()
{
    if constexpr (!valid_mask(F)) return nullptr;
    else if constexpr (specialised_mask(F)) return &k_warpreg<T, StaticF<F>>;
    else return &k_warpreg<T, DynF>;
}

template <typename T, unsigned... Fs> struct Tables {
    static constexpr StrandFn<T> strand[sizeof...(Fs)] = {strand_entry<T, Fs>()...};
    static constexpr WarpFn<T> warp[sizeof...(Fs)] = {warp_entry<T, Fs>()...};
    static constexpr WarpFn<T> warpreg[sizeof...(Fs)] = {warpreg_entry<T, Fs>()...};
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
        ObsScene si = sc;
        if (sc.seg64) si.seg64 = sc.seg64 + i * (sc.points - 1); /* §3.15: strand i's ℓ_k */
        observe_strand(si, Arr<const T>{x + i * lay.is, lay.ks, lay.cs}, Arr<const T>{v + i * lay.is, lay.ks, lay.cs},
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
                                const T *bend_rest, T *scratch, int64_t N, int grid, int block, cudaStream_t stream,
                                const int64_t *map, int64_t n_run)
{
    if (!valid_mask(m.features)) return cudaErrorInvalidValue;
    const StrandFn<T> fn = TablesT<T>::strand[m.features];
    fn<<<grid, block, 0, stream>>>(m, q, phase, x, v, rest, bend_rest, scratch, N, map, map ? n_run : N);
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
                              const T *bend_rest, int64_t N, int grid, int block, cudaStream_t stream,
                              const int64_t *map, int64_t n_run)
{
    if (!valid_mask(m.features)) return cudaErrorInvalidValue;
    const WarpFn<T> fn = TablesT<T>::warp[m.features];
    const size_t smem = warp_smem_bytes<T>(m.points) * (size_t)(block / 32);
    fn<<<grid, block, smem, stream>>>(m, q, phase, x, v, rest, bend_rest, N, map, map ? n_run : N);
    return cudaGetLastError();
}

template <typename T>
cudaError_t launch_frame_warpreg(const DModel<T> &m, const T *q, const T *phase, T *x, T *v, const T *rest,
                                 const T *bend_rest, int64_t N, int grid, int block, cudaStream_t stream,
                                 const int64_t *map, int64_t n_run)
{
    if (!valid_mask(m.features) || m.points > kWarpregMaxPoints) return cudaErrorInvalidValue;
    const WarpFn<T> fn = TablesT<T>::warpreg[m.features];
    fn<<<grid, block, 0, stream>>>(m, q, phase, x, v, rest, bend_rest, N, map, map ? n_run : N);
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
                                                const T *, T *, int64_t, int, int, cudaStream_t, const int64_t *,      \
                                                int64_t);                                                              \
    template cudaError_t launch_frame_warp<T>(const DModel<T> &, const T *, const T *, T *, T *, const T *, const T *, \
                                              int64_t, int, int, cudaStream_t, const int64_t *, int64_t);              \
    template cudaError_t launch_frame_warpreg<T>(const DModel<T> &, const T *, const T *, T *, T *, const T *,         \
                                                 const T *, int64_t, int, int, cudaStream_t, const int64_t *,          \
                                                 int64_t);                                                             \
    template size_t warp_smem_bytes<T>(int64_t);                                                                       \
    template cudaError_t prepare_warp<T>(unsigned, size_t);                                                            \
    template cudaError_t launch_bend_rest<T>(const T *, Layout, T *, Layout1, int64_t, int64_t, cudaStream_t);         \
    template cudaError_t launch_observe<T>(const ObsScene &, const T *, const T *, Layout, int64_t, ObsPartial *,      \
                                           cudaStream_t);
/* the Makefile compiles this file once per precision (-DHB_DYN_REAL), side by side */
#ifdef HB_DYN_REAL
HB_DYN_INSTANTIATE(HB_DYN_REAL)
#else
HB_DYN_INSTANTIATE(float)
HB_DYN_INSTANTIATE(double)
#endif
#undef HB_DYN_INSTANTIATE

} /* namespace dyn */
} /* namespace hb */
