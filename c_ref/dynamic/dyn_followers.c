/* dyn_followers.c — guides and followers (docs/model.md §3.14): the host-side plan shared by
 * every backend and the reference placement of a follower in fp32 and fp64. */
#include "dynamic/dyn_followers.h"
#include "runtime/checked.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

int64_t hb_guide_count(const hb_scene *s)
{
    const int64_t N = s->n_strands;
    const hb_dynamics *d = &s->dyn;
    if (!d->guided) return N;
    int64_t g = d->guides > 1.0 ? (int64_t)d->guides : (int64_t)floor(d->guides * (double)N + 0.5);
    if (g < 1) g = 1;
    return g > N ? N : g;
}

void hb_dyn_scene_feature_names(const hb_scene *s, char *out, size_t n)
{
    hb_dyn_feature_names(hb_dyn_features(s), out, n);
    if (strcmp(out, "none") == 0) out[0] = '\0';
    if (s->dyn.guided) snprintf(out + strlen(out), n - strlen(out), "%sguides", out[0] ? "+" : "");
    if (s->dyn.lra) snprintf(out + strlen(out), n - strlen(out), "%slra", out[0] ? "+" : "");
    if (s->dyn.sag_free) snprintf(out + strlen(out), n - strlen(out), "%ssagfree", out[0] ? "+" : "");
    if (s->dyn.render_points) snprintf(out + strlen(out), n - strlen(out), "%slod", out[0] ? "+" : "");
    if (s->dyn.grid) /* §3.16 */
        snprintf(out + strlen(out), n - strlen(out), "%sgrid%s%s", out[0] ? "+" : "",
                 s->dyn.grid_friction_declared ? "+gridfriction" : "", s->dyn.grid_volume_declared ? "+volume" : "");
    if (s->dyn.colliders_path) snprintf(out + strlen(out), n - strlen(out), "%scolliders", out[0] ? "+" : "");
    int friction = s->dyn.friction_declared;
    for (int i = 0; s->dyn.cols && i < s->dyn.cols->n; i++) friction |= s->dyn.cols->c[i].mu_s > 0.0;
    if (friction) snprintf(out + strlen(out), n - strlen(out), "%sfriction", out[0] ? "+" : "");
    if (!out[0]) snprintf(out, n, "none");
}

void hb_followers_free(hb_followers *fl)
{
    free(fl->guide);
    free(fl->follower);
    free(fl->src);
    free(fl->w32);
    free(fl->w64);
    memset(fl, 0, sizeof *fl);
}

typedef struct {
    double x, y, z;
    int64_t j; /* guide number */
} guide_root;

static int by_x(const void *a, const void *b)
{
    const guide_root *p = a, *q = b;
    if (p->x != q->x) return p->x < q->x ? -1 : 1;
    return p->j < q->j ? -1 : p->j > q->j;
}

/* (d2, j) before (e2, k): nearer first, the lower guide number on a tie. */
static int before(double d2, int64_t j, double e2, int64_t k)
{
    return d2 < e2 || (d2 == e2 && j < k);
}

static double root_coord(const hb_scene *s, const void *rest, int64_t i, int c)
{
    const size_t at = (size_t)i * (size_t)s->points * 3u + (size_t)c;
    return s->precision == HB_FP32 ? (double)((const float *)rest)[at] : ((const double *)rest)[at];
}

