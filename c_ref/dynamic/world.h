/* world.h — what couples a strand to the world beyond its own constraints: the hair–hair
 * grid (docs/model.md §3.16) and the colliders with friction (§3.17). The host plans them
 * once per run (hair_grid.c, colliders.c) and every frame (dynamics_host.c, the poses); the
 * per-point math is contact_impl.h, written once for the C reference and the CUDA port.
 */
#ifndef HB_WORLD_H
#define HB_WORLD_H

#include <stdint.h>

#include "runtime/params.h"

#ifdef __cplusplus
extern "C" {
#endif

/* ---- §3.17 colliders ---- */
enum { HB_COL_SPHERE = 0, HB_COL_CAPSULE = 1, HB_COL_PLANE = 2, HB_COL_MESH = 3 };
enum { HB_FRAME_HEAD = 0, HB_FRAME_BODY = 1 };
#define HB_MAX_COLLIDERS 64
/* Reals of one collider's pose a substep (the world at t + h), by kind:
 *   sphere  c[0..2], r_c[3]
 *   capsule a[0..2], b[3..5], r_c[6], n_perp[7..9], ℓ²[10]
 *   plane   o[0..2], n[3..5], c_m[6]
 *   mesh    M[0..8] (world ← mesh frame, row-major), o[9..11] (the mesh frame's origin), c_m[12]
 * and for every kind a bounding sphere that holds every point the collider can move, centre
 * [16..18] and radius² [19] (+∞ for a plane): a point outside it is not tested. */
#define HB_COL_POSE 20
/* Reals of one contact plane (--contact-planes): its unit normal n [0..2] and offset d [3] (the
 * point p is outside where n·p − d ≥ 0), the collider's index [4] (−1: none this frame); a point keeps
 * HB_CONTACT_K of them (the nearest colliders: hair between two, at a neck or a shoulder, meets both) */
#define HB_CONTACT 5
#define HB_CONTACT_K 3
#define HB_CONTACT_POINT (HB_CONTACT * HB_CONTACT_K)
/* Reals of a substep's back-transforms: the head's Q(t)·Q(t+h)ᵀ [0..8], the body's b(t) − b(t+h) [9..11] */
#define HB_COL_BACK 12

typedef struct {
    int kind, frame;
    double g[7]; /* at rest: sphere c, r; capsule a, b, r; plane o, n (normalised) */
    double mu_s, mu_k;
    /* a mesh's signed distance field (§3.17), in its own frame (the head or body frame at rest) */
    int64_t sdf_n;    /* nodes per axis */
    int64_t band;     /* W: exact within W spacings; 0: everywhere */
    double sdf_lo[3]; /* the cube's lowest corner */
    double sdf_h;     /* spacing Δ_s */
    double *sdf;      /* sdf_n³ values, x fastest, then y, then z; negative inside */
    char source[256]; /* the mesh file as the colliders file names it */
} hb_collider;

typedef struct hb_colliders {
    int n;
    hb_collider c[HB_MAX_COLLIDERS];
} hb_colliders;

/* The run's world in the working precision T: pointers into memory the backend owns (host for
 * the reference, device for the CUDA kernels). */
#define HB_DYN_WORLD(T)                                                                                                \
    struct {                                                                                                           \
        /* §3.16 the grid: on, its parts, nodes per axis, box corner and scale (n − 1)/(hi − lo) */               \
        int grid, grid_friction, grid_volume, grid_rebuild;                                                            \
        int64_t gn;                                                                                                    \
        T glo[3], gsc[3];                                                                                              \
        const T *ftab;   /* f̃_k, k = 0 … P − 1 */                                                                \
        const T *node_v; /* [gn³][4]: o·V_x, o·V_y, o·V_z, o (the current build) */                                \
        const T *node_a; /* [gn³][4]: A_x, A_y, A_z, 0 */                                                             \
        /* §3.17 colliders after the head sphere, and friction */                                                     \
        int ncol;                                                                                                      \
        int bounded; /* --depenetration-speed declared */                                                              \
        T depen;     /* V·h */                                                                                        \
        int sweeps;  /* the collision sweeps a point, at most: --collider-sweeps with colliders, else 1 */             \
        int planes;  /* --contact-planes with colliders: HB_CONTACT_K planes a point a frame */                        \
        T margin;    /* M: how near a collider a point finds its plane, cm */                                          \
        int head_friction;                                                                                             \
        T head_mu_s, head_mu_k;                                                                                        \
        int motion, sway; /* the head turns (its back-transform is evaluated); the body sways */                       \
        const int *col_kind, *col_frame;                                                                               \
        const T *col_mu;      /* μ_s, μ_k of each collider */                                                        \
        const T *const *sdf;  /* each mesh collider's field (NULL for the others) */                                   \
        const int64_t *sdf_n; /* its nodes per axis */                                                                 \
        const T *sdf_geo;     /* its cube: lo x, y, z and scale 1/Δ_s, 4 a collider */                                \
    }
typedef HB_DYN_WORLD(float) hb_dyn_world_f32;
typedef HB_DYN_WORLD(double) hb_dyn_world_f64;

/* ---- host side (colliders.c) ---- */
/* Reads the colliders file (docs/model.md §3.17) and computes each mesh's SDF; one line in err. */
int hb_colliders_load(const char *path, hb_colliders *out, char *err, size_t errlen);
void hb_colliders_free(hb_colliders *c);
/* The poses of substep m (the world at t + h, t = m·h) of every collider, [HB_COL_POSE] each, and
 * the back-transforms [HB_COL_BACK], in double. */
void hb_colliders_pose(const hb_scene *s, const hb_colliders *c, double t, double t_next, double *pose, double *back);
/* The body frame's translation b(t) (§3.17), in double. */
void hb_body_translation(const hb_dynamics *d, double t, double b[3]);
/* The collider of a file for the given SDF input: one mesh read from an OBJ file. */
int hb_mesh_sdf(const char *path, int64_t n, int64_t band, hb_collider *out, char *err, size_t errlen);

/* ---- host side (hair_grid.c): §3.16 run constants ---- */
typedef struct {
    int64_t n;           /* nodes per axis */
    double lo[3], hi[3]; /* the box in the head frame */
    double sc[3];        /* (n − 1)/(hi − lo) */
    double rho0_mean;    /* ρ̄₀ */
    double *target;      /* T per node, n³, double (NULL without volume) */
    double *ftab;        /* f̃_k, P values (NULL without friction) */
} hb_grid_plan;
/* Plans the grid from the rest shape (canonical [N·P][3] in the scene's precision). */
int hb_grid_plan_make(const hb_scene *s, const void *rest, hb_grid_plan *g, char *err, size_t errlen);
void hb_grid_plan_free(hb_grid_plan *g);
/* The strands in the order of their roots' Morton codes in the box [lo, hi] (ties by index), so
 * that neighbours come together: what the GPU's grid kernels take strands in (a speed choice; the
 * grid's integer sums do not depend on it). perm: N entries. 0, or −1 out of memory. */
int hb_grid_order(const hb_scene *s, const void *rest, const double lo[3], const double hi[3], int64_t *perm);

#ifdef __cplusplus
}
#endif
#endif
