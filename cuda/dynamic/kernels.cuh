/* cuda/dynamic/kernels.cuh — the launchers of the dynamic model's kernels (cuda/dynamic/kernels.cu; the
 * math is cuda/dynamic/model.cuh, the design docs/cuda.md "The dynamic model").
 *
 * Every launcher enqueues its kernel on `stream` and returns cudaGetLastError() right after
 * the launch, so the caller checks each launch (cuda/check.cuh). Instantiated for T = float
 * and T = double.
 */
#ifndef HB_DYN_KERNELS_CUH
#define HB_DYN_KERNELS_CUH

#include <cuda_runtime.h>
#include <stddef.h>
#include <stdint.h>

#include "dynamic/model.cuh"

namespace hb {
namespace dyn {

/* The kernel's feature policy from the run's mask (StaticF folds it, DynF tests it). */
template <class Feat> struct MakeFeat;
template <unsigned F> struct MakeFeat<StaticF<F>> {
    __device__ static StaticF<F> make(unsigned) { return StaticF<F>(); }
};
template <> struct MakeFeat<DynF> {
    __device__ static DynF make(unsigned f) { return DynF{f}; }
};

/* Where strand i's point k, coordinate c lies in an array: base[i·is + k·ks + c·cs].
 *   point-major X|Y|Z [P][N] (the strand variant): is = 1, ks = N, cs = N·P
 *   canonical [N][P][3] (the warp variant):        is = 3P, ks = 3, cs = 1 */
struct Layout {
    int64_t is, ks, cs;
};
/* A per-strand array of P − 2 bend rest lengths: entry j of strand i at base[i·is + j·s]. */
struct Layout1 {
    int64_t is, s;
};

/* Strands per observe block: per-strand partials are combined in strand order within a
 * chunk of this many strands, and the chunks in order on the host, exactly as
 * backend_cpu.c's cpu_dyn_observe does (its OBS_CHUNK), so the sums do not depend on the
 * block size, and equal the CPU's where the states are equal. */
constexpr int64_t kObsChunk = 1024;

/* A feature mask that a run can have: not a gust without wind. */
constexpr bool valid_mask(unsigned f)
{
    return !((f & HB_F_GUST) && !(f & HB_F_WIND)) && f < HB_F_COUNT;
}
inline bool valid_features(unsigned f)
{
    return valid_mask(f);
}

/* The feature sets with kernels of their own: the configured scenes (configs/scenes/
 * dynamic.toml: every feature; still-dynamic.toml: the collider), the analytic checks
 * (gravity only, drag, wind), the masks harness/studies/featurecost.py times (none, each feature
 * alone, each removed from the full scene; a wind needs drag, gusts need the wind) and a
 * few common runs. Masks: BEND 1, SHAPE 2, WIND 4, GUST 8, MOTION 16, COLLIDE 32, DRAG 64;
 * ALL = 127. */
constexpr bool specialised_mask(unsigned f)
{
#if defined(HB_DYN_SPECIALISE_ALL)
    return true;
#else
    switch (f) {
    case 0:         /* nothing: gravity and stretch only */
    case HB_F_BEND: /* each feature alone … */
    case HB_F_SHAPE:
    case HB_F_WIND | HB_F_DRAG:
    case HB_F_WIND | HB_F_GUST | HB_F_DRAG:
    case HB_F_MOTION:
    case HB_F_COLLIDE: /* … the default scene's collider */
    case HB_F_DRAG:
    case 127 & ~HB_F_BEND: /* each removed from all … */
    case 127 & ~HB_F_SHAPE:
    case 127 & ~(HB_F_WIND | HB_F_GUST):
    case 127 & ~HB_F_GUST:
    case 127 & ~HB_F_MOTION:
    case 127 & ~HB_F_COLLIDE:
    case 127 & ~(HB_F_DRAG | HB_F_WIND | HB_F_GUST):
    case 127:                      /* … and all (dynamic.toml) */
    case HB_F_COLLIDE | HB_F_DRAG: /* common runs */
    case HB_F_BEND | HB_F_COLLIDE | HB_F_DRAG:
    case HB_F_BEND | HB_F_SHAPE | HB_F_COLLIDE | HB_F_DRAG:
    case HB_F_BEND | HB_F_WIND | HB_F_COLLIDE | HB_F_DRAG:
    case HB_F_BEND | HB_F_WIND | HB_F_GUST | HB_F_COLLIDE | HB_F_DRAG: return true;
    default: return false;
    }
#endif
}


/* map (with n_run entries): the strands to simulate, the guides of docs/model.md §3.14;
 * nullptr simulates all N. */

/* The strand variant: one thread per strand, all S substeps of the frame in one launch.
 * x, v, rest: point-major X|Y|Z [P][N]; bend_rest [P−2][N]; scratch: 9·P·threads reals
 * (p, λ, d of each thread, interleaved so that a warp's accesses coalesce), threads =
 * grid·block. q, phase: the frame's tables on the device ([S][9], [S]). */
template <typename T>
cudaError_t launch_frame_strand(const DModel<T> &m, const T *q, const T *phase, T *x, T *v, const T *rest,
                                const T *bend_rest, T *scratch, int64_t N, int grid, int block, cudaStream_t stream,
                                const int64_t *map = nullptr, int64_t n_run = 0);

/* The warp variant: one warp per strand (block/32 strands per block), the strand's x, v, p,
 * λ and d in shared memory (warp_smem_bytes per warp). x, v, rest canonical [N][P][3];
 * bend_rest [N][P−2]. */
template <typename T>
cudaError_t launch_frame_warp(const DModel<T> &m, const T *q, const T *phase, T *x, T *v, const T *rest,
                              const T *bend_rest, int64_t N, int grid, int block, cudaStream_t stream,
                              const int64_t *map = nullptr, int64_t n_run = 0);
template <typename T> size_t warp_smem_bytes(int64_t P);

/* The warpreg variant: one warp per strand, lane k holds point k in registers and
 * neighbours exchange through warp shuffles; x, v, rest canonical [N][P][3], bend_rest
 * [N][P−2] as the warp variant. P ≤ kWarpregMaxPoints. */
constexpr int64_t kWarpregMaxPoints = 32;
template <typename T>
cudaError_t launch_frame_warpreg(const DModel<T> &m, const T *q, const T *phase, T *x, T *v, const T *rest,
                                 const T *bend_rest, int64_t N, int grid, int block, cudaStream_t stream,
                                 const int64_t *map = nullptr, int64_t n_run = 0);
/* The lanes variant (cuda/dynamic/lanes.cu; its kernel lanes_kernel.cuh): L lanes a strand, G consecutive points a lane in
 * registers (xpbd: L = 16, G = 2, 4, 8; ftl: fewer lanes with more points), P ≤
 * kLanesMaxPoints; x, v, rest canonical [N][P][3], bend_rest [N][P−2]; dynamic shared memory a
 * block (a warp's strands staged for coalesced loads and stores, their rest shape, and with the
 * grid's `held` its samples; prepare_lanes raises the limit). The launcher sizes the grid itself:
 * one pass over the strands. */
constexpr int64_t kLanesMaxPoints = 128;
constexpr int kLanesMaxBlock = 256; /* __launch_bounds__: up to 255 registers a thread */
/* seg: a groom's per-segment rest lengths (docs/model.md §3.15; launch with m.seg_rest set) */
template <typename T>
cudaError_t prepare_lanes(unsigned features, int solver, int64_t P, int block, bool seg, bool world = false);
template <typename T>
cudaError_t launch_frame_lanes(const DModel<T> &m, const T *q, const T *phase, T *x, T *v, const T *rest,
                               const T *bend_rest, int64_t N, int block, cudaStream_t stream);
/* The launches launch_frame_lanes makes for m's substeps (more than one where the staged colliders do
 * not fit a block; then --contact-planes keeps each point's planes in m.contacts between them). */
template <typename T> cudaError_t lanes_launches(const DModel<T> &m, int block, int *launches);
/* Whether m's run of N strands takes the one-wave layout (lanes.cu; set m.wave by it once a run). */
template <typename T> cudaError_t lanes_wave(const DModel<T> &m, int64_t N, int block, bool *wave);
/* The layout m's frames launch: points a lane, lanes a strand, threads a block and the strands one wave
 * of its blocks takes on this device (the JSON record's simulate "layout"). */
template <typename T> cudaError_t lanes_layout(const DModel<T> &m, int block, int layout[4]);
/* Allows the warp kernel of this feature set `bytes` of dynamic shared memory a block (the
 * opt-in above 48 KB). */
template <typename T> cudaError_t prepare_warp(unsigned features, size_t bytes);

/* Bend rest lengths |X̄_{k+1} − X̄_{k−1}| of every strand, on the device (one thread a strand). */
template <typename T>
cudaError_t launch_bend_rest(const T *rest, Layout rl, T *bend_rest, Layout1 bl, int64_t N, int64_t P,
                             cudaStream_t stream);

/* Observables: out[b] = the partials of strands b·kObsChunk … (b+1)·kObsChunk − 1, combined
 * in strand order; ceil(N / kObsChunk) blocks. */
template <typename T>
cudaError_t launch_observe(const ObsScene &sc, const T *x, const T *v, Layout lay, int64_t N, ObsPartial *out,
                           cudaStream_t stream);

} /* namespace dyn */
} /* namespace hb */

#endif
