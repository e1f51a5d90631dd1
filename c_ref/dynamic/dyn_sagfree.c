/* dyn_sagfree.c — sag-free rest (docs/model.md §3.13), the host-side precompute. */
#include "dynamic/dyn_sagfree.h"

#include <stddef.h>

double hb_sagfree_offset(const hb_scene *s)
{
    const hb_dynamics *d = &s->dyn;
    const double h = d->frame_dt / (double)d->substeps;
    const double D = d->drag_declared ? 1.0 + h * (d->drag + d->damping) : 1.0;
    return d->shape_compliance * d->gravity / D;
}

void hb_sagfree_targets(const hb_scene *s, const void *rest, void *out)
{
    const double delta = hb_sagfree_offset(s);
    const size_t N = (size_t)s->n_strands, P = (size_t)s->points, n = N * P * 3u;
    for (size_t e = 0; e < n; e++) {
        const int raise = (e / 3u) % P != 0 && e % 3u == 1u;
        if (s->precision == HB_FP32) {
            const float r = ((const float *)rest)[e];
            ((float *)out)[e] = raise ? (float)((double)r + delta) : r;
        } else {
            const double r = ((const double *)rest)[e];
            ((double *)out)[e] = raise ? r + delta : r;
        }
    }
}
