/* world_host.h — the hair–hair grid and the colliders of a run (docs/model.md §3.16, §3.17) in
 * host memory: the constants rounded once to the working precision (which the CUDA backend
 * copies to the device), and for the C reference the grid's sums and node fields themselves.
 */
#ifndef HB_WORLD_HOST_H
#define HB_WORLD_HOST_H

#include <stddef.h>
#include <stdint.h>

#include "dynamic/world.h"
#include "runtime/params.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct {
    int on; /* the grid, colliders or friction: the frame runs with a world */
    hb_grid_plan plan;
    int64_t nodes; /* n³ (0 without the grid) */
    size_t real;   /* bytes of a real */
    /* working-precision tables (host): ftab [P], target [n³], the node fields [n³][4] (C reference) */
    void *ftab, *target, *node_v, *node_a;
    int64_t *mass, *mom; /* the grid's sums [n³], [n³][3] (C reference) */
    double inv_rho0, neg_kv;
    /* colliders: kind, frame [ncol]; μ [ncol][2], SDF geometry [ncol][4] and fields in the working precision */
    int ncol;
    int kind[HB_MAX_COLLIDERS], frame[HB_MAX_COLLIDERS];
    int64_t sdf_n[HB_MAX_COLLIDERS];
    void *mu, *sdf_geo;
    void *sdf[HB_MAX_COLLIDERS];
    hb_dyn_world_f32 w32; /* pointing at the host tables */
    hb_dyn_world_f64 w64;
} hb_host_world;

/* Plans the world of a run from its rest shape (canonical, the run's precision); `sums`: also
 * allocate the grid's sums and node fields (the C reference). On no world, hw->on = 0. */
int hb_host_world_make(hb_host_world *hw, const hb_scene *s, const void *rest, int sums, char *err, size_t errlen);
void hb_host_world_free(hb_host_world *hw);
/* §3.16 builds the grid from the state (x, v canonical) with the rotation qg (NULL: still), in
 * the working precision of hw, on every OpenMP thread (the C reference: world_build.c). */
int hb_host_world_build(hb_host_world *hw, const hb_scene *s, const void *x, const void *v, const void *qg);
/* The same from the point-major rows of the simd variant (xs, vs: x, y, z rows, point k of
 * strand i at k·stride + i): the same integer sums, so the same grid. */
int hb_host_world_build_rows(hb_host_world *hw, const hb_scene *s, void *const xs[3], void *const vs[3], int64_t stride,
                             const void *qg);
/* Bytes the world adds on the host (sums_threads > 0: the C reference's grid too, on that many threads). */
uint64_t hb_host_world_bytes(const hb_scene *s, int sums_threads);

#ifdef __cplusplus
}
#endif
#endif
