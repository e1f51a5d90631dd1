/* sdf_mesh.c — a closed triangle mesh from a Wavefront OBJ file and its signed distance field
 * (docs/model.md §3.17), in double on the host: exact distances to the nearest triangle within
 * the narrow band, the sign from the parity of each node row's crossings of the surface. */
#include "dynamic/world.h"

#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "runtime/checked.h"
#include "runtime/cli.h"
#include "runtime/input.h"

#define FAIL(...)                                                                                                      \
    do {                                                                                                               \
        snprintf(err, errlen, __VA_ARGS__);                                                                            \
        goto fail;                                                                                                     \
    } while (0)

typedef struct {
    double *v; /* 3 a vertex */
    int64_t nv, cv;
    int64_t *t; /* 3 a triangle */
    int64_t nt, ct;
} mesh;

static int grow(void **p, int64_t *cap, int64_t need, size_t item)
{
    if (need <= *cap) return 0;
    int64_t c = *cap ? *cap : 256;
    while (c < need) c *= 2;
    void *q = realloc(*p, (size_t)hb_mul_sat((uint64_t)c, item));
    if (!q) return -1;
    *p = q;
    *cap = c;
    return 0;
}

/* an OBJ vertex reference (1-based, negative: from the end; "i/t/n" keeps i) */
static int vref(const char *w, int64_t nv, int64_t *out)
{
    char *end;
    errno = 0;
    const long long i = strtoll(w, &end, 10);
    if (end == w || (*end != '\0' && *end != '/') || errno) return -1;
    const long long k = i > 0 ? i - 1 : nv + i;
    if (i == 0 || k < 0 || k >= nv) return -1;
    *out = k;
    return 0;
}

static int read_obj(const char *path, mesh *m, char *err, size_t errlen)
{
    char line[4096], what[512];
    FILE *f = NULL;
    if (!(f = hb_input_fopen("--colliders mesh", path, "an OBJ mesh", 1, NULL, err, errlen))) return -1;
    for (int ln = 1; fgets(line, sizeof line, f); ln++) {
        if (!strchr(line, '\n') && !feof(f)) FAIL("mesh %s, line %d: longer than %zu bytes", path, ln, sizeof line);
        char *save = NULL, *w = strtok_r(line, " \t\r\n", &save);
        if (!w || w[0] == '#') continue;
        if (strcmp(w, "v") == 0) {
            if (grow((void **)&m->v, &m->cv, m->nv + 1, 3 * sizeof *m->v)) FAIL("mesh %s: out of memory", path);
            for (int c = 0; c < 3; c++) {
                const char *x = strtok_r(NULL, " \t\r\n", &save);
                snprintf(what, sizeof what, "mesh %s, line %d", path, ln);
                if (!x) FAIL("mesh %s, line %d: a vertex needs x y z", path, ln);
                if (hb_parse_number(what, x, &m->v[3 * m->nv + c], err, errlen)) goto fail;
            }
            m->nv++;
        } else if (strcmp(w, "f") == 0) {
            int64_t idx[3], first = -1, prev = -1;
            int n = 0;
            for (const char *x = strtok_r(NULL, " \t\r\n", &save); x; x = strtok_r(NULL, " \t\r\n", &save), n++) {
                int64_t k;
                if (vref(x, m->nv, &k)) FAIL("mesh %s, line %d: bad vertex index '%s'", path, ln, x);
                if (n == 0) first = k;
                else if (n >= 2) { /* a fan: (first, prev, k) */
                    if (grow((void **)&m->t, &m->ct, m->nt + 1, 3 * sizeof *m->t)) FAIL("mesh %s: out of memory", path);
                    idx[0] = first, idx[1] = prev, idx[2] = k;
                    memcpy(m->t + 3 * m->nt++, idx, sizeof idx);
                }
                prev = k;
            }
            if (n < 3) FAIL("mesh %s, line %d: a face needs at least 3 vertices", path, ln);
        }
    }
    if (ferror(f)) FAIL("mesh %s: read error", path);
    fclose(f);
    if (m->nt == 0) {
        snprintf(err, errlen, "mesh %s: no faces", path);
        return -1;
    }
    return 0;
fail:
    if (f) fclose(f);
    return -1;
}

typedef struct {
    int64_t a, b; /* a < b */
    int dir;      /* +1 when the face runs a → b */
} edge;

static int edge_cmp(const void *x, const void *y)
{
    const edge *p = x, *q = y;
    if (p->a != q->a) return p->a < q->a ? -1 : 1;
    if (p->b != q->b) return p->b < q->b ? -1 : 1;
    return p->dir - q->dir;
}

