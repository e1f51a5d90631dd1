/* groom.c — the curly groom and the HAIR file reader (docs/model.md §3.15). */
#include "runtime/groom.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "runtime/checked.h"
#include "runtime/host.h"
#include "runtime/input.h"

#define HAIR_HEADER 128
#define HAIR_SEGMENTS (1u << 0)
#define HAIR_POINTS (1u << 1)
#define HAIR_THICKNESS (1u << 2)
#define HAIR_TRANSPARENCY (1u << 3)
#define HAIR_COLOR (1u << 4)
/* a root farther than this fraction of the fitted radius off the sphere refuses the groom */
#define HB_GROOM_FIT_TOLERANCE 0.05
/* the curly groom's roots: cos of the polar angle from +y runs from 1 down to this */
#define HB_CURLY_COS_MIN (-0.25)

#define FAIL(...)                                                                                                      \
    do {                                                                                                               \
        snprintf(err, errlen, __VA_ARGS__);                                                                            \
        goto fail;                                                                                                     \
    } while (0)

static uint32_t le32(const unsigned char *b)
{
    return (uint32_t)b[0] | (uint32_t)b[1] << 8 | (uint32_t)b[2] << 16 | (uint32_t)b[3] << 24;
}

static float lef32(const unsigned char *b)
{
    const uint32_t u = le32(b);
    float f;
    memcpy(&f, &u, sizeof f);
    return f;
}

/* Solves the 4×4 system a·x = b by elimination with partial pivoting; −1 when a pivot falls
 * below `rel` times the largest entry (a rank below 4 at that conditioning). */
static int solve4(double a[4][4], double b[4], double x[4], double rel)
{
    double scale = 0.0;
    for (int i = 0; i < 4; i++)
        for (int j = 0; j < 4; j++) scale = fmax(scale, fabs(a[i][j]));
    for (int c = 0; c < 4; c++) {
        int piv = c;
        for (int r = c + 1; r < 4; r++)
            if (fabs(a[r][c]) > fabs(a[piv][c])) piv = r;
        if (!(fabs(a[piv][c]) > rel * scale)) return -1;
        for (int j = 0; j < 4; j++) {
            const double t = a[c][j];
            a[c][j] = a[piv][j];
            a[piv][j] = t;
        }
        const double t = b[c];
        b[c] = b[piv];
        b[piv] = t;
        for (int r = c + 1; r < 4; r++) {
            const double f = a[r][c] / a[c][c];
            for (int j = c; j < 4; j++) a[r][j] -= f * a[c][j];
            b[r] -= f * b[c];
        }
    }
    for (int r = 3; r >= 0; r--) {
        double v = b[r];
        for (int j = r + 1; j < 4; j++) v -= a[r][j] * x[j];
        x[r] = v / a[r][r];
    }
    return 0;
}

/* The points of strand i in a file's segment counts: its own, or the default's. */
static uint64_t strand_points(const unsigned char *seg_raw, uint32_t dseg, int64_t i)
{
    return seg_raw ? (uint64_t)seg_raw[2 * i] + ((uint64_t)seg_raw[2 * i + 1] << 8) + 1 : (uint64_t)dseg + 1;
}

/* The sphere |p − c| = r fitted to the N roots in the least-squares sense of |p|² = 2c·p + d,
 * solved for the roots moved to their mean and scaled to unit spread, so that the rank test
 * is relative to the roots' own conditioning, not to where they lie. 0, or −1 when the roots
 * do not determine a sphere. */
#define HB_FIT_RANK (1e-9)
static int fit_sphere(const double *pts, const unsigned char *seg_raw, uint32_t dseg, int64_t N, double c[3], double *r)
{
    double mean[3] = {0.0, 0.0, 0.0}, spread = 0.0;
    uint64_t first = 0;
    for (int64_t i = 0; i < N; first += strand_points(seg_raw, dseg, i), i++)
        for (int k = 0; k < 3; k++) mean[k] += pts[3 * first + k] / (double)N;
    first = 0;
    for (int64_t i = 0; i < N; first += strand_points(seg_raw, dseg, i), i++)
        for (int k = 0; k < 3; k++) spread = fmax(spread, fabs(pts[3 * first + k] - mean[k]));
    if (!(spread > 0.0)) return -1;
    double a[4][4] = {{0}}, b[4] = {0}, x[4] = {0};
    first = 0;
    for (int64_t i = 0; i < N; first += strand_points(seg_raw, dseg, i), i++) {
        double q[3];
        for (int k = 0; k < 3; k++) q[k] = (pts[3 * first + k] - mean[k]) / spread;
        const double row[4] = {2 * q[0], 2 * q[1], 2 * q[2], 1.0}, qq = q[0] * q[0] + q[1] * q[1] + q[2] * q[2];
        for (int p = 0; p < 4; p++) {
            for (int k = 0; k < 4; k++) a[p][k] += row[p] * row[k];
            b[p] += row[p] * qq;
        }
    }
    if (solve4(a, b, x, HB_FIT_RANK) != 0) return -1;
    for (int k = 0; k < 3; k++) c[k] = mean[k] + spread * x[k];
    *r = spread * sqrt(fmax(x[3] + x[0] * x[0] + x[1] * x[1] + x[2] * x[2], 0.0));
    return 0;
}

