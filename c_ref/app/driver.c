/* driver.c — the run shared by every backend: parse, refuse bad input before any work,
 * run the listed stages (docs/model.md §2.6: only those), time them (§5.3), write the HDF5
 * state and the JSON record (docs/interfaces.md). */
#include <limits.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "runtime/backend.h"
#include "runtime/checked.h"
#include "runtime/cli.h"
#include "runtime/groom.h"
#include "dynamic/dyn_followers.h"
#include "dynamic/dyn_lod.h"
#include "dynamic/world.h"
#include "runtime/host.h"
#include "runtime/input.h"
#include "runtime/motion_track.h"
#include "runtime/philox.h"
#include "runtime/record.h"
#include "runtime/safe_write.h"
#include "runtime/state_io.h"

static const char *g_prog = "hairsim";

static int die(int status, const char *msg)
{
    fprintf(stderr, "%s: error: %s\n", g_prog, msg);
    return status;
}


uint64_t hb_host_memory_available(void)
{
    FILE *f = fopen("/proc/meminfo", "r");
    if (!f) return 0;
    char line[256];
    unsigned long long kb = 0;
    while (fgets(line, sizeof line, f))
        if (sscanf(line, "MemAvailable: %llu kB", &kb) == 1) break;
    fclose(f);
    return (uint64_t)kb * 1024u;
}

/* ---- --self-test rng: Random123's published known-answer vectors (kat_vectors) ------- */
static int self_test_rng(void)
{
    static const struct {
        int rounds;
        uint32_t ctr[4], key[2], want[4];
    } kat[] = {
        {10, {0, 0, 0, 0}, {0, 0}, {0x6627e8d5, 0xe169c58d, 0xbc57ac4c, 0x9b00dbd8}},
        {10,
         {0xffffffff, 0xffffffff, 0xffffffff, 0xffffffff},
         {0xffffffff, 0xffffffff},
         {0x408f276d, 0x41c83b0e, 0xa20bc7c6, 0x6d5451fd}},
        {10,
         {0x243f6a88, 0x85a308d3, 0x13198a2e, 0x03707344},
         {0xa4093822, 0x299f31d0},
         {0xd16cfe09, 0x94fdcceb, 0x5001e420, 0x24126ea1}},
        {7,
         {0x243f6a88, 0x85a308d3, 0x13198a2e, 0x03707344},
         {0xa4093822, 0x299f31d0},
         {0x4dfccaba, 0x190a87f0, 0xc47362ba, 0xb6b5242a}},
    };
    int failed = 0;
    for (size_t i = 0; i < sizeof kat / sizeof kat[0]; i++) {
        uint32_t out[4];
        hb_philox4x32(kat[i].rounds, kat[i].ctr, kat[i].key, out);
        int ok = memcmp(out, kat[i].want, sizeof out) == 0;
        failed += !ok;
        printf("philox4x32 %d %08x %08x %08x %08x %08x %08x -> %08x %08x %08x %08x %s\n", kat[i].rounds, kat[i].ctr[0],
               kat[i].ctr[1], kat[i].ctr[2], kat[i].ctr[3], kat[i].key[0], kat[i].key[1], out[0], out[1], out[2],
               out[3], ok ? "ok" : "MISMATCH");
    }
    return failed ? 1 : 0;
}

/* The §3.14, §3.16, §3.17 features by HB_X_* bit: the name --list-variants gives, the flag that declares it. */
static const struct {
    const char *name, *flag;
} x_features[HB_X_COUNT] = {{"guides", "--guides"},
                            {"lra", "--lra"},
                            {"sagfree", "--sag-free"},
                            {"lod", "--render-points"},
                            {"grid", "--grid"},
                            {"colliders", "--colliders"},
                            {"friction", "--friction or --depenetration-speed"}};

/* The §3.14 features a scene declares, HB_X_* bits. */
static unsigned x_declared(const hb_dynamics *d)
{
    int friction = d->friction_declared || d->depen_declared;
    for (int i = 0; d->cols && i < d->cols->n; i++) friction |= d->cols->c[i].mu_s > 0.0;
    return (d->guided ? HB_X_GUIDES : 0u) | (d->lra ? HB_X_LRA : 0u) | (d->sag_free ? HB_X_SAGFREE : 0u) |
           (d->render_points ? HB_X_LOD : 0u) | (d->grid ? HB_X_GRID : 0u) | (d->colliders_path ? HB_X_COLLIDERS : 0u) |
           (friction ? HB_X_FRICTION : 0u);
}

/* A JSON list of the solvers in the bit set `set` (bit 1 << hb_solver), after `key`. */
static void print_solvers(const char *key, unsigned set)
{
    printf("%s[", key);
    int first = 1;
    for (int s = 0; s < HB_SOLVER_COUNT; s++)
        if (set & (1u << s)) {
            printf("%s\"%s\"", first ? "" : ", ", hb_solver_name((hb_solver)s));
            first = 0;
        }
    printf("]");
}

/* --list-variants: the backend's variants, declared once in the backend, as one JSON
 * object (docs/interfaces.md); the harness reads it instead of spelling the names. */
static int list_variants(const hb_backend *b)
{
    static const hb_stage all[] = {HB_STAGE_INIT, HB_STAGE_COLLIDE, HB_STAGE_WIND, HB_STAGE_SIMULATE};
    printf("{\"backend\": \"%s\", \"build\": \"%s\", \"default_variant\": \"%s\", "
           "\"precisions\": [\"fp32\", \"fp64\"], \"variants\": [",
           b->name, b->build, b->default_variant);
    for (const hb_variant *v = b->variants; v->name; v++) {
        printf("%s{\"name\": \"%s\", \"stages\": [", v == b->variants ? "" : ", ", v->name);
        int first = 1;
        for (size_t i = 0; i < sizeof all / sizeof all[0]; i++)
            if (v->stages & (1u << all[i])) {
                printf("%s\"%s\"", first ? "" : ", ", hb_stage_name(all[i]));
                first = 0;
            }
        printf("], \"summary\": \"%s\"", v->summary);
        if (v->max_points > 0) printf(", \"max_points\": %lld", (long long)v->max_points);
        if (v->max_block > 0) printf(", \"max_block\": %d", v->max_block);
        if (v->stages & (1u << HB_STAGE_SIMULATE)) {
            print_solvers(", \"solvers\": ", hb_variant_solvers(v));
            printf(", \"features\": [");
            for (int x = 0, first = 1; x < HB_X_COUNT; x++)
                if (!(v->lacks & (1u << x))) {
                    printf("%s\"%s\"", first ? "" : ", ", x_features[x].name);
                    first = 0;
                }
            printf("]");
            if (v->per_segment) printf(", \"per_segment\": true"); /* simulates a groom (docs/model.md §3.15) */
        }
        printf("}");
    }
    unsigned any = 0;
    for (const hb_variant *v = b->variants; v->name; v++)
        if (v->stages & (1u << HB_STAGE_SIMULATE)) any |= hb_variant_solvers(v);
    printf("]");
    print_solvers(", \"solvers\": ", any);
    printf(", \"features\": [");
    for (unsigned i = 0; (1u << i) < HB_F_COUNT; i++) {
        char name[32];
        hb_dyn_feature_names(1u << i, name, sizeof name);
        printf("%s\"%s\"", i ? ", " : "", name);
    }
    printf(
        ", \"guides\", \"lra\", \"sagfree\", \"lod\", \"grid\", \"colliders\", \"friction\"]}\n"); /* §3.14, §3.16, §3.17's */
    return HB_EXIT_OK;
}

