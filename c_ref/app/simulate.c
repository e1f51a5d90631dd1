/* simulate.c — the dynamic model's frame loop (docs/model.md §3), the run's simulate stage.
 * Starts from the current state: a new simulation takes it as the rest shape with zero
 * velocities; a resumed one (--input of a dynamic file at a simulated frame) continues with
 * that file's rest shape, velocities and time. Each frame is timed on its own (--repeat
 * times from the same state); the observables and the file's frames are taken between the
 * timed frames, outside them. Memory does not grow with the frame count: one host frame. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "app/run.h"
#include "dynamic/dyn_followers.h"
#include "dynamic/dyn_lod.h"
#include "runtime/host.h"

/* What the frames cost beside their timed simulation: --render-points' rendering of each
 * frame written, and computing the observables. */
typedef struct {
    double *render_ms;
    int64_t n_render;
    double observe_ms;
} frame_costs;

/* --frame-loop and --draw: each runs F more frames after the timed ones. */
static int64_t frames_after(const hb_options *o)
{
    return (o->frame_loop ? 1 : 0) + (o->draw_w ? 1 : 0);
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


/* resume: the input frame's velocities and rest shape, its global frame index, and (into the
 * output) the velocities and observables the input holds up to that frame */
static int resume_from_input(hb_run *r, void *rest, void **vel, int64_t *paper_frames, int64_t *gf0, char *err,
                             size_t errlen)
{
    const hb_options *o = r->o;
    const int64_t step = r->in.frames[o->input_frame].step;
    int vi = -1;
    for (int i = 0; i < r->in.n_vel; i++)
        if (r->in.vel_step[i] == step) vi = i;
    if (vi < 0) {
        snprintf(err, errlen,
                 "--input %s: frame %d has no stored velocities, so the simulation cannot resume "
                 "from it (write the file with --velocities all, or resume from its last frame)",
                 o->input, o->input_frame);
        return HB_EXIT_USAGE;
    }
    *paper_frames = r->in.paper_frames;
    *gf0 = step - *paper_frames + 1;
    *vel = malloc(hb_state_bytes(&o->scene));
    if (!*vel) {
        snprintf(err, errlen, "out of host memory for the input's velocities");
        return HB_EXIT_MEMORY;
    }
    HB_TRY(hb_input_read_rest(&r->in, rest, err, errlen), HB_EXIT_USAGE);
    HB_TRY(hb_input_read_velocity(&r->in, vi, *vel, err, errlen), HB_EXIT_USAGE);
    if (!r->w) return HB_EXIT_OK;
    char *hv = r->host;
    for (int i = 0; i < r->in.n_vel; i++)
        if (o->all_velocities && r->in.vel_step[i] <= step) {
            HB_TRY(hb_input_read_velocity(&r->in, i, hv, err, errlen), HB_EXIT_USAGE);
            HB_TRY(hb_writer_velocity(r->w, hv, r->in.vel_step[i], r->in.vel_time[i], err, errlen), HB_EXIT_RUNTIME);
        }
    for (int i = 0; i < r->in.n_obs; i++)
        if (r->in.obs_step[i] <= step)
            HB_TRY(hb_writer_observables(r->w, &r->in.obs[i], r->in.obs_step[i], r->in.obs_time[i], err, errlen),
                   HB_EXIT_RUNTIME);
    return HB_EXIT_OK;
}

/* After frame j (global frame gf) is timed: its observables, and what the file keeps of it
 * (every --output-every-th frame and the last, with velocities where asked). */
static int keep_frame(hb_run *r, hb_stage_record *sr, int64_t j, int64_t gf, int64_t paper_frames, const double *ft,
                      frame_costs *c, char *err, size_t errlen)
{
    hb_backend *b = r->b;
    const hb_options *o = r->o;
    const hb_scene *s = &o->scene;
    const hb_dynamics *d = &s->dyn;
    hb_observables obs;
    const double t0 = hb_now_ms();
    HB_TRY(b->dyn_observe(b, &obs, err, errlen), HB_EXIT_RUNTIME);
    c->observe_ms += hb_now_ms() - t0;
    const int64_t step = paper_frames - 1 + gf;
    const double time = (double)gf * d->frame_dt;
    sr->last = obs;
    sr->blown_frames += hb_obs_blown_up(&obs);
    r->sim.last_frame = gf;
    double ms;
    if (!r->w) {
        if (d->render_points) { /* §3.14: no file: every frame is rendered (and dropped), so its cost shows */
            HB_TRY(render_frame(r, 0, &ms, err, errlen), HB_EXIT_RUNTIME);
            c->render_ms[c->n_render++] = ms;
        }
        return HB_EXIT_OK;
    }
    HB_TRY(hb_writer_observables(r->w, &obs, step, time, err, errlen), HB_EXIT_RUNTIME);
    if (j % o->output_every != 0 && j != o->frames) return HB_EXIT_OK;
    hb_frame_meta m;
    hb_frame_meta_init(&m, HB_STAGE_SIMULATE, s, b->name, o->variant);
    hb_time_stats(ft, o->repeat, &m.median_ms, &m.min_ms, &m.max_ms);
    m.step = step;
    m.time = time;
    const int vel = o->all_velocities || j == o->frames;
    if (d->render_points) { /* §3.14: the rendered points, and their velocities */
        HB_TRY(render_frame(r, vel, &ms, err, errlen), HB_EXIT_RUNTIME);
        c->render_ms[c->n_render++] = ms;
        HB_TRY(hb_writer_append(r->w, r->render, &m, err, errlen), HB_EXIT_RUNTIME);
        if (vel) HB_TRY(hb_writer_velocity(r->w, r->vrender, step, time, err, errlen), HB_EXIT_RUNTIME);
        return HB_EXIT_OK;
    }
    HB_TRY(b->fetch(b, r->host, &ms, err, errlen), HB_EXIT_RUNTIME);
    HB_TRY(hb_writer_append(r->w, r->host, &m, err, errlen), HB_EXIT_RUNTIME);
    if (vel) {
        HB_TRY(b->dyn_fetch_velocity(b, r->host, err, errlen), HB_EXIT_RUNTIME);
        HB_TRY(hb_writer_velocity(r->w, r->host, step, time, err, errlen), HB_EXIT_RUNTIME);
    }
    return HB_EXIT_OK;
}

/* --frame-loop and --draw: F more frames each from the final state, after everything of the
 * timed frames is written, their tables made here as for any frame. */
static int run_after(hb_run *r, hb_stage_record *sr, int64_t gf0, char *err, size_t errlen)
{
    hb_backend *b = r->b;
    const hb_options *o = r->o;
    const hb_scene *s = &o->scene;
    sr->loop_ms = sr->loop_graph_ms = NAN;
    const int64_t after = frames_after(o);
    if (after > 0 && (o->frames > INT32_MAX || gf0 + (1 + after) * o->frames > (INT64_C(1) << 53) / s->dyn.substeps)) {
        snprintf(err, errlen, "%s: --frames %lld is too many frames to run again",
                 o->draw_w ? "--draw" : "--frame-loop", (long long)o->frames);
        return HB_EXIT_USAGE;
    }
    hb_dyn_frame *plans = NULL;
    int64_t n_plans = 0;
    int status = HB_EXIT_OK;
    int64_t next = gf0 + o->frames; /* the global frame the next of these runs starts from */
    if (o->frame_loop) {            /* the frames an application would run next */
        if (frame_plans(s, next, o->frames, &plans, &n_plans, err, errlen)) status = HB_EXIT_MEMORY;
        else if (b->dyn_loop(b, plans, (int)o->frames, &sr->loop_ms, &sr->loop_graph_ms, err, errlen))
            status = HB_EXIT_RUNTIME;
        next += o->frames;
    }
    if (status == HB_EXIT_OK && o->draw_w) { /* each simulated and drawn on the device (docs/interfaces.md) */
        if (frame_plans(s, next, o->frames, &plans, &n_plans, err, errlen)) status = HB_EXIT_MEMORY;
        else if (b->dyn_draw(b, plans, (int)o->frames, o->draw_w, o->draw_h, o->draw_image, &sr->draw, err, errlen))
            status = HB_EXIT_RUNTIME;
        else sr->drawn = 1;
    }
    for (int64_t j = 0; j < n_plans; j++) hb_dyn_frame_free(&plans[j]);
    free(plans);
    return status;
}

/* The frames from the rest shape `rest` (and `plan`, one frame's tables): loaded, each timed,
 * observed and kept, then the F more of --frame-loop and --draw. */
static int simulate_frames(hb_run *r, hb_stage_record *sr, int frame, double *times, void *rest, void **vel,
                           hb_dyn_frame *plan, frame_costs *c, char *err, size_t errlen)
{
    hb_backend *b = r->b;
    const hb_options *o = r->o;
    const hb_scene *s = &o->scene;
    const hb_dynamics *d = &s->dyn;
    const int need_save = o->repeat > 1 || o->warmup > 0;
    int64_t gf0 = 0, paper_frames = frame;
    if (r->have_input && r->in.dynamic && o->input_frame >= r->in.paper_frames) {
        const int status = resume_from_input(r, rest, vel, &paper_frames, &gf0, err, errlen);
        if (status != HB_EXIT_OK) return status;
    } else {
        double ms;
        HB_TRY(b->fetch(b, rest, &ms, err, errlen), HB_EXIT_RUNTIME);
    }
    if (gf0 + o->frames > (INT64_C(1) << 53) / d->substeps) {
        snprintf(err, errlen,
                 "--frames %lld x --substeps %lld from frame %lld passes 2^53 substeps: times would "
                 "no longer be exact",
                 (long long)o->frames, (long long)d->substeps, (long long)gf0);
        return HB_EXIT_USAGE;
    }
    const double t_end = (double)(gf0 + (1 + frames_after(o)) * o->frames) * d->frame_dt;
    HB_TRY(hb_dynamics_validate_time(s, t_end, err, errlen), HB_EXIT_USAGE);
    HB_TRY(b->dyn_load(b, *vel, rest, err, errlen), HB_EXIT_RUNTIME);
    memcpy(sr->layout, b->layout, sizeof sr->layout);
    if (r->w) HB_TRY(hb_writer_rest(r->w, hb_run_as_written(r, rest), err, errlen), HB_EXIT_RUNTIME);

    r->sim.dynamic = 1;
    r->sim.paper_frames = paper_frames;
    hb_dyn_scene_feature_names(s, r->sim.features, sizeof r->sim.features);
    snprintf(sr->features, sizeof sr->features, "%s", r->sim.features);
    sr->frames = o->frames;
    sr->times_ms = times;
    sr->n_times = (int)(o->frames * o->repeat);
    for (int64_t j = 1; j <= o->frames; j++) {
        const int64_t gf = gf0 + j;
        hb_dyn_frame_plan(s, (gf - 1) * d->substeps, plan);
        if (need_save) HB_TRY(b->save(b, err, errlen), HB_EXIT_RUNTIME);
        double *ft = times + (j - 1) * o->repeat;
        for (int k = 0; k < o->warmup + o->repeat; k++) {
            if (k > 0) HB_TRY(b->restore(b, err, errlen), HB_EXIT_RUNTIME);
            hb_stage_result res = {0, -1, 1};
            HB_TRY(b->dyn_frame(b, plan, &res, err, errlen), HB_EXIT_RUNTIME);
            if (k >= o->warmup) ft[k - o->warmup] = res.ms;
        }
        const int status = keep_frame(r, sr, j, gf, paper_frames, ft, c, err, errlen);
        if (status != HB_EXIT_OK) return status;
    }
    sr->observe_ms = c->observe_ms;
    sr->render_ms = NAN;
    if (c->n_render > 0) {
        double lo, hi;
        hb_time_stats(c->render_ms, (int)c->n_render, &sr->render_ms, &lo, &hi);
    }
    hb_time_stats(sr->times_ms, sr->n_times, &sr->meta.median_ms, &sr->meta.min_ms, &sr->meta.max_ms);
    return run_after(r, sr, gf0, err, errlen);
}

int hb_run_simulate(hb_run *r, hb_stage_record *sr, int frame, double *times, char *err, size_t errlen)
{
    const hb_options *o = r->o;
    const hb_scene *s = &o->scene;
    void *rest = malloc(hb_state_bytes(s)), *vel = NULL;
    hb_dyn_frame plan;
    memset(&plan, 0, sizeof plan);
    frame_costs c = {NULL, 0, 0.0}; /* --render-points: each written frame's rendering time */
    int status;
    if (s->dyn.render_points && !(c.render_ms = malloc((size_t)o->frames * sizeof *c.render_ms))) {
        snprintf(err, errlen, "out of host memory for the rendering times");
        status = HB_EXIT_MEMORY;
    } else if (!rest || hb_dyn_frame_alloc(&plan, s->dyn.substeps) != 0 || hb_dyn_frame_alloc_world(&plan, s) != 0) {
        snprintf(err, errlen, "out of host memory for the simulation's rest shape and substep tables");
        status = HB_EXIT_MEMORY;
    } else {
        status = simulate_frames(r, sr, frame, times, rest, &vel, &plan, &c, err, errlen);
    }
    hb_dyn_frame_free(&plan);
    free(rest);
    free(vel);
    free(c.render_ms);
    return status;
}
