/* dyn_post.cuh — what the dynamic model does after a frame's substeps (cuda/dyn_post.cu):
 * the followers of docs/model.md §3.13, placed from their guides by a kernel of their own. */
#ifndef HB_DYN_POST_CUH
#define HB_DYN_POST_CUH

#include <cuda_runtime.h>
#include <stdint.h>

#include "dyn_kernels.cuh"

namespace hb {
namespace dyn {

/* One thread per follower j: strand follower[j] placed from the strands src[width·j + i]
 * with weights w[width·j + i] (c_ref/dyn_followers.c's plan, on the device); q the head
 * rotation at the frame's end ([9] on the device; nullptr: still head); x, v, rest in the
 * variant's layout `lay`. The same operations in the same order as
 * c_ref/dyn_followers_impl.h. */
template <typename T>
cudaError_t launch_place_followers(const DModel<T> &m, const T *q, T *x, T *v, const T *rest, Layout lay,
                                   const int64_t *follower, const int64_t *src, const T *w, int width,
                                   int64_t n_followers, cudaStream_t stream);

} /* namespace dyn */
} /* namespace hb */
#endif
