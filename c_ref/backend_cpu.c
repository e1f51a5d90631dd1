/* backend_cpu.c — the C reference backend: the canonical strand-major state in host
 * memory, OpenMP over strands (docs/model.md §5.1). Strands are independent and each is computed by
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

#include "app/backend.h"
#include "runtime/checked.h"
#include "runtime/cli.h"
#include "dynamic/dyn_followers.h"
#include "dynamic/dyn_sagfree.h"
#include "dynamic/dynamics.h"
#include "dynamic/world_host.h"
#include "simd/dynamics_simd.h"
#include "runtime/host.h"
#include "dynamic/dyn_lod.h"
#include "paper/model.h"
#include "simd/model_simd.h"
#include "app/record.h"

typedef struct {
    hb_scene scene;
    hb_model_f32 m32;
    hb_model_f64 m64;
    void *state, *saved; /* ref: the canonical state [N·P][3] and its copy for repeats */
    uint64_t bytes;
    /* simd: X, Y, Z as [P][stride] each (point k of strand i at k·stride + i), the strands
     * in blocks of `block`, the last block padded; `pm_saved` for repeats */
    int simd;
    const hb_simd_model_fns *sm; /* the build of model_simd.c and dynamics_simd.c picked at setup */
    const hb_simd_dyn_fns *sd;
    int64_t block, nblocks, stride;
    void *pm[3], *pm_saved[3];
    /* simd: a wind followed by collide runs as one pass (consumed 2); with `keep` (a file
     * is written) the wind frame's Y, Z go to pm_wind, allocated on first use */
    int keep;
    void *pm_wind[2];
    size_t pm_bytes; /* bytes of one of X, Y, Z (allocation size) */
    /* simulate (ref): velocities [N·P][3], rest shape [N·P][3], bend rest lengths [N][P−2],
     * a copy of the velocities for repeats; the run's constants */
    int dynamic;
    void *vel, *vel_saved, *rest, *bend_rest;
    void *seg_rest; /* a groom's ℓ_k [N][P−1] (docs/model.md §3.15), and in double for the observables */
    double *seg64;
    void *contacts; /* --contact-planes: each point's planes [N·P][HB_CONTACT_POINT] (docs/model.md §3.17) */
    hb_dyn_model_f32 d32;
    hb_dyn_model_f64 d64;
    /* simulate (simd): velocities, saved velocities, rest shape as [P][stride], bend rest [P−2][stride] */
    void *pv[3], *pv_saved[3], *pr[3], *pb;
    void *ps;              /* a groom's ℓ_k as rows [P−1][stride] (seg_rest and seg64 canonical beside it) */
    hb_followers fl;       /* ref with --guides (docs/model.md §3.14) */
    void *shape_rest;      /* ref with --sag-free: the rest shape the frame reads (root, shape targets) */
    hb_host_world world;   /* ref: the grid and colliders (docs/model.md §3.16, §3.17) */
    const void *last_pose; /* the last frame's colliders at its end, for the observables */
} cpu_impl;


/* First touch: each thread zeroes the strands it will compute (static schedule). */
static void first_touch(void *p, const hb_scene *s)
{
    const int64_t N = s->n_strands;
    const size_t strand = (size_t)s->points * 3u * hb_real_size(s->precision);
#pragma omp parallel for schedule(static)
    for (int64_t i = 0; i < N; i++) memset((char *)p + (size_t)i * strand, 0, strand);
}

static int simd_setup(cpu_impl *c, const hb_options *o, int need_save, uint64_t driver_bytes, char *err, size_t errlen);

/* The threads of a run without --threads: OpenMP's default, read before any run set another
 * (a --batch runs several in one process). */
static int default_threads(void)
{
    static int n = 0;
    if (n == 0) n = omp_get_max_threads();
    return n;
}

