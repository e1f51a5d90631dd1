/* kernels.cu — the stage kernels of the CUDA backend: init, wind, collide and the fused
 * wind+collide, one thread per strand, templated on the precision T and the layout
 * (cuda/paper/model.cuh holds the per-strand math; this file only maps threads to strands).
 *
 * Launch shape: `block` threads per block (--block-size, 32…1024, a multiple of 32), a
 * grid of ceil(N / block) blocks; each kernel loops with the grid's stride so that a
 * grid capped at 2^31 − 1 blocks still covers every strand (at the sizes that fit in GPU
 * memory the cap is never reached and each thread takes exactly one strand).
 *
 * __launch_bounds__(1024): every stage kernel must launch with any block size up to 1024,
 * so it must fit in 64 registers a thread (65536 / 1024). The fp32 kernels need fewer; the
 * fp64 fused and point-major collide kernels spill a few words at 64. A second build with
 * __launch_bounds__(512) (up to 128 registers, no spills) for blocks of at most 512 threads
 * was measured and dropped: on an H100 its lower occupancy made the fp64 fused pair slower
 * (4M x 32: 2.73 ms at block 256, 3.57 ms at block 512, against 2.61 ms for the 64-register
 * build at block 1024); docs/cuda.md.
 *
 * Point-major kernels take X, Y, Z as separate __restrict__ pointers; wind, collide and the
 * fused kernel without the intermediate never touch X. That kernel runs HB_WC_TILE strands a
 * thread in fp32 (k_wind_collide_tile; docs/cuda.md, "Two strands a thread").
 *
 * Prefetch depth (paper/model.cuh, walk_points): the paper variant's strand-major kernels load
 * each point when its turn comes (D = 0, as the C code and the paper do: that variant is
 * the untuned baseline); the point-major kernels keep HB_PREFETCH_F32 (fp32) or HB_PREFETCH_F64 (fp64)
 * points' loads in flight per thread.
 */
#include "paper/kernels.cuh"

