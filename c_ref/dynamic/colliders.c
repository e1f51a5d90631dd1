/* colliders.c — the colliders of docs/model.md §3.17 on the host: the colliders file, each
 * collider's pose a substep, and the body frame's sway. A mesh's signed distance field is
 * sdf_mesh.c's. Everything here is double; the backends round the poses once. */
#include "dynamic/world.h"

#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "dynamic/dynamics.h"
#include "runtime/cli.h"
#include "runtime/input.h"

#define FAIL(...)                                                                                                      \
    do {                                                                                                               \
        snprintf(err, errlen, __VA_ARGS__);                                                                            \
        goto fail;                                                                                                     \
    } while (0)

void hb_colliders_free(hb_colliders *c)
{
    for (int i = 0; i < c->n; i++) free(c->c[i].sdf);
    memset(c, 0, sizeof *c);
}

/* the words of a line, split at spaces and tabs; a '#' ends the line */
static int split_words(char *line, char **w, int max)
{
    int n = 0;
    char *hash = strchr(line, '#');
    if (hash) *hash = '\0';
    for (char *save = NULL, *t = strtok_r(line, " \t\r\n", &save); t; t = strtok_r(NULL, " \t\r\n", &save)) {
        if (n == max) return max + 1;
        w[n++] = t;
    }
    return n;
}

/* the numbers w[0 … n−1] of line `ln` */
static int numbers(const char *path, int ln, char **w, int n, double *out, char *err, size_t errlen)
{
    char what[128];
    for (int i = 0; i < n; i++) {
        snprintf(what, sizeof what, "--colliders %s, line %d", path, ln);
        if (hb_parse_number(what, w[i], &out[i], err, errlen)) return -1;
    }
    return 0;
}

/* The mesh's file: relative to the colliders file's folder unless absolute. */
static void mesh_path(const char *colliders, const char *name, char *out, size_t n)
{
    const char *slash = strrchr(colliders, '/');
    if (name[0] == '/' || !slash) snprintf(out, n, "%s", name);
    else snprintf(out, n, "%.*s/%s", (int)(slash - colliders), colliders, name);
}

/* One line: kind, frame, geometry, optional friction. */
static int parse_line(const char *path, int ln, char **w, int nw, hb_collider *c, char *err, size_t errlen)
{
    static const struct {
        const char *kind;
        int id, nums;
    } kinds[] = {{"sphere", HB_COL_SPHERE, 4},
                 {"capsule", HB_COL_CAPSULE, 7},
                 {"plane", HB_COL_PLANE, 6},
                 {"mesh", HB_COL_MESH, 0}};
    int k = -1;
    for (int i = 0; i < 4; i++)
        if (strcmp(w[0], kinds[i].kind) == 0) k = i;
    if (k < 0) FAIL("--colliders %s, line %d: unknown collider '%s' (sphere, capsule, plane or mesh)", path, ln, w[0]);
    memset(c, 0, sizeof *c);
    c->kind = kinds[k].id;
    if (nw < 2 || (strcmp(w[1], "head") != 0 && strcmp(w[1], "body") != 0))
        FAIL("--colliders %s, line %d: the frame must be head or body (got '%s')", path, ln, nw < 2 ? "" : w[1]);
    c->frame = strcmp(w[1], "head") == 0 ? HB_FRAME_HEAD : HB_FRAME_BODY;
    int at = 2;
    double mesh_n = 0.0, band = 4.0;
    if (c->kind == HB_COL_MESH) {
        if (nw < 4) FAIL("--colliders %s, line %d: a mesh needs a file and its SDF's nodes per axis", path, ln);
        snprintf(c->source, sizeof c->source, "%s", w[2]);
        if (numbers(path, ln, w + 3, 1, &mesh_n, err, errlen)) return -1;
        if (!(mesh_n == floor(mesh_n) && mesh_n >= 8 && mesh_n <= 512))
            FAIL("--colliders %s, line %d: a mesh's SDF takes 8 to 512 nodes per axis (got %s)", path, ln, w[3]);
        at = 4;
    } else {
        if (nw < 2 + kinds[k].nums)
            FAIL("--colliders %s, line %d: a %s needs %d numbers after its frame", path, ln, w[0], kinds[k].nums);
        if (numbers(path, ln, w + 2, kinds[k].nums, c->g, err, errlen)) return -1;
        at = 2 + kinds[k].nums;
    }
    int have_k = 0;
    while (at < nw) {
        double v;
        if (at + 1 >= nw) FAIL("--colliders %s, line %d: '%s' needs a value", path, ln, w[at]);
        if (numbers(path, ln, w + at + 1, 1, &v, err, errlen)) return -1;
        if (strcmp(w[at], "mu_s") == 0) c->mu_s = v;
        else if (strcmp(w[at], "mu_k") == 0) c->mu_k = v, have_k = 1;
        else if (strcmp(w[at], "band") == 0 && c->kind == HB_COL_MESH) band = v;
        else FAIL("--colliders %s, line %d: unknown word '%s'", path, ln, w[at]);
        at += 2;
    }
    if (!have_k) c->mu_k = c->mu_s;
    if (!(c->mu_s >= 0.0 && c->mu_k >= 0.0 && c->mu_k <= c->mu_s))
        FAIL("--colliders %s, line %d: friction needs 0 <= mu_k <= mu_s (got %g, %g)", path, ln, c->mu_s, c->mu_k);
    if (c->kind == HB_COL_MESH) {
        if (!(band == floor(band) && band >= 0.0 && band <= 512.0))
            FAIL("--colliders %s, line %d: band takes 0 (every node) to 512 node spacings (got %g)", path, ln, band);
        char file[4096];
        mesh_path(path, c->source, file, sizeof file);
        return hb_mesh_sdf(file, (int64_t)mesh_n, (int64_t)band, c, err, errlen);
    }
    if ((c->kind == HB_COL_SPHERE && !(c->g[3] > 0.0)) || (c->kind == HB_COL_CAPSULE && !(c->g[6] > 0.0)))
        FAIL("--colliders %s, line %d: the radius must be > 0", path, ln);
    if (c->kind == HB_COL_CAPSULE) {
        const double e[3] = {c->g[3] - c->g[0], c->g[4] - c->g[1], c->g[5] - c->g[2]};
        if (!((e[0] * e[0] + e[1] * e[1]) + e[2] * e[2] > 0.0))
            FAIL("--colliders %s, line %d: a capsule's two ends must differ", path, ln);
    }
    if (c->kind == HB_COL_PLANE) {
        const double l = sqrt((c->g[3] * c->g[3] + c->g[4] * c->g[4]) + c->g[5] * c->g[5]);
        if (!(l > 0.0 && isfinite(l))) FAIL("--colliders %s, line %d: a plane's normal must not be zero", path, ln);
        for (int i = 3; i < 6; i++) c->g[i] /= l;
    }
    return 0;
fail:
    return -1;
}

