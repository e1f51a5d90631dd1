/* world_build.c — the C reference's build of the hair–hair grid (docs/model.md §3.16): the
 * splat over strands on every thread, then the node fields. */
#include <omp.h>
#include <stdlib.h>
#include <string.h>

#include "dynamic/world_host.h"

#include "dynamic/precision_f32.h"
#include "dynamic/contact_impl.h"
#include "dynamic/precision_end.h"
#include "dynamic/precision_f64.h"
#include "dynamic/contact_impl.h"
#include "dynamic/precision_end.h"

/* One precision's build: the splat over strands (each thread into its own sums where they fit,
 * else atomically: integer sums, so the order changes nothing), then the node fields. FETCH(T,
 * r, xr, vr): point r's position and velocity, from either layout. */
#define BUILD(T, SFX, W)                                                                                               \
    do {                                                                                                               \
        const T *q = (const T *)qg;                                                                                    \
        const int64_t n = hw->plan.n, nodes = hw->nodes, rows = s->n_strands * s->points, P = s->points;               \
        (void)P;                                                                                                       \
        memset(hw->mass, 0, (size_t)nodes * sizeof *hw->mass);                                                         \
        memset(hw->mom, 0, (size_t)nodes * 3 * sizeof *hw->mom);                                                       \
        const int nt = omp_get_max_threads();                                                                          \
        const int private_sums = (uint64_t)nodes * 32u * (uint64_t)nt <= (UINT64_C(256) << 20);                        \
        _Pragma("omp parallel")                                                                                        \
        {                                                                                                              \
            int64_t *pm = private_sums ? calloc((size_t)nodes * 4, sizeof *pm) : NULL;                                 \
            _Pragma("omp for schedule(static)") for (int64_t r = 0; r < rows; r++)                                     \
            {                                                                                                          \
                int64_t base, m[8], p[24];                                                                             \
                T xr[3], vr[3];                                                                                        \
                FETCH(T, r, xr, vr);                                                                                   \
                if (!hb_grid_splat_point_##SFX(q, (W).glo, (W).gsc, n, xr, vr, &base, m, p)) continue;                 \
                for (int k = 0; k < 8; k++) {                                                                          \
                    const int64_t j = hb_grid_corner_##SFX(base, n, k);                                                \
                    if (pm) {                                                                                          \
                        pm[4 * j] += m[k];                                                                             \
                        for (int c = 0; c < 3; c++) pm[4 * j + 1 + c] += p[3 * k + c];                                 \
                    } else {                                                                                           \
                        _Pragma("omp atomic") hw->mass[j] += m[k];                                                     \
                        for (int c = 0; c < 3; c++) { _Pragma("omp atomic") hw->mom[3 * j + c] += p[3 * k + c]; }      \
                    }                                                                                                  \
                }                                                                                                      \
            }                                                                                                          \
            if (pm) {                                                                                                  \
                _Pragma("omp critical(hb_grid_sums)") for (int64_t j = 0; j < nodes; j++)                              \
                {                                                                                                      \
                    hw->mass[j] += pm[4 * j];                                                                          \
                    for (int c = 0; c < 3; c++) hw->mom[3 * j + c] += pm[4 * j + 1 + c];                               \
                }                                                                                                      \
                free(pm);                                                                                              \
            } else if (private_sums) {                                                                                 \
                _Pragma("omp atomic write") failed = 1;                                                                \
            }                                                                                                          \
        }                                                                                                              \
        _Pragma("omp parallel for schedule(static)") for (int64_t j = 0; j < nodes; j++)                               \
            hb_grid_node_##SFX(j, n, hw->mass, hw->mom, (const T *)hw->target, (T)hw->inv_rho0, (T)hw->neg_kv,         \
                               (W).gsc, q, (T *)hw->node_v, (T *)hw->node_a);                                          \
    } while (0)

/* point r (strand r / P, point r % P) of the canonical layout [N·P][3] */
#define FETCH(T, r, xr, vr)                                                                                            \
    for (int c = 0; c < 3; c++) {                                                                                      \
        xr[c] = ((const T *)x)[3 * (r) + c];                                                                           \
        vr[c] = ((const T *)v)[3 * (r) + c];                                                                           \
    }
int hb_host_world_build(hb_host_world *hw, const hb_scene *s, const void *x, const void *v, const void *qg)
{
    int failed = 0;
    if (s->precision == HB_FP32) BUILD(float, f32, hw->w32);
    else BUILD(double, f64, hw->w64);
    return failed ? -1 : 0;
}
#undef FETCH

/* the point-major rows (simd), taken row by row (point k of strand i at k·stride + i, r = k·N + i:
 * the sums are integers, so the order changes nothing) */
#define FETCH(T, r, xr, vr)                                                                                            \
    {                                                                                                                  \
        const int64_t at = ((r) / s->n_strands) * stride + (r) % s->n_strands;                                         \
        for (int c = 0; c < 3; c++) {                                                                                  \
            xr[c] = ((const T *)xs[c])[at];                                                                            \
            vr[c] = ((const T *)vs[c])[at];                                                                            \
        }                                                                                                              \
    }
int hb_host_world_build_rows(hb_host_world *hw, const hb_scene *s, void *const xs[3], void *const vs[3], int64_t stride,
                             const void *qg)
{
    int failed = 0;
    if (s->precision == HB_FP32) BUILD(float, f32, hw->w32);
    else BUILD(double, f64, hw->w64);
    return failed ? -1 : 0;
}
#undef FETCH
#undef BUILD
