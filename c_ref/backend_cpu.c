/* backend_cpu.c — the C reference backend: the canonical strand-major state in host
 * memory, OpenMP over strands (DESIGN §5). Strands are independent and each is computed by
 * one thread start to finish, so the bits do not depend on the thread count.
 *
 * Two variants:
 *  - `ref`: the oracle, model_impl.h one strand at a time on the canonical layout.
 *  - `simd`: model_simd.c on a point-major structure of arrays X, Y, Z [P][S], one strand
 *    per SIMD lane, OpenMP over fixed blocks of strands (docs/cpu_simd.md). The state is
 *    converted between the canonical layout and point-major in load and fetch, outside the
 *    timed stages, as a GPU backend copies host ↔ device. */
#include <math.h>
#include <omp.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/mman.h>
#include <time.h>

#include "backend.h"
#include "cli.h"
#include "model.h"
#include "model_simd.h"
#include "record.h"

typedef struct {
    hb_scene scene;
    hb_model_f32 m32;
    hb_model_f64 m64;
    void *state, *saved; /* ref: the canonical state [N·P][3] and its copy for repeats */
    uint64_t bytes;
    /* simd: X, Y, Z as [P][stride] each (point k of strand i at k·stride + i), the strands
     * in blocks of `block`, the last block padded; `pm_saved` for repeats */
    int simd;
    int64_t block, nblocks, stride;
    void *pm[3], *pm_saved[3];
    size_t pm_bytes; /* bytes of one of X, Y, Z (allocation size) */
} cpu_impl;

static double now_ms(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return 1e3 * (double)ts.tv_sec + 1e-6 * (double)ts.tv_nsec;
}

/* The scene's numbers rounded once to the working precision (docs/decisions.md). */
static void round_scene(cpu_impl *c, const hb_scene *s)
{
    c->m64 = (hb_model_f64){s->seed, s->points, s->head_radius, s->hair_offset, s->face_margin,
                            hb_segment_length(s), s->wind_strength, hb_wind_angle_reduced(s)};
    c->m32 = (hb_model_f32){s->seed, s->points, (float)c->m64.head_radius, (float)c->m64.hair_offset,
                            (float)c->m64.face_margin, (float)c->m64.seg_len, (float)c->m64.wind_strength,
                            (float)c->m64.wind_angle};
}

/* First touch: each thread zeroes the strands it will compute (static schedule). */
static void first_touch(void *p, const hb_scene *s)
{
    const int64_t N = s->n_strands;
    const size_t strand = (size_t)s->points * 3u * hb_real_size(s->precision);
#pragma omp parallel for schedule(static)
    for (int64_t i = 0; i < N; i++) memset((char *)p + (size_t)i * strand, 0, strand);
}

static int simd_setup(cpu_impl *c, const hb_options *o, int need_save, uint64_t driver_bytes, char *err,
                      size_t errlen);

static int cpu_setup(hb_backend *b, const hb_options *o, int need_save, uint64_t driver_bytes, char *err,
                     size_t errlen)
{
    cpu_impl *c = calloc(1, sizeof *c);
    if (!c) { snprintf(err, errlen, "out of host memory"); return HB_EXIT_MEMORY; }
    b->impl = c;
    c->scene = o->scene;
    c->bytes = hb_state_bytes(&o->scene);
    round_scene(c, &o->scene);
    if (o->threads > 0) omp_set_num_threads(o->threads);
    b->threads = omp_get_max_threads();
    if (o->variant && strcmp(o->variant, "simd") == 0)
        return simd_setup(c, o, need_save, driver_bytes, err, errlen);

    uint64_t need = c->bytes * (need_save ? 2u : 1u) + driver_bytes;
    uint64_t avail = hb_host_memory_available();
    if (avail && need > avail) {
        snprintf(err, errlen, "the state needs %.2f GB of host memory (%lld strands x %lld points, %s) but only %.2f GB "
                 "is available", 1e-9 * (double)need, (long long)o->scene.n_strands, (long long)o->scene.points,
                 hb_precision_name(o->scene.precision), 1e-9 * (double)avail);
        return HB_EXIT_MEMORY;
    }
    c->state = malloc(c->bytes);
    if (need_save) c->saved = malloc(c->bytes);
    if (!c->state || (need_save && !c->saved)) {
        snprintf(err, errlen, "cannot allocate %.2f GB of host memory for the state", 1e-9 * (double)need);
        return HB_EXIT_MEMORY;
    }
    first_touch(c->state, &o->scene);
    if (c->saved) first_touch(c->saved, &o->scene);
    return HB_EXIT_OK;
}

