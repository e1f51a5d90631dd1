/* check.cuh — CUDA error checking for the hairbench CUDA backend.
 *
 * Every CUDA API call and every kernel launch is checked. On an error the macros write one
 * line into the caller's `err` buffer,
 *
 *     CUDA error in <what> (cuda/file.cu:123): <cudaGetErrorString>
 *
 * and make the enclosing function return -1, so that the shared driver prints
 * `hairsim-cuda: error: …` and exits with its runtime status (4). No exit() here, no
 * stack traces. The macros need `char *err` and `size_t errlen` in scope.
 *
 *   HB_CUDA(call)              an API call; <what> is the call's text
 *   HB_CUDA_AS(call, what)     an API call with a short description instead
 *   HB_LAUNCHED(what)          right after a kernel launch: cudaGetLastError()
 *
 * Asynchronous faults of a kernel (an illegal address, say) surface at the next
 * synchronising call, which is checked like any other (run_stage's cudaEventSynchronize).
 */
#ifndef HB_CHECK_CUH
#define HB_CHECK_CUH

#include <cuda_runtime.h>
#include <stddef.h>
#include <stdio.h>

static inline int hb_cuda_fail(cudaError_t e, const char *what, const char *file, int line, char *err, size_t errlen)
{
    if (err && errlen) snprintf(err, errlen, "CUDA error in %s (%s:%d): %s", what, file, line, cudaGetErrorString(e));
    return -1;
}

#define HB_CUDA_AS(call, what)                                                                                         \
    do {                                                                                                               \
        cudaError_t hb_e_ = (call);                                                                                    \
        if (hb_e_ != cudaSuccess) return hb_cuda_fail(hb_e_, (what), __FILE__, __LINE__, err, errlen);                 \
    } while (0)

#define HB_CUDA(call) HB_CUDA_AS(call, #call)

#define HB_LAUNCHED(what) HB_CUDA_AS(cudaGetLastError(), (what))

#endif