static int cpu_setup(hb_backend *b, const hb_options *o, int need_save, uint64_t driver_bytes, char *err, size_t errlen)
{
    cpu_impl *c = calloc(1, sizeof *c);
    if (!c) {
        snprintf(err, errlen, "out of host memory");
        return HB_EXIT_MEMORY;
    }
    b->impl = c;
    c->scene = o->scene;
    c->bytes = hb_state_bytes(&o->scene);
    hb_model_round(&o->scene, &c->m32, &c->m64);
    const int all_cores = default_threads(); /* read before this run sets its own */
    omp_set_num_threads(o->threads > 0 ? o->threads : all_cores);
    b->threads = omp_get_max_threads();
    if (o->variant && strcmp(o->variant, "simd") == 0) {
        const int status = simd_setup(c, o, need_save, driver_bytes, err, errlen);
        if (c->sm == &hb_simd_model_v4) b->flags = HB_FLAGS_SIMD_V4; /* the record names the build that runs */
        return status;
    }

    for (int i = 0; i < o->n_stages; i++) c->dynamic |= o->stages[i] == HB_STAGE_SIMULATE;
    /* simulate adds velocities, the rest shape, bend rest lengths and a saved velocity copy */
    uint64_t bend_bytes; /* saturated sizes: the memory check below refuses them */
    hb_mul3_u64((uint64_t)o->scene.n_strands, (uint64_t)(o->scene.points - 2 > 0 ? o->scene.points - 2 : 1),
                hb_real_size(o->scene.precision), &bend_bytes);
    const unsigned copies = (need_save ? 3u : 2u) + (o->scene.dyn.sag_free ? 1u : 0u);
    uint64_t seg_bytes = 0; /* a groom's ℓ_k in the working precision and in double */
    if (o->scene.dyn.per_segment)
        hb_mul3_u64((uint64_t)o->scene.n_strands, (uint64_t)(o->scene.points - 1),
                    hb_real_size(o->scene.precision) + sizeof(double), &seg_bytes);
    if (o->scene.dyn.planes_declared) /* §3.17 the points' contact planes */
        seg_bytes = hb_add_sat(seg_bytes, hb_mul_sat(c->bytes / 3u, HB_CONTACT_POINT));
    const uint64_t dyn = c->dynamic
                             ? hb_add_sat(hb_add_sat(hb_add_sat(hb_mul_sat(c->bytes, copies), bend_bytes), seg_bytes),
                                          hb_host_world_bytes(&o->scene, omp_get_max_threads()))
                             : 0;
    const uint64_t need = hb_add_sat(hb_add_sat(hb_mul_sat(c->bytes, need_save ? 2u : 1u), dyn), driver_bytes);
    if (need == UINT64_MAX) {
        snprintf(err, errlen, "--strands x --points: the run's memory does not fit in 64 bits");
        return HB_EXIT_USAGE;
    }
    uint64_t avail = hb_host_memory_available();
    if (avail && need > avail) {
        hb_memory_message(err, errlen, &o->scene, "host", need, avail, c->dynamic ? ", simulate" : "", NULL);
        return HB_EXIT_MEMORY;
    }
    c->state = malloc(c->bytes);
    if (need_save) c->saved = malloc(c->bytes);
    int bad = !c->state || (need_save && !c->saved);
    if (c->dynamic) {
        c->vel = malloc(c->bytes);
        c->rest = malloc(c->bytes);
        c->bend_rest = malloc(bend_bytes);
        if (need_save) c->vel_saved = malloc(c->bytes);
        if (o->scene.dyn.sag_free) bad |= !(c->shape_rest = malloc(c->bytes));
        if (o->scene.dyn.planes_declared) bad |= !(c->contacts = malloc(c->bytes / 3u * HB_CONTACT_POINT));
        bad |= !c->vel || !c->rest || !c->bend_rest || (need_save && !c->vel_saved);
        if (o->scene.dyn.per_segment) {
            const size_t nseg = (size_t)o->scene.n_strands * (size_t)(o->scene.points - 1);
            c->seg_rest = malloc(nseg * hb_real_size(o->scene.precision));
            c->seg64 = malloc(nseg * sizeof *c->seg64);
            bad |= !c->seg_rest || !c->seg64;
        }
        hb_dyn_round(&o->scene, &c->d32, &c->d64);
    }
    if (bad) {
        snprintf(err, errlen, "cannot allocate %.2f GB of host memory for the state", 1e-9 * (double)need);
        return HB_EXIT_MEMORY;
    }
    first_touch(c->state, &o->scene);
    if (c->saved) first_touch(c->saved, &o->scene);
    if (c->dynamic) {
        first_touch(c->vel, &o->scene);
        first_touch(c->rest, &o->scene);
        if (c->vel_saved) first_touch(c->vel_saved, &o->scene);
    }
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

/* Which build of the simd files runs (docs/cpu_simd.md, "Two builds"): the x86-64-v4 one
 * where the CPU has it (AVX-512 F, VL, BW, DQ, CD), else the x86-64-v3 one.
 * HAIRBENCH_SIMD_ISA=avx2 or =avx512 asks for one (avx512 is refused on a CPU without it);
 * any other value is refused. Returns 0, or an exit status with err set. */
static int simd_pick_isa(cpu_impl *c, char *err, size_t errlen)
{
    const char *want = getenv("HAIRBENCH_SIMD_ISA");
    const int v4 = __builtin_cpu_supports("x86-64-v4") && __builtin_cpu_supports("avx512f") &&
                   __builtin_cpu_supports("avx512vl") && __builtin_cpu_supports("avx512bw") &&
                   __builtin_cpu_supports("avx512dq");
    int use_v4 = v4;
    if (want && *want) {
        if (strcmp(want, "avx2") == 0) use_v4 = 0;
        else if (strcmp(want, "avx512") == 0) {
            if (!v4) {
                snprintf(err, errlen,
                         "HAIRBENCH_SIMD_ISA=avx512 needs an x86-64-v4 CPU (AVX-512) and this CPU lacks it");
                return HB_EXIT_USAGE;
            }
            use_v4 = 1;
        } else {
            snprintf(err, errlen, "HAIRBENCH_SIMD_ISA must be avx2 or avx512 (got '%s')", want);
            return HB_EXIT_USAGE;
        }
    }
    c->sm = use_v4 ? &hb_simd_model_v4 : &hb_simd_model_v3;
    c->sd = use_v4 ? &hb_simd_dyn_v4 : &hb_simd_dyn_v3;
    return HB_EXIT_OK;
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

/* dst = src, or zeros without src, block by block: each thread writes the rows of the blocks
 * it will compute (the same static schedule over blocks as the stages: the first touch). */
static void pm_fill(cpu_impl *c, void *const dst[3], void *const src[3])
{
    const size_t rs = hb_real_size(c->scene.precision), chunk = (size_t)c->block * rs;
    const int64_t P = c->scene.points;
#pragma omp parallel for schedule(static)
    for (int64_t blk = 0; blk < c->nblocks; blk++)
        for (int64_t k = 0; k < P; k++)
            for (int d = 0; d < 3; d++) {
                size_t off = ((size_t)k * (size_t)c->stride + (size_t)blk * (size_t)c->block) * rs;
                if (src) memcpy((char *)dst[d] + off, (const char *)src[d] + off, chunk);
                else memset((char *)dst[d] + off, 0, chunk);
            }
}

static void pm_first_touch(cpu_impl *c, void *const a[3])
{
    pm_fill(c, a, NULL);
}

static void pm_copy(cpu_impl *c, void *const dst[3], void *const src[3])
{
    pm_fill(c, dst, src);
}

static uint64_t simd_dyn_bytes(const cpu_impl *c, uint64_t one, int need_save);
static int simd_dyn_setup(cpu_impl *c, int need_save, uint64_t need, char *err, size_t errlen);

static int simd_setup(cpu_impl *c, const hb_options *o, int need_save, uint64_t driver_bytes, char *err, size_t errlen)
{
    const hb_scene *s = &o->scene;
    if (!simd_cpu_ok()) {
        snprintf(err, errlen,
                 "--variant simd needs an x86-64-v3 CPU (AVX2 + FMA) and this CPU lacks it; "
                 "use --variant ref");
        return HB_EXIT_USAGE;
    }
    const int isa_status = simd_pick_isa(c, err, errlen);
    if (isa_status != HB_EXIT_OK) return isa_status;
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
    /* 3 arrays of P × stride reals (saturated: the memory check below refuses it) */
    uint64_t one;
    hb_mul3_u64((uint64_t)s->points, (uint64_t)c->stride, rs, &one);
    for (int i = 0; i < o->n_stages; i++) c->dynamic |= o->stages[i] == HB_STAGE_SIMULATE;
    const uint64_t dyn = c->dynamic ? simd_dyn_bytes(c, one, need_save) : 0;
    const uint64_t need =
        hb_add_sat(hb_add_sat(hb_mul_sat(hb_mul_sat(one, 3u), need_save ? 2u : 1u), dyn), driver_bytes);
    uint64_t avail = hb_host_memory_available();
    if ((avail && need > avail) || one > SIZE_MAX / 4) {
        hb_memory_message(err, errlen, s, "host", need, avail, c->dynamic ? ", simd, simulate" : ", simd", NULL);
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
    if (c->dynamic) return simd_dyn_setup(c, need_save, need, err, errlen);
    return HB_EXIT_OK;
}

/* canonical [N][P][3] ↔ a[0..2] as X, Y, Z [P][stride] (positions, velocities, rest shape),
 * parallel over blocks; padding lanes keep what they hold (computed, never read back) */
#define PM_CONVERT(T, TO_PM)                                                                                           \
    do {                                                                                                               \
        T *X = a[0], *Y = a[1], *Z = a[2];                                                                             \
        T *cs = (T *)canonical;                                                                                        \
        _Pragma("omp parallel for schedule(static)") for (int64_t blk = 0; blk < c->nblocks; blk++)                    \
        {                                                                                                              \
            const int64_t i1 = (blk + 1) * c->block < N ? (blk + 1) * c->block : N;                                    \
            for (int64_t i = blk * c->block; i < i1; i++) {                                                            \
                T *q = cs + (size_t)i * (size_t)P * 3u;                                                                \
                for (int64_t k = 0; k < P; k++) {                                                                      \
                    const size_t e = (size_t)k * (size_t)S + (size_t)i;                                                \
                    if (TO_PM) {                                                                                       \
                        X[e] = q[3 * k + 0];                                                                           \
                        Y[e] = q[3 * k + 1];                                                                           \
                        Z[e] = q[3 * k + 2];                                                                           \
                    } else {                                                                                           \
                        q[3 * k + 0] = X[e];                                                                           \
                        q[3 * k + 1] = Y[e];                                                                           \
                        q[3 * k + 2] = Z[e];                                                                           \
                    }                                                                                                  \
                }                                                                                                      \
            }                                                                                                          \
        }                                                                                                              \
    } while (0)

static void simd_convert(cpu_impl *c, void *const a[3], void *canonical, int to_pm)
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

#define SIMD_STAGE(T, SFX, M)                                                                                          \
    do {                                                                                                               \
        T *X = c->pm[0], *Y = c->pm[1], *Z = c->pm[2];                                                                 \
        if (st == HB_STAGE_INIT) {                                                                                     \
            _Pragma("omp parallel for schedule(static)") for (int64_t b = 0; b < NB; b++)                              \
                c->sm->init_##SFX(M, (uint64_t)(b * B), X + b * B, Y + b * B, Z + b * B, S);                           \
        } else if (st == HB_STAGE_WIND) {                                                                              \
            _Pragma("omp parallel for schedule(static)") for (int64_t b = 0; b < NB; b++)                              \
                c->sm->wind_##SFX(M, Y + b * B, Z + b * B, S);                                                         \
        } else {                                                                                                       \
            _Pragma("omp parallel for schedule(static) reduction(+ : moved)") for (int64_t b = 0; b < NB; b++)         \
            {                                                                                                          \
                const int real = (int)(N - b * B < B ? N - b * B : B); /* strands of the block */                      \
                moved += c->sm->collide_##SFX(M, real, Y + b * B, Z + b * B, S);                                       \
            }                                                                                                          \
        }                                                                                                              \
    } while (0)

/* One stage over all blocks of strands; the split into blocks does not depend on the
 * thread count, and every strand is one lane of one block from start to finish. */
static int64_t simd_run_stage(cpu_impl *c, hb_stage st)
{
    const int64_t N = c->scene.n_strands, B = c->block, NB = c->nblocks, S = c->stride;
    int64_t moved = 0;
    if (c->scene.precision == HB_FP32) SIMD_STAGE(float, f32, &c->m32);
    else SIMD_STAGE(double, f64, &c->m64);
    return moved;
}
#undef SIMD_STAGE

#define SIMD_WIND_COLLIDE(T, SFX, M)                                                                                   \
    do {                                                                                                               \
        T *Y = c->pm[1], *Z = c->pm[2], *WY = c->keep ? c->pm_wind[0] : NULL, *WZ = c->keep ? c->pm_wind[1] : NULL;    \
        _Pragma("omp parallel for schedule(static) reduction(+ : moved)") for (int64_t b = 0; b < NB; b++)             \
        {                                                                                                              \
            const int real = (int)(N - b * B < B ? N - b * B : B);                                                     \
            moved += c->sm->wind_collide_##SFX(M, real, Y + b * B, Z + b * B, WY ? WY + b * B : NULL,                  \
                                               WZ ? WZ + b * B : NULL, S);                                             \
        }                                                                                                              \
    } while (0)

/* wind then collide, one pass over the points (model_simd.h), the same bits as the two
 * stages; the wind frame is stored to pm_wind when the driver keeps it. Returns −1 when
 * pm_wind cannot be allocated. */
static int64_t simd_run_wind_collide(cpu_impl *c)
{
    const int64_t N = c->scene.n_strands, B = c->block, NB = c->nblocks, S = c->stride;
    if (c->keep && !c->pm_wind[0]) {
        for (int d = 0; d < 2; d++) c->pm_wind[d] = pm_alloc(c->pm_bytes);
        if (!c->pm_wind[0] || !c->pm_wind[1]) return -1;
    }
    int64_t moved = 0;
    if (c->scene.precision == HB_FP32) SIMD_WIND_COLLIDE(float, f32, &c->m32);
    else SIMD_WIND_COLLIDE(double, f64, &c->m64);
    return moved;
}
#undef SIMD_WIND_COLLIDE

/* ---- the simd variant: the dynamic model (docs/cpu_simd.md, "The dynamic model") ------ */

/* Bytes simulate adds: velocities (and their saved copy), the rest shape, bend rest lengths. */
static uint64_t simd_dyn_bytes(const cpu_impl *c, uint64_t one, int need_save)
{
    const int64_t rows = c->scene.points - 2 > 0 ? c->scene.points - 2 : 1;
    uint64_t bend;
    hb_mul3_u64((uint64_t)rows, (uint64_t)c->stride, hb_real_size(c->scene.precision), &bend);
    uint64_t seg = 0; /* a groom's ℓ_k: rows, canonical, canonical in double */
    if (c->scene.dyn.per_segment)
        hb_mul3_u64((uint64_t)c->stride, (uint64_t)(c->scene.points - 1), 2u * hb_real_size(c->scene.precision) + 8u,
                    &seg);
    if (c->scene.dyn.planes_declared) /* §3.17 the points' contact planes, [P][block][HB_CONTACT_POINT] a block */
        seg = hb_add_sat(seg, hb_mul_sat(one, HB_CONTACT_POINT));
    return hb_add_sat(hb_add_sat(hb_mul_sat(hb_mul_sat(one, 3u), need_save ? 3u : 2u), bend), seg);
}

static int simd_dyn_setup(cpu_impl *c, int need_save, uint64_t need, char *err, size_t errlen)
{
    const int64_t rows = c->scene.points - 2 > 0 ? c->scene.points - 2 : 1;
    int bad = 0;
    for (int d = 0; d < 3; d++) {
        c->pv[d] = pm_alloc(c->pm_bytes);
        c->pr[d] = pm_alloc(c->pm_bytes);
        if (need_save) c->pv_saved[d] = pm_alloc(c->pm_bytes);
        bad |= !c->pv[d] || !c->pr[d] || (need_save && !c->pv_saved[d]);
    }
    c->pb = pm_alloc((size_t)rows * (size_t)c->stride * hb_real_size(c->scene.precision));
    if (c->scene.dyn.planes_declared) bad |= !(c->contacts = malloc(c->pm_bytes * HB_CONTACT_POINT));
    if (c->scene.dyn.per_segment) {
        const size_t nseg = (size_t)c->scene.n_strands * (size_t)(c->scene.points - 1),
                     rs = hb_real_size(c->scene.precision);
        const size_t rows = (size_t)(c->scene.points - 1) * (size_t)c->stride * rs;
        c->seg_rest = malloc(nseg * rs);
        c->seg64 = malloc(nseg * sizeof *c->seg64);
        c->ps = pm_alloc(rows);
        bad |= !c->seg_rest || !c->seg64 || !c->ps;
        if (c->ps) memset(c->ps, 0, rows); /* padding lanes: 0 */
    }
    if (bad || !c->pb) {
        snprintf(err, errlen, "cannot allocate %.2f GB of host memory for the state", 1e-9 * (double)need);
        return HB_EXIT_MEMORY;
    }
    pm_first_touch(c, c->pv);
    pm_first_touch(c, c->pr);
    if (need_save) pm_first_touch(c, c->pv_saved);
    hb_dyn_round(&c->scene, &c->d32, &c->d64);
    return HB_EXIT_OK;
}

/* Velocities (zero without) and the rest shape to point-major, then the bend rest lengths:
 * outside the timed frames, as positions are in load. Padding lanes keep their zeros. */
static int simd_dyn_load(cpu_impl *c, const void *velocity, const void *rest)
{
    if (velocity) simd_convert(c, c->pv, (void *)velocity, 1);
    else pm_first_touch(c, c->pv);
    simd_convert(c, c->pr, (void *)rest, 1);
    const int64_t DB = HB_SIMD_DYN_BLOCK, nb = c->stride / HB_SIMD_DYN_BLOCK, S = c->stride;
    if (c->scene.precision == HB_FP32) {
        const float *RX = c->pr[0], *RY = c->pr[1], *RZ = c->pr[2];
        float *BR = c->pb;
#pragma omp parallel for schedule(static)
        for (int64_t b = 0; b < nb; b++)
            c->sd->bend_rest_f32(&c->d32, RX + b * DB, RY + b * DB, RZ + b * DB, BR + b * DB, S);
    } else {
        const double *RX = c->pr[0], *RY = c->pr[1], *RZ = c->pr[2];
        double *BR = c->pb;
#pragma omp parallel for schedule(static)
        for (int64_t b = 0; b < nb; b++)
            c->sd->bend_rest_f64(&c->d64, RX + b * DB, RY + b * DB, RZ + b * DB, BR + b * DB, S);
    }
    if (c->ps) { /* §3.15: a groom's ℓ_k, canonical then as rows */
        const int64_t N = c->scene.n_strands, P = c->scene.points;
        hb_dyn_seg_rest(&c->scene, rest, c->seg64, c->seg_rest);
        const size_t rs = hb_real_size(c->scene.precision);
        for (int64_t i = 0; i < N; i++)
            for (int64_t k = 1; k < P; k++)
                memcpy((char *)c->ps + ((size_t)(k - 1) * (size_t)S + (size_t)i) * rs,
                       (const char *)c->seg_rest + ((size_t)i * (size_t)(P - 1) + (size_t)(k - 1)) * rs, rs);
    }
    if (c->scene.dyn.sag_free) { /* §3.14: the frame's rest rows become the raised targets */
        void *targets = malloc(hb_state_bytes(&c->scene));
        if (!targets) return -1;
        hb_sagfree_targets(&c->scene, rest, targets);
        simd_convert(c, c->pr, targets, 1);
        free(targets);
    }
    return 0;
}

/* A dynamic frame's stage result (ref and simd), or the error when a thread's scratch
 * could not be allocated. */
static int dyn_frame_result(hb_stage_result *r, double t0, int failed, const char *scratch, int64_t P, char *err,
                            size_t errlen)
{
    r->ms = hb_now_ms() - t0;
    r->moved_points = -1;
    r->consumed = 1;
    if (failed) {
        snprintf(err, errlen, "out of host memory for the %s (%lld points)", scratch, (long long)P);
        return -1;
    }
    return 0;
}

/* Dynamic blocks over threads (static schedule: the bits do not depend on it); each
 * thread's block scratch (hb_simd_dyn_scratch_reals) is its own. */
#define SIMD_DYN_FRAME(T, SFX, M, W)                                                                                   \
    do {                                                                                                               \
        T *X = c->pm[0], *Y = c->pm[1], *Z = c->pm[2], *VX = c->pv[0], *VY = c->pv[1], *VZ = c->pv[2];                 \
        const T *RX = c->pr[0], *RY = c->pr[1], *RZ = c->pr[2], *BR = c->pb, *SR = c->ps;                              \
        _Pragma("omp parallel")                                                                                        \
        {                                                                                                              \
            T *scratch = aligned_alloc(64, ((size_t)c->sd->scratch_reals(P) * sizeof(T) + 63) / 64 * 64);              \
            if (!scratch) {                                                                                            \
                _Pragma("omp atomic write") failed = 1;                                                                \
            } else {                                                                                                   \
                _Pragma("omp for schedule(static)") for (int64_t b = 0; b < nb; b++)                                   \
                {                                                                                                      \
                    const int64_t o = b * DB;                                                                          \
                    T *con = c->contacts ? (T *)c->contacts + (size_t)o * (size_t)P * HB_CONTACT_POINT : NULL;         \
                    c->sd->frame_##SFX(M, f, W, j0, j1, X + o, Y + o, Z + o, VX + o, VY + o, VZ + o, RX + o, RY + o,   \
                                       RZ + o, BR + o, SR ? SR + o : NULL, S, scratch, con);                           \
                }                                                                                                      \
                free(scratch);                                                                                         \
            }                                                                                                          \
        }                                                                                                              \
    } while (0)

/* §3.16 (ref and simd): without the grid, or built once a frame, the frame's substeps at once;
 * built every substep, substep by substep over all strands */
static int64_t grid_step(const cpu_impl *c, const hb_dyn_frame *f)
{
    return c->scene.dyn.grid && c->scene.dyn.grid_rebuild == HB_GRID_SUBSTEP ? 1 : f->substeps;
}

/* §3.16 the rotation of the grid built before substep j0: Q at the frame's start, then at the
 * end of substep j0 − 1; NULL for a still head */
static const void *grid_rotation(const cpu_impl *c, const hb_dyn_frame *f, int64_t j0)
{
    const int fp32 = c->scene.precision == HB_FP32;
    if (c->scene.dyn.motion == HB_MOTION_STILL) return NULL;
    if (j0 == 0) return fp32 ? (const void *)f->qs32 : (const void *)f->qs64;
    return fp32 ? (const void *)(f->q32 + 9 * (j0 - 1)) : (const void *)(f->q64 + 9 * (j0 - 1));
}

/* §3.17 the frame's last poses, for the observables (NULL without colliders) */
static const void *frame_last_pose(const cpu_impl *c, const hb_dyn_frame *f)
{
    const size_t at = (size_t)(f->substeps - 1) * (size_t)(f->ncol > 0 ? f->ncol : 1) * HB_COL_POSE;
    if (!f->back64) return NULL;
    return c->scene.precision == HB_FP32 ? (const void *)(f->pose32 + at) : (const void *)(f->pose64 + at);
}

static int simd_dyn_frame(cpu_impl *c, const hb_dyn_frame *f, hb_stage_result *r, char *err, size_t errlen)
{
    const int64_t P = c->scene.points, DB = HB_SIMD_DYN_BLOCK, nb = c->stride / HB_SIMD_DYN_BLOCK, S = c->stride;
    int failed = 0;
    const double t0 = hb_now_ms();
    const hb_host_world *hw = &c->world;
    const int fp32 = c->scene.precision == HB_FP32;
    /* §3.16 the grid built from the rows once a frame, or before every substep (grid_step) */
    const int64_t FS = f->substeps, step = grid_step(c, f);
    for (int64_t j0 = 0, j1 = step; j0 < FS && !failed; j0 = j1, j1 += step) {
        if (c->scene.dyn.grid) {
            if (hb_host_world_build_rows(&c->world, &c->scene, c->pm, c->pv, S, grid_rotation(c, f, j0))) failed = 1;
        }
        if (fp32) SIMD_DYN_FRAME(float, f32, &c->d32, hw->on ? &hw->w32 : NULL);
        else SIMD_DYN_FRAME(double, f64, &c->d64, hw->on ? &hw->w64 : NULL);
    }
    c->last_pose = frame_last_pose(c, f);
    return dyn_frame_result(r, t0, failed, "per-thread block scratch", P, err, errlen);
}
#undef SIMD_DYN_FRAME

/* Per-strand partials, the same bits as ref's, combined over the same fixed chunks of
 * SIMD_OBS_CHUNK (= OBS_CHUNK below) strands in the same order: ref's observables. */
#define SIMD_OBS_CHUNK 1024

static int simd_dyn_observe(cpu_impl *c, hb_observables *obs, char *err, size_t errlen)
{
    const int64_t N = c->scene.n_strands, P = c->scene.points, S = c->stride;
    const int64_t nchunks = (N + SIMD_OBS_CHUNK - 1) / SIMD_OBS_CHUNK;
    hb_obs_partial *part = calloc((size_t)nchunks, sizeof *part);
    hb_obs_partial *strand = malloc((size_t)hb_mul_sat((uint64_t)N, sizeof *strand));
    if (!part || !strand) {
        free(part);
        free(strand);
        snprintf(err, errlen, "out of host memory for the observables");
        return -1;
    }
#pragma omp parallel for schedule(static)
    for (int64_t ch = 0; ch < nchunks; ch++) {
        const int64_t i0 = ch * SIMD_OBS_CHUNK, i1 = i0 + SIMD_OBS_CHUNK < N ? i0 + SIMD_OBS_CHUNK : N;
        if (c->scene.precision == HB_FP32)
            c->sd->observe_f32(&c->scene, c->world.on ? &c->world.w32 : NULL, (const float *)c->last_pose, c->pm[0],
                               c->pm[1], c->pm[2], c->pv[0], c->pv[1], c->pv[2], S, i0, i1 - i0, c->seg64, strand + i0);
        else
            c->sd->observe_f64(&c->scene, c->world.on ? &c->world.w64 : NULL, (const double *)c->last_pose, c->pm[0],
                               c->pm[1], c->pm[2], c->pv[0], c->pv[1], c->pv[2], S, i0, i1 - i0, c->seg64, strand + i0);
        hb_obs_partial acc = {0, 0, 0, 0};
        for (int64_t i = i0; i < i1; i++) hb_dyn_reduce_into(&acc, &strand[i]);
        part[ch] = acc;
    }
    hb_dyn_reduce(part, nchunks, P, N, obs);
    free(part);
    free(strand);
    return 0;
}
#undef SIMD_OBS_CHUNK

/* ---- the backend interface ----------------------------------------------------------- */

/* The positions from (to_backend) or to canonical [N][P][3], timed. */
static double cpu_transfer_positions(cpu_impl *c, void *canonical, int to_backend)
{
    const double t0 = hb_now_ms();
    if (c->simd) simd_convert(c, c->pm, canonical, to_backend);
    else if (to_backend) memcpy(c->state, canonical, c->bytes);
    else memcpy(canonical, c->state, c->bytes);
    return hb_now_ms() - t0;
}

static int cpu_load(hb_backend *b, const void *canonical, double *ms, char *err, size_t errlen)
{
    (void)err;
    (void)errlen;
    *ms = cpu_transfer_positions(b->impl, (void *)canonical, 1);
    return 0;
}

static int cpu_fetch(hb_backend *b, void *canonical, double *ms, char *err, size_t errlen)
{
    (void)err;
    (void)errlen;
    *ms = cpu_transfer_positions(b->impl, canonical, 0);
    return 0;
}

/* After a fused wind+collide (simd): the wind frame, canonical. */
static int cpu_fetch_intermediate(hb_backend *b, void *canonical, char *err, size_t errlen)
{
    cpu_impl *c = b->impl;
    if (!c->simd || !c->pm_wind[0]) {
        snprintf(err, errlen, "internal: no wind frame was kept");
        return HB_EXIT_RUNTIME;
    }
    void *const a[3] = {c->pm[0], c->pm_wind[0], c->pm_wind[1]};
    simd_convert(c, a, canonical, 0);
    return 0;
}

static void cpu_keep_intermediate(hb_backend *b, int keep)
{
    cpu_impl *c = b->impl;
    c->keep = keep;
}

/* Positions and velocities into (to_saved) or back from the saved copies. */
static void cpu_copy_saved(cpu_impl *c, int to_saved)
{
    if (c->simd) pm_copy(c, to_saved ? c->pm_saved : c->pm, to_saved ? c->pm : c->pm_saved);
    else memcpy(to_saved ? c->saved : c->state, to_saved ? c->state : c->saved, c->bytes);
    if (c->pv_saved[0]) pm_copy(c, to_saved ? c->pv_saved : c->pv, to_saved ? c->pv : c->pv_saved);
    if (c->vel_saved) memcpy(to_saved ? c->vel_saved : c->vel, to_saved ? c->vel : c->vel_saved, c->bytes);
}

static int cpu_save(hb_backend *b, char *err, size_t errlen)
{
    (void)err;
    (void)errlen;
    cpu_copy_saved(b->impl, 1);
    return 0;
}

static int cpu_restore(hb_backend *b, char *err, size_t errlen)
{
    (void)err;
    (void)errlen;
    cpu_copy_saved(b->impl, 0);
    return 0;
}

#define REF_STAGE(T, SFX, M)                                                                                           \
    do {                                                                                                               \
        T *s = c->state;                                                                                               \
        if (st == HB_STAGE_INIT) {                                                                                     \
            _Pragma("omp parallel for schedule(static)") for (int64_t k = 0; k < N; k++)                               \
                hb_init_strand_##SFX(M, (uint64_t)k, s + (size_t)k * stride);                                          \
        } else if (st == HB_STAGE_WIND) {                                                                              \
            _Pragma("omp parallel for schedule(static)") for (int64_t k = 0; k < N; k++)                               \
                hb_wind_strand_##SFX(M, s + (size_t)k * stride);                                                       \
        } else {                                                                                                       \
            _Pragma("omp parallel for schedule(static) reduction(+ : moved)") for (int64_t k = 0; k < N; k++) moved += \
                hb_collide_strand_##SFX(M, s + (size_t)k * stride);                                                    \
        }                                                                                                              \
    } while (0)

/* One stage over all strands. Strand i lives at state + 3·P·i (canonical layout). */
static int cpu_run_stage(hb_backend *b, const hb_stage *stages, int i, int n, hb_stage_result *r, char *err,
                         size_t errlen)
{
    cpu_impl *c = b->impl;
    const int64_t N = c->scene.n_strands;
    const size_t stride = (size_t)c->scene.points * 3u;
    const hb_stage st = stages[i];
    int64_t moved = 0;
    if (c->simd && st == HB_STAGE_WIND && i + 1 < n && stages[i + 1] == HB_STAGE_COLLIDE) {
        double t0 = hb_now_ms();
        moved = simd_run_wind_collide(c);
        r->ms = hb_now_ms() - t0;
        if (moved < 0) {
            snprintf(err, errlen, "cannot allocate %.2f GB of host memory for the wind frame",
                     2e-9 * (double)c->pm_bytes);
            return HB_EXIT_RUNTIME;
        }
        r->moved_points = moved;
        r->consumed = 2;
        return 0;
    }
    double t0 = hb_now_ms();
    if (c->simd) {
        moved = simd_run_stage(c, st);
    } else if (c->scene.precision == HB_FP32) {
        REF_STAGE(float, f32, &c->m32);
    } else {
        REF_STAGE(double, f64, &c->m64);
    }
    r->ms = hb_now_ms() - t0;
    r->moved_points = st == HB_STAGE_COLLIDE ? moved : -1;
    r->consumed = 1;
    return 0;
}
#undef REF_STAGE

/* ---- the dynamic model (ref): one strand per thread from start to finish ------------- */

static int cpu_dyn_load(hb_backend *b, const void *velocity, const void *rest, char *err, size_t errlen)
{
    (void)err;
    (void)errlen;
    cpu_impl *c = b->impl;
    if (c->simd && simd_dyn_load(c, velocity, rest) != 0) {
        snprintf(err, errlen, "out of host memory for the sag-free shape targets");
        return -1;
    }
    if (c->simd) { /* §3.16, §3.17 the grid and the colliders */
        hb_host_world_free(&c->world);
        return hb_host_world_make(&c->world, &c->scene, rest, 1, err, errlen);
    }
    const int64_t N = c->scene.n_strands, P = c->scene.points;
    const size_t stride = (size_t)P * 3u, bstride = (size_t)(P - 2 > 0 ? P - 2 : 0);
    if (velocity) memcpy(c->vel, velocity, c->bytes);
    else memset(c->vel, 0, c->bytes);
    memcpy(c->rest, rest, c->bytes);
    if (c->scene.precision == HB_FP32) {
#pragma omp parallel for schedule(static)
        for (int64_t i = 0; i < N; i++)
            hb_dyn_bend_rest_f32(&c->d32, (const float *)c->rest + (size_t)i * stride,
                                 (float *)c->bend_rest + (size_t)i * bstride);
    } else {
#pragma omp parallel for schedule(static)
        for (int64_t i = 0; i < N; i++)
            hb_dyn_bend_rest_f64(&c->d64, (const double *)c->rest + (size_t)i * stride,
                                 (double *)c->bend_rest + (size_t)i * bstride);
    }
    if (c->seg_rest) hb_dyn_seg_rest(&c->scene, c->rest, c->seg64, c->seg_rest); /* §3.15 */
    if (c->shape_rest) hb_sagfree_targets(&c->scene, c->rest, c->shape_rest);    /* §3.14 */
    hb_followers_free(&c->fl);
    if (c->scene.dyn.guided && hb_followers_plan(&c->scene, c->rest, &c->fl, err, errlen) != 0) return -1;
    hb_host_world_free(&c->world);
    return hb_host_world_make(&c->world, &c->scene, c->rest, 1, err, errlen);
}

/* Strands over threads, substeps j0 … j1 − 1; each thread's scratch (17·P reals, dynamics.h) is its own. */
#define DYN_FRAME(T, SFX, M, W)                                                                                        \
    _Pragma("omp parallel")                                                                                            \
    {                                                                                                                  \
        T *scratch = malloc((size_t)hb_mul_sat((uint64_t)P, 17u * sizeof(T)));                                         \
        if (!scratch) {                                                                                                \
            _Pragma("omp atomic write") failed = 1;                                                                    \
        } else {                                                                                                       \
            _Pragma("omp for schedule(static)") for (int64_t j = 0; j < NS; j++)                                       \
            {                                                                                                          \
                const int64_t i = c->scene.dyn.guided ? c->fl.guide[j] : j;                                            \
                hb_dyn_frame_strand_##SFX(                                                                             \
                    M, W, f, j0, j1, (T *)c->state + (size_t)i * stride, (T *)c->vel + (size_t)i * stride,             \
                    (const T *)(c->shape_rest ? c->shape_rest : c->rest) + (size_t)i * stride,                         \
                    (const T *)c->bend_rest + (size_t)i * bstride,                                                     \
                    c->seg_rest ? (const T *)c->seg_rest + (size_t)i * (P - 1) : NULL, scratch,                        \
                    c->contacts ? (T *)c->contacts + (size_t)i * (size_t)P * HB_CONTACT_POINT : NULL);                 \
            }                                                                                                          \
            free(scratch);                                                                                             \
        }                                                                                                              \
    }