/* closed and consistently oriented: every edge in exactly two faces, run in opposite directions */
static int check_closed(const char *path, const mesh *m, char *err, size_t errlen)
{
    edge *e = malloc((size_t)hb_mul_sat((uint64_t)m->nt, 3 * sizeof *e));
    if (!e) return snprintf(err, errlen, "mesh %s: out of memory", path), -1;
    for (int64_t i = 0; i < m->nt; i++)
        for (int j = 0; j < 3; j++) {
            const int64_t u = m->t[3 * i + j], v = m->t[3 * i + (j + 1) % 3];
            edge *x = &e[3 * i + j];
            x->a = u < v ? u : v;
            x->b = u < v ? v : u;
            x->dir = u < v ? 1 : -1;
            if (u == v) {
                free(e);
                return snprintf(err, errlen, "mesh %s: face %lld repeats a vertex", path, (long long)i + 1), -1;
            }
        }
    qsort(e, (size_t)(3 * m->nt), sizeof *e, edge_cmp);
    for (int64_t i = 0; i < 3 * m->nt; i += 2) {
        if (i + 1 >= 3 * m->nt || e[i].a != e[i + 1].a || e[i].b != e[i + 1].b || e[i].dir == e[i + 1].dir ||
            (i + 2 < 3 * m->nt && e[i + 2].a == e[i].a && e[i + 2].b == e[i].b)) {
            snprintf(err, errlen,
                     "mesh %s: not a closed, consistently oriented surface (the edge of vertices %lld-%lld is not "
                     "shared by exactly two faces running opposite ways)",
                     path, (long long)e[i].a + 1, (long long)e[i].b + 1);
            free(e);
            return -1;
        }
    }
    free(e);
    return 0;
}

static double dot3(const double *a, const double *b)
{
    return (a[0] * b[0] + a[1] * b[1]) + a[2] * b[2];
}

/* squared distance from p to the triangle abc (the closest point by regions, Ericson 2005 §5.1.5) */
static double tri_dist2(const double *p, const double *a, const double *b, const double *c)
{
    double ab[3], ac[3], ap[3], q[3];
    for (int i = 0; i < 3; i++) ab[i] = b[i] - a[i], ac[i] = c[i] - a[i], ap[i] = p[i] - a[i];
    const double d1 = dot3(ab, ap), d2 = dot3(ac, ap);
    if (d1 <= 0.0 && d2 <= 0.0) {
        memcpy(q, a, sizeof q);
    } else {
        double bp[3], cp[3];
        for (int i = 0; i < 3; i++) bp[i] = p[i] - b[i], cp[i] = p[i] - c[i];
        const double d3 = dot3(ab, bp), d4 = dot3(ac, bp), d5 = dot3(ab, cp), d6 = dot3(ac, cp);
        const double vc = d1 * d4 - d3 * d2, vb = d5 * d2 - d1 * d6, va = d3 * d6 - d5 * d4;
        if (d3 >= 0.0 && d4 <= d3) memcpy(q, b, sizeof q);
        else if (d6 >= 0.0 && d5 <= d6) memcpy(q, c, sizeof q);
        else if (vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0) {
            const double v = d1 / (d1 - d3);
            for (int i = 0; i < 3; i++) q[i] = a[i] + v * ab[i];
        } else if (vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0) {
            const double w = d2 / (d2 - d6);
            for (int i = 0; i < 3; i++) q[i] = a[i] + w * ac[i];
        } else if (va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0) {
            const double w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
            for (int i = 0; i < 3; i++) q[i] = b[i] + w * (c[i] - b[i]);
        } else {
            const double den = 1.0 / (va + vb + vc), v = vb * den, w = vc * den;
            for (int i = 0; i < 3; i++) q[i] = a[i] + ab[i] * v + ac[i] * w;
        }
    }
    double d[3];
    for (int i = 0; i < 3; i++) d[i] = p[i] - q[i];
    return dot3(d, d);
}

/* The x at which the line {y = y0, z = z0} crosses triangle abc, counted once per crossing of a
 * closed surface: the half-open rule in the (y, z) projection. 0 when it does not cross. */
static int row_cross(const double *a, const double *b, const double *c, double y0, double z0, double *x)
{
    const double *v[3] = {a, b, c};
    double w[3];
    const double area = (b[1] - a[1]) * (c[2] - a[2]) - (b[2] - a[2]) * (c[1] - a[1]);
    if (area == 0.0) return 0;
    const double sg = area > 0.0 ? 1.0 : -1.0;
    for (int i = 0; i < 3; i++) {
        const double *p = v[(i + 1) % 3], *q = v[(i + 2) % 3];
        const double e = sg * ((q[1] - p[1]) * (z0 - p[2]) - (q[2] - p[2]) * (y0 - p[1]));
        if (e < 0.0) return 0;
        if (e == 0.0) { /* on the edge p–q: count it for one of the two faces that share it */
            const double dy = sg * (q[1] - p[1]), dz = sg * (q[2] - p[2]);
            if (!(dz > 0.0 || (dz == 0.0 && dy < 0.0))) return 0;
        }
        w[i] = e;
    }
    const double s = (w[0] + w[1]) + w[2];
    *x = ((w[0] * a[0] + w[1] * b[0]) + w[2] * c[0]) / s;
    return 1;
}

static int cmp_double(const void *x, const void *y)
{
    const double a = *(const double *)x, b = *(const double *)y;
    return a < b ? -1 : a > b;
}

