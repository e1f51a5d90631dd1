/* world_host.c — a run's grid and colliders in host memory (world_host.h). */
#include "dynamic/world_host.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "dynamic/dynamics.h"
#include "runtime/checked.h"
#include "runtime/cli.h" /* HB_GRID_POINTS_MAX */


uint64_t hb_host_world_bytes(const hb_scene *s, int sums_threads)
{
    const hb_dynamics *d = &s->dyn;
    const size_t real = hb_real_size(s->precision);
    uint64_t b = 0;
    if (d->grid) {
        const uint64_t nodes = (uint64_t)d->grid_n * (uint64_t)d->grid_n * (uint64_t)d->grid_n;
        b = hb_add_sat(b, hb_mul_sat(nodes, real + sizeof(double))); /* target */
        if (sums_threads > 0) { /* the sums, the node fields and each thread's own sums */
            b = hb_add_sat(b, hb_mul_sat(nodes, 4 * sizeof(int64_t) + 8 * real));
            b = hb_add_sat(b, hb_mul_sat(hb_mul_sat(nodes, 4 * sizeof(int64_t)), (uint64_t)sums_threads));
        }
    }
    for (int i = 0; d->cols && i < d->cols->n; i++)
        if (d->cols->c[i].sdf) {
            const uint64_t n = (uint64_t)d->cols->c[i].sdf_n;
            b = hb_add_sat(b, hb_mul_sat(n * n * n, real));
        }
    return b;
}

void hb_host_world_free(hb_host_world *hw)
{
    hb_grid_plan_free(&hw->plan);
    free(hw->ftab);
    free(hw->target);
    free(hw->node_v);
    free(hw->node_a);
    free(hw->mass);
    free(hw->mom);
    free(hw->mu);
    free(hw->sdf_geo);
    for (int i = 0; i < hw->ncol; i++) free(hw->sdf[i]);
    memset(hw, 0, sizeof *hw);
}

/* The world's struct of one precision, pointing at the host tables. */
#define FILL_WORLD(W, T)                                                                                               \
    do {                                                                                                               \
        memset(&(W), 0, sizeof(W));                                                                                    \
        (W).grid = d->grid;                                                                                            \
        (W).grid_friction = d->grid && d->grid_friction_declared;                                                      \
        (W).grid_volume = d->grid && d->grid_volume_declared;                                                          \
        (W).grid_rebuild = d->grid_rebuild;                                                                            \
        (W).gn = hw->plan.n;                                                                                           \
        for (int c = 0; c < 3; c++) {                                                                                  \
            (W).glo[c] = (T)hw->plan.lo[c];                                                                            \
            (W).gsc[c] = (T)hw->plan.sc[c];                                                                            \
        }                                                                                                              \
        (W).ftab = (const T *)hw->ftab;                                                                                \
        (W).node_v = (const T *)hw->node_v;                                                                            \
        (W).node_a = (const T *)hw->node_a;                                                                            \
        (W).ncol = hw->ncol;                                                                                           \
        (W).bounded = d->depen_declared;                                                                               \
        (W).depen = (T)(d->depen_speed * (d->frame_dt / (double)d->substeps));                                         \
        (W).sweeps = hw->ncol > 0 ? (int)d->collider_sweeps : 1;                                                       \
        (W).planes = hw->ncol > 0 && d->planes_declared;                                                               \
        (W).margin = (T)d->contact_margin;                                                                             \
        (W).head_friction = d->friction_declared;                                                                      \
        (W).head_mu_s = (T)d->friction[0];                                                                             \
        (W).head_mu_k = (T)d->friction[1];                                                                             \
        (W).motion = d->motion != HB_MOTION_STILL;                                                                     \
        (W).sway = d->body_motion != HB_BODY_STILL;                                                                    \
        (W).col_kind = hw->kind;                                                                                       \
        (W).col_frame = hw->frame;                                                                                     \
        (W).col_mu = (const T *)hw->mu;                                                                                \
        (W).sdf = (const T *const *)hw->sdf;                                                                           \
        (W).sdf_n = hw->sdf_n;                                                                                         \
        (W).sdf_geo = (const T *)hw->sdf_geo;                                                                          \
    } while (0)

