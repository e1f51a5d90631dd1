/* cuda/dynamic/lod.cu — the rendered points of docs/model.md §3.14 (--render-points) as a kernel of
 * their own, launched on the frames that are written: one thread per rendered point, reading
 * the state (and velocities) in the variant's layout and writing canonical [N·P_r][3]. The
 * arithmetic is cuda/dynamic/lod.cuh's, which follows c_ref/dynamic/dyn_lod_impl.h. */
#include "dynamic/lod.cuh"

namespace hb {
namespace dyn {

namespace {

template <typename T>
__global__ void k_lod(const T *x, const T *v, Layout lay, int64_t n, int64_t ps, int64_t pr, T *xr, T *vr)
{
    const int64_t g = (int64_t)blockIdx.x * blockDim.x + threadIdx.x;
    if (g >= n * pr) return;
    const int64_t i = g / pr, j = g - i * pr;
    lod_render_point(x, x, lay, i, ps, pr, j, xr + 3 * g);
    if (v) lod_render_point(x, v, lay, i, ps, pr, j, vr + 3 * g);
}

} /* namespace */

template <typename T>
cudaError_t launch_lod_render(const T *x, const T *v, Layout lay, int64_t n, int64_t ps, int64_t pr, T *xr, T *vr,
                              cudaStream_t stream)
{
    if (n <= 0) return cudaSuccess;
    const int block = 256;
    const int64_t grid = (n * pr + block - 1) / block;
    if (grid > 2147483647) return cudaErrorInvalidValue;
    k_lod<T><<<(int)grid, block, 0, stream>>>(x, v, lay, n, ps, pr, xr, vr);
    return cudaGetLastError();
}

template cudaError_t launch_lod_render<float>(const float *, const float *, Layout, int64_t, int64_t, int64_t, float *,
                                              float *, cudaStream_t);
template cudaError_t launch_lod_render<double>(const double *, const double *, Layout, int64_t, int64_t, int64_t,
                                               double *, double *, cudaStream_t);

} /* namespace dyn */
} /* namespace hb */
