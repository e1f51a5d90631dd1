/* dyn_followers.h — guides and followers (docs/model.md §3.14): which strands are simulated,
 * which guides each follower takes and with what weights (host side, once per run, shared by
 * every backend), and the placement of one follower in the working precision (the C
 * reference; the CUDA backend has its own kernel with the same arithmetic). */
#ifndef HB_DYN_FOLLOWERS_H
#define HB_DYN_FOLLOWERS_H

#include <stddef.h>
#include <stdint.h>

#include "dynamic/dynamics.h"
#include "runtime/params.h"

#ifdef __cplusplus
extern "C" {
#endif

/* The plan of a guided run: guide j is strand guide[j]; follower j is strand follower[j]
 * and takes guides src[width·j + i] with weights w[width·j + i], i < width. */
typedef struct {
    int64_t n_guides, n_followers;
    int width; /* 1 (one) or min(3, G) (blend3) */
    int64_t *guide, *follower, *src;
    float *w32;
    double *w64;
} hb_followers;

/* G of §3.14 for a scene that declares --guides (N otherwise). */
int64_t hb_guide_count(const hb_scene *s);
/* The plan from the rest shape (canonical [N·P][3] in the scene's precision); 0 on success,
 * else one line in err (out of memory). */
int hb_followers_plan(const hb_scene *s, const void *rest, hb_followers *fl, char *err, size_t errlen);
void hb_followers_free(hb_followers *fl);
/* The features of a run as a name ("bend+shape+…+guides+lra"). */
void hb_dyn_scene_feature_names(const hb_scene *s, char *out, size_t n);

/* Places follower j (§3.14) in the canonical arrays x, v (all strands) from its guides, with
 * the head rotation q at the frame's end (NULL: still head); seg_rest: a groom's ℓ_k as
 * [N][P−1] (§3.15), NULL for ℓ = L/(P−1). */
void hb_follower_place_f32(const hb_dyn_model_f32 *m, const hb_followers *fl, int64_t j, const float *q, float *x,
                           float *v, const float *rest, const float *seg_rest);
void hb_follower_place_f64(const hb_dyn_model_f64 *m, const hb_followers *fl, int64_t j, const double *q, double *x,
                           double *v, const double *rest, const double *seg_rest);

#ifdef __cplusplus
}
#endif
#endif