/* ---- the simd variant: point-major state ------------------------------------------- */

/* model_simd.c is compiled for x86-64-v3 (AVX2, FMA, BMI1/2, …): refuse the variant on a
 * CPU without it, before any of its code runs. HAIRBENCH_SIMD_PRETEND_NO_AVX2=1 takes this
 * path on any CPU, so the tests can check the refusal. */
static int simd_cpu_ok(void)
{
    const char *pretend = getenv("HAIRBENCH_SIMD_PRETEND_NO_AVX2");
    if (pretend && strcmp(pretend, "1") == 0) return 0;
    __builtin_cpu_init();
    return __builtin_cpu_supports("x86-64-v3") && __builtin_cpu_supports("avx2") && __builtin_cpu_supports("fma");
}

/* An array for the point-major state: 2 MiB aligned and advised as huge pages where it is
 * that large (each block touches P rows, i.e. P pages, per stage), not yet touched. */
static void *pm_alloc(size_t bytes)
{
    const size_t huge = (size_t)2 << 20;
    size_t align = bytes >= huge ? huge : 64;
    size_t size = (bytes + align - 1) / align * align;
    void *p = aligned_alloc(align, size);
#ifdef MADV_HUGEPAGE
    if (p && align == huge) (void)madvise(p, size, MADV_HUGEPAGE);
#endif
    return p;
}

/* First touch: each thread zeroes the rows of the blocks it will compute (the same static
 * schedule over blocks as the stages). */
static void pm_first_touch(cpu_impl *c, void *const a[3])
{
    const size_t rs = hb_real_size(c->scene.precision), chunk = (size_t)c->block * rs;
    const int64_t P = c->scene.points;
#pragma omp parallel for schedule(static)
    for (int64_t blk = 0; blk < c->nblocks; blk++)
        for (int64_t k = 0; k < P; k++)
            for (int d = 0; d < 3; d++) {
                size_t off = ((size_t)k * (size_t)c->stride + (size_t)blk * (size_t)c->block) * rs;
                memset((char *)a[d] + off, 0, chunk);
            }
}

static void pm_copy(cpu_impl *c, void *const dst[3], void *const src[3])
{
    const size_t rs = hb_real_size(c->scene.precision), chunk = (size_t)c->block * rs;
    const int64_t P = c->scene.points;
#pragma omp parallel for schedule(static)
    for (int64_t blk = 0; blk < c->nblocks; blk++)
        for (int64_t k = 0; k < P; k++)
            for (int d = 0; d < 3; d++) {
                size_t off = ((size_t)k * (size_t)c->stride + (size_t)blk * (size_t)c->block) * rs;
                memcpy((char *)dst[d] + off, (const char *)src[d] + off, chunk);
            }
}