/* Distance from q to the segment a–b. */
static double point_segment(const double *q, const double *a, const double *b)
{
    double e[3], d[3], ee = 0.0, ed = 0.0;
    for (int c = 0; c < 3; c++) {
        e[c] = b[c] - a[c];
        d[c] = q[c] - a[c];
        ee += e[c] * e[c];
        ed += e[c] * d[c];
    }
    const double t = ee > 0.0 ? fmin(fmax(ed / ee, 0.0), 1.0) : 0.0;
    double r2 = 0.0;
    for (int c = 0; c < 3; c++) r2 += (d[c] - t * e[c]) * (d[c] - t * e[c]);
    return sqrt(r2);
}

/* One strand of n points resampled to P points equally spaced in arc length (the first
 * and last kept exactly); returns the most an input point lies off the result. */
static double resample(const double *in, int64_t n, const double *arc, int64_t P, double *out)
{
    const double total = arc[n - 1];
    int64_t j = 0;
    for (int64_t k = 0; k < P; k++) {
        double *o = out + 3 * k;
        if (k == 0 || k == P - 1) {
            memcpy(o, in + 3 * (k == 0 ? 0 : n - 1), 3 * sizeof *o);
            continue;
        }
        const double s = total * (double)k / (double)(P - 1);
        while (j + 2 < n && arc[j + 1] <= s) j++;
        const double len = arc[j + 1] - arc[j];
        const double t = len > 0.0 ? (s - arc[j]) / len : 0.0;
        for (int c = 0; c < 3; c++) o[c] = in[3 * j + c] + t * (in[3 * (j + 1) + c] - in[3 * j + c]);
    }
    double worst = 0.0;
    for (int64_t i = 0; i < n; i++) {
        int64_t k = (int64_t)floor(arc[i] / total * (double)(P - 1));
        if (k > P - 2) k = P - 2;
        if (k < 0) k = 0;
        worst = fmax(worst, point_segment(in + 3 * i, out + 3 * k, out + 3 * (k + 1)));
    }
    return worst;
}

/* Whether strand i's resampled points (P of them at out) keep every segment in the working
 * precision: the points rounded to it, each segment's length at least the shortest length it
 * squares. The length of the shortest one in *seg. */
static int segments_representable(const double *out, int64_t P, hb_precision prec, double *seg)
{
    *seg = INFINITY;
    for (int64_t k = 1; k < P; k++) {
        double e2 = 0.0;
        for (int c = 0; c < 3; c++) {
            const double a = out[3 * (k - 1) + c], b = out[3 * k + c];
            const double d = prec == HB_FP32 ? (double)(float)b - (double)(float)a : b - a;
            e2 += d * d;
        }
        *seg = fmin(*seg, sqrt(e2));
    }
    return *seg >= hb_length_min(prec);
}

/* The HAIR header's sizes against the file and the run, before anything is allocated: the
 * segments array's bytes, the strands taken (*N), the resampled state's bytes. */