int hb_followers_plan(const hb_scene *s, const void *rest, hb_followers *fl, char *err, size_t errlen)
{
    memset(fl, 0, sizeof *fl);
    const int64_t N = s->n_strands, G = hb_guide_count(s), F = N - G;
    const int W = s->dyn.follow == HB_FOLLOW_ONE ? 1 : (G < 3 ? (int)G : 3);
    fl->n_guides = G;
    fl->n_followers = F;
    fl->width = W;
    const uint64_t nw = hb_mul_sat((uint64_t)(F > 0 ? F : 1), (uint64_t)W);
    fl->guide = malloc((size_t)hb_mul_sat((uint64_t)G, sizeof *fl->guide));
    fl->follower = malloc((size_t)hb_mul_sat((uint64_t)(F > 0 ? F : 1), sizeof *fl->follower));
    fl->src = malloc((size_t)hb_mul_sat(nw, sizeof *fl->src));
    fl->w32 = malloc((size_t)hb_mul_sat(nw, sizeof *fl->w32));
    fl->w64 = malloc((size_t)hb_mul_sat(nw, sizeof *fl->w64));
    guide_root *roots = malloc((size_t)hb_mul_sat((uint64_t)G, sizeof *roots));
    if (!fl->guide || !fl->follower || !fl->src || !fl->w32 || !fl->w64 || !roots) {
        free(roots);
        hb_followers_free(fl);
        snprintf(err, errlen, "out of host memory for the followers' plan (%lld strands)", (long long)N);
        return -1;
    }
    /* guide j is strand ⌊j·N/G⌋; the others follow, in strand order */
    int64_t nf = 0;
    for (int64_t j = 0, i = 0; i < N; i++) {
        if (j < G && i == (int64_t)((__int128)j * N / G)) {
            fl->guide[j] = i;
            roots[j] = (guide_root){root_coord(s, rest, i, 0), root_coord(s, rest, i, 1), root_coord(s, rest, i, 2), j};
            j++;
        } else {
            fl->follower[nf++] = i;
        }
    }
    qsort(roots, (size_t)G, sizeof *roots, by_x);
    /* each follower's W nearest guide roots (exact: a sweep outward in x, pruned by the W-th
     * distance) and its weights */
    for (int64_t f = 0; f < F; f++) {
        const int64_t i = fl->follower[f];
        const double px = root_coord(s, rest, i, 0), py = root_coord(s, rest, i, 1), pz = root_coord(s, rest, i, 2);
        double best2[3] = {INFINITY, INFINITY, INFINITY};
        int64_t bestj[3] = {INT64_MAX, INT64_MAX, INT64_MAX};
        int64_t lo = 0, hi = G;
        while (lo < hi) { /* first root with x ≥ px */
            const int64_t mid = lo + (hi - lo) / 2;
            if (roots[mid].x < px) lo = mid + 1;
            else hi = mid;
        }
        for (int dir = 0; dir < 2; dir++)
            for (int64_t r = dir ? lo - 1 : lo; r >= 0 && r < G; r += dir ? -1 : 1) {
                const double dx = roots[r].x - px, dy = roots[r].y - py, dz = roots[r].z - pz;
                if (dx * dx > best2[W - 1]) break;
                const double d2 = dx * dx + dy * dy + dz * dz;
                const int64_t j = roots[r].j;
                if (!before(d2, j, best2[W - 1], bestj[W - 1])) continue;
                int at = W - 1;
                while (at > 0 && before(d2, j, best2[at - 1], bestj[at - 1])) {
                    best2[at] = best2[at - 1];
                    bestj[at] = bestj[at - 1];
                    at--;
                }
                best2[at] = d2;
                bestj[at] = j;
            }
        double w[3] = {1.0, 0.0, 0.0};
        if (W > 1 && best2[0] > 0.0) {
            double inv[3], sum = 0.0;
            for (int k = 0; k < W; k++) {
                inv[k] = 1.0 / sqrt(best2[k]);
                sum += inv[k];
            }
            for (int k = 0; k < W; k++) w[k] = inv[k] / sum;
        }
        for (int k = 0; k < W; k++) {
            fl->src[(size_t)f * (size_t)W + (size_t)k] = fl->guide[bestj[k]];
            fl->w64[(size_t)f * (size_t)W + (size_t)k] = w[k];
            fl->w32[(size_t)f * (size_t)W + (size_t)k] = (float)w[k];
        }
    }
    free(roots);
    return 0;
}

#define REAL float
#define SFX(name) name##_f32
#define DMODEL hb_dyn_model_f32
#define SQRT sqrtf
#define WEIGHTS(fl) ((fl)->w32)
#include "dynamic/dyn_followers_impl.h"
#undef REAL
#undef SFX
#undef DMODEL
#undef SQRT
#undef WEIGHTS

#define REAL double
#define SFX(name) name##_f64
#define DMODEL hb_dyn_model_f64
#define SQRT sqrt
#define WEIGHTS(fl) ((fl)->w64)
#include "dynamic/dyn_followers_impl.h"