static int simd_setup(cpu_impl *c, const hb_options *o, int need_save, uint64_t driver_bytes, char *err,
                      size_t errlen)
{
    const hb_scene *s = &o->scene;
    if (!simd_cpu_ok()) {
        snprintf(err, errlen, "--variant simd needs an x86-64-v3 CPU (AVX2 + FMA) and this CPU lacks it; "
                 "use --variant ref");
        return HB_EXIT_USAGE;
    }
    if (s->points > INT32_MAX) {
        snprintf(err, errlen, "--variant simd takes at most %d points per strand (got %lld)", INT32_MAX,
                 (long long)s->points);
        return HB_EXIT_USAGE;
    }
    c->simd = 1;
    c->block = s->precision == HB_FP64 ? HB_SIMD_BLOCK_F64 : HB_SIMD_BLOCK_F32;
    c->nblocks = (s->n_strands + c->block - 1) / c->block;
    c->stride = c->nblocks * c->block;
    const uint64_t rs = hb_real_size(s->precision);
    /* 3 arrays of P × stride reals; no overflow: stride < N + block and the canonical
     * state of N strands fits in uint64 (hb_state_bytes) */
    const uint64_t one = (uint64_t)s->points * (uint64_t)c->stride * rs;
    uint64_t need = 3u * one * (need_save ? 2u : 1u) + driver_bytes;
    uint64_t avail = hb_host_memory_available();
    if ((avail && need > avail) || one > SIZE_MAX / 4) {
        snprintf(err, errlen, "the state needs %.2f GB of host memory (%lld strands x %lld points, %s, simd) but "
                 "only %.2f GB is available", 1e-9 * (double)need, (long long)s->n_strands, (long long)s->points,
                 hb_precision_name(s->precision), 1e-9 * (double)avail);
        return HB_EXIT_MEMORY;
    }
    c->pm_bytes = (size_t)one;
    for (int d = 0; d < 3; d++) {
        c->pm[d] = pm_alloc(c->pm_bytes);
        if (need_save) c->pm_saved[d] = pm_alloc(c->pm_bytes);
        if (!c->pm[d] || (need_save && !c->pm_saved[d])) {
            snprintf(err, errlen, "cannot allocate %.2f GB of host memory for the state", 1e-9 * (double)need);
            return HB_EXIT_MEMORY;
        }
    }
    pm_first_touch(c, c->pm);
    if (need_save) pm_first_touch(c, c->pm_saved);
    return HB_EXIT_OK;
}

/* canonical [N][P][3] → X, Y, Z [P][stride], parallel over blocks; padding lanes keep what
 * they hold (they are computed, never read back) */
#define PM_CONVERT(T, TO_PM)                                                                   \
    do {                                                                                       \
        T *X = c->pm[0], *Y = c->pm[1], *Z = c->pm[2];                                         \
        T *cs = (T *)canonical;                                                                \
        _Pragma("omp parallel for schedule(static)")                                           \
        for (int64_t blk = 0; blk < c->nblocks; blk++) {                                       \
            const int64_t i1 = (blk + 1) * c->block < N ? (blk + 1) * c->block : N;            \
            for (int64_t i = blk * c->block; i < i1; i++) {                                    \
                T *q = cs + (size_t)i * (size_t)P * 3u;                                        \
                for (int64_t k = 0; k < P; k++) {                                              \
                    const size_t e = (size_t)k * (size_t)S + (size_t)i;                       \
                    if (TO_PM) {                                                               \
                        X[e] = q[3 * k + 0];                                                   \
                        Y[e] = q[3 * k + 1];                                                   \
                        Z[e] = q[3 * k + 2];                                                   \
                    } else {                                                                   \
                        q[3 * k + 0] = X[e];                                                   \
                        q[3 * k + 1] = Y[e];                                                   \
                        q[3 * k + 2] = Z[e];                                                   \
                    }                                                                          \
                }                                                                              \
            }                                                                                  \
        }                                                                                      \
    } while (0)

static void simd_convert(cpu_impl *c, void *canonical, int to_pm)
{
    const int64_t N = c->scene.n_strands, P = c->scene.points, S = c->stride;
    if (c->scene.precision == HB_FP32) {
        if (to_pm) PM_CONVERT(float, 1);
        else PM_CONVERT(float, 0);
    } else {
        if (to_pm) PM_CONVERT(double, 1);
        else PM_CONVERT(double, 0);
    }
}
#undef PM_CONVERT

