/* cuda/dynamic/chain.cuh — kernels launched as programmatic dependents of the kernel before them in
 * their stream (docs/cuda.md "The hair–hair grid and the colliders"): the launch overlaps that
 * kernel's tail, and the dependent waits for its completion and writes before its first read. */
#ifndef HB_DYN_CHAIN_CUH
#define HB_DYN_CHAIN_CUH

#include <cuda_runtime.h>

namespace hb {
namespace dyn {

/* the kernel before's writes visible: the first statement of a kernel that launch_chained launches
 * (where it was launched plainly, nothing to wait for) */
__device__ __forceinline__ void wait_for_previous()
{
    asm volatile("griddepcontrol.wait;" ::: "memory");
}

/* kernel<<<grid, block, smem, stream>>>(args...) as a programmatic dependent */
template <typename K, typename... A>
cudaError_t launch_chained(K kernel, dim3 grid, dim3 block, size_t smem, cudaStream_t stream, A... args)
{
    cudaLaunchConfig_t cfg = {};
    cfg.gridDim = grid;
    cfg.blockDim = block;
    cfg.dynamicSmemBytes = smem;
    cfg.stream = stream;
    cudaLaunchAttribute at[1];
    at[0].id = cudaLaunchAttributeProgrammaticStreamSerialization;
    at[0].val.programmaticStreamSerializationAllowed = 1;
    cfg.attrs = at;
    cfg.numAttrs = 1;
    return cudaLaunchKernelEx(&cfg, kernel, args...);
}

} /* namespace dyn */
} /* namespace hb */

#endif