/* With --input the geometry comes from the file; a flag given that disagrees is refused. */
static int adopt_input_scene(hb_options *o, const hb_scene *f, int dynamic, char *err, size_t errlen)
{
    hb_scene *s = &o->scene;
#define SAME(bit, field, flag, fmt, cast)                                                                              \
    if ((o->given & (bit)) && s->field != f->field) {                                                                  \
        snprintf(err, errlen, flag " " fmt " does not match the input file's " fmt, cast s->field, cast f->field);     \
        return -1;                                                                                                     \
    }
    SAME(HB_GIVEN_STRANDS, n_strands, "--strands", "%lld", (long long))
    SAME(HB_GIVEN_POINTS, points, "--points", "%lld", (long long))
    SAME(HB_GIVEN_SEED, seed, "--seed", "%llu", (unsigned long long))
    SAME(HB_GIVEN_RADIUS, head_radius, "--head-radius", "%.17g", (double))
    SAME(HB_GIVEN_OFFSET, hair_offset, "--hair-offset", "%.17g", (double))
    SAME(HB_GIVEN_LENGTH, hair_length, "--hair-length", "%.17g", (double))
    SAME(HB_GIVEN_MARGIN, face_margin, "--face-margin", "%.17g", (double))
#undef SAME
    if ((o->given & HB_GIVEN_PRECISION) && s->precision != f->precision) {
        snprintf(err, errlen, "--precision %s does not match the input file's %s", hb_precision_name(s->precision),
                 hb_precision_name(f->precision));
        return -1;
    }
    double w = s->wind_strength, a = s->wind_angle;
    hb_dynamics dyn = s->dyn;
    *s = *f;
    s->wind_strength = w;
    s->wind_angle = a;
    if (!dynamic) {
        s->dyn = dyn; /* a paper file: the simulation's physics come from the flags */
        return 0;
    }
    /* a dynamic file: its physics continue; a flag given that disagrees is refused */
    for (int i = 0; hb_dyn_flag_name(i); i++)
        if ((o->dyn_given & (1ull << i)) && hb_dyn_flag_differs(i, &dyn, &f->dyn)) {
            snprintf(err, errlen, "%s does not match the input file's simulation (a resumed run keeps its physics)",
                     hb_dyn_flag_name(i));
            return -1;
        }
    if (o->given & HB_GIVEN_ANGLE && a != f->wind_angle) {
        snprintf(err, errlen,
                 "--wind-angle does not match the input file's simulation (a resumed run keeps its physics)");
        return -1;
    }
    s->wind_angle = f->wind_angle;
    return 0;
}

static int same_file(const char *a, const char *b)
{
    char ra[PATH_MAX], rb[PATH_MAX];
    if (!realpath(a, ra) || !realpath(b, rb)) return 0;
    return strcmp(ra, rb) == 0;
}

static void frame_meta(hb_frame_meta *m, hb_stage st, const hb_scene *s, const char *backend, const char *variant)
{
    memset(m, 0, sizeof *m);
    snprintf(m->stage, sizeof m->stage, "%s", hb_stage_name(st));
    snprintf(m->backend, sizeof m->backend, "%s/%s", backend, variant);
    m->moved_points = -1;
    m->wind_strength = st == HB_STAGE_WIND ? s->wind_strength : NAN;
    m->wind_angle = st == HB_STAGE_WIND ? s->wind_angle : NAN;
}

typedef struct {
    hb_backend *b;
    hb_options *o;
    hb_record *rec;
    hb_writer *w;
    void *host;                     /* canonical host frame (output, end-to-end) */
    void *input;                    /* the input's last frame */
    void *render, *vrender, *vhost; /* --render-points: a rendered frame and its velocities; simulated velocities */
    hb_input in;
    int have_input;
    hb_groom groom;      /* --groom: what init places (docs/model.md §3.15) */
    hb_colliders cols;   /* --colliders (docs/model.md §3.17) */
    hb_head_track track; /* --motion-track: the head's transform track (motion_track.h) */
    double *times;       /* all stages' timed runs */
    struct {             /* the simulation, for the file's /parameters */
        int dynamic;
        int64_t paper_frames, last_frame;
        char features[192];
    } sim;
} hb_run;

static void run_free(hb_run *r)
{
    if (r->w) hb_writer_abort(r->w);
    if (r->have_input) hb_input_close(&r->in);
    hb_groom_free(&r->groom);
    hb_colliders_free(&r->cols);
    hb_track_free(&r->track);
    if (r->b->teardown) r->b->teardown(r->b);
    free(r->host);
    free(r->input);
    free(r->render);
    free(r->vrender);
    free(r->vhost);
    free(r->times);
}


/* The frame as the file holds it: the state itself, or with --render-points its rendered
 * points (docs/model.md §3.14, the C reference's spline on the host). */
static const void *as_written(hb_run *r, const void *state)
{
    const hb_scene *s = &r->o->scene;
    if (!s->dyn.render_points) return state;
    hb_lod_render(s->precision, state, NULL, s->n_strands, s->points, s->dyn.render_points, r->render, NULL);
    return r->render;
}

/* A simulated frame's rendered points (and velocities when `vel`) into r->render (r->vrender):
 * by the backend's own kernel where it has one, else fetched and rendered on the host; *ms
 * the rendering's time (the kernel, or the host spline; transfers not counted). */
static int render_frame(hb_run *r, int vel, double *ms, char *err, size_t errlen)
{
    hb_backend *b = r->b;
    const hb_scene *s = &r->o->scene;
    if (b->dyn_render) return b->dyn_render(b, r->render, vel ? r->vrender : NULL, ms, err, errlen);
    double fetch_ms;
    if (b->fetch(b, r->host, &fetch_ms, err, errlen)) return -1;
    if (vel && b->dyn_fetch_velocity(b, r->vhost, err, errlen)) return -1;
    const double t0 = hb_now_ms();
    hb_lod_render(s->precision, r->host, vel ? r->vhost : NULL, s->n_strands, s->points, s->dyn.render_points,
                  r->render, r->vrender);
    *ms = hb_now_ms() - t0;
    return 0;
}