/* One stage over all blocks of strands; the split into blocks does not depend on the
 * thread count, and every strand is one lane of one block from start to finish. */
static int64_t simd_run_stage(cpu_impl *c, hb_stage st)
{
    const int64_t N = c->scene.n_strands, B = c->block, NB = c->nblocks, S = c->stride;
    int64_t moved = 0;
    if (c->scene.precision == HB_FP32) {
        float *X = c->pm[0], *Y = c->pm[1], *Z = c->pm[2];
        const hb_model_f32 *m = &c->m32;
        if (st == HB_STAGE_INIT) {
#pragma omp parallel for schedule(static)
            for (int64_t b = 0; b < NB; b++)
                hb_simd_init_block_f32(m, (uint64_t)(b * B), X + b * B, Y + b * B, Z + b * B, S);
        } else if (st == HB_STAGE_WIND) {
#pragma omp parallel for schedule(static)
            for (int64_t b = 0; b < NB; b++) hb_simd_wind_block_f32(m, Y + b * B, Z + b * B, S);
        } else {
#pragma omp parallel for schedule(static) reduction(+ : moved)
            for (int64_t b = 0; b < NB; b++) {
                const int real = (int)(N - b * B < B ? N - b * B : B); /* strands of the block */
                moved += hb_simd_collide_block_f32(m, real, Y + b * B, Z + b * B, S);
            }
        }
    } else {
        double *X = c->pm[0], *Y = c->pm[1], *Z = c->pm[2];
        const hb_model_f64 *m = &c->m64;
        if (st == HB_STAGE_INIT) {
#pragma omp parallel for schedule(static)
            for (int64_t b = 0; b < NB; b++)
                hb_simd_init_block_f64(m, (uint64_t)(b * B), X + b * B, Y + b * B, Z + b * B, S);
        } else if (st == HB_STAGE_WIND) {
#pragma omp parallel for schedule(static)
            for (int64_t b = 0; b < NB; b++) hb_simd_wind_block_f64(m, Y + b * B, Z + b * B, S);
        } else {
#pragma omp parallel for schedule(static) reduction(+ : moved)
            for (int64_t b = 0; b < NB; b++) {
                const int real = (int)(N - b * B < B ? N - b * B : B); /* strands of the block */
                moved += hb_simd_collide_block_f64(m, real, Y + b * B, Z + b * B, S);
            }
        }
    }
    return moved;
}

/* ---- the backend interface ----------------------------------------------------------- */

static int cpu_load(hb_backend *b, const void *canonical, double *ms, char *err, size_t errlen)
{
    (void)err; (void)errlen;
    cpu_impl *c = b->impl;
    double t0 = now_ms();
    if (c->simd) {
        simd_convert(c, (void *)canonical, 1);
        *ms = now_ms() - t0;
        return 0;
    }
    memcpy(c->state, canonical, c->bytes);
    *ms = now_ms() - t0;
    return 0;
}

static int cpu_fetch(hb_backend *b, void *canonical, double *ms, char *err, size_t errlen)
{
    (void)err; (void)errlen;
    cpu_impl *c = b->impl;
    double t0 = now_ms();
    if (c->simd) {
        simd_convert(c, canonical, 0);
        *ms = now_ms() - t0;
        return 0;
    }
    memcpy(canonical, c->state, c->bytes);
    *ms = now_ms() - t0;
    return 0;
}

static int cpu_save(hb_backend *b, char *err, size_t errlen)
{
    (void)err; (void)errlen;
    cpu_impl *c = b->impl;
    if (c->simd) pm_copy(c, c->pm_saved, c->pm);
    else memcpy(c->saved, c->state, c->bytes);
    return 0;
}