int hb_colliders_load(const char *path, hb_colliders *out, char *err, size_t errlen)
{
    memset(out, 0, sizeof *out);
    FILE *f = NULL;
    char *line = NULL;
    size_t cap = 0;
    f = hb_input_fopen("--colliders", path, "a colliders file", 1, NULL, err, errlen);
    if (!f) goto fail_quiet;
    ssize_t got;
    for (int ln = 1; (got = getline(&line, &cap, f)) >= 0; ln++) {
        if ((size_t)got != strlen(line)) FAIL("--colliders %s, line %d: holds a NUL byte", path, ln);
        char *w[32];
        const int nw = split_words(line, w, 32);
        if (nw == 0) continue;
        if (nw > 32) FAIL("--colliders %s, line %d: too many words", path, ln);
        if (out->n == HB_MAX_COLLIDERS) FAIL("--colliders %s: more than %d colliders", path, HB_MAX_COLLIDERS);
        if (parse_line(path, ln, w, nw, &out->c[out->n], err, errlen)) goto fail_quiet;
        out->n++;
    }
    if (ferror(f)) FAIL("--colliders %s: read error", path);
    fclose(f);
    free(line);
    if (out->n == 0) {
        snprintf(err, errlen, "--colliders %s: the file declares no collider", path);
        return -1;
    }
    return 0;
fail:
fail_quiet:
    if (f) fclose(f);
    free(line);
    hb_colliders_free(out);
    return -1;
}

void hb_body_translation(const hb_dynamics *d, double t, double b[3])
{
    const double rest = 1.0 - d->body_frequency * t; /* rise: the share of the way still to go */
    b[0] = d->body_motion == HB_BODY_SWAY ? d->body_amplitude * sin(2.0 * M_PI * d->body_frequency * t) : 0.0;
    b[1] = d->body_motion == HB_BODY_RISE && rest > 0.0 ? -d->body_amplitude * rest : 0.0;
    b[2] = 0.0;
}

/* r = Q·a (rows left to right) */
static void rot(const double *q, const double *a, double *r)
{
    for (int i = 0; i < 3; i++) r[i] = (q[3 * i] * a[0] + q[3 * i + 1] * a[1]) + q[3 * i + 2] * a[2];
}

/* a point of frame `frame` at rest, in the world at the pose (q, b) */
static void place(int frame, const double *q, const double *b, const double *a, double *r)
{
    if (frame == HB_FRAME_HEAD) rot(q, a, r);
    else
        for (int i = 0; i < 3; i++) r[i] = a[i] + b[i];
}

/* A sphere (centre, radius²) that holds every point collider k (margin cm) can move: its reach
 * grown by 0.1% and 1e-6 cm, well beyond the working precision's rounding, so that a point
 * outside it is outside the collider in any arithmetic. */
