/* driver.c — the run shared by every backend: parse, refuse bad input before any work,
 * run the listed stages (docs/model.md §2.6: only those), time them (§5.3), write the HDF5
 * state and the JSON record (docs/interfaces.md). */
#include <limits.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "app/backend.h"
#include "runtime/checked.h"
#include "runtime/cli.h"
#include "runtime/groom.h"
#include "dynamic/dyn_followers.h"
#include "dynamic/dyn_lod.h"
#include "dynamic/world.h"
#include "runtime/host.h"
#include "runtime/input.h"
#include "dynamic/motion_track.h"
#include "runtime/philox.h"
#include "app/record.h"
#include "runtime/safe_write.h"
#include "app/run.h"
#include "app/state_io.h"

static const char *g_prog = "hairsim";

static int die(int status, const char *msg)
{
    fprintf(stderr, "%s: error: %s\n", g_prog, msg);
    return status;
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
                            {"friction", "--friction or --depenetration-speed"},
                            {"planes", "--contact-planes"},
                            {"collideonce", "--collide-once"}};

/* The §3.14 features a scene declares, HB_X_* bits. */
static unsigned x_declared(const hb_dynamics *d)
{
    int friction = d->friction_declared || d->depen_declared;
    for (int i = 0; d->cols && i < d->cols->n; i++) friction |= d->cols->c[i].mu_s > 0.0;
    return (d->guided ? HB_X_GUIDES : 0u) | (d->lra ? HB_X_LRA : 0u) | (d->sag_free ? HB_X_SAGFREE : 0u) |
           (d->render_points ? HB_X_LOD : 0u) | (d->grid ? HB_X_GRID : 0u) | (d->colliders_path ? HB_X_COLLIDERS : 0u) |
           (friction ? HB_X_FRICTION : 0u) | (d->planes_declared ? HB_X_PLANES : 0u) |
           (d->collide_once ? HB_X_ONCE : 0u);
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
        ", \"guides\", \"lra\", \"sagfree\", \"lod\", \"grid\", \"colliders\", \"friction\", \"planes\"]}\n"); /* §3.14, §3.16, §3.17's */
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

void hb_frame_meta_init(hb_frame_meta *m, hb_stage st, const hb_scene *s, const char *backend, const char *variant)
{
    memset(m, 0, sizeof *m);
    snprintf(m->stage, sizeof m->stage, "%s", hb_stage_name(st));
    snprintf(m->backend, sizeof m->backend, "%s/%s", backend, variant);
    m->moved_points = -1;
    m->wind_strength = st == HB_STAGE_WIND ? s->wind_strength : NAN;
    m->wind_angle = st == HB_STAGE_WIND ? s->wind_angle : NAN;
}

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


