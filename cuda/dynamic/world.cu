/* cuda/dynamic/world.cu — the hair–hair grid's kernels (docs/model.md §3.16; the design in docs/cuda.md
 * "The hair–hair grid"): the splat of every point into 64-bit fixed-point sums, whose order
 * changes no bit, and the node fields. */
#include "dynamic/world.cuh"

#include <climits>

namespace hb {
namespace dyn {
namespace {

template <typename T> struct Splat;
template <> struct Splat<float> {
    __device__ static int point(const World<float> &w, const float *qg, const float *x, const float *v, int64_t *base,
                                int64_t *m, int64_t *p)
    {
        return hb_grid_splat_point_f32(qg, w.glo, w.gsc, w.gn, x, v, base, m, p);
    }
    __device__ static void node(int64_t j, const World<float> &w, const int64_t *mass, const int64_t *mom,
                                const float *target, float inv_rho0, float neg_kv, const float *qg, float *nv,
                                float *na)
    {
        hb_grid_node_f32(j, w.gn, mass, mom, target, inv_rho0, neg_kv, w.gsc, qg, nv, na);
    }
};
template <> struct Splat<double> {
    __device__ static int point(const World<double> &w, const double *qg, const double *x, const double *v,
                                int64_t *base, int64_t *m, int64_t *p)
    {
        return hb_grid_splat_point_f64(qg, w.glo, w.gsc, w.gn, x, v, base, m, p);
    }
    __device__ static void node(int64_t j, const World<double> &w, const int64_t *mass, const int64_t *mom,
                                const double *target, double inv_rho0, double neg_kv, const double *qg, double *nv,
                                double *na)
    {
        hb_grid_node_f64(j, w.gn, mass, mom, target, inv_rho0, neg_kv, w.gsc, qg, nv, na);
    }
};

/* The warp's sum of x over the lanes of `group` (lanes with the same cell), exact for any 64-bit
 * x within ±2^46: its low 16 bits and the rest summed apart by the warp's reduction unit. */
__device__ __forceinline__ int64_t group_sum(unsigned group, int64_t x)
{
    const unsigned lo = __reduce_add_sync(group, (unsigned)(x & 0xffff));
    const int hi = __reduce_add_sync(group, (int)(x >> 16));
    return (int64_t)hi * 65536 + (int64_t)lo;
}

/* The splat (docs/cuda.md "The hair–hair grid"). A block takes 32 neighbouring strands (the
 * order perm; nullptr: as stored): lane l of every warp holds strand s0 + l, and warp w its
 * points k ≡ w (mod warps), so a warp's 32 lanes hold point k of 32 neighbours, mostly in one
 * cell. Pass 1 finds the block's box of cells; when its nodes fit the shared window, pass 2
 * adds each cell's lanes' shares there (one shared atomic a node and channel a cell), and the
 * window goes to the grid with one global atomic a touched node and channel; otherwise pass 2
 * adds to the grid directly. Integer sums: no order changes a bit. */
constexpr int kSplatStrands = 32, kSplatWarps = 8, kWindow = 1024; /* nodes: 32 KB of int64 × 4 */

template <typename T> struct Locate;
template <> struct Locate<float> {
    __device__ static int at(const World<float> &w, const float *qg, const float *x, int64_t *b, float *wt)
    {
        return hb_grid_locate_f32(qg, w.glo, w.gsc, w.gn, x, b, wt);
    }
};
template <> struct Locate<double> {
    __device__ static int at(const World<double> &w, const double *qg, const double *x, int64_t *b, double *wt)
    {
        return hb_grid_locate_f64(qg, w.glo, w.gsc, w.gn, x, b, wt);
    }
};

template <typename T> __device__ __forceinline__ bool finite3(const T *p)
{
    return isfinite(p[0]) && isfinite(p[1]) && isfinite(p[2]);
}

template <typename T>
__global__ void __launch_bounds__(kSplatWarps * 32)
    k_grid_splat(World<T> w, const T *qg, const T *x, const T *v, int64_t N, int P, const int64_t *perm, int64_t *mass,
                 int64_t *mom)
{
    __shared__ int64_t win[4 * kWindow];
    __shared__ int lo[3], hi[3];
    const int lane = (int)(threadIdx.x & 31u), warp = (int)(threadIdx.x >> 5);
    const int64_t slot = (int64_t)blockIdx.x * kSplatStrands + lane;
    const bool live = slot < N;
    const int64_t strand = live ? (perm ? perm[slot] : slot) : 0;
    const int64_t n = w.gn;
    if (threadIdx.x < 3) lo[threadIdx.x] = INT_MAX, hi[threadIdx.x] = -1;
    __syncthreads();
    /* pass 1: the block's box of cells */
    for (int k = warp; k < P; k += kSplatWarps) {
        const T *xp = x + 3 * (strand * P + k);
        int64_t b;
        T wt[8];
        const bool in = live && finite3(xp) && finite3(v + 3 * (strand * P + k)) && Locate<T>::at(w, qg, xp, &b, wt);
        const int c[3] = {in ? (int)(b % n) : INT_MAX, in ? (int)((b / n) % n) : INT_MAX,
                          in ? (int)(b / (n * n)) : INT_MAX};
        for (int a = 0; a < 3; a++) { /* the warp's extremes first: one shared atomic a warp */
            const int mn = __reduce_min_sync(0xffffffffu, c[a]);
            const int mx = __reduce_max_sync(0xffffffffu, in ? c[a] + 1 : -1);
            if (lane == 0 && mx >= 0) {
                atomicMin(&lo[a], mn);
                atomicMax(&hi[a], mx);
            }
        }
    }
    __syncthreads();
    const int ex = hi[0] - lo[0] + 1, ey = hi[1] - lo[1] + 1, ez = hi[2] - lo[2] + 1;
    const bool windowed = hi[0] >= 0 && (int64_t)ex * ey * ez <= kWindow;
    if (hi[0] < 0) return; /* no point of the block in the grid */
    if (windowed) {
        for (int i = threadIdx.x; i < 4 * ex * ey * ez; i += blockDim.x) win[i] = 0;
        __syncthreads();
    }
    /* pass 2: each cell's lanes sum their shares, one atomic a node and channel */
    for (int k = warp; k < P; k += kSplatWarps) {
        const int64_t r = strand * P + k;
        const T *xp = x + 3 * r, *vp = v + 3 * r;
        int64_t b = -1;
        T wt[8];
        const bool in = live && finite3(xp) && finite3(vp) && Locate<T>::at(w, qg, xp, &b, wt);
        if (!in) b = -1;
        T vc[3];
        for (int c = 0; c < 3; c++) {
            const T lim = (T)HB_GRID_VEL_CLAMP;
            vc[c] = in ? (vp[c] < -lim ? -lim : vp[c] > lim ? lim : vp[c]) : (T)0;
        }
        const unsigned same = __match_any_sync(0xffffffffu, (unsigned long long)b);
        const bool leader = lane == __ffs(same) - 1;
        for (int c8 = 0; c8 < 8; c8++) {
            /* the point's fixed-point shares at corner c8, as hb_grid_splat_point computes them */
            const T wc = in ? wt[c8] : (T)0;
            const int64_t sm = group_sum(same, HB_RINT64(wc * (T)HB_GRID_MASS_SCALE));
            int64_t sp[3];
            for (int c = 0; c < 3; c++) sp[c] = group_sum(same, HB_RINT64((wc * vc[c]) * (T)HB_GRID_MOM_SCALE));
            if (!(in && leader)) continue;
            const int64_t j = hb_grid_corner_f64(b, n, c8);
            if (windowed) {
                const int jx = (int)(j % n) - lo[0], jy = (int)((j / n) % n) - lo[1], jz = (int)(j / (n * n)) - lo[2];
                int64_t *cell = win + 4 * (jx + ex * (jy + ey * jz));
                atomicAdd((unsigned long long *)&cell[0], (unsigned long long)sm);
                for (int c = 0; c < 3; c++) atomicAdd((unsigned long long *)&cell[1 + c], (unsigned long long)sp[c]);
            } else {
                atomicAdd((unsigned long long *)&mass[j], (unsigned long long)sm);
                for (int c = 0; c < 3; c++) atomicAdd((unsigned long long *)&mom[3 * j + c], (unsigned long long)sp[c]);
            }
        }
    }
    if (!windowed) return;
    __syncthreads();
    for (int i = threadIdx.x; i < ex * ey * ez; i += blockDim.x) {
        const int64_t *cell = win + 4 * i;
        if (cell[0] == 0 && cell[1] == 0 && cell[2] == 0 && cell[3] == 0) continue;
        const int jx = i % ex + lo[0], jy = (i / ex) % ey + lo[1], jz = i / (ex * ey) + lo[2];
        const int64_t j = jx + n * (jy + n * (int64_t)jz);
        atomicAdd((unsigned long long *)&mass[j], (unsigned long long)cell[0]);
        for (int c = 0; c < 3; c++) atomicAdd((unsigned long long *)&mom[3 * j + c], (unsigned long long)cell[1 + c]);
    }
}

template <typename T>
__global__ void k_grid_nodes(World<T> w, const T *qg, const int64_t *mass, const int64_t *mom, const T *target,
                             T inv_rho0, T neg_kv, T *node_v, T *node_a)
{
    const int64_t j = (int64_t)blockIdx.x * blockDim.x + threadIdx.x;
    if (j < w.gn * w.gn * w.gn) Splat<T>::node(j, w, mass, mom, target, inv_rho0, neg_kv, qg, node_v, node_a);
}

int blocks_for(int64_t items, int block)
{
    const int64_t g = (items + block - 1) / block;
    return (int)(g < 1 ? 1 : g > 2147483647 ? 2147483647 : g);
}

} /* namespace */

template <typename T>
cudaError_t launch_grid_splat(const World<T> &w, const T *qg, const T *x, const T *v, int64_t N, int64_t P,
                              const int64_t *perm, int64_t *mass, int64_t *mom, cudaStream_t stream)
{
    const int64_t nodes = w.gn * w.gn * w.gn;
    cudaError_t e = cudaMemsetAsync(mass, 0, (size_t)nodes * sizeof *mass, stream);
    if (e == cudaSuccess) e = cudaMemsetAsync(mom, 0, (size_t)nodes * 3 * sizeof *mom, stream);
    if (e != cudaSuccess) return e;
    const int64_t blocks = (N + kSplatStrands - 1) / kSplatStrands;
    k_grid_splat<T>
        <<<(int)(blocks < 1 ? 1 : blocks), kSplatWarps * 32, 0, stream>>>(w, qg, x, v, N, (int)P, perm, mass, mom);
    return cudaGetLastError();
}

template <typename T>
cudaError_t launch_grid_nodes(const World<T> &w, const T *qg, const int64_t *mass, const int64_t *mom, const T *target,
                              T inv_rho0, T neg_kv, T *node_v, T *node_a, cudaStream_t stream)
{
    k_grid_nodes<T><<<blocks_for(w.gn * w.gn * w.gn, 256), 256, 0, stream>>>(w, qg, mass, mom, target, inv_rho0, neg_kv,
                                                                             node_v, node_a);
    return cudaGetLastError();
}

template cudaError_t launch_grid_splat<float>(const World<float> &, const float *, const float *, const float *,
                                              int64_t, int64_t, const int64_t *, int64_t *, int64_t *, cudaStream_t);
template cudaError_t launch_grid_splat<double>(const World<double> &, const double *, const double *, const double *,
                                               int64_t, int64_t, const int64_t *, int64_t *, int64_t *, cudaStream_t);
template cudaError_t launch_grid_nodes<float>(const World<float> &, const float *, const int64_t *, const int64_t *,
                                              const float *, float, float, float *, float *, cudaStream_t);
template cudaError_t launch_grid_nodes<double>(const World<double> &, const double *, const int64_t *, const int64_t *,
                                               const double *, double, double, double *, double *, cudaStream_t);

} /* namespace dyn */
} /* namespace hb */
