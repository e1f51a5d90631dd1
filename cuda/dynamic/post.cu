/* cuda/dynamic/post.cu — the followers' placement (docs/model.md §3.14) as a kernel of its own, launched
 * after each frame's simulate kernel on the same stream. One thread per follower; the guides
 * it reads are final for the frame and no follower is another's guide, so the threads are
 * independent. Follows c_ref/dynamic/dyn_followers_impl.h operation by operation. */
#include "dynamic/post.cuh"

namespace hb {
namespace dyn {

namespace {

template <typename T>
__global__ void k_place(DModel<T> m, const T *q, T *xb, T *vb, const T *restb, Layout lay, const int64_t *follower,
                        const int64_t *src, const T *wt, int W, int64_t n)
{
    const int64_t j = (int64_t)blockIdx.x * blockDim.x + threadIdx.x;
    if (j >= n) return;
    place_follower(m, q, At<T>{xb, lay}, At<T>{vb, lay}, At<const T>{restb, lay}, follower[j], src + (int64_t)W * j,
                   wt + (int64_t)W * j, W);
}

} /* namespace */

template <typename T>
cudaError_t launch_place_followers(const DModel<T> &m, const T *q, T *x, T *v, const T *rest, Layout lay,
                                   const int64_t *follower, const int64_t *src, const T *w, int width,
                                   int64_t n_followers, cudaStream_t stream)
{
    if (n_followers <= 0) return cudaSuccess;
    const int block = 128;
    const int64_t grid = (n_followers + block - 1) / block;
    if (grid > 2147483647) return cudaErrorInvalidValue;
    k_place<T><<<(int)grid, block, 0, stream>>>(m, q, x, v, rest, lay, follower, src, w, width, n_followers);
    return cudaGetLastError();
}

template cudaError_t launch_place_followers<float>(const DModel<float> &, const float *, float *, float *,
                                                   const float *, Layout, const int64_t *, const int64_t *,
                                                   const float *, int, int64_t, cudaStream_t);
template cudaError_t launch_place_followers<double>(const DModel<double> &, const double *, double *, double *,
                                                    const double *, Layout, const int64_t *, const int64_t *,
                                                    const double *, int, int64_t, cudaStream_t);

} /* namespace dyn */
} /* namespace hb */
