/* dynamics.h — the dynamic model (docs/model.md §3) on one strand, in fp32 and fp64, and
 * the host-side numbers every backend shares: the run's constants rounded once to the
 * working precision, and each frame's per-substep table of head rotations and gust phases
 * computed in double (§3.10).
 *
 * A strand's positions x, velocities v and rest shape X̄ are P points of (x, y, z) in the
 * canonical strand-major layout, as in model.h. dynamics_impl.h holds the math, written
 * once; dynamics_f32.c and dynamics_f64.c instantiate it for float and double.
 */
#ifndef HB_DYNAMICS_H
#define HB_DYNAMICS_H

#include <stdint.h>

#include "runtime/params.h"
#include "dynamic/world.h"

#ifdef __cplusplus
extern "C" {
#endif

/* The features of a run (docs/model.md §3.9): the inner loop is compiled once per set,
 * so what a scene does not declare costs nothing. */
enum {
    HB_F_BEND = 1u << 0,
    HB_F_SHAPE = 1u << 1,
    HB_F_WIND = 1u << 2,
    HB_F_GUST = 1u << 3, /* only with HB_F_WIND */
    HB_F_MOTION = 1u << 4,
    HB_F_COLLIDE = 1u << 5,
    HB_F_DRAG = 1u << 6,  /* the implicit divide by 1 + h(c_d + β) */
    HB_F_COUNT = 1u << 7, /* number of feature sets */
};

/* The run's constants in the working precision (each computed in double, rounded once). */
#define HB_DYN_MODEL(T)                                                                                                \
    struct {                                                                                                           \
        int64_t points, substeps, iterations, shape_count; /* P, S, I, K */                                            \
        int64_t collide_from; /* xpbd: the first iteration with a collision step (0; I − 1: --collide-once) */       \
        int solver;                                                                                                    \
        unsigned features;                                                                                             \
        T h, seg_len, gravity_y;         /* h = Δt/S, ℓ, −g0 */                                                   \
        T wind_y, wind_z;                /* c_d·U·d̂ (the drag-scaled wind velocity) */                             \
        T dir_y, dir_z, kappa, gust;     /* d̂, κ = 2π/λ_g, A_g */                                                 \
        T den;                           /* 1 + h(c_d + β) */                                                         \
        T stretch_at, bend_at, shape_at; /* α̃ = α/h² */                                                           \
        T collide_r;                     /* R_c = R + c_m */                                                           \
        T ftl_s;                         /* s */                                                                       \
        int lra;                         /* §3.13: long-range attachments (a run-time switch) */                      \
        T lra_len;                       /* s_L·ℓ */                                                                \
    }
typedef HB_DYN_MODEL(float) hb_dyn_model_f32;
typedef HB_DYN_MODEL(double) hb_dyn_model_f64;

/* One frame's substeps: for substep j (global index m = first_substep + j, time t = m·h),
 * the head rotation Q(t + h) as a row-major 3×3 matrix and the gust phase φ(t). */
typedef struct {
    int64_t first_substep;
    int64_t substeps;
    double *q64, *phase64; /* [S·9], [S] */
    float *q32, *phase32;
    /* §3.16: Q(t) at the start of the frame's first substep (the frame's first grid build) */
    double qs64[9];
    float qs32[9];
    /* §3.17 (hb_dyn_frame_alloc_world): each substep's collider poses [S][ncol][HB_COL_POSE]
     * and back-transforms [S][HB_COL_BACK] (NULL without colliders or friction) */
    int ncol;
    double *pose64, *back64;
    float *pose32, *back32;
} hb_dyn_frame;

/* Observables of a frame (docs/model.md §3.8), in double. */
typedef struct {
    double stretch_max, penetration_max, kinetic_energy;
    int64_t blown_up_strands;
} hb_observables;

/* Per-strand partial observables, reduced in a fixed order by hb_dyn_reduce. */
typedef struct {
    double stretch_max, penetration_max, v2_sum;
    int64_t blown;
} hb_obs_partial;

/* ---- host side (dynamics_host.c) ---- */
unsigned hb_dyn_features(const hb_scene *s);
/* A string naming the features, e.g. "bend+shape+wind+collide" ("none" when empty). */
void hb_dyn_feature_names(unsigned features, char *out, size_t n);
void hb_dyn_round(const hb_scene *s, hb_dyn_model_f32 *m32, hb_dyn_model_f64 *m64);
/* Allocates the per-substep tables for S substeps; 0 on success. */
int hb_dyn_frame_alloc(hb_dyn_frame *f, int64_t substeps);
/* Adds the tables of §3.17 for the scene's colliders and friction (nothing without them); 0 on success. */
int hb_dyn_frame_alloc_world(hb_dyn_frame *f, const hb_scene *s);
/* Whether a scene's frames need the tables of §3.17 (colliders, head friction or a bounded depenetration). */
int hb_dyn_has_world(const hb_scene *s);
void hb_dyn_frame_free(hb_dyn_frame *f);
/* Fills the tables for the frame whose first substep is m0 (§3.2, §3.3, §3.4). */
void hb_dyn_frame_plan(const hb_scene *s, int64_t m0, hb_dyn_frame *f);
/* The rotation Q(t) of §3.2 in double, row-major. */
void hb_head_rotation(const hb_dynamics *d, double t, double q[9]);
/* Combines partials in index order: the result does not depend on how they were made. */
void hb_dyn_reduce(const hb_obs_partial *p, int64_t n, int64_t points_per_strand, int64_t strands, hb_observables *out);
int hb_obs_blown_up(const hb_observables *o);
/* acc ← acc combined with o (max, max, sum, sum). */
void hb_dyn_reduce_into(hb_obs_partial *acc, const hb_obs_partial *o);

/* ---- one strand (dynamics_impl.h via dynamics_f32.c, dynamics_f64.c) ----
 * `scratch` holds 17·P reals. `bend_rest` holds P − 2 rest lengths (hb_dyn_bend_rest). */
void hb_dyn_bend_rest_f32(const hb_dyn_model_f32 *m, const float *rest, float *bend_rest);
void hb_dyn_bend_rest_f64(const hb_dyn_model_f64 *m, const double *rest, double *bend_rest);
/* `seg_rest` holds the P − 1 stretch rest lengths ℓ_k of a groom (§3.15), NULL for ℓ = L/(P−1). */
/* Substeps j0 … j1 − 1 of the frame; w: the grid and colliders (§3.16, §3.17), NULL without them; `con`:
 * the strand's contact planes (§3.17 --contact-planes, HB_CONTACT_POINT·P reals, found at the frame's first
 * substep and kept through its calls), NULL without them. */
void hb_dyn_frame_strand_f32(const hb_dyn_model_f32 *m, const hb_dyn_world_f32 *w, const hb_dyn_frame *f, int64_t j0,
                             int64_t j1, float *x, float *v, const float *rest, const float *bend_rest,
                             const float *seg_rest, float *scratch, float *con);
void hb_dyn_frame_strand_f64(const hb_dyn_model_f64 *m, const hb_dyn_world_f64 *w, const hb_dyn_frame *f, int64_t j0,
                             int64_t j1, double *x, double *v, const double *rest, const double *bend_rest,
                             const double *seg_rest, double *scratch, double *con);
/* `seg64`: the strand's ℓ_k in double (§3.15), NULL for ℓ = L/(P−1). */
/* w, pose: the colliders of §3.17 and their poses at the frame's end (NULL: none). */
void hb_dyn_observe_strand_f32(const hb_scene *s, const hb_dyn_world_f32 *w, const float *pose, const float *x,
                               const float *v, const double *seg64, hb_obs_partial *o);
void hb_dyn_observe_strand_f64(const hb_scene *s, const hb_dyn_world_f64 *w, const double *pose, const double *x,
                               const double *v, const double *seg64, hb_obs_partial *o);
/* §3.15: the N·(P − 1) rest lengths |X̄_k − X̄_{k−1}| of a rest shape in the run's precision,
 * computed in double (seg64) and rounded once (seg, float or double as the precision). */
void hb_dyn_seg_rest(const hb_scene *s, const void *rest, double *seg64, void *seg);

#ifdef __cplusplus
}
#endif
#endif
