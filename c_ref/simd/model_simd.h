/* model_simd.h — the paper model (docs/model.md §2) on the point-major layout, vectorised across
 * strands: the `simd` variant of hairsim-cpu (docs/cpu_simd.md).
 *
 * Layout: three arrays X, Y, Z of [P][S] reals, S = the row stride (N rounded up to a whole
 * number of blocks); point k of strand i is element k·S + i. A block is HB_SIMD_BLOCK(prec)
 * consecutive strands; each function below computes one whole block, one strand per SIMD
 * lane from the first point to the last, with the running state of every lane in small
 * arrays on the stack (L1), or, in the fp32 fused pass, in registers. The block's pointers point at its first strand in row 0 and
 * must be 64-byte aligned; every lane of the block is computed (lanes past the last real
 * strand are padding: computed, never read back, never counted).
 *
 * The formulas and decisions are those of model_impl.h (including the two
 * better-conditioned evaluations of docs/model.md §2.3, §2.5), with its branches turned into
 * selects, in the free arithmetic of model_simd_impl.h (fewer operations, judged by
 * tolerance); sin/cos/asin/atan2 are glibc's libmvec vector functions or, for the fp32
 * drape, c_ref/paper/fast_trig.h's. model_simd.c is compiled for x86-64-v3 (AVX2 + FMA) and
 * model_simd_v4.c for x86-64-v4: call them only after backend_cpu.c's CPU check (a file
 * compiled for the baseline ISA).
 */
#ifndef HB_MODEL_SIMD_H
#define HB_MODEL_SIMD_H

#include <stdint.h>

#include "paper/model.h"

#ifdef __cplusplus
extern "C" {
#endif

/* Strands per block: 2 KiB of one row in either precision, so that a lane state of a few
 * reals per strand stays in L1. Fixed: it does not depend on the thread count, and since
 * every strand is one lane start to finish, the bits do not depend on it either. */
#ifndef HB_SIMD_BLOCK_F32 /* (overridable with -D for experiments; a multiple of 64) */
#define HB_SIMD_BLOCK_F32 512
#endif
#ifndef HB_SIMD_BLOCK_F64
#define HB_SIMD_BLOCK_F64 256
#endif
/* collide runs its pull (or its projection) on a chunk of this many lanes only at a point
 * where one lane of the chunk has moved (or penetrates); a multiple of every vector width,
 * so no lane is ever left to a scalar remainder loop. 64 rather than 16: after a wind most
 * chunks take the pull anyway, and the longer loops cost less control (docs/cpu_simd.md).
 * Overridable with -D for experiments; it changes no bit. */
#ifndef HB_SIMD_CHUNK
#define HB_SIMD_CHUNK 64
#endif

/* The fp64 fused wind+collide pass requests the block's rows this many points ahead into
 * the cache (0: none; docs/cpu_simd.md). Overridable with -D; it changes no bit. */
#ifndef HB_SIMD_PREFETCH_ROWS
#define HB_SIMD_PREFETCH_ROWS 2
#endif
/* The fp32 fused pass is a strand walk: groups of HB_WALK_NV vectors of lanes walk the
 * points with their state in registers, and each group requests the lanes this many groups
 * ahead (0: none). Overridable with -D; neither changes a bit. */
#ifndef HB_WALK_NV
#define HB_WALK_NV 2
#endif
#ifndef HB_SIMD_WALK_PREFETCH
#define HB_SIMD_WALK_PREFETCH 1
#endif

/* init: roots (strands first … first + block − 1) and drape; writes X, Y, Z. */
void hb_simd_init_block_f32(const hb_model_f32 *m, uint64_t first, float *X, float *Y, float *Z, int64_t stride);
void hb_simd_init_block_f64(const hb_model_f64 *m, uint64_t first, double *X, double *Y, double *Z, int64_t stride);

/* wind (w ≠ 0): reads and writes Y, Z; X is not touched. */
void hb_simd_wind_block_f32(const hb_model_f32 *m, float *Y, float *Z, int64_t stride);
void hb_simd_wind_block_f64(const hb_model_f64 *m, double *Y, double *Z, int64_t stride);

/* collide: reads Y, Z and writes only the points it changes; returns the number of points
 * changed in the first `real` lanes of the block. */
int64_t hb_simd_collide_block_f32(const hb_model_f32 *m, int real, float *Y, float *Z, int64_t stride);
int64_t hb_simd_collide_block_f64(const hb_model_f64 *m, int real, double *Y, double *Z, int64_t stride);

/* wind then collide in one pass over the points (each point read and written once), the
 * same bits as the two calls above; with WY, WZ (same layout, or NULL) the state between
 * the two is stored there too. Returns collide's count. */
int64_t hb_simd_wind_collide_block_f32(const hb_model_f32 *m, int real, float *Y, float *Z, float *WY, float *WZ,
                                       int64_t stride);
int64_t hb_simd_wind_collide_block_f64(const hb_model_f64 *m, int real, double *Y, double *Z, double *WY, double *WZ,
                                       int64_t stride);

/* The ISA model_simd.c is compiled for, as the compiler saw it (for messages). */
extern const char hb_simd_isa[];

/* The functions above as one table. model_simd.c is built twice (docs/cpu_simd.md, "Two
 * builds"): for x86-64-v3 (hb_simd_model_v3) and, as model_simd_v4.c, for x86-64-v4 with
 * 512-bit vectors (hb_simd_model_v4, its exported names ending in _v4). backend_cpu.c picks
 * one at setup from what the CPU supports and calls it through the table. */
typedef struct {
    const char *isa;
    void (*init_f32)(const hb_model_f32 *, uint64_t, float *, float *, float *, int64_t);
    void (*init_f64)(const hb_model_f64 *, uint64_t, double *, double *, double *, int64_t);
    void (*wind_f32)(const hb_model_f32 *, float *, float *, int64_t);
    void (*wind_f64)(const hb_model_f64 *, double *, double *, int64_t);
    int64_t (*collide_f32)(const hb_model_f32 *, int, float *, float *, int64_t);
    int64_t (*collide_f64)(const hb_model_f64 *, int, double *, double *, int64_t);
    int64_t (*wind_collide_f32)(const hb_model_f32 *, int, float *, float *, float *, float *, int64_t);
    int64_t (*wind_collide_f64)(const hb_model_f64 *, int, double *, double *, double *, double *, int64_t);
} hb_simd_model_fns;
extern const hb_simd_model_fns hb_simd_model_v3, hb_simd_model_v4;

#ifdef __cplusplus
}
#endif
#endif
