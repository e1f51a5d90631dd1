/* dyn_lod.c — simulated-point LOD (docs/model.md §3.14): the rendered points of every strand
 * in fp32 and fp64 (the reference; the CUDA backend's kernel does the same operations). */
#include "dynamic/dyn_lod.h"

#include <math.h>
#include <stddef.h>

#define REAL float
#define SFX(name) name##_f32
#define SQRT sqrtf
#include "dynamic/dyn_lod_impl.h"
#undef REAL
#undef SFX
#undef SQRT

#define REAL double
#define SFX(name) name##_f64
#define SQRT sqrt
#include "dynamic/dyn_lod_impl.h"
#undef REAL
#undef SFX
#undef SQRT

void hb_lod_render(hb_precision p, const void *x, const void *v, int64_t n, int64_t ps, int64_t pr, void *xr, void *vr)
{
    if (p == HB_FP32) hb_lod_render_f32((const float *)x, (const float *)v, n, ps, pr, (float *)xr, (float *)vr);
    else hb_lod_render_f64((const double *)x, (const double *)v, n, ps, pr, (double *)xr, (double *)vr);
}