static void bound(const hb_collider *k, const double *q, const double *b, double cm, double *out)
{
    double c[3] = {0, 0, 0}, r = INFINITY;
    if (k->kind == HB_COL_SPHERE) {
        place(k->frame, q, b, k->g, c);
        r = k->g[3] + cm;
    } else if (k->kind == HB_COL_CAPSULE) {
        const double mid[3] = {0.5 * (k->g[0] + k->g[3]), 0.5 * (k->g[1] + k->g[4]), 0.5 * (k->g[2] + k->g[5])};
        const double e[3] = {k->g[3] - k->g[0], k->g[4] - k->g[1], k->g[5] - k->g[2]};
        place(k->frame, q, b, mid, c);
        r = 0.5 * sqrt((e[0] * e[0] + e[1] * e[1]) + e[2] * e[2]) + k->g[6] + cm;
    } else if (k->kind == HB_COL_MESH) { /* the SDF's cube: a point outside it is not tested */
        const double half = 0.5 * (double)(k->sdf_n - 1) * k->sdf_h;
        const double mid[3] = {k->sdf_lo[0] + half, k->sdf_lo[1] + half, k->sdf_lo[2] + half};
        place(k->frame, q, b, mid, c);
        r = half * sqrt(3.0);
    }
    memcpy(out, c, sizeof c);
    out[3] = isfinite(r) ? (r * 1.001 + 1e-6) * (r * 1.001 + 1e-6) : INFINITY;
}

void hb_colliders_pose(const hb_scene *s, const hb_colliders *c, double t, double t_next, double *pose, double *back)
{
    const hb_dynamics *d = &s->dyn;
    double q0[9], q1[9], b0[3], b1[3];
    hb_head_rotation(d, t, q0);
    hb_head_rotation(d, t_next, q1);
    hb_body_translation(d, t, b0);
    hb_body_translation(d, t_next, b1);
    /* back-transforms: the head's Q(t)·Q(t+h)ᵀ, the body's b(t) − b(t+h) */
    for (int i = 0; i < 3; i++)
        for (int j = 0; j < 3; j++)
            back[3 * i + j] = (q0[3 * i] * q1[3 * j] + q0[3 * i + 1] * q1[3 * j + 1]) + q0[3 * i + 2] * q1[3 * j + 2];
    for (int i = 0; i < 3; i++) back[9 + i] = b0[i] - b1[i];
    const double cm = d->collision_margin;
    for (int i = 0; c && i < c->n; i++) {
        const hb_collider *k = &c->c[i];
        double *p = pose + (size_t)i * HB_COL_POSE;
        memset(p, 0, HB_COL_POSE * sizeof *p);
        switch (k->kind) {
        case HB_COL_SPHERE:
            place(k->frame, q1, b1, k->g, p);
            p[3] = k->g[3] + cm;
            break;
        case HB_COL_CAPSULE: {
            place(k->frame, q1, b1, k->g, p);
            place(k->frame, q1, b1, k->g + 3, p + 3);
            p[6] = k->g[6] + cm;
            /* a unit vector ⟂ b − a at rest, turned with the frame: (b − a) × the axis it leans on least */
            const double e[3] = {k->g[3] - k->g[0], k->g[4] - k->g[1], k->g[5] - k->g[2]};
            int m = 0;
            for (int j = 1; j < 3; j++)
                if (fabs(e[j]) < fabs(e[m])) m = j;
            const double ax[3] = {m == 0 ? 1.0 : 0.0, m == 1 ? 1.0 : 0.0, m == 2 ? 1.0 : 0.0};
            double u[3] = {e[1] * ax[2] - e[2] * ax[1], e[2] * ax[0] - e[0] * ax[2], e[0] * ax[1] - e[1] * ax[0]};
            const double ul = sqrt((u[0] * u[0] + u[1] * u[1]) + u[2] * u[2]);
            for (int j = 0; j < 3; j++) u[j] /= ul;
            if (k->frame == HB_FRAME_HEAD) rot(q1, u, p + 7);
            else memcpy(p + 7, u, sizeof u);
            p[10] = (e[0] * e[0] + e[1] * e[1]) + e[2] * e[2];
            break;
        }
        case HB_COL_PLANE:
            place(k->frame, q1, b1, k->g, p);
            if (k->frame == HB_FRAME_HEAD) rot(q1, k->g + 3, p + 3);
            else memcpy(p + 3, k->g + 3, 3 * sizeof *p);
            p[6] = cm;
            break;
        case HB_COL_MESH:
            if (k->frame == HB_FRAME_HEAD) memcpy(p, q1, 9 * sizeof *p);
            else {
                p[0] = p[4] = p[8] = 1.0;
                memcpy(p + 9, b1, 3 * sizeof *p);
            }
            p[12] = cm;
            break;
        }
        bound(k, q1, b1, cm, p + 16);
    }
}