static int cpu_restore(hb_backend *b, char *err, size_t errlen)
{
    (void)err; (void)errlen;
    cpu_impl *c = b->impl;
    if (c->simd) pm_copy(c, c->pm, c->pm_saved);
    else memcpy(c->state, c->saved, c->bytes);
    return 0;
}

/* One stage over all strands. Strand i lives at state + 3·P·i (canonical layout). */
static int cpu_run_stage(hb_backend *b, const hb_stage *stages, int i, int n, hb_stage_result *r, char *err,
                         size_t errlen)
{
    (void)n; (void)err; (void)errlen;
    cpu_impl *c = b->impl;
    const int64_t N = c->scene.n_strands;
    const size_t stride = (size_t)c->scene.points * 3u;
    const hb_stage st = stages[i];
    int64_t moved = 0;
    double t0 = now_ms();
    if (c->simd) {
        moved = simd_run_stage(c, st);
    } else if (c->scene.precision == HB_FP32) {
        float *s = c->state;
        const hb_model_f32 *m = &c->m32;
        if (st == HB_STAGE_INIT) {
#pragma omp parallel for schedule(static)
            for (int64_t k = 0; k < N; k++) hb_init_strand_f32(m, (uint64_t)k, s + (size_t)k * stride);
        } else if (st == HB_STAGE_WIND) {
#pragma omp parallel for schedule(static)
            for (int64_t k = 0; k < N; k++) hb_wind_strand_f32(m, s + (size_t)k * stride);
        } else {
#pragma omp parallel for schedule(static) reduction(+ : moved)
            for (int64_t k = 0; k < N; k++) moved += hb_collide_strand_f32(m, s + (size_t)k * stride);
        }
    } else {
        double *s = c->state;
        const hb_model_f64 *m = &c->m64;
        if (st == HB_STAGE_INIT) {
#pragma omp parallel for schedule(static)
            for (int64_t k = 0; k < N; k++) hb_init_strand_f64(m, (uint64_t)k, s + (size_t)k * stride);
        } else if (st == HB_STAGE_WIND) {
#pragma omp parallel for schedule(static)
            for (int64_t k = 0; k < N; k++) hb_wind_strand_f64(m, s + (size_t)k * stride);
        } else {
#pragma omp parallel for schedule(static) reduction(+ : moved)
            for (int64_t k = 0; k < N; k++) moved += hb_collide_strand_f64(m, s + (size_t)k * stride);
        }
    }
    r->ms = now_ms() - t0;
    r->moved_points = st == HB_STAGE_COLLIDE ? moved : -1;
    r->consumed = 1;
    return 0;
}

/* STREAM-style kernels over all cores (after McCalpin's STREAM definitions, written here):
 * copy c = a, counted as 16 bytes per element (read + write), and triad a = b + q·c,
 * counted as 24 bytes per element (two reads + one write; as in STREAM, the write-allocate
 * read is not counted). Arrays of 2^26 doubles (512 MiB each: far beyond any cache), the
 * best of 6 timed runs after one warm-up run, static schedule, first touch by the threads
 * that use the data. */
