/* dynamics_simd.h — the dynamic model (docs/model.md §3) on the point-major layout,
 * vectorised across strands: the simulate stage of the `simd` variant of hairsim-cpu
 * (docs/cpu_simd.md, "The dynamic model").
 *
 * Layout: as model_simd.h. Positions X, Y, Z, velocities VX, VY, VZ and the rest shape
 * RX, RY, RZ are [P][stride] arrays (point k of strand i at k·stride + i); the bend rest
 * lengths BR are [P−2][stride]. A dynamic block is HB_SIMD_DYN_BLOCK consecutive strands
 * (it divides the layout blocks HB_SIMD_BLOCK_F32/_F64); each call below computes one
 * whole block, one strand per SIMD lane, with the lane state of the block (the predicted
 * positions of all P points, the multipliers) in a block-sized scratch array.
 *
 * The model is dynamics_impl.h's, its branches turned into selects; the arithmetic is free
 * (reciprocal square roots, reciprocals of the constant denominators; docs/cpu_simd.md), so
 * the result is judged against the `ref` variant by the one-frame rule, not bit for bit.
 * dynamics_simd.c is compiled for x86-64-v3 and dynamics_simd_v4.c for x86-64-v4: call
 * them only after the CPU check of backend_cpu.c.
 */
#ifndef HB_DYNAMICS_SIMD_H
#define HB_DYNAMICS_SIMD_H

#include <stdint.h>

#include "dynamic/dynamics.h"
#include "dynamic/world.h"

#ifdef __cplusplus
extern "C" {
#endif

/* Strands per dynamic block (a multiple of 64, dividing 256). The block's scratch is
 * (6P + 8) reals per lane (p: 3P, multipliers: up to 3P, the ftl correction of one point:
 * 3, one constraint's |e|², 1/|e| and e: 5): at P = 32, 200 KiB (fp32) or 400 KiB (fp64)
 * for 256 lanes, in L2. 256 lanes were faster than 64 and 128 on the dev machine in both
 * the memory-bound and the default scene (docs/cpu_simd.md, "The dynamic model"). */
#ifndef HB_SIMD_DYN_BLOCK
#define HB_SIMD_DYN_BLOCK 256
#endif

/* 1: the last substep of a block requests the next block's rows of x and v. Off: on the GPU
 * node's Xeon it made the memory-bound case 18% slower (docs/cpu_simd.md). */
#ifndef HB_SIMD_DYN_PREFETCH
#define HB_SIMD_DYN_PREFETCH 0
#endif
/* __builtin_prefetch's locality of those requests (3: L1, 2: L2, 1: L3 on x86). */
#ifndef HB_SIMD_DYN_PREFETCH_HINT
#define HB_SIMD_DYN_PREFETCH_HINT 2
#endif

/* Reals of scratch one block needs (allocate 64-byte aligned). */
int64_t hb_simd_dyn_scratch_reals(int64_t points);

/* Bend rest lengths of one block: BR[k−1][lane] = |X̄_{k+1} − X̄_{k−1}|, k = 1…P−2. */
void hb_simd_dyn_bend_rest_block_f32(const hb_dyn_model_f32 *m, const float *RX, const float *RY, const float *RZ,
                                     float *BR, int64_t stride);
void hb_simd_dyn_bend_rest_block_f64(const hb_dyn_model_f64 *m, const double *RX, const double *RY, const double *RZ,
                                     double *BR, int64_t stride);

/* Substeps j0 … j1 − 1 of a frame of one block (all S of them, or one where the grid is built
 * before each); w: the grid and colliders (docs/model.md §3.16, §3.17), NULL without them; SR: a
 * groom's stretch rest lengths ℓ_k as rows [P−1][stride] (docs/model.md §3.15), NULL for
 * ℓ = L/(P−1). All pointers point at the block's first strand in row 0 and are 64-byte aligned;
 * scratch holds hb_simd_dyn_scratch_reals(P) reals; con: the block's contact planes
 * [P][block][HB_CONTACT_POINT] with --contact-planes (kept between the calls of a frame), else NULL. */
void hb_simd_dyn_frame_block_f32(const hb_dyn_model_f32 *m, const hb_dyn_frame *f, const hb_dyn_world_f32 *w,
                                 int64_t j0, int64_t j1, float *X, float *Y, float *Z, float *VX, float *VY, float *VZ,
                                 const float *RX, const float *RY, const float *RZ, const float *BR, const float *SR,
                                 int64_t stride, float *scratch, float *con);
void hb_simd_dyn_frame_block_f64(const hb_dyn_model_f64 *m, const hb_dyn_frame *f, const hb_dyn_world_f64 *w,
                                 int64_t j0, int64_t j1, double *X, double *Y, double *Z, double *VX, double *VY,
                                 double *VZ, const double *RX, const double *RY, const double *RZ, const double *BR,
                                 const double *SR, int64_t stride, double *scratch, double *con);

/* The per-strand observables (docs/model.md §3.8) of `count` consecutive strands starting
 * at lane `first` (any alignment), into out[0 … count−1]: each strand's partial is the
 * same bits as hb_dyn_observe_strand's, so a reduction in strand order gives ref's. */
void hb_simd_dyn_observe_f32(const hb_scene *s, const hb_dyn_world_f32 *w, const float *pose, const float *X,
                             const float *Y, const float *Z, const float *VX, const float *VY, const float *VZ,
                             int64_t stride, int64_t first, int64_t count, const double *seg64, hb_obs_partial *out);
void hb_simd_dyn_observe_f64(const hb_scene *s, const hb_dyn_world_f64 *w, const double *pose, const double *X,
                             const double *Y, const double *Z, const double *VX, const double *VY, const double *VZ,
                             int64_t stride, int64_t first, int64_t count, const double *seg64, hb_obs_partial *out);

/* The functions above as one table, built twice as model_simd.h's (hb_simd_dyn_v3 from
 * dynamics_simd.c, hb_simd_dyn_v4 from dynamics_simd_v4.c). */
typedef struct {
    int64_t (*scratch_reals)(int64_t);
    void (*bend_rest_f32)(const hb_dyn_model_f32 *, const float *, const float *, const float *, float *, int64_t);
    void (*bend_rest_f64)(const hb_dyn_model_f64 *, const double *, const double *, const double *, double *, int64_t);
    void (*frame_f32)(const hb_dyn_model_f32 *, const hb_dyn_frame *, const hb_dyn_world_f32 *, int64_t, int64_t,
                      float *, float *, float *, float *, float *, float *, const float *, const float *, const float *,
                      const float *, const float *, int64_t, float *, float *);
    void (*frame_f64)(const hb_dyn_model_f64 *, const hb_dyn_frame *, const hb_dyn_world_f64 *, int64_t, int64_t,
                      double *, double *, double *, double *, double *, double *, const double *, const double *,
                      const double *, const double *, const double *, int64_t, double *, double *);
    void (*observe_f32)(const hb_scene *, const hb_dyn_world_f32 *, const float *, const float *, const float *,
                        const float *, const float *, const float *, const float *, int64_t, int64_t, int64_t,
                        const double *, hb_obs_partial *);
    void (*observe_f64)(const hb_scene *, const hb_dyn_world_f64 *, const double *, const double *, const double *,
                        const double *, const double *, const double *, const double *, int64_t, int64_t, int64_t,
                        const double *, hb_obs_partial *);
} hb_simd_dyn_fns;
extern const hb_simd_dyn_fns hb_simd_dyn_v3, hb_simd_dyn_v4;

#ifdef __cplusplus
}
#endif
#endif