/* §3.14: the followers placed from the guides at the frame's end pose, after every guide. */
static void cpu_place_followers(cpu_impl *c, const hb_dyn_frame *f)
{
    const int still = c->scene.dyn.motion == HB_MOTION_STILL;
    const int64_t last = 9 * (f->substeps - 1);
    if (c->scene.precision == HB_FP32) {
#pragma omp parallel for schedule(static)
        for (int64_t j = 0; j < c->fl.n_followers; j++)
            hb_follower_place_f32(&c->d32, &c->fl, j, still ? NULL : f->q32 + last, c->state, c->vel, c->rest,
                                  (const float *)c->seg_rest);
    } else {
#pragma omp parallel for schedule(static)
        for (int64_t j = 0; j < c->fl.n_followers; j++)
            hb_follower_place_f64(&c->d64, &c->fl, j, still ? NULL : f->q64 + last, c->state, c->vel, c->rest,
                                  (const double *)c->seg_rest);
    }
}

static int cpu_dyn_frame(hb_backend *b, const hb_dyn_frame *f, hb_stage_result *r, char *err, size_t errlen)
{
    cpu_impl *c = b->impl;
    if (c->simd) return simd_dyn_frame(c, f, r, err, errlen);
    const int64_t NS = c->scene.dyn.guided ? c->fl.n_guides : c->scene.n_strands, P = c->scene.points;
    const size_t stride = (size_t)P * 3u, bstride = (size_t)(P - 2 > 0 ? P - 2 : 0);
    int failed = 0;
    const double t0 = hb_now_ms();
    const hb_host_world *hw = &c->world;
    const int fp32 = c->scene.precision == HB_FP32;
    const int64_t S = f->substeps, step = grid_step(c, f);
    for (int64_t j0 = 0, j1 = step; j0 < S && !failed; j0 = j1, j1 += step) {
        if (c->scene.dyn.grid) {
            if (hb_host_world_build(&c->world, &c->scene, c->state, c->vel, grid_rotation(c, f, j0))) failed = 1;
        }
        if (fp32) DYN_FRAME(float, f32, &c->d32, hw->on ? &hw->w32 : NULL)
        else DYN_FRAME(double, f64, &c->d64, hw->on ? &hw->w64 : NULL)
    }
    c->last_pose = frame_last_pose(c, f);
    if (c->scene.dyn.guided && !failed) cpu_place_followers(c, f);
    return dyn_frame_result(r, t0, failed, "per-thread scratch", P, err, errlen);
}
#undef DYN_FRAME