/* ---- the simulate stage (docs/model.md §3) ---------------------------------------------
 * Starts from the current state: a new simulation takes it as the rest shape with zero
 * velocities; a resumed one (--input of a dynamic file at a simulated frame) continues with
 * that file's rest shape, velocities and time. Each frame is timed on its own (--repeat
 * times from the same state); the observables and the file's frames are taken between the
 * timed frames, outside them. Memory does not grow with the frame count: one host frame. */
static int frame_plans(const hb_scene *s, int64_t first, int64_t n, hb_dyn_frame **plans, int64_t *n_plans, char *err,
                       size_t errlen);

static int run_simulate(hb_run *r, hb_stage_record *sr, int frame, double *times, char *err, size_t errlen)
{
    hb_backend *b = r->b;
    const hb_options *o = r->o;
    const hb_scene *s = &o->scene;
    const hb_dynamics *d = &s->dyn;
    const uint64_t bytes = hb_state_bytes(s);
    const int need_save = o->repeat > 1 || o->warmup > 0;
    int64_t gf0 = 0, paper_frames = frame;
    void *rest = malloc(bytes), *vel = NULL;
    hb_dyn_frame plan, *plans = NULL;
    int64_t n_plans = 0;
    double *rt = NULL; /* --render-points: each written frame's rendering time */
    int64_t n_rt = 0;
    memset(&plan, 0, sizeof plan);
    int status = HB_EXIT_OK;
#define FAIL_IF(cond, st)                                                                                              \
    do {                                                                                                               \
        if (cond) {                                                                                                    \
            status = (st);                                                                                             \
            goto out;                                                                                                  \
        }                                                                                                              \
    } while (0)
    if (d->render_points && !(rt = malloc((size_t)o->frames * sizeof *rt))) {
        snprintf(err, errlen, "out of host memory for the rendering times");
        FAIL_IF(1, HB_EXIT_MEMORY);
    }
    if (!rest || hb_dyn_frame_alloc(&plan, d->substeps) != 0 || hb_dyn_frame_alloc_world(&plan, s) != 0) {
        snprintf(err, errlen, "out of host memory for the simulation's rest shape and substep tables");
        FAIL_IF(1, HB_EXIT_MEMORY);
    }
    if (r->have_input && r->in.dynamic && o->input_frame >= r->in.paper_frames) {
        /* resume: the frame's velocities, the rest shape and the global frame index */
        const int64_t step = r->in.frames[o->input_frame].step;
        int vi = -1;
        for (int i = 0; i < r->in.n_vel; i++)
            if (r->in.vel_step[i] == step) vi = i;
        if (vi < 0) {
            snprintf(err, errlen,
                     "--input %s: frame %d has no stored velocities, so the simulation cannot resume "
                     "from it (write the file with --velocities all, or resume from its last frame)",
                     o->input, o->input_frame);
            FAIL_IF(1, HB_EXIT_USAGE);
        }
        paper_frames = r->in.paper_frames;
        gf0 = step - paper_frames + 1;
        vel = malloc(bytes);
        if (!vel) {
            snprintf(err, errlen, "out of host memory for the input's velocities");
            FAIL_IF(1, HB_EXIT_MEMORY);
        }
        FAIL_IF(hb_input_read_rest(&r->in, rest, err, errlen), HB_EXIT_USAGE);
        FAIL_IF(hb_input_read_velocity(&r->in, vi, vel, err, errlen), HB_EXIT_USAGE);
        if (r->w) {
            char *hv = r->host;
            for (int i = 0; i < r->in.n_vel; i++)
                if (o->all_velocities && r->in.vel_step[i] <= step) {
                    FAIL_IF(hb_input_read_velocity(&r->in, i, hv, err, errlen), HB_EXIT_USAGE);
                    FAIL_IF(hb_writer_velocity(r->w, hv, r->in.vel_step[i], r->in.vel_time[i], err, errlen),
                            HB_EXIT_RUNTIME);
                }
            for (int i = 0; i < r->in.n_obs; i++)
                if (r->in.obs_step[i] <= step)
                    FAIL_IF(
                        hb_writer_observables(r->w, &r->in.obs[i], r->in.obs_step[i], r->in.obs_time[i], err, errlen),
                        HB_EXIT_RUNTIME);
        }
    } else {
        double ms;
        FAIL_IF(b->fetch(b, rest, &ms, err, errlen), HB_EXIT_RUNTIME);
    }
    if (gf0 + o->frames > (INT64_C(1) << 53) / d->substeps) {
        snprintf(err, errlen,
                 "--frames %lld x --substeps %lld from frame %lld passes 2^53 substeps: times would "
                 "no longer be exact",
                 (long long)o->frames, (long long)d->substeps, (long long)gf0);
        FAIL_IF(1, HB_EXIT_USAGE);
    }
    const int64_t after = (o->frame_loop ? 1 : 0) + (o->draw_w ? 1 : 0); /* F more frames each */
    const double t_end = (double)(gf0 + (1 + after) * o->frames) * d->frame_dt;
    FAIL_IF(hb_dynamics_validate_time(s, t_end, err, errlen), HB_EXIT_USAGE);
    FAIL_IF(b->dyn_load(b, vel, rest, err, errlen), HB_EXIT_RUNTIME);
    if (r->w) FAIL_IF(hb_writer_rest(r->w, as_written(r, rest), err, errlen), HB_EXIT_RUNTIME);

    r->sim.dynamic = 1;
    r->sim.paper_frames = paper_frames;
    hb_dyn_scene_feature_names(s, r->sim.features, sizeof r->sim.features);
    snprintf(sr->features, sizeof sr->features, "%s", r->sim.features);
    sr->frames = o->frames;
    sr->times_ms = times;
    sr->n_times = (int)(o->frames * o->repeat);
    double observe_ms = 0.0;
    for (int64_t j = 1; j <= o->frames; j++) {
        const int64_t gf = gf0 + j;
        hb_dyn_frame_plan(s, (gf - 1) * d->substeps, &plan);
        if (need_save) FAIL_IF(b->save(b, err, errlen), HB_EXIT_RUNTIME);
        double *ft = times + (j - 1) * o->repeat;
        for (int k = 0; k < o->warmup + o->repeat; k++) {
            if (k > 0) FAIL_IF(b->restore(b, err, errlen), HB_EXIT_RUNTIME);
            hb_stage_result res = {0, -1, 1};
            FAIL_IF(b->dyn_frame(b, &plan, &res, err, errlen), HB_EXIT_RUNTIME);
            if (k >= o->warmup) ft[k - o->warmup] = res.ms;
        }
        hb_observables obs;
        const double t0 = hb_now_ms();
        FAIL_IF(b->dyn_observe(b, &obs, err, errlen), HB_EXIT_RUNTIME);
        observe_ms += hb_now_ms() - t0;
        const int64_t step = paper_frames - 1 + gf;
        const double time = (double)gf * d->frame_dt;
        sr->last = obs;
        sr->blown_frames += hb_obs_blown_up(&obs);
        r->sim.last_frame = gf;
        if (!r->w) {
            if (d->render_points) { /* §3.14: no file: every frame is rendered (and dropped), so its cost shows */
                double ms;
                FAIL_IF(render_frame(r, 0, &ms, err, errlen), HB_EXIT_RUNTIME);
                rt[n_rt++] = ms;
            }
            continue;
        }
        FAIL_IF(hb_writer_observables(r->w, &obs, step, time, err, errlen), HB_EXIT_RUNTIME);
        if (j % o->output_every != 0 && j != o->frames) continue;
        hb_frame_meta m;
        frame_meta(&m, HB_STAGE_SIMULATE, s, b->name, o->variant);
        hb_time_stats(ft, o->repeat, &m.median_ms, &m.min_ms, &m.max_ms);
        m.step = step;
        m.time = time;
        double ms;
        if (d->render_points) { /* §3.14: the rendered points, and their velocities */
            const int vel = o->all_velocities || j == o->frames;
            FAIL_IF(render_frame(r, vel, &ms, err, errlen), HB_EXIT_RUNTIME);
            rt[n_rt++] = ms;
            FAIL_IF(hb_writer_append(r->w, r->render, &m, err, errlen), HB_EXIT_RUNTIME);
            if (vel) FAIL_IF(hb_writer_velocity(r->w, r->vrender, step, time, err, errlen), HB_EXIT_RUNTIME);
            continue;
        }
        FAIL_IF(b->fetch(b, r->host, &ms, err, errlen), HB_EXIT_RUNTIME);
        FAIL_IF(hb_writer_append(r->w, r->host, &m, err, errlen), HB_EXIT_RUNTIME);
        if (o->all_velocities || j == o->frames) {
            FAIL_IF(b->dyn_fetch_velocity(b, r->host, err, errlen), HB_EXIT_RUNTIME);
            FAIL_IF(hb_writer_velocity(r->w, r->host, step, time, err, errlen), HB_EXIT_RUNTIME);
        }
    }
    sr->observe_ms = observe_ms;
    sr->render_ms = NAN;
    if (n_rt > 0) {
        double lo, hi;
        hb_time_stats(rt, (int)n_rt, &sr->render_ms, &lo, &hi);
    }
    hb_time_stats(sr->times_ms, sr->n_times, &sr->meta.median_ms, &sr->meta.min_ms, &sr->meta.max_ms);
    sr->loop_ms = sr->loop_graph_ms = NAN;
    if (after > 0 && (o->frames > INT32_MAX || gf0 + (1 + after) * o->frames > (INT64_C(1) << 53) / d->substeps)) {
        snprintf(err, errlen, "%s: --frames %lld is too many frames to run again",
                 o->draw_w ? "--draw" : "--frame-loop", (long long)o->frames);
        FAIL_IF(1, HB_EXIT_USAGE);
    }
    int64_t next = gf0 + o->frames; /* the global frame the next of these runs starts from */
    if (o->frame_loop) {
        /* F more frames from the final state, after everything above is written: the frames
         * an application would run next, their tables made here as for any frame */
        FAIL_IF(frame_plans(s, next, o->frames, &plans, &n_plans, err, errlen), HB_EXIT_MEMORY);
        FAIL_IF(b->dyn_loop(b, plans, (int)o->frames, &sr->loop_ms, &sr->loop_graph_ms, err, errlen), HB_EXIT_RUNTIME);
        next += o->frames;
    }
    if (o->draw_w) { /* F more frames, each simulated and drawn on the device (docs/interfaces.md) */
        FAIL_IF(frame_plans(s, next, o->frames, &plans, &n_plans, err, errlen), HB_EXIT_MEMORY);
        FAIL_IF(b->dyn_draw(b, plans, (int)o->frames, o->draw_w, o->draw_h, o->draw_image, &sr->draw, err, errlen),
                HB_EXIT_RUNTIME);
        sr->drawn = 1;
    }
out:
#undef FAIL_IF
    for (int64_t j = 0; j < n_plans; j++) hb_dyn_frame_free(&plans[j]);
    free(plans);
    hb_dyn_frame_free(&plan);
    free(rest);
    free(vel);
    free(rt);
    return status;
}