int hb_mesh_sdf(const char *path, int64_t n, int64_t band, hb_collider *out, char *err, size_t errlen)
{
    mesh m;
    memset(&m, 0, sizeof m);
    double *cross = NULL;
    int status = -1;
    if (read_obj(path, &m, err, errlen) || check_closed(path, &m, err, errlen)) goto done;
    double lo[3], hi[3];
    for (int c = 0; c < 3; c++) lo[c] = hi[c] = m.v[c];
    for (int64_t i = 0; i < m.nv; i++)
        for (int c = 0; c < 3; c++) {
            if (m.v[3 * i + c] < lo[c]) lo[c] = m.v[3 * i + c];
            if (m.v[3 * i + c] > hi[c]) hi[c] = m.v[3 * i + c];
        }
    double side = 0.0, mid[3];
    for (int c = 0; c < 3; c++) {
        if (hi[c] - lo[c] > side) side = hi[c] - lo[c];
        mid[c] = 0.5 * (lo[c] + hi[c]);
    }
    if (!(side > 0.0 && isfinite(side))) {
        snprintf(err, errlen, "mesh %s: its vertices span no volume", path);
        goto done;
    }
    /* the cube: the bounding box's largest side grown by 10% and two spacings a side */
    const double h = 1.1 * side / (double)(n - 5);
    out->sdf_n = n;
    out->band = band;
    out->sdf_h = h;
    for (int c = 0; c < 3; c++) out->sdf_lo[c] = mid[c] - 0.5 * (double)(n - 1) * h;
    const uint64_t nodes = (uint64_t)n * (uint64_t)n * (uint64_t)n;
    out->sdf = malloc((size_t)hb_mul_sat(nodes, sizeof *out->sdf));
    cross = malloc((size_t)hb_mul_sat((uint64_t)m.nt, sizeof *cross));
    if (!out->sdf || !cross) {
        snprintf(err, errlen, "mesh %s: out of memory for its %lld^3 SDF", path, (long long)n);
        goto done;
    }
    const double far = band > 0 ? (double)band * h : INFINITY;
    for (uint64_t j = 0; j < nodes; j++) out->sdf[j] = far * far; /* squared until the end */
    /* exact squared distances within the band (every node without one) */
    for (int64_t t = 0; t < m.nt; t++) {
        const double *a = m.v + 3 * m.t[3 * t], *b = m.v + 3 * m.t[3 * t + 1], *c = m.v + 3 * m.t[3 * t + 2];
        int64_t i0[3], i1[3];
        for (int k = 0; k < 3; k++) {
            double l = fmin(a[k], fmin(b[k], c[k])), u = fmax(a[k], fmax(b[k], c[k]));
            if (band > 0) l -= far, u += far;
            i0[k] = band > 0 ? (int64_t)floor((l - out->sdf_lo[k]) / h) : 0;
            i1[k] = band > 0 ? (int64_t)ceil((u - out->sdf_lo[k]) / h) : n - 1;
            if (i0[k] < 0) i0[k] = 0;
            if (i1[k] > n - 1) i1[k] = n - 1;
        }
        for (int64_t z = i0[2]; z <= i1[2]; z++)
            for (int64_t y = i0[1]; y <= i1[1]; y++)
                for (int64_t x = i0[0]; x <= i1[0]; x++) {
                    const double p[3] = {out->sdf_lo[0] + (double)x * h, out->sdf_lo[1] + (double)y * h,
                                         out->sdf_lo[2] + (double)z * h};
                    const double d2 = tri_dist2(p, a, b, c);
                    double *s = &out->sdf[x + n * (y + n * z)];
                    if (d2 < *s) *s = d2;
                }
    }
    /* the sign: along each x row, a node is inside when an odd number of crossings lie beyond it */
    for (int64_t z = 0; z < n; z++)
        for (int64_t y = 0; y < n; y++) {
            const double y0 = out->sdf_lo[1] + (double)y * h, z0 = out->sdf_lo[2] + (double)z * h;
            int64_t nc = 0;
            for (int64_t t = 0; t < m.nt; t++) {
                const double *a = m.v + 3 * m.t[3 * t], *b = m.v + 3 * m.t[3 * t + 1], *c = m.v + 3 * m.t[3 * t + 2];
                if (fmin(a[1], fmin(b[1], c[1])) > y0 || fmax(a[1], fmax(b[1], c[1])) < y0 ||
                    fmin(a[2], fmin(b[2], c[2])) > z0 || fmax(a[2], fmax(b[2], c[2])) < z0)
                    continue;
                double xc;
                if (row_cross(a, b, c, y0, z0, &xc)) cross[nc++] = xc;
            }
            qsort(cross, (size_t)nc, sizeof *cross, cmp_double);
            int64_t beyond = nc, ci = 0;
            for (int64_t x = 0; x < n; x++) {
                const double x0 = out->sdf_lo[0] + (double)x * h;
                while (ci < nc && cross[ci] <= x0) ci++, beyond--;
                double *s = &out->sdf[x + n * (y + n * z)];
                const double d = sqrt(*s);
                *s = (beyond & 1) ? -d : d;
            }
        }
    status = 0;
done:
    if (status != 0) {
        free(out->sdf);
        out->sdf = NULL;
    }
    free(cross);
    free(m.v);
    free(m.t);
    return status;
}