static int check_sizes(const char *path, hb_options *o, const unsigned char *h, uint64_t size, int64_t *N, char *err,
                       size_t errlen)
{
    hb_scene *s = &o->scene;
    const uint32_t nh = le32(h + 4), np = le32(h + 8), flags = le32(h + 12);
    if (nh == 0 || np == 0) return snprintf(err, errlen, "--groom %s: the file holds no strands", path), HB_EXIT_USAGE;
    if (!(flags & HAIR_POINTS))
        return snprintf(err, errlen, "--groom %s: the file has no points array", path), HB_EXIT_USAGE;
    if ((flags & HAIR_SEGMENTS) && size < HAIR_HEADER + 2u * (uint64_t)nh)
        return snprintf(err, errlen, "--groom %s: truncated in its segments array", path), HB_EXIT_USAGE;
    if ((o->given & HB_GIVEN_STRANDS) && s->n_strands > (int64_t)nh)
        return snprintf(err, errlen, "--strands %lld: --groom %s holds %u strands", (long long)s->n_strands, path, nh),
               HB_EXIT_USAGE;
    *N = (o->given & HB_GIVEN_STRANDS) ? s->n_strands : (int64_t)nh;
    if (!(o->given & HB_GIVEN_CENTER) && *N < 4)
        return snprintf(err, errlen,
                        "--groom %s: %lld strands: fewer than 4 strands do not determine a sphere (--head-center gives "
                        "the head instead)",
                        path, (long long)*N),
               HB_EXIT_USAGE;
    uint64_t bytes;
    if (hb_mul3_u64((uint64_t)*N, (uint64_t)s->points, 3u * sizeof(double), &bytes) || bytes > SIZE_MAX / 2)
        return snprintf(err, errlen, "--points %lld: %lld strands of %lld points are too large to address",
                        (long long)s->points, (long long)*N, (long long)s->points),
               HB_EXIT_USAGE;
    const uint64_t avail = hb_host_memory_available();
    if (avail && bytes > avail)
        return snprintf(err, errlen,
                        "--points %lld: --groom %s's %lld strands resampled to %lld points need %.3g GB of host "
                        "memory, %.3g GB is available",
                        (long long)s->points, path, (long long)*N, (long long)s->points, (double)bytes / 1e9,
                        (double)avail / 1e9),
               HB_EXIT_MEMORY;
    return 0;
}

