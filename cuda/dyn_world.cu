/* dyn_world.cu — the hair–hair grid's kernels (docs/model.md §3.16; the design in docs/cuda.md
 * "The hair–hair grid"): the splat of every point into 64-bit fixed-point sums, whose order
 * changes no bit, and the node fields. */
#include "dyn_world.cuh"

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

/* One thread a strand, its points one after another; the strands in the order perm (nullptr:
 * as stored), so the 32 lanes of a warp hold point k of 32 neighbouring strands, mostly in one
 * cell: the lanes of each cell sum their shares first, then one atomic a node and channel. */
template <typename T>
__global__ void k_grid_splat(World<T> w, const T *qg, const T *x, const T *v, int64_t N, int P, const int64_t *perm,
                             int64_t *mass, int64_t *mom)
{
    const int64_t s = (int64_t)blockIdx.x * blockDim.x + threadIdx.x;
    const bool live = s < N;
    const int64_t strand = live ? (perm ? perm[s] : s) : 0;
    const int lane = (int)(threadIdx.x & 31u);
    for (int k = 0; k < P; k++) {
        int64_t base = -1, m[8], p[24];
        const int64_t r = strand * P + k;
        const bool in = live && Splat<T>::point(w, qg, x + 3 * r, v + 3 * r, &base, m, p);
        if (!in) base = -1;
        const unsigned same = __match_any_sync(0xffffffffu, (unsigned long long)base);
        const bool leader = lane == __ffs(same) - 1;
#pragma unroll
        for (int c8 = 0; c8 < 8; c8++) {
            const int64_t sm = group_sum(same, in ? m[c8] : 0);
            int64_t sp[3];
            for (int c = 0; c < 3; c++) sp[c] = group_sum(same, in ? p[3 * c8 + c] : 0);
            if (in && leader) {
                const int64_t j = hb_grid_corner_f64(base, w.gn, c8);
                atomicAdd((unsigned long long *)&mass[j], (unsigned long long)sm);
                for (int c = 0; c < 3; c++) atomicAdd((unsigned long long *)&mom[3 * j + c], (unsigned long long)sp[c]);
            }
        }
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
    k_grid_splat<T><<<blocks_for(N, 128), 128, 0, stream>>>(w, qg, x, v, N, (int)P, perm, mass, mom);
    return cudaGetLastError();
}

template <typename T>
cudaError_t launch_grid_nodes(const World<T> &w, const T *qg, const int64_t *mass, const int64_t *mom, const T *target,
                              T inv_rho0, T neg_kv, T *node_v, T *node_a, cudaStream_t stream)
{
    k_grid_nodes<T><<<blocks_for(w.gn * w.gn * w.gn, 256), 256, 0, stream>>>(w, qg, mass, mom, target, inv_rho0,
                                                                             neg_kv, node_v, node_a);
    return cudaGetLastError();
}

template cudaError_t launch_grid_splat<float>(const World<float> &, const float *, const float *, const float *,
                                              int64_t, int64_t, const int64_t *, int64_t *, int64_t *, cudaStream_t);
template cudaError_t launch_grid_splat<double>(const World<double> &, const double *, const double *, const double *,
                                               int64_t, int64_t, const int64_t *, int64_t *, int64_t *, cudaStream_t);
template cudaError_t launch_grid_nodes<float>(const World<float> &, const float *, const int64_t *, const int64_t *,
                                              const float *, float, float, float *, float *, cudaStream_t);
template cudaError_t launch_grid_nodes<double>(const World<double> &, const double *, const int64_t *,
                                               const int64_t *, const double *, double, double, double *, double *,
                                               cudaStream_t);

} /* namespace dyn */
} /* namespace hb */
