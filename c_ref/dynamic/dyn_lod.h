/* dyn_lod.h — simulated-point LOD (docs/model.md §3.14, --render-points): each strand is
 * written with P_r points, a centripetal Catmull–Rom spline through its P_s simulated ones.
 * The C reference of the rendering; the CUDA backend has its own kernel with the same
 * arithmetic (cuda/dynamic/lod.cu). c_ref/dynamic/dyn_lod_impl.h is the normative text. */
#ifndef HB_DYN_LOD_H
#define HB_DYN_LOD_H

#include <stdint.h>

#include "runtime/params.h"

#ifdef __cplusplus
extern "C" {
#endif

/* Strand of ps simulated points x into pr points `out` ([pr][3]) of the values y: x itself
 * (positions) or the strand's velocities, interpolated with the positions' knots and weights.
 * (pr − 1) is a multiple of (ps − 1). */
void hb_lod_strand_f32(const float *x, const float *y, int64_t ps, int64_t pr, float *out);
void hb_lod_strand_f64(const double *x, const double *y, int64_t ps, int64_t pr, double *out);
/* n strands, canonical [n·ps][3] into [n·pr][3] (velocities v into vr when v is not NULL),
 * one after the other (the CPU backend renders its simulated frames in parallel itself). */
void hb_lod_render_f32(const float *x, const float *v, int64_t n, int64_t ps, int64_t pr, float *xr, float *vr);
void hb_lod_render_f64(const double *x, const double *v, int64_t n, int64_t ps, int64_t pr, double *xr, double *vr);
/* Either, by the precision. */
void hb_lod_render(hb_precision p, const void *x, const void *v, int64_t n, int64_t ps, int64_t pr, void *xr, void *vr);

#ifdef __cplusplus
}
#endif
#endif
