/* layout.cu — conversion between the canonical state [N][P][3] (what crosses the backend
 * interface and the HDF5 file) and the point-major structure of arrays X, Y, Z [P][N] of
 * the soa and fused variants. Outside the timed stages (it is part of load/fetch).
 *
 * The canonical array is a matrix of N rows (strands) and C = 3P columns (point k,
 * coordinate c at column 3k + c); point-major is its transpose, split by c. A block moves a
 * 32 x 32 tile through shared memory (padded against bank conflicts), so that both the
 * reads and the writes of a warp are 32 consecutive elements.
 */
#include "paper/kernels.cuh"

namespace hb {

namespace {

constexpr int kTile = 32; /* tile edge; threadIdx.x runs along it */
constexpr int kRows = 8;  /* threadIdx.y: each thread moves kTile / kRows elements */

dim3 tile_grid(int64_t N, int64_t C)
{
    int64_t gx = (N + kTile - 1) / kTile, gy = (C + kTile - 1) / kTile;
    if (gx > 0x7fffffff) gx = 0x7fffffff;
    if (gy > 65535) gy = 65535;
    return dim3((unsigned)gx, (unsigned)gy, 1);
}

} /* namespace */

/* One kernel for both directions: pass 1 reads the source into tile[j][tx], pass 2 writes
 * tile[tx][j] to the destination. The canonical side of element (j, tx) is row r0 + j, column
 * c0 + tx; the point-major side is column c0 + j (point k, coordinate comp), strand r0 + tx;
 * both are consecutive along tx. */
template <typename T, bool kToPointMajor>
__global__ void __launch_bounds__(kTile *kRows) k_transpose(T *__restrict__ canon, T *__restrict__ X, T *__restrict__ Y,
                                                            T *__restrict__ Z, const int64_t N, const int64_t P)
{
    __shared__ T tile[kTile][kTile + 1];
    const int64_t C = 3 * P;
    const int tx = threadIdx.x, ty = threadIdx.y;
    for (int64_t r0 = (int64_t)blockIdx.x * kTile; r0 < N; r0 += (int64_t)gridDim.x * kTile) {
        for (int64_t c0 = (int64_t)blockIdx.y * kTile; c0 < C; c0 += (int64_t)gridDim.y * kTile) {
            auto canon_at = [&](int j) -> T * {
                const int64_t r = r0 + j, c = c0 + tx;
                return r < N && c < C ? canon + r * C + c : nullptr;
            };
            auto point_major_at = [&](int j) -> T * {
                const int64_t c = c0 + j, r = r0 + tx;
                if (r >= N || c >= C) return nullptr;
                const int64_t k = c / 3;
                const int comp = (int)(c - 3 * k);
                return (comp == 0 ? X : (comp == 1 ? Y : Z)) + k * N + r;
            };
            for (int j = ty; j < kTile; j += kRows)
                if (const T *src = kToPointMajor ? canon_at(j) : point_major_at(j)) tile[j][tx] = *src;
            __syncthreads();
            for (int j = ty; j < kTile; j += kRows)
                if (T *dst = kToPointMajor ? point_major_at(j) : canon_at(j)) *dst = tile[tx][j];
            __syncthreads();
        }
    }
}

template <typename T>
cudaError_t launch_to_point_major(const T *canonical, const PointMajor<T> &pm, int64_t N, int64_t P,
                                  cudaStream_t stream)
{
    /* the kernel only reads canonical in this direction */
    k_transpose<T, true>
        <<<tile_grid(N, 3 * P), dim3(kTile, kRows, 1), 0, stream>>>(const_cast<T *>(canonical), pm.X, pm.Y, pm.Z, N, P);
    return cudaGetLastError();
}

template <typename T>
cudaError_t launch_to_canonical(const PointMajor<T> &pm, T *canonical, int64_t N, int64_t P, cudaStream_t stream)
{
    k_transpose<T, false><<<tile_grid(N, 3 * P), dim3(kTile, kRows, 1), 0, stream>>>(canonical, pm.X, pm.Y, pm.Z, N, P);
    return cudaGetLastError();
}

template cudaError_t launch_to_point_major<float>(const float *, const PointMajor<float> &, int64_t, int64_t,
                                                  cudaStream_t);
template cudaError_t launch_to_point_major<double>(const double *, const PointMajor<double> &, int64_t, int64_t,
                                                   cudaStream_t);
template cudaError_t launch_to_canonical<float>(const PointMajor<float> &, float *, int64_t, int64_t, cudaStream_t);
template cudaError_t launch_to_canonical<double>(const PointMajor<double> &, double *, int64_t, int64_t, cudaStream_t);

} /* namespace hb */