/* Partials over fixed chunks of strands, combined in chunk order: the same sums for every
 * thread count. */
#define OBS_CHUNK 1024

static int cpu_dyn_observe(hb_backend *b, hb_observables *obs, char *err, size_t errlen)
{
    cpu_impl *c = b->impl;
    if (c->simd) return simd_dyn_observe(c, obs, err, errlen);
    const int64_t N = c->scene.n_strands, P = c->scene.points;
    const size_t stride = (size_t)P * 3u;
    const int64_t nchunks = (N + OBS_CHUNK - 1) / OBS_CHUNK;
    hb_obs_partial *part = calloc((size_t)nchunks, sizeof *part);
    if (!part) {
        snprintf(err, errlen, "out of host memory for the observables");
        return -1;
    }
#pragma omp parallel for schedule(static)
    for (int64_t ch = 0; ch < nchunks; ch++) {
        const int64_t i1 = (ch + 1) * OBS_CHUNK < N ? (ch + 1) * OBS_CHUNK : N;
        hb_obs_partial acc = {0, 0, 0, 0};
        for (int64_t i = ch * OBS_CHUNK; i < i1; i++) {
            hb_obs_partial o;
            if (c->scene.precision == HB_FP32)
                hb_dyn_observe_strand_f32(&c->scene, c->world.on ? &c->world.w32 : NULL, (const float *)c->last_pose,
                                          (const float *)c->state + (size_t)i * stride,
                                          (const float *)c->vel + (size_t)i * stride,
                                          c->seg64 ? c->seg64 + (size_t)i * (P - 1) : NULL, &o);
            else
                hb_dyn_observe_strand_f64(&c->scene, c->world.on ? &c->world.w64 : NULL, (const double *)c->last_pose,
                                          (const double *)c->state + (size_t)i * stride,
                                          (const double *)c->vel + (size_t)i * stride,
                                          c->seg64 ? c->seg64 + (size_t)i * (P - 1) : NULL, &o);
            hb_dyn_reduce_into(&acc, &o);
        }
        part[ch] = acc;
    }
    hb_dyn_reduce(part, nchunks, P, N, obs);
    free(part);
    return 0;
}

