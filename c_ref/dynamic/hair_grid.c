/* hair_grid.c — the hair–hair grid's run constants (docs/model.md §3.16) on the host: its box,
 * the rest pose's target density and the friction profile, in double; the backends round them
 * once. The rest pose is splatted by the working precision's rule (contact_impl.h). */
#include "dynamic/world.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "dynamic/dynamics.h"
#include "runtime/checked.h"

#include "dynamic/precision_f32.h"
#include "dynamic/contact_impl.h"
#include "dynamic/precision_end.h"
#include "dynamic/precision_f64.h"
#include "dynamic/contact_impl.h"
#include "dynamic/precision_end.h"

void hb_grid_plan_free(hb_grid_plan *g)
{
    free(g->target);
    free(g->ftab);
    memset(g, 0, sizeof *g);
}

/* The rest pose's fixed-point mass at every node (Q_g = identity), into mass[n³]. */
static void rest_mass(const hb_scene *s, const void *rest, const hb_grid_plan *g, int64_t *mass)
{
    const int64_t rows = s->n_strands * s->points, n = g->n;
    float lo32[3], sc32[3];
    double lo64[3], sc64[3];
    for (int c = 0; c < 3; c++) {
        lo32[c] = (float)g->lo[c], sc32[c] = (float)g->sc[c];
        lo64[c] = g->lo[c], sc64[c] = g->sc[c];
    }
    for (int64_t r = 0; r < rows; r++) {
        int64_t base, m[8], p[24];
        int in;
        if (s->precision == HB_FP32)
            in = hb_grid_splat_point_f32(NULL, lo32, sc32, n, (const float *)rest + 3 * r, NULL, &base, m, p);
        else in = hb_grid_splat_point_f64(NULL, lo64, sc64, n, (const double *)rest + 3 * r, NULL, &base, m, p);
        if (!in) continue;
        for (int k = 0; k < 8; k++) mass[hb_grid_corner_f64(base, n, k)] += m[k];
    }
}

int hb_grid_plan_make(const hb_scene *s, const void *rest, hb_grid_plan *g, char *err, size_t errlen)
{
    const hb_dynamics *d = &s->dyn;
    memset(g, 0, sizeof *g);
    g->n = d->grid_n;
    const int64_t rows = s->n_strands * s->points;
    if (d->grid_box_given) {
        memcpy(g->lo, d->grid_box, 3 * sizeof(double));
        memcpy(g->hi, d->grid_box + 3, 3 * sizeof(double));
    } else { /* the rest shape's bounds, padded */
        for (int c = 0; c < 3; c++) g->lo[c] = INFINITY, g->hi[c] = -INFINITY;
        for (int64_t r = 0; r < rows; r++)
            for (int c = 0; c < 3; c++) {
                const double x = s->precision == HB_FP32 ? (double)((const float *)rest)[3 * r + c]
                                                         : ((const double *)rest)[3 * r + c];
                if (x < g->lo[c]) g->lo[c] = x;
                if (x > g->hi[c]) g->hi[c] = x;
            }
        for (int c = 0; c < 3; c++) {
            g->lo[c] -= d->grid_padding;
            g->hi[c] += d->grid_padding;
            if (!(g->hi[c] > g->lo[c])) { /* a flat rest shape with no padding */
                snprintf(err, errlen, "--grid: the rest shape spans no length along %c; give --grid-padding > 0",
                         "xyz"[c]);
                return -1;
            }
        }
    }
    for (int c = 0; c < 3; c++) {
        g->sc[c] = (double)(g->n - 1) / (g->hi[c] - g->lo[c]);
        if (!(isfinite(g->sc[c]) && isfinite((float)g->sc[c]) && (float)g->sc[c] > 0.0f)) {
            snprintf(err, errlen, "--grid-box: the box's %c side is too short or too long for the grid", "xyz"[c]);
            return -1;
        }
    }
    if (d->grid_friction_declared) {
        const double h = d->frame_dt / (double)d->substeps, h0 = 1.0 / 480.0;
        if (!(g->ftab = malloc((size_t)s->points * sizeof *g->ftab))) goto oom;
        for (int64_t k = 0; k < s->points; k++) {
            const double f =
                d->grid_friction[0] + (d->grid_friction[1] - d->grid_friction[0]) * (double)k / (double)(s->points - 1);
            g->ftab[k] = 1.0 - pow(1.0 - f, h / h0);
        }
    }
    if (d->grid_volume_declared) {
        const uint64_t nodes = (uint64_t)g->n * (uint64_t)g->n * (uint64_t)g->n;
        int64_t *mass = calloc((size_t)nodes, sizeof *mass);
        g->target = malloc((size_t)nodes * sizeof *g->target);
        if (!mass || !g->target) {
            free(mass);
            goto oom;
        }
        rest_mass(s, rest, g, mass);
        double sum = 0.0;
        int64_t occ = 0;
        for (uint64_t j = 0; j < nodes; j++)
            if (mass[j] > 0) sum += (double)mass[j] * HB_GRID_INV_MASS_SCALE, occ++;
        g->rho0_mean = occ > 0 ? sum / (double)occ : 1.0;
        for (uint64_t j = 0; j < nodes; j++) {
            const double r0 = (double)mass[j] * HB_GRID_INV_MASS_SCALE;
            g->target[j] = r0 > g->rho0_mean ? r0 : g->rho0_mean;
        }
        free(mass);
    }
    return 0;
oom:
    hb_grid_plan_free(g);
    snprintf(err, errlen, "out of host memory for the hair-hair grid's tables");
    return -1;
}

/* a strand's root as a 30-bit Morton code of its place in the box, and its index (ties) */
typedef struct {
    uint64_t key;
    int64_t strand;
} order_item;

static int order_cmp(const void *a, const void *b)
{
    const order_item *p = a, *q = b;
    if (p->key != q->key) return p->key < q->key ? -1 : 1;
    return (p->strand > q->strand) - (p->strand < q->strand);
}

static uint64_t spread10(uint64_t v) /* bit i of v to bit 3i */
{
    uint64_t r = 0;
    for (int i = 0; i < 10; i++) r |= ((v >> i) & 1u) << (3 * i);
    return r;
}

int hb_grid_order(const hb_scene *s, const void *rest, const double lo[3], const double hi[3], int64_t *perm)
{
    const int64_t N = s->n_strands, P = s->points;
    order_item *it = malloc((size_t)N * sizeof *it);
    if (!it) return -1;
    for (int64_t i = 0; i < N; i++) {
        uint64_t key = 0;
        for (int c = 0; c < 3; c++) {
            const double x = s->precision == HB_FP32 ? (double)((const float *)rest)[3 * i * P + c]
                                                     : ((const double *)rest)[3 * i * P + c];
            double u = (x - lo[c]) / (hi[c] - lo[c]) * 1023.0;
            u = u < 0.0 ? 0.0 : u > 1023.0 ? 1023.0 : u;
            key |= spread10((uint64_t)u) << c;
        }
        it[i].key = key;
        it[i].strand = i;
    }
    qsort(it, (size_t)N, sizeof *it, order_cmp);
    for (int64_t i = 0; i < N; i++) perm[i] = it[i].strand;
    free(it);
    return 0;
}