static int cpu_stream(const hb_options *o, double *copy_gbps, double *copy_bytes, double *triad_gbps,
                      double *triad_bytes, char *err, size_t errlen)
{
    if (o->threads > 0) omp_set_num_threads(o->threads);
    const size_t n = (size_t)1 << 26;
    double *a = malloc(n * sizeof *a), *c = malloc(n * sizeof *c);
    double *bb = triad_gbps ? malloc(n * sizeof *bb) : NULL;
    if (!a || !c || (triad_gbps && !bb)) {
        free(a);
        free(c);
        free(bb);
        snprintf(err, errlen, "cannot allocate %d MiB for the bandwidth measurement", triad_gbps ? 1536 : 1024);
        return -1;
    }
#pragma omp parallel for schedule(static)
    for (size_t i = 0; i < n; i++) {
        a[i] = (double)i;
        c[i] = 0.0;
        if (bb) bb[i] = 1.0;
    }
    double best = 1e30;
    for (int rep = 0; rep < 7; rep++) {
        double t0 = now_ms();
#pragma omp parallel for schedule(static)
        for (size_t i = 0; i < n; i++) c[i] = a[i];
        double t = now_ms() - t0;
        if (rep > 0 && t < best) best = t; /* the first run warms up */
    }
    *copy_bytes = 2.0 * (double)n * sizeof(double);
    *copy_gbps = *copy_bytes / (best * 1e-3) * 1e-9;
    double sum = c[n / 2];
    if (triad_gbps) {
        const double q = 3.0;
        best = 1e30;
        for (int rep = 0; rep < 7; rep++) {
            double t0 = now_ms();
#pragma omp parallel for schedule(static)
            for (size_t i = 0; i < n; i++) a[i] = bb[i] + q * c[i];
            double t = now_ms() - t0;
            if (rep > 0 && t < best) best = t;
        }
        *triad_bytes = 3.0 * (double)n * sizeof(double);
        *triad_gbps = *triad_bytes / (best * 1e-3) * 1e-9;
        sum += a[n / 3];
    }
    volatile double sink = sum;
    (void)sink;
    free(a);
    free(c);
    free(bb);
    return 0;
}

/* The driver's --measure-bandwidth: the copy, then the triad (each its own allocation). */
static int cpu_measure_bandwidth(hb_backend *b, const hb_options *o, double *gbps, double *bytes, char *err,
                                 size_t errlen)
{
    int rc = cpu_stream(o, gbps, bytes, NULL, NULL, err, errlen);
    b->threads = omp_get_max_threads();
    return rc;
}

static int cpu_measure_triad(hb_backend *b, const hb_options *o, double *gbps, double *bytes, char *err,
                             size_t errlen)
{
    double copy, copy_bytes;
    (void)b;
    return cpu_stream(o, &copy, &copy_bytes, gbps, bytes, err, errlen);
}

static void cpu_describe(hb_backend *b, char *device, size_t dlen, char *driver, size_t vlen)
{
    (void)b;
    char model[200];
    hb_cpu_model(model, sizeof model);
    snprintf(device, dlen, "%s (%d cores)", model, omp_get_num_procs());
    if (vlen) driver[0] = '\0';
}

static void cpu_teardown(hb_backend *b)
{
    cpu_impl *c = b->impl;
    if (!c) return;
    free(c->state);
    free(c->saved);
    for (int d = 0; d < 3; d++) {
        free(c->pm[d]);
        free(c->pm_saved[d]);
    }
    free(c);
    b->impl = NULL;
}

#define CPU_PAPER_STAGES ((1u << HB_STAGE_INIT) | (1u << HB_STAGE_COLLIDE) | (1u << HB_STAGE_WIND))
static const hb_variant cpu_variants[] = {
    {"ref", CPU_PAPER_STAGES, "the oracle: model_impl.h one strand at a time, OpenMP over strands"},
    {"simd", CPU_PAPER_STAGES, "point-major structure of arrays, one strand per SIMD lane, OpenMP over blocks"},
    {NULL, 0, NULL},
};

#ifndef HB_FLAGS
#define HB_FLAGS "unknown"
#endif

int main(int argc, char **argv)
{
    hb_backend b = {0};
    b.name = "cpu";
    b.default_variant = "ref";
    b.variants = cpu_variants;
    b.build = "default";
    b.flags = HB_FLAGS;
    b.setup = cpu_setup;
    b.load = cpu_load;
    b.run_stage = cpu_run_stage;
    b.save = cpu_save;
    b.restore = cpu_restore;
    b.fetch = cpu_fetch;
    b.measure_bandwidth = cpu_measure_bandwidth;
    b.describe = cpu_describe;
    b.teardown = cpu_teardown;
    b.measure_triad = cpu_measure_triad;
    return hb_main(argc, argv, &b);
}