namespace hb {

namespace {

constexpr int kMaxThreads = 1024;

/* The stage kernels' register bound. HB_MAXNREG (an experiment knob, unset in the Makefile's
 * builds) caps the registers instead, to measure occupancy against spills. */
#if defined(HB_MAXNREG)
#define HB_STAGE_BOUNDS __maxnreg__(HB_MAXNREG)
#define HB_POINT_BOUNDS(T) __maxnreg__(HB_MAXNREG)
#else
#define HB_STAGE_BOUNDS __launch_bounds__(kMaxThreads)
#define HB_POINT_BOUNDS(T) __maxnreg__(PointRegs<T>::value)
#endif
#define HB_TILE_BOUNDS(T) __maxnreg__(TileRegs<T>::value)

/* The fused wind+collide and the init kernels' register cap: fp32 HB_POINT_REGS_F32 (more warps a
 * SM hide the walks' latencies better than the registers saved cost; measured, docs/cuda.md),
 * fp64 the 64 of any 1024-thread block. */
#ifndef HB_POINT_REGS_F32
#define HB_POINT_REGS_F32 40
#endif
template <typename T> struct PointRegs {
    static constexpr int value = sizeof(T) == 4 ? HB_POINT_REGS_F32 : 64;
};
/* The tile kernel's cap: HB_TILE_REGS_F32 for fp32, 64 for fp64 */
#ifndef HB_TILE_REGS_F32
#define HB_TILE_REGS_F32 64
#endif
template <typename T> struct TileRegs {
    static constexpr int value = sizeof(T) == 4 ? HB_TILE_REGS_F32 : 64;
};

/* Prefetch depth of the point-major kernels, per precision: D points of y and z in flight
 * per thread. Measured on an H100 (4M strands x 32 points, block 256, fused wind+collide):
 * fp32 D = 1: 1.35 ms, 2: 1.50, 4: 1.52, 8: 1.53; fp64 D = 1: 2.74, 2: 2.73. The kernels are
 * compute-bound (docs/cuda.md), so the loads of one point ahead already hide the memory
 * latency among the other warps, and every extra level only costs registers. */
#ifndef HB_PREFETCH_F32
#define HB_PREFETCH_F32 1
#endif
#ifndef HB_PREFETCH_F64
#define HB_PREFETCH_F64 1
#endif
template <typename T> struct Prefetch;
template <> struct Prefetch<float> {
    static constexpr int value = HB_PREFETCH_F32;
};
template <> struct Prefetch<double> {
    static constexpr int value = HB_PREFETCH_F64;
};

template <class Layout> struct Depth;
template <typename T> struct Depth<StrandMajor<T>> {
    static constexpr int value = 0;
}; /* paper: untuned */
template <typename T> struct Depth<PointMajor<T>> {
    static constexpr int value = Prefetch<T>::value;
};

__device__ __forceinline__ int64_t first_strand()
{
    return (int64_t)blockIdx.x * blockDim.x + threadIdx.x;
}
__device__ __forceinline__ int64_t grid_stride()
{
    return (int64_t)gridDim.x * blockDim.x;
}

/* Adds every thread's v into *out exactly: a shuffle reduction in each warp, the warps'
 * sums through shared memory, then one 64-bit atomicAdd for the block. Every thread of
 * the block must call it (blockDim.x is a multiple of 32). */
__device__ __forceinline__ void block_add(unsigned long long v, unsigned long long *out)
{
    __shared__ unsigned long long warp_sum[kMaxThreads / 32];
    const unsigned lane = threadIdx.x & 31u, warp = threadIdx.x >> 5;
    for (int off = 16; off > 0; off >>= 1) v += __shfl_down_sync(0xffffffffu, v, off);
    if (lane == 0) warp_sum[warp] = v;
    __syncthreads();
    if (warp == 0) {
        const unsigned nwarps = blockDim.x >> 5;
        v = lane < nwarps ? warp_sum[lane] : 0ull;
        for (int off = 16; off > 0; off >>= 1) v += __shfl_down_sync(0xffffffffu, v, off);
        if (lane == 0 && v != 0ull) atomicAdd(out, v);
    }
}

unsigned grid_for(int64_t N, int block)
{
    int64_t g = (N + block - 1) / block;
    if (g > 0x7fffffff) g = 0x7fffffff;
    if (g < 1) g = 1;
    return (unsigned)g;
}

} /* namespace */

/* ---- the kernels ------------------------------------------------------------------------ */
/* a, b, c: StrandMajor: the canonical array (b, c unused); PointMajor: X, Y, Z. */

template <typename T, class Layout>
__global__ void HB_POINT_BOUNDS(T)
    k_init(const Model<T> m, T *__restrict__ a, T *__restrict__ b, T *__restrict__ c, const int64_t N)
{
    const Layout lay = Layout::make(a, b, c, N, m.points);
    for (int64_t i = first_strand(); i < N; i += grid_stride()) init_strand(m, lay, i);
}

template <typename T, class Layout>
__global__ void HB_STAGE_BOUNDS k_wind(const Model<T> m, T *__restrict__ a, T *__restrict__ b, T *__restrict__ c,
                                       const int64_t N)
{
    const Layout lay = Layout::make(a, b, c, N, m.points);
    for (int64_t i = first_strand(); i < N; i += grid_stride()) wind_strand<Depth<Layout>::value>(m, lay, i);
}

template <typename T, class Layout>
__global__ void HB_STAGE_BOUNDS k_collide(const Model<T> m, T *__restrict__ a, T *__restrict__ b, T *__restrict__ c,
                                          const int64_t N, unsigned long long *__restrict__ count)
{
    const Layout lay = Layout::make(a, b, c, N, m.points);
    unsigned long long changed = 0;
    for (int64_t i = first_strand(); i < N; i += grid_stride())
        changed += (unsigned long long)collide_strand<Depth<Layout>::value>(m, lay, i);
    block_add(changed, count);
}

/* Idx: the type of a point's offset within its array (int when N·P fits, see the launcher) */
template <typename T, bool Keep, class Idx>
__global__ void HB_POINT_BOUNDS(T)
    k_wind_collide(const Model<T> m, T *__restrict__ X, T *__restrict__ Y, T *__restrict__ Z, const int64_t N,
                   T *__restrict__ inter, unsigned long long *__restrict__ count)
{
    const PointMajor<T> lay = {X, Y, Z, N};
    const StrandMajor<T> keep = {inter, m.points};
    unsigned long long changed = 0;
    for (int64_t i = first_strand(); i < N; i += grid_stride())
        changed +=
            (unsigned long long)wind_collide_strand<Keep, Prefetch<T>::value, T, PointMajor<T>, Idx>(m, lay, i, keep);
    block_add(changed, count);
}

/* The fused kernel without the intermediate: K strands a thread. A warp takes a tile of 32·K
 * consecutive strands, lane l the strands l, l + 32, …, l + 32·(K − 1) of it, so each of
 * the K loads and stores of a point is one coalesced access of the warp, and the K walks
 * share the offsets, the loop and the prefetch (point k + 1 of every strand is loaded before
 * point k is computed). A strand past N (the last tile) computes on zeros and stores
 * nothing. Offsets in int: the launcher checks that N·P + 32·K fits. */
#ifndef HB_WC_TILE
#define HB_WC_TILE 2
#endif
template <typename T, int K>
__global__ void HB_TILE_BOUNDS(T) k_wind_collide_tile(const Model<T> m, T *__restrict__ Y, T *__restrict__ Z,
                                                      const int64_t N, unsigned long long *__restrict__ count)
{
    const int lane = threadIdx.x & 31;
    const int64_t tile = ((int64_t)blockIdx.x * blockDim.x + threadIdx.x) >> 5;
    const int64_t tiles = ((int64_t)gridDim.x * blockDim.x) >> 5;
    const int P = (int)m.points;
    const int stride = (int)N;
    unsigned long long changed = 0;
    for (int64_t base = tile * 32 * K; base < N; base += tiles * 32 * K) {
        const int first = (int)base + lane; /* point 0 of slot 0 */
        bool ok[K];
        T qy[K], qz[K];
        HB_UNROLL
        for (int j = 0; j < K; j++) {
            ok[j] = base + lane + 32 * j < N;
            qy[j] = ok[j] ? Y[first + 32 * j] : (T)0;
            qz[j] = ok[j] ? Z[first + 32 * j] : (T)0;
        }
        WindWalk<T> wind[K];
        CollideWalk<T, int> col[K];
        HB_UNROLL
        for (int j = 0; j < K; j++) {
            wind[j] = WindWalk<T>(m, qy[j], qz[j]);
            col[j] = CollideWalk<T, int>(m, qy[j], qz[j]);
        }
        int at = first + stride; /* point k of slot 0 */
        HB_UNROLL
        for (int j = 0; j < K; j++) {
            qy[j] = ok[j] && P > 1 ? Y[at + 32 * j] : (T)0;
            qz[j] = ok[j] && P > 1 ? Z[at + 32 * j] : (T)0;
        }
        HB_NO_UNROLL
        for (int k = 1; k < P; k++) {
            T cy[K], cz[K];
            HB_UNROLL
            for (int j = 0; j < K; j++) {
                cy[j] = qy[j];
                cz[j] = qz[j];
                qy[j] = ok[j] && k + 1 < P ? Y[at + stride + 32 * j] : (T)0;
                qz[j] = ok[j] && k + 1 < P ? Z[at + stride + 32 * j] : (T)0;
            }
            HB_UNROLL
            for (int j = 0; j < K; j++) {
                wind[j].step(k, cy[j], cz[j]);
                T wy = wind[j].ny, wz = wind[j].nz;
                col[j].step(wy, wz);
                if (ok[j]) {
                    Y[at + 32 * j] = wy;
                    Z[at + 32 * j] = wz;
                }
            }
            at += stride;
        }
        HB_UNROLL
        for (int j = 0; j < K; j++)
            if (ok[j]) changed += (unsigned long long)col[j].changed;
    }
    block_add(changed, count);
}

/* ---- the launchers ---------------------------------------------------------------------- */
/* The three arrays a stage kernel takes: strand-major passes its one array first. */
template <typename T> struct Arrays {
    T *a, *b, *c;
};
template <typename T> Arrays<T> arrays_of(const StrandMajor<T> &lay)
{
    return {lay.s, nullptr, nullptr};
}
template <typename T> Arrays<T> arrays_of(const PointMajor<T> &lay)
{
    return {lay.X, lay.Y, lay.Z};
}

template <typename T, class Layout>
cudaError_t launch_stage(hb_stage st, const Model<T> &m, const Layout &lay, int64_t N, unsigned long long *count,
                         int block, cudaStream_t stream)
{
    const Arrays<T> p = arrays_of(lay);
    const unsigned grid = grid_for(N, block);
    switch (st) {
    case HB_STAGE_INIT: k_init<T, Layout><<<grid, block, 0, stream>>>(m, p.a, p.b, p.c, N); break;
    case HB_STAGE_WIND: k_wind<T, Layout><<<grid, block, 0, stream>>>(m, p.a, p.b, p.c, N); break;
    case HB_STAGE_COLLIDE: k_collide<T, Layout><<<grid, block, 0, stream>>>(m, p.a, p.b, p.c, N, count); break;
    default: return cudaErrorInvalidValue;
    }
    return cudaGetLastError();
}

template <typename T>
cudaError_t launch_wind_collide(const Model<T> &m, const PointMajor<T> &lay, int64_t N, T *inter,
                                unsigned long long *count, int block, cudaStream_t stream)
{
    const bool narrow = N * m.points < (int64_t)INT32_MAX; /* every offset of a point fits an int */
    const unsigned grid = grid_for(N, block);
    constexpr int K = sizeof(T) == 4 ? HB_WC_TILE : 1; /* fp64 spills at K = 2 */
    const bool tile_fits = N * m.points + 32 * K < (int64_t)INT32_MAX;
    if (inter) {
        k_wind_collide<T, true, int64_t><<<grid, block, 0, stream>>>(m, lay.X, lay.Y, lay.Z, N, inter, count);
    } else if (K > 1 && tile_fits) {
        k_wind_collide_tile<T, K><<<grid_for((N + K - 1) / K, block), block, 0, stream>>>(m, lay.Y, lay.Z, N, count);
    } else if (narrow) {
        k_wind_collide<T, false, int><<<grid, block, 0, stream>>>(m, lay.X, lay.Y, lay.Z, N, nullptr, count);
    } else {
        k_wind_collide<T, false, int64_t><<<grid, block, 0, stream>>>(m, lay.X, lay.Y, lay.Z, N, nullptr, count);
    }
    return cudaGetLastError();
}

#define HB_INSTANTIATE(T)                                                                                              \
    template cudaError_t launch_stage<T, StrandMajor<T>>(hb_stage, const Model<T> &, const StrandMajor<T> &, int64_t,  \
                                                         unsigned long long *, int, cudaStream_t);                     \
    template cudaError_t launch_stage<T, PointMajor<T>>(hb_stage, const Model<T> &, const PointMajor<T> &, int64_t,    \
                                                        unsigned long long *, int, cudaStream_t);                      \
    template cudaError_t launch_wind_collide<T>(const Model<T> &, const PointMajor<T> &, int64_t, T *,                 \
                                                unsigned long long *, int, cudaStream_t);

HB_INSTANTIATE(float)
HB_INSTANTIATE(double)

} /* namespace hb */
