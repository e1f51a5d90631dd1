/* kernels.cuh — the launchers of the CUDA backend's kernels (cuda/paper/kernels.cu: the stages,
 * cuda/paper/layout.cu: canonical <-> point-major conversion).
 *
 * Every launcher enqueues its kernel(s) on `stream` and returns cudaGetLastError() right
 * after the launch, so the caller checks each launch (cuda/check.cuh). Stage kernels run
 * one thread per strand, `block` threads per block (32…1024, a multiple of 32), a grid of
 * ceil(N / block) blocks (capped at 2^31 − 1 blocks, past which each thread takes several
 * strands, strided by the grid). Instantiated for T = float and T = double.
 */
#ifndef HB_KERNELS_CUH
#define HB_KERNELS_CUH

#include <cuda_runtime.h>
#include <stdint.h>

#include "paper/model.cuh"
#include "runtime/params.h" /* hb_stage */

namespace hb {

/* One stage kernel on either layout (StrandMajor: the paper's scheme; PointMajor: soa):
 *   init     roots and drape, writing x, y and z of every point;
 *   wind     in place; point-major reads and writes y and z only;
 *   collide  in place; adds the number of points changed to *count (exactly: a per-block
 *            reduction, then one 64-bit atomicAdd per block); point-major: y and z only.
 * `count` is used by collide only. An unknown stage returns cudaErrorInvalidValue. */
template <typename T, class Layout>
cudaError_t launch_stage(hb_stage st, const Model<T> &m, const Layout &lay, int64_t N, unsigned long long *count,
                         int block, cudaStream_t stream);

/* Wind immediately followed by collide, one kernel, point-major. With `inter` non-null the
 * post-wind state is also written there (canonical [N][P][3]; x is then read as well);
 * with `inter` null only y and z are read once and written once. */
template <typename T>
cudaError_t launch_wind_collide(const Model<T> &m, const PointMajor<T> &lay, int64_t N, T *inter,
                                unsigned long long *count, int block, cudaStream_t stream);

/* Canonical [N][P][3] <-> point-major X, Y, Z [P][N] (tiled through shared memory). */
template <typename T>
cudaError_t launch_to_point_major(const T *canonical, const PointMajor<T> &pm, int64_t N, int64_t P,
                                  cudaStream_t stream);
template <typename T>
cudaError_t launch_to_canonical(const PointMajor<T> &pm, T *canonical, int64_t N, int64_t P, cudaStream_t stream);

} /* namespace hb */

#endif