static int cpu_dyn_fetch_velocity(hb_backend *b, void *canonical, char *err, size_t errlen)
{
    (void)err;
    (void)errlen;
    cpu_impl *c = b->impl;
    if (c->simd) {
        simd_convert(c, c->pv, canonical, 0);
        return 0;
    }
    memcpy(canonical, c->vel, c->bytes);
    return 0;
}

/* --render-points (docs/model.md §3.14): the rendered points of the current state, strands
 * in parallel; the simd variant's state is made canonical first (not timed). */
static int cpu_dyn_render(hb_backend *b, void *position, void *velocity, double *ms, char *err, size_t errlen)
{
    cpu_impl *c = b->impl;
    const hb_scene *s = &c->scene;
    const int64_t N = s->n_strands, ps = s->points, pr = s->dyn.render_points;
    const void *x = c->state, *v = c->vel;
    void *xs = NULL, *vs = NULL;
    if (c->simd) {
        xs = malloc(c->bytes);
        vs = velocity ? malloc(c->bytes) : NULL;
        if (!xs || (velocity && !vs)) {
            free(xs);
            free(vs);
            snprintf(err, errlen, "out of host memory for the state to render (--render-points)");
            return -1;
        }
        simd_convert(c, c->pm, xs, 0);
        if (vs) simd_convert(c, c->pv, vs, 0);
        x = xs;
        v = vs;
    }
    const size_t ss = (size_t)ps * 3u, sr = (size_t)pr * 3u;
    const double t0 = hb_now_ms();
#pragma omp parallel for schedule(static)
    for (int64_t i = 0; i < N; i++) {
        if (s->precision == HB_FP32) {
            const float *xi = (const float *)x + (size_t)i * ss;
            hb_lod_strand_f32(xi, xi, ps, pr, (float *)position + (size_t)i * sr);
            if (velocity)
                hb_lod_strand_f32(xi, (const float *)v + (size_t)i * ss, ps, pr, (float *)velocity + (size_t)i * sr);
        } else {
            const double *xi = (const double *)x + (size_t)i * ss;
            hb_lod_strand_f64(xi, xi, ps, pr, (double *)position + (size_t)i * sr);
            if (velocity)
                hb_lod_strand_f64(xi, (const double *)v + (size_t)i * ss, ps, pr, (double *)velocity + (size_t)i * sr);
        }
    }
    *ms = hb_now_ms() - t0;
    free(xs);
    free(vs);
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
    const int all_cores = default_threads(); /* read before this run sets its own */
    omp_set_num_threads(o->threads > 0 ? o->threads : all_cores);
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
        double t0 = hb_now_ms();
#pragma omp parallel for schedule(static)
        for (size_t i = 0; i < n; i++) c[i] = a[i];
        double t = hb_now_ms() - t0;
        if (rep > 0 && t < best) best = t; /* the first run warms up */
    }
    *copy_bytes = 2.0 * (double)n * sizeof(double);
    *copy_gbps = *copy_bytes / (best * 1e-3) * 1e-9;
    double sum = c[n / 2];
    if (triad_gbps) {
        const double q = 3.0;
        best = 1e30;
        for (int rep = 0; rep < 7; rep++) {
            double t0 = hb_now_ms();
#pragma omp parallel for schedule(static)
            for (size_t i = 0; i < n; i++) a[i] = bb[i] + q * c[i];
            double t = hb_now_ms() - t0;
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

static int cpu_measure_triad(hb_backend *b, const hb_options *o, double *gbps, double *bytes, char *err, size_t errlen)
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
    free(c->vel);
    free(c->vel_saved);
    free(c->rest);
    free(c->bend_rest);
    free(c->seg_rest);
    free(c->seg64);
    free(c->contacts);
    free(c->shape_rest);
    hb_followers_free(&c->fl);
    for (int d = 0; d < 3; d++) {
        free(c->pm[d]);
        free(c->pm_saved[d]);
        free(c->pv[d]);
        free(c->pv_saved[d]);
        free(c->pr[d]);
    }
    free(c->pm_wind[0]);
    free(c->pm_wind[1]);
    free(c->pb);
    free(c->ps);
    hb_host_world_free(&c->world);
    free(c);
    b->impl = NULL;
}

#define CPU_PAPER_STAGES ((1u << HB_STAGE_INIT) | (1u << HB_STAGE_COLLIDE) | (1u << HB_STAGE_WIND))
static const hb_variant cpu_variants[] = {
    {"ref", CPU_PAPER_STAGES | (1u << HB_STAGE_SIMULATE),
     "the oracle: model_impl.h and dynamics_impl.h one strand at a time, OpenMP over strands", 0, 0,
     (1u << HB_SOLVER_XPBD) | (1u << HB_SOLVER_FTL) | (1u << HB_SOLVER_RIGID), 1, 0},
    {"simd", CPU_PAPER_STAGES | (1u << HB_STAGE_SIMULATE),
     "point-major structure of arrays, one strand per SIMD lane, OpenMP over blocks; built for x86-64-v3 and "
     "x86-64-v4, the CPU's widest runs (the record's flags say which)",
     0, 0, 0, 1, HB_X_GUIDES},
    {NULL, 0, NULL, 0, 0, 0, 0, 0},
};

#ifndef HB_FLAGS
#define HB_FLAGS "unknown"
#endif
#ifndef HB_FLAGS_SIMD_V4
#define HB_FLAGS_SIMD_V4 HB_FLAGS
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
    b.fetch_intermediate = cpu_fetch_intermediate;
    b.keep_intermediate = cpu_keep_intermediate;
    b.measure_bandwidth = cpu_measure_bandwidth;
    b.describe = cpu_describe;
    b.teardown = cpu_teardown;
    b.measure_triad = cpu_measure_triad;
    b.dyn_load = cpu_dyn_load;
    b.dyn_frame = cpu_dyn_frame;
    b.dyn_observe = cpu_dyn_observe;
    b.dyn_fetch_velocity = cpu_dyn_fetch_velocity;
    b.dyn_render = cpu_dyn_render;
    return hb_main(argc, argv, &b);
}