/* The tables of n frames from global frame `first` (its substeps first·S …) into *plans,
 * the ones there before freed; −1 with one line when the host memory runs out. */
static int frame_plans(const hb_scene *s, int64_t first, int64_t n, hb_dyn_frame **plans, int64_t *n_plans, char *err,
                       size_t errlen)
{
    for (int64_t j = 0; j < *n_plans; j++) hb_dyn_frame_free(&(*plans)[j]);
    free(*plans);
    *n_plans = 0;
    *plans = calloc((size_t)n, sizeof **plans);
    for (int64_t j = 0; *plans && j < n; j++) {
        if (hb_dyn_frame_alloc(&(*plans)[j], s->dyn.substeps) != 0 || hb_dyn_frame_alloc_world(&(*plans)[j], s) != 0) {
            hb_dyn_frame_free(&(*plans)[j]);
            break;
        }
        *n_plans = j + 1;
        hb_dyn_frame_plan(s, (first + j) * s->dyn.substeps, &(*plans)[j]);
    }
    if (*n_plans < n) return snprintf(err, errlen, "out of host memory for the frames' tables"), -1;
    return 0;
}

/* --groom (docs/model.md §3.15): init places the groom; the paper stages, which keep each
 * strand in its slice plane, and what is not yet defined for a groom are refused. */
static int check_groom(hb_options *o, hb_groom *g, char *err, size_t errlen)
{
    if (o->input) return snprintf(err, errlen, "--groom with --input: the input file holds the state"), -1;
    for (int i = 0; i < o->n_stages; i++)
        if (o->stages[i] == HB_STAGE_COLLIDE || o->stages[i] == HB_STAGE_WIND)
            return snprintf(err, errlen,
                            "--stages: a groom runs init then simulate; '%s' moves strands in their slice planes, "
                            "which a groom's strands are not",
                            hb_stage_name(o->stages[i])),
                   -1;
    if (o->end_to_end) return snprintf(err, errlen, "--end-to-end is not measured with --groom"), -1;
    if (o->scene.dyn.lra || o->scene.dyn.sag_free)
        return snprintf(err, errlen, "--lra and --sag-free are not defined for a groom yet (docs/model.md §3.15)"), -1;
    return hb_groom_prepare(o, g, err, errlen);
}