static int read_hair(const char *path, hb_options *o, hb_groom *g, char *err, size_t errlen)
{
    hb_scene *s = &o->scene;
    unsigned char h[HAIR_HEADER];
    unsigned char *seg_raw = NULL, *pts_raw = NULL;
    double *pts = NULL, *arc = NULL;
    int status = HB_EXIT_USAGE;
    uint64_t size = 0;
    int64_t N = 0;
    FILE *f = hb_input_fopen("--groom", path, "a HAIR file", 1, &size, err, errlen);
    if (!f) return HB_EXIT_USAGE;
    if (fread(h, 1, sizeof h, f) != sizeof h) FAIL("--groom %s: truncated HAIR header (under 128 bytes)", path);
    if (memcmp(h, "HAIR", 4) != 0) FAIL("--groom %s: not a HAIR file (its first 4 bytes are not 'HAIR')", path);
    if ((status = check_sizes(path, o, h, size, &N, err, errlen)) != 0) goto fail;
    status = HB_EXIT_USAGE;
    const uint32_t nh = le32(h + 4), np = le32(h + 8), flags = le32(h + 12), dseg = le32(h + 16);
    const int64_t P = s->points;
    uint64_t total = 0;
    if (flags & HAIR_SEGMENTS) {
        seg_raw = malloc(2u * (size_t)nh);
        if (!seg_raw || fread(seg_raw, 2, nh, f) != nh) FAIL("--groom %s: truncated in its segments array", path);
        for (uint32_t i = 0; i < nh; i++) total += strand_points(seg_raw, dseg, i);
    } else {
        total = (uint64_t)nh * ((uint64_t)dseg + 1);
    }
    if (total != np)
        FAIL("--groom %s: wrong counts: the strands' segments need %llu points, the header says %u", path,
             (unsigned long long)total, np);
    /* the arrays follow the header in this order, each present when its bit is set */
    const double want = HAIR_HEADER + ((flags & HAIR_SEGMENTS) ? 2.0 * nh : 0.0) + 12.0 * np +
                        ((flags & HAIR_THICKNESS) ? 4.0 * np : 0.0) + ((flags & HAIR_TRANSPARENCY) ? 4.0 * np : 0.0) +
                        ((flags & HAIR_COLOR) ? 12.0 * np : 0.0);
    if ((double)size < want)
        FAIL("--groom %s: truncated (%llu bytes; its header's %u strands and %u points need %.0f)", path,
             (unsigned long long)size, nh, np, want);
    pts_raw = malloc(12u * (size_t)np); /* np points fit in the file: checked against its size */
    if (!pts_raw || fread(pts_raw, 12, np, f) != np) FAIL("--groom %s: cannot read the points array", path);
    fclose(f);
    f = NULL;
    if (!(o->given & HB_GIVEN_STRANDS)) s->n_strands = nh;
    pts = malloc(sizeof *pts * 3u * (size_t)np);
    arc = malloc(sizeof *arc * (size_t)np);
    g->pos = malloc(sizeof *g->pos * 3u * (size_t)N * (size_t)P); /* its size checked by check_sizes */
    if (!pts || !arc || !g->pos) {
        status = HB_EXIT_MEMORY;
        FAIL("--groom %s: out of host memory", path);
    }
    for (uint32_t i = 0; i < 3 * np; i++) {
        pts[i] = (double)lef32(pts_raw + 4 * (size_t)i);
        if (!isfinite(pts[i])) FAIL("--groom %s: point %u holds a NaN or Inf", path, i / 3);
    }
    /* the head: given by --head-center, or a sphere fitted to the roots */
    const int given = (o->given & HB_GIVEN_CENTER) != 0;
    const double far = hb_length_max(s->precision);
    double x[3] = {0}, fit_r = 0.0;
    if (given) {
        memcpy(x, o->head_center, sizeof x);
        for (int c = 0; c < 3; c++)
            if (!(fabs(x[c]) <= far))
                FAIL("--head-center %g,%g,%g: beyond the lengths %s can square (%g cm; docs/decisions/paper-model.md)",
                     x[0], x[1], x[2], hb_precision_name(s->precision), far);
    } else if (fit_sphere(pts, seg_raw, dseg, N, x, &fit_r) != 0) {
        FAIL("--groom %s: the roots do not determine a sphere (the roots on one circle or plane; --head-center gives "
             "the head instead)",
             path);
    }
    double rmin = INFINITY, off = 0.0;
    g->length_min = INFINITY;
    g->length_max = 0.0;
    g->resample_error = 0.0;
    uint64_t first = 0;
    for (int64_t i = 0; i < N; i++) {
        const uint64_t n = strand_points(seg_raw, dseg, i);
        double *in = pts + 3 * first;
        for (uint64_t j = 0; j < n; j++)
            for (int c = 0; c < 3; c++) {
                in[3 * j + c] -= x[c];
                if (!(fabs(in[3 * j + c]) <= far))
                    FAIL("--groom %s: point %llu lies %g cm from the head's centre, beyond the lengths %s can square "
                         "(%g cm)",
                         path, (unsigned long long)(first + j), fabs(in[3 * j + c]), hb_precision_name(s->precision),
                         far);
            }
        const double rho = sqrt(in[0] * in[0] + in[1] * in[1] + in[2] * in[2]);
        rmin = fmin(rmin, rho);
        off = fmax(off, fabs(rho - fit_r));
        arc[first] = 0.0;
        for (uint64_t j = 1; j < n; j++) {
            double e2 = 0.0;
            for (int c = 0; c < 3; c++)
                e2 += (in[3 * j + c] - in[3 * (j - 1) + c]) * (in[3 * j + c] - in[3 * (j - 1) + c]);
            arc[first + j] = arc[first + j - 1] + sqrt(e2);
        }
        const double len = arc[first + n - 1];
        if (n < 2 || !(len > 0.0)) FAIL("--groom %s: strand %lld has zero length", path, (long long)i);
        g->length_min = fmin(g->length_min, len);
        g->length_max = fmax(g->length_max, len);
        double *out = g->pos + 3 * (size_t)i * (size_t)P, seg;
        const double e = resample(in, (int64_t)n, arc + first, P, out);
        if (!segments_representable(out, P, s->precision, &seg))
            FAIL("--groom %s: strand %lld resampled to %lld points has segments of %.3g cm, which %s cannot hold "
                 "(shorter than %g cm once rounded; give fewer --points, or --precision fp64)",
                 path, (long long)i, (long long)P, seg, hb_precision_name(s->precision), hb_length_min(s->precision));
        g->resample_error = fmax(g->resample_error, e);
        first += n;
    }
    if (!given && off > HB_GROOM_FIT_TOLERANCE * fit_r)
        FAIL("--groom %s: the roots do not lie near one sphere (up to %.3g cm off the %.3g cm sphere fitted to them, "
             "more than %g of its radius; --head-center gives the head instead)",
             path, off, fit_r, HB_GROOM_FIT_TOLERANCE);
    if (!(rmin > 0.0)) FAIL("--groom %s: a root lies at the %s head's centre", path, given ? "given" : "fitted");
    g->fit_offset = given ? 0.0 : off;
    g->file_strands = nh;
    g->head_given = given;
    memcpy(g->head_center, x, sizeof g->head_center);
    if (!(given && (o->given & HB_GIVEN_RADIUS))) s->head_radius = rmin;
    s->hair_length = g->length_max;
    free(seg_raw);
    free(pts_raw);
    free(pts);
    free(arc);
    return 0;
fail:
    if (f) fclose(f);
    free(seg_raw);
    free(pts_raw);
    free(pts);
    free(arc);
    free(g->pos);
    g->pos = NULL;
    return status;
}