/* a double table rounded once into a new array of the working precision */
static void *rounded(const double *src, int64_t n, int fp32)
{
    void *dst = malloc((size_t)hb_mul_sat((uint64_t)(n > 0 ? n : 1), fp32 ? sizeof(float) : sizeof(double)));
    if (!dst) return NULL;
    for (int64_t i = 0; i < n; i++) {
        if (fp32) ((float *)dst)[i] = (float)src[i];
        else ((double *)dst)[i] = src[i];
    }
    return dst;
}

int hb_host_world_make(hb_host_world *hw, const hb_scene *s, const void *rest, int sums, char *err, size_t errlen)
{
    const hb_dynamics *d = &s->dyn;
    memset(hw, 0, sizeof *hw);
    hw->on = d->grid || hb_dyn_has_world(s);
    if (!hw->on) return 0;
    const int fp32 = s->precision == HB_FP32;
    hw->real = hb_real_size(s->precision);
    if (d->grid) {
        if ((uint64_t)s->n_strands * (uint64_t)s->points > HB_GRID_POINTS_MAX) {
            snprintf(err, errlen,
                     "--grid: --strands x --points must be at most 2^31 points, the bound that keeps the grid's "
                     "fixed-point sums from overflowing (docs/model.md §3.16)");
            return -1;
        }
        if (hb_grid_plan_make(s, rest, &hw->plan, err, errlen)) return -1;
        hw->nodes = hw->plan.n * hw->plan.n * hw->plan.n;
        if (hw->plan.ftab && !(hw->ftab = rounded(hw->plan.ftab, s->points, fp32))) goto oom;
        if (hw->plan.target) {
            if (!(hw->target = rounded(hw->plan.target, hw->nodes, fp32))) goto oom;
            hw->inv_rho0 = 1.0 / hw->plan.rho0_mean;
            hw->neg_kv = -d->grid_volume;
        }
        if (sums) {
            hw->mass = malloc((size_t)hw->nodes * sizeof *hw->mass);
            hw->mom = malloc((size_t)hw->nodes * 3 * sizeof *hw->mom);
            hw->node_v = d->grid_friction_declared ? malloc((size_t)hw->nodes * 4 * hw->real) : NULL;
            hw->node_a = d->grid_volume_declared ? malloc((size_t)hw->nodes * 4 * hw->real) : NULL;
            if (!hw->mass || !hw->mom || (d->grid_friction_declared && !hw->node_v) ||
                (d->grid_volume_declared && !hw->node_a))
                goto oom;
        }
    }
    const hb_colliders *cols = d->cols;
    hw->ncol = cols ? cols->n : 0;
    double mu[2 * HB_MAX_COLLIDERS], geo[4 * HB_MAX_COLLIDERS];
    memset(geo, 0, sizeof geo);
    for (int i = 0; i < hw->ncol; i++) {
        const hb_collider *k = &cols->c[i];
        hw->kind[i] = k->kind;
        hw->frame[i] = k->frame;
        mu[2 * i] = k->mu_s;
        mu[2 * i + 1] = k->mu_k;
        if (k->sdf) {
            hw->sdf_n[i] = k->sdf_n;
            for (int c = 0; c < 3; c++) geo[4 * i + c] = k->sdf_lo[c];
            geo[4 * i + 3] = 1.0 / k->sdf_h;
            if (!(hw->sdf[i] = rounded(k->sdf, k->sdf_n * k->sdf_n * k->sdf_n, fp32))) goto oom;
        }
    }
    if (!(hw->mu = rounded(mu, 2 * hw->ncol, fp32)) || !(hw->sdf_geo = rounded(geo, 4 * hw->ncol, fp32))) goto oom;
    FILL_WORLD(hw->w32, float);
    FILL_WORLD(hw->w64, double);
    return 0;
oom:
    hb_host_world_free(hw);
    snprintf(err, errlen, "out of host memory for the grid and colliders");
    return -1;
}
#undef FILL_WORLD