/* init with a groom: the state computed on the host, loaded as the stage's work. */
static int place_groom(hb_run *r, hb_stage_record *sr, double *times, char *err, size_t errlen)
{
    const hb_options *o = r->o;
    const uint64_t bytes = hb_state_bytes(&o->scene);
    void *buf = r->host ? r->host : malloc(bytes);
    if (!buf) return snprintf(err, errlen, "out of host memory for the groom"), -1;
    hb_groom_state(&o->scene, &r->groom, buf);
    int rc = 0;
    for (int j = 0; j < o->warmup + o->repeat && rc == 0; j++) {
        const double t0 = hb_now_ms();
        double ms;
        rc = r->b->load(r->b, buf, &ms, err, errlen);
        if (j >= o->warmup) times[j - o->warmup] = hb_now_ms() - t0;
    }
    if (rc == 0) {
        sr->times_ms = times;
        sr->n_times = o->repeat;
        hb_time_stats(times, o->repeat, &sr->meta.median_ms, &sr->meta.min_ms, &sr->meta.max_ms);
        if (r->w) rc = hb_writer_append(r->w, buf, &sr->meta, err, errlen);
    }
    if (buf != r->host) free(buf);
    return rc;
}

/* --head-motion track (docs/model.md §3.2): the samples of --motion-track, or those a resumed
 * dynamic file holds (then a --motion-track given must hold the same). */
static int adopt_track(hb_options *o, hb_run *r, char *err, size_t errlen)
{
    hb_dynamics *d = &o->scene.dyn;
    const int from_input = r->have_input && r->in.dynamic && r->in.scene.dyn.motion == HB_MOTION_TRACK;
    if (o->motion_track) {
        if (hb_track_load_csv(o->motion_track, &r->track, err, errlen)) return -1;
        if (from_input && !hb_track_same(&r->track, &r->in.track))
            return snprintf(err, errlen,
                            "--motion-track %s does not match the input file's track (a resumed run "
                            "keeps its physics)",
                            o->motion_track),
                   -1;
        if (!from_input) d->track = &r->track;
    }
    if (d->motion == HB_MOTION_TRACK && !d->track)
        return snprintf(err, errlen, "--head-motion track needs --motion-track FILE (a CSV head transform track)"), -1;
    return 0;
}

/* One line on stderr when simulate runs a new simulation on the bare defaults: no physics
 * flag at all (docs/interfaces.md, "Defaults"). */
static void note_untuned(const hb_options *o, const hb_run *r)
{
    if (o->quiet || (r->have_input && r->in.dynamic) || (o->dyn_given & ~HB_DYN_GIVEN_RUN)) return;
    fprintf(stderr,
            "%s: note: no physics flag given: simulate runs the bare defaults (S = 1, I = 1, no bend, shape, drag or "
            "wind), not a tuned setting; configs/scenes/dynamic.toml is one (python3 -m harness run dynamic)\n",
            g_prog);
}

#define CHECK(call, status)                                                                                            \
    do {                                                                                                               \
        if ((call) != 0) {                                                                                             \
            run_free(&run);                                                                                            \
            return die(status, err);                                                                                   \
        }                                                                                                              \
    } while (0)

static int run_one(int argc, char **argv, hb_backend *b);

/* --batch FILE: one run a line, its flags separated by tabs, all in this process, so that a
 * GPU's context is made once for all of them (docs/interfaces.md, "Batches"). The runs go in
 * order; the first that fails ends the batch with its exit status, after the records of the
 * runs before it; a run that blew up (status 5) does not end it, and the batch then exits 5
 * when none failed. The backend starts every run as it started the first. */
#define HB_BATCH_MAX_ARGS 256

/* A batch line is a run: the words that print something else on stdout are not. */
static int batch_word_allowed(const char *w)
{
    static const char *const not_runs[] = {"--help", "-h", "--version", "--list-variants", "--self-test"};
    for (size_t i = 0; i < sizeof not_runs / sizeof not_runs[0]; i++)
        if (strcmp(w, not_runs[i]) == 0) return 0;
    return 1;
}
static int run_batch(char *prog, const char *path, hb_backend *b)
{
    char err[HB_ERRLEN];
    FILE *f = hb_input_fopen("--batch", path, "a batch file: a run's flags a line", 1, NULL, err, sizeof err);
    if (!f) return die(HB_EXIT_USAGE, err);
    const hb_backend pristine = *b;
    char *line = NULL;
    size_t cap = 0;
    ssize_t n;
    int status = HB_EXIT_OK, blown = 0;
    for (long lineno = 1; status == HB_EXIT_OK && (n = getline(&line, &cap, f)) >= 0; lineno++) {
        while (n > 0 && (line[n - 1] == '\n' || line[n - 1] == '\r')) line[--n] = '\0';
        if (n == 0) continue;
        if (memchr(line, '\0', (size_t)n)) { /* the flags after it would be lost without a word */
            snprintf(err, sizeof err, "--batch %s: line %ld holds a NUL byte", path, lineno);
            status = die(HB_EXIT_USAGE, err);
            break;
        }
        char *argv[HB_BATCH_MAX_ARGS + 1];
        int argc = 0;
        argv[argc++] = prog;
        for (char *tok = line; tok;) {
            char *tab = strchr(tok, '\t');
            if (tab) *tab = '\0';
            if (argc == HB_BATCH_MAX_ARGS) {
                snprintf(err, sizeof err, "--batch %s: line %ld has more than %d flags and values", path, lineno,
                         HB_BATCH_MAX_ARGS - 1);
                status = die(HB_EXIT_USAGE, err);
                break;
            }
            if (strcmp(tok, "--batch") == 0) {
                snprintf(err, sizeof err, "--batch %s: line %ld holds --batch (batches do not nest)", path, lineno);
                status = die(HB_EXIT_USAGE, err);
                break;
            }
            if (!batch_word_allowed(tok)) { /* it would print among the records on stdout */
                snprintf(err, sizeof err, "--batch %s: line %ld holds %s (each line is a run)", path, lineno, tok);
                status = die(HB_EXIT_USAGE, err);
                break;
            }
            argv[argc++] = tok;
            tok = tab ? tab + 1 : NULL;
        }
        argv[argc] = NULL;
        if (status == HB_EXIT_OK) status = run_one(argc, argv, b);
        if (status == HB_EXIT_BLOWN_UP) { /* a run that blew up ended well: its record says so */
            blown = 1;
            status = HB_EXIT_OK;
        }
        *b = pristine;
        fflush(stdout);
        fflush(stderr);
    }
    if (status == HB_EXIT_OK && ferror(f)) {
        snprintf(err, sizeof err, "--batch %s: a read failed", path);
        status = die(HB_EXIT_USAGE, err);
    }
    free(line);
    fclose(f);
    return status == HB_EXIT_OK && blown ? HB_EXIT_BLOWN_UP : status;
}

int hb_main(int argc, char **argv, hb_backend *b)
{
    const char *slash = strrchr(argv[0], '/');
    g_prog = slash ? slash + 1 : argv[0];
    for (int i = 1; i < argc; i++)
        if (strcmp(argv[i], "--batch") == 0) {
            if (argc != 3 || i != 1)
                return die(HB_EXIT_USAGE, "--batch FILE takes no other flag (each line of FILE holds a run's flags)");
            return run_batch(argv[0], argv[2], b);
        }
    return run_one(argc, argv, b);
}