int hb_groom_prepare(hb_options *o, hb_groom *g, char *err, size_t errlen)
{
    memset(g, 0, sizeof *g);
    hb_scene *s = &o->scene;
    if (s->groom == HB_GROOM_CURLY) {
        if (s->curl_radius == 0.0 && s->curl_pitch == 0.0)
            FAIL("--groom curly: --curl-radius and --curl-pitch are both 0 (no helix)");
        g->length_min = g->length_max = s->hair_length;
        return 0;
    }
    if (o->given & (HB_GIVEN_LENGTH | HB_GIVEN_OFFSET | HB_GIVEN_MARGIN | HB_GIVEN_SEED))
        FAIL("--groom %s: the file decides the head and the strands; --hair-length, --hair-offset, --face-margin and "
             "--seed do not apply (--head-radius only beside --head-center)",
             o->groom);
    if ((o->given & HB_GIVEN_RADIUS) && !(o->given & HB_GIVEN_CENTER))
        FAIL("--groom %s: the file decides the head unless --head-center gives it; --head-radius needs --head-center",
             o->groom);
    if ((o->given & HB_GIVEN_RADIUS) && !(isfinite(s->head_radius) && s->head_radius > 0.0))
        FAIL("--head-radius must be a finite number > 0 (got %g)", s->head_radius);
    return read_hair(o->groom, o, g, err, errlen);
fail:
    return HB_EXIT_USAGE;
}

/* §3.15 the curly groom: strand i's root on the head at the i-th point of a golden-angle
 * spiral over the cap cos θ ≥ HB_CURLY_COS_MIN (θ from +y), a helix of radius r and pitch q
 * about an axis down the scalp's slope t = (−ŷ + c·n)/s, raised r off the head through the
 * root, so that the curl lies outside it and hangs rather than stands. */
static void curly_point(const hb_scene *s, int64_t i, int64_t k, double p[3])
{
    const double N = (double)s->n_strands, R = s->head_radius, r = s->curl_radius, c = s->curl_pitch / (2.0 * M_PI);
    const double ct = 1.0 - (1.0 - HB_CURLY_COS_MIN) * ((double)i + 0.5) / N, st = sqrt(fmax(1.0 - ct * ct, 0.0));
    const double phi = (double)i * M_PI * (3.0 - sqrt(5.0));
    const double n[3] = {st * cos(phi), ct, st * sin(phi)};
    const double t[3] = {ct * cos(phi), -st, ct * sin(phi)}; /* (−ŷ + c·n)/s: down the slope */
    const double b[3] = {n[1] * t[2] - n[2] * t[1], n[2] * t[0] - n[0] * t[2], n[0] * t[1] - n[1] * t[0]};
    const double tau = (double)k * s->hair_length / (double)(s->points - 1) / sqrt(r * r + c * c);
    for (int d = 0; d < 3; d++) p[d] = (R + r * (1.0 - cos(tau))) * n[d] + r * sin(tau) * b[d] + c * tau * t[d];
}

void hb_groom_state(const hb_scene *s, const hb_groom *g, void *out)
{
    const int64_t N = s->n_strands, P = s->points;
    for (int64_t i = 0; i < N; i++)
        for (int64_t k = 0; k < P; k++) {
            double p[3];
            if (s->groom == HB_GROOM_CURLY) curly_point(s, i, k, p);
            else memcpy(p, g->pos + 3 * (i * P + k), sizeof p);
            for (int d = 0; d < 3; d++) {
                const size_t j = 3 * (size_t)(i * P + k) + (size_t)d;
                if (s->precision == HB_FP32) ((float *)out)[j] = (float)p[d];
                else ((double *)out)[j] = p[d];
            }
        }
}

void hb_groom_free(hb_groom *g)
{
    free(g->pos);
    g->pos = NULL;
}
