/* backend_cpu.c — the C reference backend: the canonical strand-major state in host
 * memory, OpenMP over strands (DESIGN §5). Strands are independent and each is computed by
 * one thread start to finish, so the bits do not depend on the thread count. */
#include <math.h>
#include <omp.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "backend.h"
#include "model.h"
#include "record.h"

typedef struct {
    hb_scene scene;
    hb_model_f32 m32;
    hb_model_f64 m64;
    void *state, *saved;
    uint64_t bytes;
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

static int cpu_load(hb_backend *b, const void *canonical, double *ms, char *err, size_t errlen)
{
    (void)err; (void)errlen;
    cpu_impl *c = b->impl;
    double t0 = now_ms();
    memcpy(c->state, canonical, c->bytes);
    *ms = now_ms() - t0;
    return 0;
}

static int cpu_fetch(hb_backend *b, void *canonical, double *ms, char *err, size_t errlen)
{
    (void)err; (void)errlen;
    cpu_impl *c = b->impl;
    double t0 = now_ms();
    memcpy(canonical, c->state, c->bytes);
    *ms = now_ms() - t0;
    return 0;
}

static int cpu_save(hb_backend *b, char *err, size_t errlen)
{
    (void)err; (void)errlen;
    cpu_impl *c = b->impl;
    memcpy(c->saved, c->state, c->bytes);
    return 0;
}

static int cpu_restore(hb_backend *b, char *err, size_t errlen)
{
    (void)err; (void)errlen;
    cpu_impl *c = b->impl;
    memcpy(c->state, c->saved, c->bytes);
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
    if (c->scene.precision == HB_FP32) {
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

/* A STREAM-style copy over all cores: bytes read + bytes written per second. */
static int cpu_measure_bandwidth(hb_backend *b, const hb_options *o, double *gbps, double *bytes, char *err,
                                 size_t errlen)
{
    (void)b;
    if (o->threads > 0) omp_set_num_threads(o->threads);
    const size_t n = (size_t)1 << 26; /* 2 × 512 MiB of doubles: far beyond any cache */
    double *a = malloc(n * sizeof *a), *c = malloc(n * sizeof *c);
    if (!a || !c) {
        free(a);
        free(c);
        snprintf(err, errlen, "cannot allocate 1 GiB for the bandwidth measurement");
        return -1;
    }
#pragma omp parallel for schedule(static)
    for (size_t i = 0; i < n; i++) {
        a[i] = (double)i;
        c[i] = 0.0;
    }
    double best = 1e30;
    for (int rep = 0; rep < 7; rep++) {
        double t0 = now_ms();
#pragma omp parallel for schedule(static)
        for (size_t i = 0; i < n; i++) c[i] = a[i];
        double t = now_ms() - t0;
        if (rep > 0 && t < best) best = t; /* the first run warms up */
    }
    volatile double sink = c[n / 2];
    (void)sink;
    free(a);
    free(c);
    *bytes = 2.0 * (double)n * sizeof(double);
    *gbps = *bytes / (best * 1e-3) * 1e-9;
    return 0;
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
    free(c);
    b->impl = NULL;
}

static const char *const cpu_variants[] = {"ref", NULL};

#ifndef HB_FLAGS
#define HB_FLAGS "unknown"
#endif

int main(int argc, char **argv)
{
    hb_backend b = {0};
    b.name = "cpu";
    b.default_variant = "ref";
    b.variants = cpu_variants;
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
    return hb_main(argc, argv, &b);
}