static int run_one(int argc, char **argv, hb_backend *b)
{
    char err[HB_ERRLEN] = "";
    hb_options o;

    int rc = hb_parse_args(argc, argv, b->name, &o, err, sizeof err);
    if (rc < 0) return die(HB_EXIT_USAGE, err);
    if (rc > 0) return HB_EXIT_OK;
    if (o.self_test) return self_test_rng();

    if (o.list_variants) return list_variants(b);

    if (!o.variant) o.variant = b->default_variant;
    const hb_variant *var = NULL;
    for (const hb_variant *v = b->variants; v->name; v++)
        if (strcmp(v->name, o.variant) == 0) var = v;
    if (!var) {
        char list[256] = "";
        for (const hb_variant *v = b->variants; v->name; v++)
            snprintf(list + strlen(list), sizeof list - strlen(list), "%s%s", list[0] ? ", " : "", v->name);
        snprintf(err, sizeof err, "--variant %s is not a %s variant (known: %s)", o.variant, b->name, list);
        return die(HB_EXIT_USAGE, err);
    }
    for (int i = 0; i < o.n_stages; i++)
        if (!(var->stages & (1u << o.stages[i]))) {
            snprintf(err, sizeof err, "--stages: the %s variant %s does not run '%s' (see --list-variants)", b->name,
                     var->name, hb_stage_name(o.stages[i]));
            return die(HB_EXIT_USAGE, err);
        }

    hb_record rec;
    memset(&rec, 0, sizeof rec);
    rec.opt = &o;
    rec.backend = b->name;
    rec.variant = o.variant;
    rec.flags = b->flags;
    rec.compiler = b->compiler ? b->compiler : hb_compiler();
    rec.git_revision = hb_git_revision();
    rec.end_to_end_ms = rec.h2d_ms = rec.d2h_ms = rec.hdf5_write_ms = NAN;

    hb_run run;
    memset(&run, 0, sizeof run);
    run.b = b;
    run.o = &o;
    run.rec = &rec;
    rec.groom = &run.groom;

    if (o.measure_bandwidth) {
        double gbps = 0, bytes = 0, triad = NAN, triad_bytes = NAN;
        CHECK(b->measure_bandwidth(b, &o, &gbps, &bytes, err, sizeof err), HB_EXIT_RUNTIME);
        if (b->measure_triad) CHECK(b->measure_triad(b, &o, &triad, &triad_bytes, err, sizeof err), HB_EXIT_RUNTIME);
        b->describe(b, rec.device, sizeof rec.device, rec.driver, sizeof rec.driver);
        if (o.json) {
            printf("{\"backend\": \"%s\", \"copy_gbps\": %.6g, \"bytes\": %.17g", b->name, gbps, bytes);
            if (isfinite(triad)) printf(", \"triad_gbps\": %.6g, \"triad_bytes\": %.17g", triad, triad_bytes);
            if (b->threads > 0) printf(", \"threads\": %d", b->threads);
            printf(", \"device\": \"%s\"}\n", rec.device);
        } else {
            printf("%s copy bandwidth: %.1f GB/s (read + write, %.0f bytes per copy)", b->name, gbps, bytes);
            if (isfinite(triad)) printf("; triad %.1f GB/s (%.0f bytes)", triad, triad_bytes);
            printf(" on %s\n", rec.device);
        }
        run_free(&run);
        return HB_EXIT_OK;
    }

    /* ---- refuse bad input before any work (docs/model.md §2.6) ---- */
    if (o.input) {
        CHECK(hb_input_open(o.input, &run.in, err, sizeof err), HB_EXIT_USAGE);
        run.have_input = 1;
        CHECK(adopt_input_scene(&o, &run.in.scene, run.in.dynamic, err, sizeof err), HB_EXIT_USAGE);
        for (int i = 0; i < o.n_stages; i++)
            if (o.stages[i] == HB_STAGE_INIT) {
                snprintf(err, sizeof err, "--stages: init cannot run on an --input state (it would replace it)");
                CHECK(1, HB_EXIT_USAGE);
            }
    }
    if (o.groom) {
        const int groom_status = check_groom(&o, &run.groom, err, sizeof err);
        CHECK(groom_status, groom_status < 0 ? HB_EXIT_USAGE : groom_status);
    }
    if (o.scene.dyn.colliders_path && !o.scene.dyn.cols) { /* docs/model.md §3.17 (a resumed run has the file's) */
        CHECK(hb_colliders_load(o.scene.dyn.colliders_path, &run.cols, err, sizeof err), HB_EXIT_USAGE);
        o.scene.dyn.cols = &run.cols;
    }
    if (!o.input && o.stages[0] != HB_STAGE_INIT) {
        snprintf(err, sizeof err, "--stages: '%s' needs a state: list init first or give --input",
                 hb_stage_name(o.stages[0]));
        CHECK(1, HB_EXIT_USAGE);
    }
    CHECK(hb_scene_validate(&o.scene, err, sizeof err), HB_EXIT_USAGE);
    const int simulate = o.stages[o.n_stages - 1] == HB_STAGE_SIMULATE;
    if (simulate) {
        CHECK(adopt_track(&o, &run, err, sizeof err), HB_EXIT_USAGE);
        CHECK(hb_dynamics_validate(&o.scene.dyn, err, sizeof err), HB_EXIT_USAGE);
        CHECK(hb_dynamics_validate_scene(&o.scene, err, sizeof err), HB_EXIT_USAGE);
        if (o.end_to_end) {
            snprintf(err, sizeof err, "--end-to-end is not measured for simulate: its frames are timed one by one");
            CHECK(1, HB_EXIT_USAGE);
        }
        if (var->max_points > 0 && o.scene.points > var->max_points) {
            snprintf(err, sizeof err,
                     "--points %lld: the %s variant %s simulates at most %lld points a strand (see --list-variants)",
                     (long long)o.scene.points, b->name, var->name, (long long)var->max_points);
            CHECK(1, HB_EXIT_USAGE);
        }
        if (!(hb_variant_solvers(var) & (1u << o.scene.dyn.solver))) {
            snprintf(err, sizeof err, "--solver %s: the %s variant %s does not run it (see --list-variants)",
                     hb_solver_name(o.scene.dyn.solver), b->name, var->name);
            CHECK(1, HB_EXIT_USAGE);
        }
        if (o.scene.dyn.per_segment && !var->per_segment) {
            snprintf(err, sizeof err,
                     "%s: the %s variant %s does not simulate a groom's per-segment rest lengths yet (docs/model.md "
                     "§3.15)",
                     o.groom ? "--groom" : "--input", b->name, var->name);
            CHECK(1, HB_EXIT_USAGE);
        }
        const unsigned lacking = x_declared(&o.scene.dyn) & var->lacks;
        for (int x = 0; x < HB_X_COUNT; x++)
            if (lacking & (1u << x)) {
                snprintf(err, sizeof err, "--variant %s does not run %s (see --list-variants)", var->name,
                         x_features[x].flag);
                CHECK(1, HB_EXIT_USAGE);
            }
        if (var->max_block > 0 && o.block_size > var->max_block) {
            snprintf(err, sizeof err,
                     "--block-size %d: the %s variant %s simulates with at most %d threads a block (see "
                     "--list-variants)",
                     o.block_size, b->name, var->name, var->max_block);
            CHECK(1, HB_EXIT_USAGE);
        }
        if ((o.frame_loop || o.draw_w) && (o.scene.dyn.grid || hb_dyn_has_world(&o.scene))) {
            snprintf(err, sizeof err, "%s does not yet run the grid and colliders (docs/model.md §3.16, §3.17)",
                     o.frame_loop ? "--frame-loop" : "--draw");
            CHECK(1, HB_EXIT_USAGE);
        }
        if (o.frame_loop && !b->dyn_loop) {
            snprintf(err, sizeof err, "--frame-loop is measured by the cuda backend only");
            CHECK(1, HB_EXIT_USAGE);
        }
        if (o.draw_w && !b->dyn_draw) {
            snprintf(err, sizeof err, "--draw draws on the GPU: the cuda backend only");
            CHECK(1, HB_EXIT_USAGE);
        }
    } else if (o.frame_loop) {
        snprintf(err, sizeof err, "--frame-loop needs simulate in --stages");
        CHECK(1, HB_EXIT_USAGE);
    } else if (o.draw_w) {
        snprintf(err, sizeof err, "--draw needs simulate in --stages");
        CHECK(1, HB_EXIT_USAGE);
    }
    if (o.draw_image && !o.draw_w) {
        snprintf(err, sizeof err, "--draw-image needs --draw");
        CHECK(1, HB_EXIT_USAGE);
    }
    if (o.input) {
        if (o.input_frame >= run.in.n_frames) {
            snprintf(err, sizeof err, "--input-frame %d: %s has frames 0 to %d", o.input_frame, o.input,
                     run.in.n_frames - 1);
            CHECK(1, HB_EXIT_USAGE);
        }
        if (o.input_frame < 0) o.input_frame = run.in.n_frames - 1;
        if (run.in.dynamic && o.input_frame >= run.in.paper_frames && !simulate) {
            snprintf(err, sizeof err, "--stages: frame %d of %s is simulated; only simulate can follow it",
                     o.input_frame, o.input);
            CHECK(1, HB_EXIT_USAGE);
        }
    } else if (o.input_frame >= 0) {
        snprintf(err, sizeof err, "--input-frame needs --input");
        CHECK(1, HB_EXIT_USAGE);
    }
    if (o.output && o.input && same_file(o.output, o.input)) {
        snprintf(err, sizeof err, "--output %s is the --input file; write to another name", o.output);
        CHECK(1, HB_EXIT_USAGE);
    }

    if (simulate) note_untuned(&o, &run);

    const uint64_t bytes = hb_state_bytes(&o.scene);
    const int need_host = o.output != NULL || o.end_to_end || simulate;
    /* simulate: the rest shape and the velocities pass through the host once */
    /* --render-points: a rendered frame, its velocities and the simulated velocities */
    const int64_t pr = simulate ? o.scene.dyn.render_points : 0;
    const uint64_t render_bytes =
        pr ? hb_mul_sat(hb_mul_sat((uint64_t)o.scene.n_strands, (uint64_t)pr), 3u * hb_real_size(o.scene.precision))
           : 0;
    const uint64_t driver_bytes = hb_add_sat(
        hb_add_sat(hb_add_sat(need_host ? bytes : 0, o.input ? bytes : 0), simulate ? hb_mul_sat(bytes, 2u) : 0),
        hb_add_sat(hb_mul_sat(render_bytes, 2u), render_bytes ? bytes : 0));
    const int need_save = o.repeat > 1 || o.warmup > 0;
    int status = b->setup(b, &o, need_save, driver_bytes, err, sizeof err);
    if (status != HB_EXIT_OK) {
        run_free(&run);
        return die(status, err);
    }
    b->describe(b, rec.device, sizeof rec.device, rec.driver, sizeof rec.driver);
    rec.flags = b->flags; /* setup may name the build that runs (cpu simd: x86-64-v3 or -v4) */
    rec.threads = b->threads;
    rec.block_size = b->block_size;
    if (need_host && !(run.host = malloc(bytes))) {
        snprintf(err, sizeof err, "cannot allocate the %llu-byte host frame", (unsigned long long)bytes);
        CHECK(1, HB_EXIT_MEMORY);
    }
    if (render_bytes && (!(run.render = malloc(render_bytes)) || !(run.vrender = malloc(render_bytes)) ||
                         !(run.vhost = malloc(bytes)))) {
        snprintf(err, sizeof err, "cannot allocate the %llu-byte rendered frames (--render-points)",
                 (unsigned long long)render_bytes);
        CHECK(1, HB_EXIT_MEMORY);
    }
    if (o.input && !(run.input = malloc(bytes))) {
        snprintf(err, sizeof err, "cannot allocate the %llu-byte input frame", (unsigned long long)bytes);
        CHECK(1, HB_EXIT_MEMORY);
    }
    /* one time per stage (or simulated frame) and repeat, counted by an int */
    uint64_t n_times, times_bytes;
    if (hb_add_u64((uint64_t)o.n_stages, simulate ? (uint64_t)o.frames : 0, &n_times) ||
        hb_mul_u64(n_times, (uint64_t)o.repeat, &n_times) || n_times > INT32_MAX ||
        hb_mul_u64(n_times, sizeof *run.times, &times_bytes)) {
        snprintf(err, sizeof err, "--frames %lld x --repeat %lld is more timings than a run keeps (at most %d)",
                 (long long)(simulate ? o.frames : 0), (long long)o.repeat, INT32_MAX);
        CHECK(1, HB_EXIT_USAGE);
    }
    run.times = calloc((size_t)n_times, sizeof *run.times);
    if (!run.times) {
        snprintf(err, sizeof err, "out of host memory");
        CHECK(1, HB_EXIT_MEMORY);
    }
    if (o.output) {
        int open_status;
        run.w = hb_writer_open(o.output, o.force, &o.scene, &open_status, err, sizeof err);
        if (!run.w) CHECK(1, open_status);
    }

    /* ---- the input state: its frames go into the output first ---- */
    int frame = 0;
    if (o.input) {
        const int last = o.input_frame;
        CHECK(hb_input_read_frame(&run.in, last, run.input, err, sizeof err), HB_EXIT_USAGE);
        if (run.w) {
            for (int f = 0; f <= last; f++) {
                const void *src = run.input;
                if (f != last) {
                    CHECK(hb_input_read_frame(&run.in, f, run.host, err, sizeof err), HB_EXIT_USAGE);
                    src = run.host;
                }
                CHECK(hb_writer_append(run.w, as_written(&run, src), &run.in.frames[f], err, sizeof err),
                      HB_EXIT_RUNTIME);
            }
        }
        frame = last + 1;
        double ms;
        CHECK(b->load(b, run.input, &ms, err, sizeof err), HB_EXIT_RUNTIME);
    }
    if (b->keep_intermediate) b->keep_intermediate(b, run.w != NULL);

    /* ---- the stages, each timed from the same input (docs/model.md §5.3) ---- */
    double *times = run.times;
    for (int i = 0; i < o.n_stages;) {
        hb_stage st = o.stages[i];
        hb_stage_record *sr = &rec.stages[rec.n_stages++];
        sr->frame = frame;
        sr->stage = st;
        frame_meta(&sr->meta, st, &o.scene, b->name, o.variant);
        sr->meta.step = frame;
        if (st == HB_STAGE_INIT && o.groom) {
            CHECK(place_groom(&run, sr, times, err, sizeof err), HB_EXIT_RUNTIME);
            times += o.repeat;
            frame++;
            i++;
            continue;
        }
        if (st == HB_STAGE_SIMULATE) {
            status = run_simulate(&run, sr, frame, times, err, sizeof err);
            if (status != HB_EXIT_OK) {
                run_free(&run);
                return die(status, err);
            }
            break; /* simulate is the last stage */
        }
        if (st == HB_STAGE_WIND && o.scene.wind_strength == 0.0) {
            /* a stage whose effect is nil is not launched (docs/model.md §2.6) */
            sr->meta.skipped = 1;
            if (run.w) {
                double ms;
                CHECK(b->fetch(b, run.host, &ms, err, sizeof err), HB_EXIT_RUNTIME);
                CHECK(hb_writer_append(run.w, as_written(&run, run.host), &sr->meta, err, sizeof err), HB_EXIT_RUNTIME);
            }
            frame++;
            i++;
            continue;
        }
        if (need_save) CHECK(b->save(b, err, sizeof err), HB_EXIT_RUNTIME);
        hb_stage_result r = {0, -1, 1};
        for (int j = 0; j < o.warmup + o.repeat; j++) {
            if (j > 0) CHECK(b->restore(b, err, sizeof err), HB_EXIT_RUNTIME);
            CHECK(b->run_stage(b, o.stages, i, o.n_stages, &r, err, sizeof err), HB_EXIT_RUNTIME);
            if (j >= o.warmup) times[j - o.warmup] = r.ms;
        }
        sr->times_ms = times;
        sr->n_times = o.repeat;
        times += o.repeat;
        hb_time_stats(sr->times_ms, sr->n_times, &sr->meta.median_ms, &sr->meta.min_ms, &sr->meta.max_ms);
        if (r.consumed == 2) {
            /* a fused wind+collide: one time for the pair, two frames */
            hb_stage_record *sc = &rec.stages[rec.n_stages++];
            snprintf(sr->meta.fused, sizeof sr->meta.fused, "wind+collide");
            sc->frame = frame + 1;
            sc->stage = o.stages[i + 1];
            frame_meta(&sc->meta, sc->stage, &o.scene, b->name, o.variant);
            sc->meta.step = frame + 1;
            snprintf(sc->meta.fused, sizeof sc->meta.fused, "into-previous");
            sc->meta.moved_points = r.moved_points;
            if (run.w) {
                CHECK(b->fetch_intermediate(b, run.host, err, sizeof err), HB_EXIT_RUNTIME);
                CHECK(hb_writer_append(run.w, as_written(&run, run.host), &sr->meta, err, sizeof err), HB_EXIT_RUNTIME);
            }
            sr = sc;
        } else {
            sr->meta.moved_points = r.moved_points;
        }
        if (run.w) {
            double ms;
            CHECK(b->fetch(b, run.host, &ms, err, sizeof err), HB_EXIT_RUNTIME);
            CHECK(hb_writer_append(run.w, as_written(&run, run.host), &sr->meta, err, sizeof err), HB_EXIT_RUNTIME);
        }
        frame += r.consumed;
        i += r.consumed;
    }

    /* ---- one whole pass, transfers included, timed apart from the stages ---- */
    if (o.end_to_end) {
        if (b->keep_intermediate) b->keep_intermediate(b, 0);
        double t0 = hb_now_ms(), h2d = 0, d2h = 0;
        if (o.input) CHECK(b->load(b, run.input, &h2d, err, sizeof err), HB_EXIT_RUNTIME);
        for (int i = 0; i < o.n_stages;) {
            if (o.stages[i] == HB_STAGE_WIND && o.scene.wind_strength == 0.0) {
                i++;
                continue;
            }
            hb_stage_result r = {0, -1, 1};
            CHECK(b->run_stage(b, o.stages, i, o.n_stages, &r, err, sizeof err), HB_EXIT_RUNTIME);
            i += r.consumed;
        }
        CHECK(b->fetch(b, run.host, &d2h, err, sizeof err), HB_EXIT_RUNTIME);
        rec.end_to_end_ms = hb_now_ms() - t0;
        if (strcmp(b->name, "cpu") != 0) {
            rec.h2d_ms = o.input ? h2d : NAN;
            rec.d2h_ms = d2h;
        }
    }

    if (run.w) {
        hb_run_meta rm = {b->name,
                          o.variant,
                          rec.git_revision,
                          rec.compiler,
                          b->flags,
                          rec.device,
                          rec.driver,
                          rec.threads,
                          rec.block_size,
                          o.repeat,
                          o.warmup,
                          rec.end_to_end_ms,
                          0,
                          run.sim.dynamic,
                          run.sim.paper_frames,
                          run.sim.last_frame,
                          (int)o.output_every,
                          run.sim.features,
                          NULL,
                          {0.0, 0.0, 0.0}};
        if (o.scene.groom == HB_GROOM_FILE) {
            rm.groom_head = run.groom.head_given ? "given" : "fitted";
            memcpy(rm.groom_head_center, run.groom.head_center, sizeof rm.groom_head_center);
        }
        double t0 = hb_now_ms(), before = 1e3 * hb_writer_seconds(run.w);
        hb_writer *w = run.w;
        run.w = NULL;
        const int rc_close = hb_writer_close(w, &rm, err, sizeof err);
        CHECK(rc_close, rc_close == HB_SAFE_EXISTS ? HB_EXIT_USAGE : HB_EXIT_RUNTIME);
        rec.hdf5_write_ms = before + (hb_now_ms() - t0);
    }
    if (o.json) hb_record_json(stdout, &rec);
    if (!o.quiet) hb_record_summary(stderr, &rec);
    run_free(&run);
    return hb_record_blown_frames(&rec) ? HB_EXIT_BLOWN_UP : HB_EXIT_OK;
}