const void *hb_run_as_written(hb_run *r, const void *state)
{
    const hb_scene *s = &r->o->scene;
    if (!s->dyn.render_points) return state;
    hb_lod_render(s->precision, state, NULL, s->n_strands, s->points, s->dyn.render_points, r->render, NULL);
    return r->render;
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

/* ---- refuse bad input before any work (docs/model.md §2.6) ---- */

/* The variant --variant names (the backend's default if none); it must run every stage listed. */
static int pick_variant(hb_options *o, const hb_backend *b, const hb_variant **var, char *err, size_t errlen)
{
    if (!o->variant) o->variant = b->default_variant;
    *var = NULL;
    for (const hb_variant *v = b->variants; v->name; v++)
        if (strcmp(v->name, o->variant) == 0) *var = v;
    if (!*var) {
        char list[256] = "";
        for (const hb_variant *v = b->variants; v->name; v++)
            snprintf(list + strlen(list), sizeof list - strlen(list), "%s%s", list[0] ? ", " : "", v->name);
        snprintf(err, errlen, "--variant %s is not a %s variant (known: %s)", o->variant, b->name, list);
        return -1;
    }
    for (int i = 0; i < o->n_stages; i++)
        if (!((*var)->stages & (1u << o->stages[i]))) {
            snprintf(err, errlen, "--stages: the %s variant %s does not run '%s' (see --list-variants)", b->name,
                     (*var)->name, hb_stage_name(o->stages[i]));
            return -1;
        }
    return 0;
}

/* Where the state comes from: --input (its scene adopted), --groom, the drape of init; and
 * the --colliders file. */
static int check_state_source(hb_run *r, char *err, size_t errlen)
{
    hb_options *o = r->o;
    if (o->input) {
        HB_TRY(hb_input_open(o->input, &r->in, err, errlen), HB_EXIT_USAGE);
        r->have_input = 1;
        HB_TRY(adopt_input_scene(o, &r->in.scene, r->in.dynamic, err, errlen), HB_EXIT_USAGE);
        for (int i = 0; i < o->n_stages; i++)
            if (o->stages[i] == HB_STAGE_INIT) {
                snprintf(err, errlen, "--stages: init cannot run on an --input state (it would replace it)");
                return HB_EXIT_USAGE;
            }
    }
    if (o->groom) {
        const int groom_status = check_groom(o, &r->groom, err, errlen);
        if (groom_status) return groom_status < 0 ? HB_EXIT_USAGE : groom_status;
    }
    if (o->scene.dyn.colliders_path && !o->scene.dyn.cols) { /* docs/model.md §3.17 (a resumed run has the file's) */
        HB_TRY(hb_colliders_load(o->scene.dyn.colliders_path, &r->cols, err, errlen), HB_EXIT_USAGE);
        o->scene.dyn.cols = &r->cols;
    }
    if (!o->input && o->stages[0] != HB_STAGE_INIT) {
        snprintf(err, errlen, "--stages: '%s' needs a state: list init first or give --input",
                 hb_stage_name(o->stages[0]));
        return HB_EXIT_USAGE;
    }
    HB_TRY(hb_scene_validate(&o->scene, err, errlen), HB_EXIT_USAGE);
    return HB_EXIT_OK;
}

/* simulate's physics, and what the variant runs of them (--list-variants); --frame-loop and
 * --draw only after simulate. */
static int check_simulate(hb_run *r, const hb_variant *var, int simulate, char *err, size_t errlen)
{
    hb_options *o = r->o;
    const hb_backend *b = r->b;
    if (!simulate) {
        if (o->frame_loop) return snprintf(err, errlen, "--frame-loop needs simulate in --stages"), HB_EXIT_USAGE;
        if (o->draw_w) return snprintf(err, errlen, "--draw needs simulate in --stages"), HB_EXIT_USAGE;
        return HB_EXIT_OK;
    }
    HB_TRY(adopt_track(o, r, err, errlen), HB_EXIT_USAGE);
    HB_TRY(hb_dynamics_validate(&o->scene.dyn, err, errlen), HB_EXIT_USAGE);
    HB_TRY(hb_dynamics_validate_scene(&o->scene, err, errlen), HB_EXIT_USAGE);
    if (o->end_to_end)
        return snprintf(err, errlen, "--end-to-end is not measured for simulate: its frames are timed one by one"),
               HB_EXIT_USAGE;
    if (var->max_points > 0 && o->scene.points > var->max_points)
        return snprintf(err, errlen,
                        "--points %lld: the %s variant %s simulates at most %lld points a strand (see --list-variants)",
                        (long long)o->scene.points, b->name, var->name, (long long)var->max_points),
               HB_EXIT_USAGE;
    if (!(hb_variant_solvers(var) & (1u << o->scene.dyn.solver)))
        return snprintf(err, errlen, "--solver %s: the %s variant %s does not run it (see --list-variants)",
                        hb_solver_name(o->scene.dyn.solver), b->name, var->name),
               HB_EXIT_USAGE;
    if (o->scene.dyn.per_segment && !var->per_segment)
        return snprintf(err, errlen,
                        "%s: the %s variant %s does not simulate a groom's per-segment rest lengths yet (docs/model.md "
                        "§3.15)",
                        o->groom ? "--groom" : "--input", b->name, var->name),
               HB_EXIT_USAGE;
    const unsigned lacking = x_declared(&o->scene.dyn) & var->lacks;
    for (int x = 0; x < HB_X_COUNT; x++)
        if (lacking & (1u << x))
            return snprintf(err, errlen, "--variant %s does not run %s (see --list-variants)", var->name,
                            x_features[x].flag),
                   HB_EXIT_USAGE;
    if (var->max_block > 0 && o->block_size > var->max_block)
        return snprintf(err, errlen,
                        "--block-size %d: the %s variant %s simulates with at most %d threads a block (see "
                        "--list-variants)",
                        o->block_size, b->name, var->name, var->max_block),
               HB_EXIT_USAGE;
    if ((o->frame_loop || o->draw_w) && (o->scene.dyn.grid || hb_dyn_has_world(&o->scene)))
        return snprintf(err, errlen, "%s does not yet run the grid and colliders (docs/model.md §3.16, §3.17)",
                        o->frame_loop ? "--frame-loop" : "--draw"),
               HB_EXIT_USAGE;
    if (o->frame_loop && !b->dyn_loop)
        return snprintf(err, errlen, "--frame-loop is measured by the cuda backend only"), HB_EXIT_USAGE;
    if (o->draw_w && !b->dyn_draw)
        return snprintf(err, errlen, "--draw draws on the GPU: the cuda backend only"), HB_EXIT_USAGE;
    return HB_EXIT_OK;
}

/* --input-frame (the input's last frame by default) and --output against --input. */
static int check_input_frame(hb_run *r, int simulate, char *err, size_t errlen)
{
    hb_options *o = r->o;
    if (o->input) {
        if (o->input_frame >= r->in.n_frames)
            return snprintf(err, errlen, "--input-frame %d: %s has frames 0 to %d", o->input_frame, o->input,
                            r->in.n_frames - 1),
                   HB_EXIT_USAGE;
        if (o->input_frame < 0) o->input_frame = r->in.n_frames - 1;
        if (r->in.dynamic && o->input_frame >= r->in.paper_frames && !simulate)
            return snprintf(err, errlen, "--stages: frame %d of %s is simulated; only simulate can follow it",
                            o->input_frame, o->input),
                   HB_EXIT_USAGE;
    } else if (o->input_frame >= 0) {
        return snprintf(err, errlen, "--input-frame needs --input"), HB_EXIT_USAGE;
    }
    if (o->output && o->input && same_file(o->output, o->input))
        return snprintf(err, errlen, "--output %s is the --input file; write to another name", o->output),
               HB_EXIT_USAGE;
    return HB_EXIT_OK;
}

static int check_run(hb_run *r, const hb_variant *var, int simulate, char *err, size_t errlen)
{
    int status = check_state_source(r, err, errlen);
    if (status == HB_EXIT_OK) status = check_simulate(r, var, simulate, err, errlen);
    if (status == HB_EXIT_OK && r->o->draw_image && !r->o->draw_w)
        status = (snprintf(err, errlen, "--draw-image needs --draw"), HB_EXIT_USAGE);
    if (status == HB_EXIT_OK) status = check_input_frame(r, simulate, err, errlen);
    return status;
}

/* --measure-bandwidth: the backend's copy (and triad) bandwidth, printed; no stage runs. */
static int print_bandwidth(hb_run *r, char *err, size_t errlen)
{
    hb_backend *b = r->b;
    hb_options *o = r->o;
    hb_record *rec = r->rec;
    double gbps = 0, bytes = 0, triad = NAN, triad_bytes = NAN;
    HB_TRY(b->measure_bandwidth(b, o, &gbps, &bytes, err, errlen), HB_EXIT_RUNTIME);
    if (b->measure_triad) HB_TRY(b->measure_triad(b, o, &triad, &triad_bytes, err, errlen), HB_EXIT_RUNTIME);
    b->describe(b, rec->device, sizeof rec->device, rec->driver, sizeof rec->driver);
    if (o->json) {
        printf("{\"backend\": \"%s\", \"copy_gbps\": %.6g, \"bytes\": %.17g", b->name, gbps, bytes);
        if (isfinite(triad)) printf(", \"triad_gbps\": %.6g, \"triad_bytes\": %.17g", triad, triad_bytes);
        if (b->threads > 0) printf(", \"threads\": %d", b->threads);
        printf(", \"device\": \"%s\"}\n", rec->device);
    } else {
        printf("%s copy bandwidth: %.1f GB/s (read + write, %.0f bytes per copy)", b->name, gbps, bytes);
        if (isfinite(triad)) printf("; triad %.1f GB/s (%.0f bytes)", triad, triad_bytes);
        printf(" on %s\n", rec->device);
    }
    return HB_EXIT_OK;
}

/* ---- the run's memory: the backend's state, the host frames, the times; the output opened ---- */
static int prepare_run(hb_run *r, int simulate, char *err, size_t errlen)
{
    hb_backend *b = r->b;
    hb_options *o = r->o;
    hb_record *rec = r->rec;
    const uint64_t bytes = hb_state_bytes(&o->scene);
    const int need_host = o->output != NULL || o->end_to_end || simulate;
    /* simulate: the rest shape and the velocities pass through the host once */
    /* --render-points: a rendered frame, its velocities and the simulated velocities */
    const int64_t pr = simulate ? o->scene.dyn.render_points : 0;
    const uint64_t render_bytes =
        pr ? hb_mul_sat(hb_mul_sat((uint64_t)o->scene.n_strands, (uint64_t)pr), 3u * hb_real_size(o->scene.precision))
           : 0;
    const uint64_t driver_bytes = hb_add_sat(
        hb_add_sat(hb_add_sat(need_host ? bytes : 0, o->input ? bytes : 0), simulate ? hb_mul_sat(bytes, 2u) : 0),
        hb_add_sat(hb_mul_sat(render_bytes, 2u), render_bytes ? bytes : 0));
    const int need_save = o->repeat > 1 || o->warmup > 0;
    const int status = b->setup(b, o, need_save, driver_bytes, err, errlen);
    if (status != HB_EXIT_OK) return status;
    b->describe(b, rec->device, sizeof rec->device, rec->driver, sizeof rec->driver);
    rec->flags = b->flags; /* setup may name the build that runs (cpu simd: x86-64-v3 or -v4) */
    rec->threads = b->threads;
    rec->block_size = b->block_size;
    if (need_host && !(r->host = malloc(bytes)))
        return snprintf(err, errlen, "cannot allocate the %llu-byte host frame", (unsigned long long)bytes),
               HB_EXIT_MEMORY;
    if (render_bytes &&
        (!(r->render = malloc(render_bytes)) || !(r->vrender = malloc(render_bytes)) || !(r->vhost = malloc(bytes))))
        return snprintf(err, errlen, "cannot allocate the %llu-byte rendered frames (--render-points)",
                        (unsigned long long)render_bytes),
               HB_EXIT_MEMORY;
    if (o->input && !(r->input = malloc(bytes)))
        return snprintf(err, errlen, "cannot allocate the %llu-byte input frame", (unsigned long long)bytes),
               HB_EXIT_MEMORY;
    /* one time per stage (or simulated frame) and repeat, counted by an int */
    uint64_t n_times, times_bytes;
    if (hb_add_u64((uint64_t)o->n_stages, simulate ? (uint64_t)o->frames : 0, &n_times) ||
        hb_mul_u64(n_times, (uint64_t)o->repeat, &n_times) || n_times > INT32_MAX ||
        hb_mul_u64(n_times, sizeof *r->times, &times_bytes))
        return snprintf(err, errlen, "--frames %lld x --repeat %lld is more timings than a run keeps (at most %d)",
                        (long long)(simulate ? o->frames : 0), (long long)o->repeat, INT32_MAX),
               HB_EXIT_USAGE;
    r->times = calloc((size_t)n_times, sizeof *r->times);
    if (!r->times) return snprintf(err, errlen, "out of host memory"), HB_EXIT_MEMORY;
    if (o->output) {
        int open_status;
        r->w = hb_writer_open(o->output, o->force, &o->scene, &open_status, err, errlen);
        if (!r->w) return open_status;
    }
    return HB_EXIT_OK;
}

/* ---- the input state: its frames go into the output first, its last loaded ---- */
static int load_input(hb_run *r, int *frame, char *err, size_t errlen)
{
    const hb_options *o = r->o;
    if (!o->input) return HB_EXIT_OK;
    const int last = o->input_frame;
    HB_TRY(hb_input_read_frame(&r->in, last, r->input, err, errlen), HB_EXIT_USAGE);
    for (int f = 0; r->w && f <= last; f++) {
        const void *src = r->input;
        if (f != last) {
            HB_TRY(hb_input_read_frame(&r->in, f, r->host, err, errlen), HB_EXIT_USAGE);
            src = r->host;
        }
        HB_TRY(hb_writer_append(r->w, hb_run_as_written(r, src), &r->in.frames[f], err, errlen), HB_EXIT_RUNTIME);
    }
    *frame = last + 1;
    double ms;
    HB_TRY(r->b->load(r->b, r->input, &ms, err, errlen), HB_EXIT_RUNTIME);
    return HB_EXIT_OK;
}

/* The backend's current state into the file (nothing without --output). */
static int write_current(hb_run *r, const hb_frame_meta *m, char *err, size_t errlen)
{
    if (!r->w) return 0;
    double ms;
    if (r->b->fetch(r->b, r->host, &ms, err, errlen)) return -1;
    return hb_writer_append(r->w, hb_run_as_written(r, r->host), m, err, errlen);
}

/* Paper stage i (frame `frame`), timed from the same input (docs/model.md §5.3), and what it
 * made into the file: a fused wind+collide runs two stages in one time, two frames. */
static int run_paper_stage(hb_run *r, int i, int frame, hb_stage_record *sr, double *times, int *consumed, char *err,
                           size_t errlen)
{
    hb_backend *b = r->b;
    hb_options *o = r->o;
    hb_record *rec = r->rec;
    if (o->repeat > 1 || o->warmup > 0) HB_TRY(b->save(b, err, errlen), HB_EXIT_RUNTIME);
    hb_stage_result res = {0, -1, 1};
    for (int j = 0; j < o->warmup + o->repeat; j++) {
        if (j > 0) HB_TRY(b->restore(b, err, errlen), HB_EXIT_RUNTIME);
        HB_TRY(b->run_stage(b, o->stages, i, o->n_stages, &res, err, errlen), HB_EXIT_RUNTIME);
        if (j >= o->warmup) times[j - o->warmup] = res.ms;
    }
    sr->times_ms = times;
    sr->n_times = o->repeat;
    hb_time_stats(sr->times_ms, sr->n_times, &sr->meta.median_ms, &sr->meta.min_ms, &sr->meta.max_ms);
    if (res.consumed == 2) {
        /* a fused wind+collide: one time for the pair, two frames */
        hb_stage_record *sc = &rec->stages[rec->n_stages++];
        snprintf(sr->meta.fused, sizeof sr->meta.fused, "wind+collide");
        sc->frame = frame + 1;
        sc->stage = o->stages[i + 1];
        hb_frame_meta_init(&sc->meta, sc->stage, &o->scene, b->name, o->variant);
        sc->meta.step = frame + 1;
        snprintf(sc->meta.fused, sizeof sc->meta.fused, "into-previous");
        sc->meta.moved_points = res.moved_points;
        if (r->w) {
            HB_TRY(b->fetch_intermediate(b, r->host, err, errlen), HB_EXIT_RUNTIME);
            HB_TRY(hb_writer_append(r->w, hb_run_as_written(r, r->host), &sr->meta, err, errlen), HB_EXIT_RUNTIME);
        }
        sr = sc;
    } else {
        sr->meta.moved_points = res.moved_points;
    }
    HB_TRY(write_current(r, &sr->meta, err, errlen), HB_EXIT_RUNTIME);
    *consumed = res.consumed;
    return HB_EXIT_OK;
}

/* ---- the stages in order from frame `frame`, simulate (the dynamic model's) last ---- */
static int run_stages(hb_run *r, int frame, char *err, size_t errlen)
{
    hb_backend *b = r->b;
    hb_options *o = r->o;
    hb_record *rec = r->rec;
    if (b->keep_intermediate) b->keep_intermediate(b, r->w != NULL);
    double *times = r->times;
    for (int i = 0; i < o->n_stages;) {
        hb_stage st = o->stages[i];
        hb_stage_record *sr = &rec->stages[rec->n_stages++];
        sr->frame = frame;
        sr->stage = st;
        hb_frame_meta_init(&sr->meta, st, &o->scene, b->name, o->variant);
        sr->meta.step = frame;
        if (st == HB_STAGE_SIMULATE) return hb_run_simulate(r, sr, frame, times, err, errlen);
        int consumed = 1;
        if (st == HB_STAGE_INIT && o->groom) {
            HB_TRY(place_groom(r, sr, times, err, errlen), HB_EXIT_RUNTIME);
            times += o->repeat;
        } else if (st == HB_STAGE_WIND && o->scene.wind_strength == 0.0) {
            /* a stage whose effect is nil is not launched (docs/model.md §2.6) */
            sr->meta.skipped = 1;
            HB_TRY(write_current(r, &sr->meta, err, errlen), HB_EXIT_RUNTIME);
        } else {
            const int status = run_paper_stage(r, i, frame, sr, times, &consumed, err, errlen);
            if (status != HB_EXIT_OK) return status;
            times += o->repeat;
        }
        frame += consumed;
        i += consumed;
    }
    return HB_EXIT_OK;
}

/* ---- one whole pass, transfers included, timed apart from the stages ---- */
static int run_end_to_end(hb_run *r, char *err, size_t errlen)
{
    hb_backend *b = r->b;
    hb_options *o = r->o;
    hb_record *rec = r->rec;
    if (b->keep_intermediate) b->keep_intermediate(b, 0);
    double t0 = hb_now_ms(), h2d = 0, d2h = 0;
    if (o->input) HB_TRY(b->load(b, r->input, &h2d, err, errlen), HB_EXIT_RUNTIME);
    for (int i = 0; i < o->n_stages;) {
        if (o->stages[i] == HB_STAGE_WIND && o->scene.wind_strength == 0.0) {
            i++;
            continue;
        }
        hb_stage_result res = {0, -1, 1};
        HB_TRY(b->run_stage(b, o->stages, i, o->n_stages, &res, err, errlen), HB_EXIT_RUNTIME);
        i += res.consumed;
    }
    HB_TRY(b->fetch(b, r->host, &d2h, err, errlen), HB_EXIT_RUNTIME);
    rec->end_to_end_ms = hb_now_ms() - t0;
    if (strcmp(b->name, "cpu") != 0) {
        rec->h2d_ms = o->input ? h2d : NAN;
        rec->d2h_ms = d2h;
    }
    return HB_EXIT_OK;
}

/* ---- the file's /parameters, then the file closed into place ---- */
static int close_output(hb_run *r, char *err, size_t errlen)
{
    const hb_backend *b = r->b;
    const hb_options *o = r->o;
    hb_record *rec = r->rec;
    hb_run_meta rm = {b->name,
                      o->variant,
                      rec->git_revision,
                      rec->compiler,
                      b->flags,
                      rec->device,
                      rec->driver,
                      rec->threads,
                      rec->block_size,
                      o->repeat,
                      o->warmup,
                      rec->end_to_end_ms,
                      0,
                      r->sim.dynamic,
                      r->sim.paper_frames,
                      r->sim.last_frame,
                      (int)o->output_every,
                      r->sim.features,
                      NULL,
                      {0.0, 0.0, 0.0}};
    if (o->scene.groom == HB_GROOM_FILE) {
        rm.groom_head = r->groom.head_given ? "given" : "fitted";
        memcpy(rm.groom_head_center, r->groom.head_center, sizeof rm.groom_head_center);
    }
    double t0 = hb_now_ms(), before = 1e3 * hb_writer_seconds(r->w);
    hb_writer *w = r->w;
    r->w = NULL;
    const int rc_close = hb_writer_close(w, &rm, err, errlen);
    if (rc_close) return rc_close == HB_SAFE_EXISTS ? HB_EXIT_USAGE : HB_EXIT_RUNTIME;
    rec->hdf5_write_ms = before + (hb_now_ms() - t0);
    return HB_EXIT_OK;
}

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
    static const char *const not_runs[] = {"--help", "-h", "--version", "--list-variants", "--limits", "--self-test"};
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

    const hb_variant *var;
    if (pick_variant(&o, b, &var, err, sizeof err)) return die(HB_EXIT_USAGE, err);

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

    int status;
    if (o.measure_bandwidth) {
        status = print_bandwidth(&run, err, sizeof err);
        run_free(&run);
        return status == HB_EXIT_OK ? HB_EXIT_OK : die(status, err);
    }
    const int simulate = o.stages[o.n_stages - 1] == HB_STAGE_SIMULATE;
    int frame = 0;
    status = check_run(&run, var, simulate, err, sizeof err);
    if (status == HB_EXIT_OK) {
        if (simulate) note_untuned(&o, &run);
        status = prepare_run(&run, simulate, err, sizeof err);
    }
    if (status == HB_EXIT_OK) status = load_input(&run, &frame, err, sizeof err);
    if (status == HB_EXIT_OK) status = run_stages(&run, frame, err, sizeof err);
    if (status == HB_EXIT_OK && o.end_to_end) status = run_end_to_end(&run, err, sizeof err);
    if (status == HB_EXIT_OK && run.w) status = close_output(&run, err, sizeof err);
    if (status != HB_EXIT_OK) {
        run_free(&run);
        return die(status, err);
    }
    if (o.json) hb_record_json(stdout, &rec);
    if (!o.quiet) hb_record_summary(stderr, &rec);
    run_free(&run);
    return hb_record_blown_frames(&rec) ? HB_EXIT_BLOWN_UP : HB_EXIT_OK;
}
