/* cli.c — strict command-line parsing: every number is checked whole (no trailing junk,
 * no NaN, no overflow) and every error names its flag. */
#include "runtime/cli.h"

#include <errno.h>
#include <inttypes.h>
#include <math.h>
#include <stddef.h>
#include <stdlib.h>
#include <string.h>

#include "runtime/checked.h"

void hb_default_options(hb_options *o)
{
    memset(o, 0, sizeof *o);
    o->scene.n_strands = 1000;
    o->scene.points = 32;
    o->scene.seed = 1;
    o->scene.head_radius = 10.0;
    o->scene.hair_offset = 0.1;
    o->scene.hair_length = 30.0;
    o->scene.face_margin = 1.0;
    o->scene.curl_radius = 1.0;
    o->scene.curl_pitch = 2.0;
    o->scene.wind_strength = 0.5;
    o->scene.wind_angle = M_PI;
    o->scene.precision = HB_FP32;
    o->stages[0] = HB_STAGE_INIT;
    o->stages[1] = HB_STAGE_COLLIDE;
    o->stages[2] = HB_STAGE_WIND;
    o->stages[3] = HB_STAGE_COLLIDE;
    o->n_stages = 4;
    o->block_size = 256;
    o->repeat = 1;
    o->warmup = -1;
    o->input_frame = -1;
    o->frames = 1;
    o->output_every = 1;
    hb_dynamics_defaults(&o->scene.dyn);
}

/* ---- every flag, one table (docs/interfaces.md "Command line", docs/model.md §3) ---------
 * Each entry names its flag, how its value is parsed, where it goes and its --help line. The
 * dynamic model's flags come last, in their own block: bit i of hb_options.dyn_given is the
 * i-th of them. A NULL flag is a heading of --help. */
typedef enum {
    /* the dynamic model's: `offset` into hb_dynamics, `declares` an int set to 1 when given */
    DF_REAL,
    DF_COUNT,
    DF_SOLVER,
    DF_MOTION,
    DF_SWITCH,
    DF_FOLLOW,
    DF_OPTREAL,
    DF_FLAG,
    DF_PAIR,    /* A[,B]: two doubles, B = A when omitted */
    DF_BOX,     /* six doubles X0,Y0,Z0,X1,Y1,Z1 */
    DF_REBUILD, /* frame | substep */
    DF_BODY,    /* still | sway | rise */
    DF_PATH,    /* a file name */
    /* the run's and the scene's: `offset` into hb_options */
    F_ON,       /* int set to 1, no value */
    F_I64,      /* int64_t in [lo, hi] (hi 0: no bound) */
    F_INT,      /* int in [lo, hi] */
    F_U64,      /* uint64_t, 0 to 2^64 - 1 */
    F_REAL,     /* double, finite */
    F_NONNEG,   /* double, finite, >= 0 */
    F_VEC3,     /* double[3], "X,Y,Z" */
    F_STAGES,   /* --stages */
    F_PREC,     /* --precision */
    F_VEL,      /* --velocities */
    F_DRAW,     /* --draw WxH */
    F_GROOM,    /* --groom: "curly" or a file */
    F_PATH,     /* const char *, not empty */
    F_WORD,     /* const char * */
    F_SELFTEST, /* --self-test rng */
    F_HELP,     /* --help, --version: printed, then exit 0 */
    F_BATCH     /* --batch FILE: alone on the command line (driver.c) */
} flag_kind;

typedef struct {
    const char *flag;
    flag_kind kind;
    size_t offset;
    size_t declares; /* DF_*: the offset of an int in hb_dynamics set to 1 when given (0: none) */
    const char *help;
    const char *arg;  /* F_*: the value's name in --help */
    int64_t lo, hi;   /* F_I64, F_INT: the range */
    unsigned given;   /* F_*: the HB_GIVEN_* bit it sets; HB_GIVEN_SIM: HB_DYN_GIVEN_RUN */
    const char *only; /* "cpu" or "cuda": the one backend that takes it */
} flag_spec;

#define HB_GIVEN_SIM (1u << 31)
#define OPT(field) offsetof(hb_options, field)
#define DYN(field) offsetof(hb_dynamics, field)
/* the dynamic flags' entries give the first five fields only */
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wmissing-field-initializers"
static const flag_spec flags[] = {
    {.help = "scene:"},
    {.flag = "--strands",
     .kind = F_I64,
     .offset = OPT(scene.n_strands),
     .arg = "N",
     .lo = 1,
     .given = HB_GIVEN_STRANDS,
     .help = "number of strands (default 1000)"},
    {.flag = "--points",
     .kind = F_I64,
     .offset = OPT(scene.points),
     .arg = "P",
     .lo = 2,
     .given = HB_GIVEN_POINTS,
     .help = "points per strand incl. the root, >= 2 (default 32)"},
    {.flag = "--seed",
     .kind = F_U64,
     .offset = OPT(scene.seed),
     .arg = "S",
     .given = HB_GIVEN_SEED,
     .help = "64-bit RNG seed (default 1)"},
    {.flag = "--head-radius",
     .kind = F_REAL,
     .offset = OPT(scene.head_radius),
     .arg = "R",
     .given = HB_GIVEN_RADIUS,
     .help = "head sphere radius (default 10; with --groom FILE only with --head-center)"},
    {.flag = "--head-center",
     .kind = F_VEC3,
     .offset = OPT(head_center),
     .arg = "X,Y,Z",
     .given = HB_GIVEN_CENTER,
     .help = "with --groom FILE: the head sphere's centre in the file's cm, not fitted\n"
             "to the roots; R then defaults to the smallest root distance from it"},
    {.flag = "--hair-offset",
     .kind = F_REAL,
     .offset = OPT(scene.hair_offset),
     .arg = "H",
     .given = HB_GIVEN_OFFSET,
     .help = "shell offset above the head (default 0.1)"},
    {.flag = "--hair-length",
     .kind = F_REAL,
     .offset = OPT(scene.hair_length),
     .arg = "L",
     .given = HB_GIVEN_LENGTH,
     .help = "strand length; L/(P-1) must be >= H (default 30)"},
    {.flag = "--face-margin",
     .kind = F_REAL,
     .offset = OPT(scene.face_margin),
     .arg = "M",
     .given = HB_GIVEN_MARGIN,
     .help = "face margin of the root draw (default 1)"},
    {.flag = "--wind-strength",
     .kind = F_REAL,
     .offset = OPT(scene.wind_strength),
     .arg = "W",
     .help = "wind strength in [0, 1] (default 0.5)"},
    {.flag = "--wind-angle",
     .kind = F_REAL,
     .offset = OPT(scene.wind_angle),
     .arg = "PSI",
     .given = HB_GIVEN_ANGLE,
     .help = "wind direction, radians from +z toward +y (default pi)"},
    {.flag = "--stages",
     .kind = F_STAGES,
     .arg = "LIST",
     .help = "comma-separated, in order: init,collide,wind of the paper model (repeats\n"
             "allowed, init first), then simulate of the dynamic model, once and last\n"
             "(default init,collide,wind,collide)"},
    {.flag = "--precision",
     .kind = F_PREC,
     .arg = "P",
     .given = HB_GIVEN_PRECISION,
     .help = "fp32 or fp64 (default fp32)"},
    {.flag = "--groom",
     .kind = F_GROOM,
     .offset = OPT(groom),
     .arg = "G",
     .help = "init places a groom, not the drape: 'curly' (helices) or a HAIR file\n"
             "(docs/model.md §3.15; per-segment rest lengths, stages init,simulate)"},
    {.flag = "--curl-radius",
     .kind = F_NONNEG,
     .offset = OPT(scene.curl_radius),
     .arg = "C",
     .given = HB_GIVEN_CURL,
     .help = "with --groom curly: helix radius, cm (default 1)"},
    {.flag = "--curl-pitch",
     .kind = F_NONNEG,
     .offset = OPT(scene.curl_pitch),
     .arg = "Q",
     .given = HB_GIVEN_CURL,
     .help = "with --groom curly: advance per turn along the root normal, cm (default 2)"},
    {.help = "run:"},
    {.flag = "--variant",
     .kind = F_WORD,
     .offset = OPT(variant),
     .arg = "NAME",
     .help = "kernel variant (--list-variants names them)"},
    {.flag = "--threads",
     .kind = F_INT,
     .offset = OPT(threads),
     .arg = "T",
     .lo = 1,
     .hi = 4096,
     .only = "cpu",
     .help = "OpenMP threads over strands (default: all cores)"},
    {.flag = "--block-size",
     .kind = F_INT,
     .offset = OPT(block_size),
     .arg = "B",
     .lo = 32,
     .hi = 1024,
     .only = "cuda",
     .help = "threads per block, a multiple of 32 from 32 to 1024 (default 256)"},
    {.flag = "--input",
     .kind = F_PATH,
     .offset = OPT(input),
     .arg = "FILE",
     .help = "resume from the last frame of FILE"},
    {.flag = "--output",
     .kind = F_PATH,
     .offset = OPT(output),
     .arg = "FILE",
     .help = "write the HDF5 state (refuses an existing file unless --force)"},
    {.flag = "--force", .kind = F_ON, .offset = OPT(force), .help = "allow replacing --output"},
    {.flag = "--repeat",
     .kind = F_INT,
     .offset = OPT(repeat),
     .arg = "K",
     .lo = 1,
     .hi = 100000,
     .help = "time each stage K times from the same input (default 1)"},
    {.flag = "--warmup",
     .kind = F_INT,
     .offset = OPT(warmup),
     .arg = "W",
     .lo = 0,
     .hi = 1000,
     .help = "untimed runs before the timed ones (default 1 if K > 1, else 0)"},
    {.flag = "--end-to-end",
     .kind = F_ON,
     .offset = OPT(end_to_end),
     .help = "also time one whole pass (transfers included)"},
    {.flag = "--json", .kind = F_ON, .offset = OPT(json), .help = "print the run record as one JSON object on stdout"},
    {.flag = "--quiet", .kind = F_ON, .offset = OPT(quiet), .help = "no summary on stderr"},
    {.flag = "--measure-bandwidth",
     .kind = F_ON,
     .offset = OPT(measure_bandwidth),
     .help = "only measure the copy bandwidth (GB/s, read + write; cpu: all-core\n"
             "memory, cuda: device-to-device)"},
    {.flag = "--self-test",
     .kind = F_SELFTEST,
     .offset = OPT(self_test),
     .arg = "rng",
     .help = "print the Philox4x32-10 known-answer checks and exit"},
    {.flag = "--list-variants",
     .kind = F_ON,
     .offset = OPT(list_variants),
     .help = "print this binary's variants, the stages each runs and its build as JSON"},
    {.flag = "--batch",
     .kind = F_BATCH,
     .arg = "FILE",
     .help = "run each line of FILE (a run's flags, separated by tabs) in this one\n"
             "process, in order, until one fails; no other flag with it"},
    {.flag = "--input-frame",
     .kind = F_INT,
     .offset = OPT(input_frame),
     .arg = "K",
     .lo = 0,
     .hi = INT32_MAX,
     .help = "with --input: resume after frame K of the file (default: its last)"},
    {.flag = "--help", .kind = F_HELP, .help = "this text (also -h)"},
    {.flag = "--version", .kind = F_HELP, .help = "the version"},
    {.flag = "--limits", .kind = F_HELP, .help = "the limits this binary checks its flags against, as one JSON object"},
    {.help = "the simulate stage (docs/model.md §3; a feature left undeclared is not evaluated):"},
    {.flag = "--frames",
     .kind = F_I64,
     .offset = OPT(frames),
     .arg = "F",
     .lo = 1,
     .given = HB_GIVEN_SIM,
     .help = "frames to simulate (default 1)"},
    {.flag = "--output-every",
     .kind = F_I64,
     .offset = OPT(output_every),
     .arg = "K",
     .lo = 1,
     .given = HB_GIVEN_SIM,
     .help = "write every K-th simulated frame; the last always (default 1)"},
    {.flag = "--velocities",
     .kind = F_VEL,
     .offset = OPT(all_velocities),
     .arg = "W",
     .given = HB_GIVEN_SIM,
     .help = "last | all: write the velocities of the last or of every written frame"},
    {.flag = "--frame-loop",
     .kind = F_ON,
     .offset = OPT(frame_loop),
     .help = "after the run, time F more frames back to back as an application's frame\n"
             "loop would (launches and the frame's tables included; cuda only)"},
    {.flag = "--motion-track",
     .kind = F_PATH,
     .offset = OPT(motion_track),
     .arg = "FILE",
     .help = "with --head-motion track: the head's transform track, a CSV file\n"
             "(docs/interfaces.md, \"Motion tracks\"; translation must be zero)"},
    {.flag = "--draw",
     .kind = F_DRAW,
     .arg = "WxH",
     .given = HB_GIVEN_SIM,
     .help = "after the run, simulate F more frames and draw each into a WxH image on\n"
             "the GPU, through OpenGL on EGL and through a CUDA rasteriser, timed\n"
             "(cuda only; docs/interfaces.md)"},
    {.flag = "--draw-image",
     .kind = F_PATH,
     .offset = OPT(draw_image),
     .arg = "PREFIX",
     .given = HB_GIVEN_SIM,
     .help = "with --draw: the last drawn frame of each path as PREFIX-gl.ppm and\n"
             "PREFIX-compute.ppm"},
    /* the dynamic model's flags (docs/model.md §3) */
    {"--frame-dt", DF_REAL, DYN(frame_dt), 0, "frame length Δt, s (default 1/60)"},
    {"--substeps", DF_COUNT, DYN(substeps), 0, "substeps S per frame (default 1)"},
    {"--iterations", DF_COUNT, DYN(iterations), 0, "solver iterations I per substep (default 1)"},
    {"--solver", DF_SOLVER, DYN(solver), 0, "xpbd | ftl | rigid (no dynamics; default xpbd)"},
    {"--gravity", DF_REAL, DYN(gravity), 0, "gravity g0, cm/s² (default 981)"},
    {"--drag", DF_REAL, DYN(drag), DYN(drag_declared), "air drag c_d toward the wind velocity, 1/s (default: none)"},
    {"--damping", DF_REAL, DYN(damping), DYN(drag_declared), "velocity damping β, 1/s (default: none)"},
    {"--stretch-compliance", DF_REAL, DYN(stretch_compliance), 0, "stretch compliance α_s (default 0: rigid)"},
    {"--bend-compliance", DF_REAL, DYN(bend_compliance), DYN(bend), "bend compliance α_b; declares bend"},
    {"--shape-compliance", DF_REAL, DYN(shape_compliance), DYN(shape), "shape compliance α_g; declares shape"},
    {"--shape-range", DF_REAL, DYN(shape_range), 0, "fraction ρ_g in (0, 1] of the strand held in shape (default 1)"},
    {"--ftl-damping", DF_REAL, DYN(ftl_damping), 0, "follow-the-leader damping s in [0, 1] (default 0.9)"},
    {"--collision-margin", DF_REAL, DYN(collision_margin), 0, "collider radius R + margin, cm (default 0)"},
    {"--no-collider", DF_SWITCH, DYN(collider), 0, "no head collision"},
    {"--wind-speed", DF_REAL, DYN(wind_speed), 0, "wind speed U, cm/s, along --wind-angle (default 0: none)"},
    {"--gust-amplitude", DF_REAL, DYN(gust_amplitude), 0, "relative gust amplitude A_g (default 0: none)"},
    {"--gust-frequency", DF_REAL, DYN(gust_frequency), 0, "gust frequency f_g, Hz (default 1)"},
    {"--gust-wavelength", DF_REAL, DYN(gust_wavelength), 0, "gust wavelength λ_g, cm (default 100)"},
    {"--head-motion", DF_MOTION, DYN(motion), 0, "still | nod | shake | tilt | track (--motion-track; default still)"},
    {"--motion-amplitude", DF_REAL, DYN(motion_amplitude), 0, "head motion amplitude A, radians (default 0.25)"},
    {"--motion-frequency", DF_REAL, DYN(motion_frequency), 0, "head motion frequency f, Hz (default 1)"},
    {"--guides", DF_REAL, DYN(guides), DYN(guided),
     "simulate only guides, a fraction in (0, 1] or a count > 1; the others follow"},
    {"--follow", DF_FOLLOW, DYN(follow), 0, "one | blend3: how followers are placed (default blend3)"},
    {"--sag-free", DF_FLAG, DYN(sag_free), 0, "shape targets that hold the groom's rest shape against gravity"},
    {"--lra", DF_OPTREAL, DYN(lra_scale), DYN(lra), "long-range attachments |p_k - p_0| <= S k l (S >= 1, default 1)"},
    {"--render-points", DF_COUNT, DYN(render_points), 0,
     "write P_r > P points a strand, a Catmull-Rom spline through the simulated ones; P_r - 1 a multiple of P - 1"},
    {"--grid", DF_COUNT, DYN(grid_n), DYN(grid),
     "hair-hair grid of N^3 nodes, 2..512 (docs/model.md §3.16); declares it"},
    {"--grid-rebuild", DF_REBUILD, DYN(grid_rebuild), 0,
     "frame | substep | held: when the grid is built and sampled (default frame)"},
    {"--grid-box", DF_BOX, DYN(grid_box), DYN(grid_box_given),
     "the grid's box X0,Y0,Z0,X1,Y1,Z1 in the head frame, cm (default: the rest shape's bounds + padding)"},
    {"--grid-padding", DF_REAL, DYN(grid_padding), 0, "padding b of the derived grid box, cm (default 2)"},
    {"--grid-friction", DF_PAIR, DYN(grid_friction), DYN(grid_friction_declared),
     "F[,F_TIP] in [0, 1]: blend toward the grid velocity, root to tip; declares hair-hair friction"},
    {"--grid-volume", DF_REAL, DYN(grid_volume), DYN(grid_volume_declared),
     "K, cm²/s²: push down the excess-density gradient; declares the volume term"},
    {"--colliders", DF_PATH, DYN(colliders_path), 0,
     "spheres, capsules, planes and meshes with friction, one a line (docs/model.md §3.17)"},
    {"--friction", DF_PAIR, DYN(friction), DYN(friction_declared),
     "MU_S[,MU_K]: the head sphere's Coulomb friction (default: frictionless)"},
    {"--depenetration-speed", DF_REAL, DYN(depen_speed), DYN(depen_declared),
     "V, cm/s: a point inside a collider at a substep's start leaves it at V at most (default: unbounded)"},
    {"--collider-sweeps", DF_COUNT, DYN(collider_sweeps), 0,
     "N in 1..8: the collision sweep (head sphere, then each collider) runs again while it moves a point, N\n"
     "sweeps at most (default 1; docs/model.md §3.17)"},
    {"--contact-planes", DF_REAL, DYN(contact_margin), DYN(planes_declared),
     "M, cm: each point finds its nearest collider within M once a frame and meets it as a plane in every\n"
     "collision step of the frame (default: every collider tested in every step; docs/model.md §3.17)"},
    {"--collide-once", DF_FLAG, DYN(collide_once), 0,
     "xpbd: the collision step (head sphere, colliders, friction) in the last of a substep's I iterations\n"
     "alone, not in every one (default: every iteration; docs/model.md §3.6)"},
    {"--body-motion", DF_BODY, DYN(body_motion), 0,
     "still | sway (along x) | rise (from A_b below, in 1/f_b s): the body frame's motion (default still)"},
    {"--body-amplitude", DF_REAL, DYN(body_amplitude), 0, "the body's sway or rise A_b, cm (default 2)"},
    {"--body-frequency", DF_REAL, DYN(body_frequency), 0,
     "the sway's frequency f_b, Hz, or the rise's 1/duration (default 1)"},
};
#pragma GCC diagnostic pop
#undef DYN
#undef OPT
#define N_FLAGS (sizeof flags / sizeof flags[0])

static int is_dyn(const flag_spec *f)
{
    return f->flag && f->kind <= DF_PATH;
}

/* The index in flags[] of the first dynamic flag (they end the table). */
static size_t first_dyn(void)
{
    size_t i = 0;
    while (i < N_FLAGS && !is_dyn(&flags[i])) i++;
    return i;
}

const char *hb_dyn_flag_name(int i)
{
    const size_t k = first_dyn() + (size_t)i;
    return i >= 0 && k < N_FLAGS ? flags[k].flag : NULL;
}

int hb_dyn_flag_differs(int i, const hb_dynamics *a, const hb_dynamics *b)
{
    const flag_spec *df = &flags[first_dyn() + (size_t)i];
    const char *pa = (const char *)a + df->offset, *pb = (const char *)b + df->offset;
    if (df->declares &&
        *(const int *)((const char *)a + df->declares) != *(const int *)((const char *)b + df->declares))
        return 1; /* declaring a feature changes the physics, whatever the value */
    switch (df->kind) {
    case DF_REAL: return *(const double *)pa != *(const double *)pb;
    case DF_COUNT: return *(const int64_t *)pa != *(const int64_t *)pb;
    case DF_SOLVER: return *(const hb_solver *)pa != *(const hb_solver *)pb;
    case DF_MOTION: return *(const hb_motion *)pa != *(const hb_motion *)pb;
    case DF_SWITCH: return *(const int *)pa != *(const int *)pb;
    case DF_FOLLOW: return *(const hb_follow *)pa != *(const hb_follow *)pb;
    case DF_OPTREAL: return *(const double *)pa != *(const double *)pb;
    case DF_FLAG: return *(const int *)pa != *(const int *)pb;
    case DF_PAIR: return memcmp(pa, pb, 2 * sizeof(double)) != 0;
    case DF_BOX: return memcmp(pa, pb, 6 * sizeof(double)) != 0;
    case DF_REBUILD:
    case DF_BODY: return *(const int *)pa != *(const int *)pb;
    case DF_PATH: return 1; /* a file's contents can change under its name: never taken as the same */
    default: return 0;
    }
}

static const flag_spec *find_flag(const char *name)
{
    for (size_t i = 0; i < N_FLAGS; i++)
        if (flags[i].flag && strcmp(flags[i].flag, name) == 0) return &flags[i];
    return NULL;
}

int hb_dyn_flag_index(const char *flag)
{
    const flag_spec *f = find_flag(flag);
    return f && is_dyn(f) ? (int)((size_t)(f - flags) - first_dyn()) : -1;
}

/* Whether the flag takes no value (an optional one for DF_OPTREAL). */
static int takes_no_value(const flag_spec *f)
{
    return f->kind == DF_SWITCH || f->kind == DF_FLAG || f->kind == F_ON || f->kind == DF_OPTREAL || f->kind == F_HELP;
}

void hb_print_usage(FILE *f, const char *prog, const char *backend)
{
    fprintf(f,
            "usage: %s [options]\n"
            "Hair-strand simulation (%s backend) with two models (docs/model.md): the paper model's one-shot\n"
            "stages init, collide and wind, and the dynamic model's time-stepped simulate stage. Writes HDF5\n"
            "states and a JSON record (docs/interfaces.md).\n",
            prog, backend);
    for (size_t i = 0; i < N_FLAGS; i++) {
        const flag_spec *fl = &flags[i];
        if (!fl->flag) {
            fprintf(f, "\n%s\n", fl->help);
            continue;
        }
        if (fl->only && strcmp(fl->only, backend) != 0) continue;
        char name[64];
        const char *arg = is_dyn(fl) ? (fl->kind == DF_SWITCH || fl->kind == DF_FLAG ? ""
                                        : fl->kind == DF_OPTREAL                     ? "[S]"
                                        : fl->kind == DF_PATH                        ? "FILE"
                                                                                     : "V")
                          : fl->arg  ? fl->arg
                                     : "";
        snprintf(name, sizeof name, "%s%s%s", fl->flag, arg[0] ? " " : "", arg);
        fprintf(f, "  %-20s ", name);
        for (const char *c = fl->help; *c; c++) /* a help of several lines: each under the first */
            if (*c == '\n') fprintf(f, "\n%23s", "");
            else fputc(*c, f);
        fputc('\n', f);
    }
}

#define FAIL(...)                                                                                                      \
    do {                                                                                                               \
        snprintf(err, errlen, __VA_ARGS__);                                                                            \
        return -1;                                                                                                     \
    } while (0)

/* The one grammar of every number on the command line (docs/interfaces.md, "Numbers"):
 * [+-]digits[.digits][(e|E)[+-]digits] or [+-].digits[…], decimal only; no spaces, hex,
 * inf or nan. Returns 1 when v matches it. */
static int decimal_syntax(const char *v)
{
    const char *c = v;
    if (*c == '+' || *c == '-') c++;
    int digits = 0;
    for (; *c >= '0' && *c <= '9'; c++) digits++;
    if (*c == '.')
        for (c++; *c >= '0' && *c <= '9'; c++) digits++;
    if (!digits) return 0;
    if (*c == 'e' || *c == 'E') {
        c++;
        if (*c == '+' || *c == '-') c++;
        if (!(*c >= '0' && *c <= '9')) return 0;
        while (*c >= '0' && *c <= '9') c++;
    }
    return *c == '\0';
}

/* A number of the one grammar read exactly as a whole number, with no rounding through a
 * double: 0 with its sign and magnitude; 1 when it is not whole (a non-zero digit below the
 * units once the exponent is applied); 2 when its magnitude exceeds 2^64 - 1. */
static int exact_whole(const char *v, int *neg, uint64_t *mag)
{
    const char *c = v;
    *neg = *c == '-';
    if (*c == '+' || *c == '-') c++;
    const char *digits = c;
    int64_t n_int = 0, n_all = 0;
    for (; (*c >= '0' && *c <= '9') || *c == '.'; c++)
        if (*c != '.') n_all++;
        else n_int = n_all + 1; /* marks the point: n_int - 1 digits before it */
    n_int = n_int ? n_int - 1 : n_all;
    int64_t e = 0; /* clamped: beyond it every non-zero number is out of range or not whole */
    if (*c == 'e' || *c == 'E') {
        c++;
        const int eneg = *c == '-';
        if (*c == '+' || *c == '-') c++;
        for (; *c >= '0' && *c <= '9'; c++)
            if (e < 100000000) e = 10 * e + (*c - '0');
        if (eneg) e = -e;
    }
    uint64_t m = 0;
    int64_t j = 0; /* the digit's index: its place is 10^(n_int - 1 - j + e) */
    for (const char *d = digits; d < c && *d != 'e' && *d != 'E'; d++) {
        if (*d == '.') continue;
        const int64_t place = n_int - 1 - j++ + e;
        if (place < 0) {
            if (*d != '0') return 1;
            continue;
        }
        if (hb_mul_u64(m, 10u, &m) || hb_add_u64(m, (uint64_t)(*d - '0'), &m)) return 2;
    }
    for (int64_t place = n_int - n_all + e; place > 0 && m != 0; place--)
        if (hb_mul_u64(m, 10u, &m)) return 2;
    *mag = m;
    return 0;
}

static int parse_i64(const char *flag, const char *v, int64_t lo, int64_t hi, int64_t *out, char *err, size_t errlen)
{
    int neg;
    uint64_t m;
    if (!decimal_syntax(v)) FAIL("%s needs a whole number (got '%s')", flag, v);
    const int r = exact_whole(v, &neg, &m);
    if (r == 1) FAIL("%s needs a whole number (got '%s')", flag, v);
    if (r == 2 || m > (neg ? (uint64_t)INT64_MAX + 1u : (uint64_t)INT64_MAX))
        FAIL("%s is out of range (got '%s')", flag, v);
    const int64_t x = neg ? (int64_t)(0u - m) : (int64_t)m;
    if (x < lo) FAIL("%s must be at least %lld (got %s)", flag, (long long)lo, v);
    if (hi && x > hi) FAIL("%s must be at most %lld (got %s)", flag, (long long)hi, v);
    *out = x;
    return 0;
}

static int parse_u64(const char *flag, const char *v, uint64_t *out, char *err, size_t errlen)
{
    int neg;
    uint64_t m;
    if (!decimal_syntax(v)) FAIL("%s needs a whole number (got '%s')", flag, v);
    const int r = exact_whole(v, &neg, &m);
    if (r == 1) FAIL("%s needs a whole number (got '%s')", flag, v);
    if (r == 2) FAIL("%s is out of range (got '%s')", flag, v);
    if (neg && m) FAIL("%s needs a non-negative whole number (got '%s')", flag, v);
    *out = m;
    return 0;
}

static int parse_f64(const char *flag, const char *v, double *out, char *err, size_t errlen)
{
    char *end;
    errno = 0;
    double x = strtod(v, &end);
    if (end != v && *end == '\0' && !isfinite(x)) FAIL("%s must be finite (got '%s')", flag, v);
    if (!decimal_syntax(v)) FAIL("%s needs a decimal number (got '%s')", flag, v);
    if (!isfinite(x)) FAIL("%s must be finite (got '%s')", flag, v);
    *out = x;
    return 0;
}

/* "X,Y,Z": three finite decimal numbers. */
static int parse_vec3(const char *flag, const char *v, double out[3], char *err, size_t errlen)
{
    char item[64];
    const char *p = v;
    for (int c = 0; c < 3; c++) {
        const char *comma = strchr(p, ',');
        const size_t n = comma ? (size_t)(comma - p) : strlen(p);
        if ((c < 2) != (comma != NULL) || n == 0 || n >= sizeof item)
            FAIL("%s needs three numbers X,Y,Z (got '%s')", flag, v);
        memcpy(item, p, n);
        item[n] = '\0';
        if (parse_f64(flag, item, &out[c], err, errlen)) return -1;
        p = comma ? comma + 1 : p + n;
    }
    return 0;
}

/* "A,B,…": exactly n finite decimal numbers (n_min … n_max of them; the rest copy the last). */
static int parse_list(const char *flag, const char *v, double *out, int n_min, int n_max, char *err, size_t errlen)
{
    char item[64];
    const char *p = v;
    int n = 0;
    while (1) {
        const char *comma = strchr(p, ',');
        const size_t len = comma ? (size_t)(comma - p) : strlen(p);
        if (len == 0 || len >= sizeof item || n == n_max) {
            if (n_min == n_max) FAIL("%s needs %d numbers separated by commas (got '%s')", flag, n_max, v);
            FAIL("%s needs %d to %d numbers separated by commas (got '%s')", flag, n_min, n_max, v);
        }
        memcpy(item, p, len);
        item[len] = '\0';
        if (parse_f64(flag, item, &out[n++], err, errlen)) return -1;
        if (!comma) break;
        p = comma + 1;
    }
    if (n < n_min) {
        if (n_min == n_max) FAIL("%s needs %d numbers separated by commas (got '%s')", flag, n_max, v);
        FAIL("%s needs %d to %d numbers separated by commas (got '%s')", flag, n_min, n_max, v);
    }
    for (int i = n; i < n_max; i++) out[i] = out[n - 1];
    return 0;
}

int hb_parse_number(const char *what, const char *v, double *out, char *err, size_t errlen)
{
    return parse_f64(what, v, out, err, errlen);
}

static int parse_dyn(const flag_spec *df, const char *v, hb_options *o, char *err, size_t errlen)
{
    char *base = (char *)&o->scene.dyn;
    int64_t iv;
    switch (df->kind) {
    case DF_REAL: {
        /* a ratio "a/b" is taken as a / b in double (e.g. --frame-dt 1/60) */
        const char *slash = strchr(v, '/');
        if (slash && slash != v) {
            char num[64];
            double a, b2;
            if ((size_t)(slash - v) >= sizeof num) FAIL("%s needs a number (got '%s')", df->flag, v);
            memcpy(num, v, (size_t)(slash - v));
            num[slash - v] = '\0';
            if (parse_f64(df->flag, num, &a, err, errlen) || parse_f64(df->flag, slash + 1, &b2, err, errlen))
                return -1;
            if (b2 == 0.0) FAIL("%s: division by zero in '%s'", df->flag, v);
            *(double *)(base + df->offset) = a / b2;
        } else if (parse_f64(df->flag, v, (double *)(base + df->offset), err, errlen)) {
            return -1;
        }
        break;
    }
    case DF_COUNT:
        if (parse_i64(df->flag, v, 1, 0, &iv, err, errlen)) return -1;
        *(int64_t *)(base + df->offset) = iv;
        break;
    case DF_SOLVER:
        if (strcmp(v, "xpbd") == 0) o->scene.dyn.solver = HB_SOLVER_XPBD;
        else if (strcmp(v, "ftl") == 0) o->scene.dyn.solver = HB_SOLVER_FTL;
        else if (strcmp(v, "rigid") == 0) o->scene.dyn.solver = HB_SOLVER_RIGID;
        else FAIL("--solver must be xpbd, ftl or rigid (got '%s')", v);
        break;
    case DF_MOTION:
        if (strcmp(v, "still") == 0) o->scene.dyn.motion = HB_MOTION_STILL;
        else if (strcmp(v, "nod") == 0) o->scene.dyn.motion = HB_MOTION_NOD;
        else if (strcmp(v, "shake") == 0) o->scene.dyn.motion = HB_MOTION_SHAKE;
        else if (strcmp(v, "tilt") == 0) o->scene.dyn.motion = HB_MOTION_TILT;
        else if (strcmp(v, "track") == 0) o->scene.dyn.motion = HB_MOTION_TRACK;
        else FAIL("--head-motion must be still, nod, shake, tilt or track (got '%s')", v);
        break;
    case DF_SWITCH: *(int *)(base + df->offset) = 0; break;
    case DF_FOLLOW:
        if (strcmp(v, "one") == 0) o->scene.dyn.follow = HB_FOLLOW_ONE;
        else if (strcmp(v, "blend3") == 0) o->scene.dyn.follow = HB_FOLLOW_BLEND3;
        else FAIL("--follow must be one or blend3 (got '%s')", v);
        break;
    case DF_FLAG: *(int *)(base + df->offset) = 1; break;
    case DF_OPTREAL: /* no value: the default stays */
        if (v[0] && parse_f64(df->flag, v, (double *)(base + df->offset), err, errlen)) return -1;
        break;
    case DF_PAIR:
        if (parse_list(df->flag, v, (double *)(base + df->offset), 1, 2, err, errlen)) return -1;
        break;
    case DF_BOX:
        if (parse_list(df->flag, v, (double *)(base + df->offset), 6, 6, err, errlen)) return -1;
        break;
    case DF_REBUILD:
        if (strcmp(v, "frame") == 0) o->scene.dyn.grid_rebuild = HB_GRID_FRAME;
        else if (strcmp(v, "substep") == 0) o->scene.dyn.grid_rebuild = HB_GRID_SUBSTEP;
        else if (strcmp(v, "held") == 0) o->scene.dyn.grid_rebuild = HB_GRID_HELD;
        else FAIL("--grid-rebuild must be frame, substep or held (got '%s')", v);
        break;
    case DF_BODY:
        if (strcmp(v, "still") == 0) o->scene.dyn.body_motion = HB_BODY_STILL;
        else if (strcmp(v, "sway") == 0) o->scene.dyn.body_motion = HB_BODY_SWAY;
        else if (strcmp(v, "rise") == 0) o->scene.dyn.body_motion = HB_BODY_RISE;
        else FAIL("--body-motion must be still, sway or rise (got '%s')", v);
        break;
    case DF_PATH:
        if (v[0] == '\0') FAIL("%s needs a file name", df->flag);
        *(const char **)(base + df->offset) = v;
        break;
    default: FAIL("%s: not a flag of the simulate stage", df->flag);
    }
    if (df->declares) *(int *)(base + df->declares) = 1;
    o->dyn_given |= 1ull << ((size_t)(df - flags) - first_dyn());
    return 0;
}

static int parse_stages(const char *v, hb_options *o, char *err, size_t errlen)
{
    char buf[1024];
    if (strlen(v) >= sizeof buf) FAIL("--stages is too long");
    strcpy(buf, v);
    if (hb_stage_list_has_empty_item(v)) FAIL("--stages: empty item in '%s' (write e.g. init,collide,wind)", v);
    o->n_stages = 0;
    char *save = NULL;
    for (char *tok = strtok_r(buf, ",", &save); tok; tok = strtok_r(NULL, ",", &save)) {
        hb_stage s;
        if (strcmp(tok, "init") == 0) s = HB_STAGE_INIT;
        else if (strcmp(tok, "wind") == 0) s = HB_STAGE_WIND;
        else if (strcmp(tok, "collide") == 0) s = HB_STAGE_COLLIDE;
        else if (strcmp(tok, "simulate") == 0) s = HB_STAGE_SIMULATE;
        else FAIL("--stages: unknown stage '%s' (known: init, collide, wind, simulate)", tok);
        if (o->n_stages == HB_MAX_STAGES) FAIL("--stages: at most %d stages", HB_MAX_STAGES);
        if (s == HB_STAGE_INIT && o->n_stages > 0)
            FAIL("--stages: init may only come first (it would replace the state)");
        o->stages[o->n_stages++] = s;
    }
    if (o->n_stages == 0) FAIL("--stages needs at least one stage");
    return 0;
}

/* A run or scene flag's value into o (the flags of flags[] that are not the dynamic model's). */
static int parse_run_flag(const flag_spec *fl, const char *v, const char *backend, hb_options *o, char *err,
                          size_t errlen)
{
    char *at = (char *)o + fl->offset;
    const char *name = fl->flag;
    int64_t iv;
    if (fl->only && strcmp(fl->only, backend) != 0)
        FAIL("%s is a flag of hairsim-%s; the %s backend takes %s", name, fl->only, backend,
             strcmp(backend, "cuda") == 0 ? "--block-size" : "--threads");
    switch (fl->kind) {
    case F_ON: *(int *)at = 1; break;
    case F_I64:
        if (parse_i64(name, v, fl->lo, fl->hi, (int64_t *)at, err, errlen)) return -1;
        break;
    case F_INT:
        if (parse_i64(name, v, fl->lo, fl->hi, &iv, err, errlen)) return -1;
        if (fl->offset == offsetof(hb_options, block_size) && iv % HB_BLOCK_MULTIPLE != 0)
            FAIL("--block-size must be a multiple of %d from %lld to %lld (got %s)", HB_BLOCK_MULTIPLE,
                 (long long)fl->lo, (long long)fl->hi, v);
        *(int *)at = (int)iv;
        break;
    case F_U64:
        if (parse_u64(name, v, (uint64_t *)at, err, errlen)) return -1;
        break;
    case F_REAL:
    case F_NONNEG:
        if (parse_f64(name, v, (double *)at, err, errlen)) return -1;
        if (fl->kind == F_NONNEG && !(*(double *)at >= 0.0)) FAIL("%s must be >= 0 (got %s)", name, v);
        break;
    case F_VEC3:
        if (parse_vec3(name, v, (double *)at, err, errlen)) return -1;
        break;
    case F_STAGES:
        if (parse_stages(v, o, err, errlen)) return -1;
        break;
    case F_PREC:
        if (strcmp(v, "fp32") == 0) o->scene.precision = HB_FP32;
        else if (strcmp(v, "fp64") == 0) o->scene.precision = HB_FP64;
        else FAIL("--precision must be fp32 or fp64 (got '%s')", v);
        break;
    case F_VEL:
        if (strcmp(v, "all") == 0) o->all_velocities = 1;
        else if (strcmp(v, "last") == 0) o->all_velocities = 0;
        else FAIL("--velocities must be last or all (got '%s')", v);
        break;
    case F_DRAW: { /* WxH, each a whole number of pixels in 16..16384 */
        char *x = NULL;
        const long w = strtol(v, &x, 10);
        char *end = NULL;
        const long h = x && *x == 'x' ? strtol(x + 1, &end, 10) : 0;
        if (!(x && *x == 'x' && end && *end == '\0' && x != v && end != x + 1 && v[0] >= '0' && v[0] <= '9' &&
              x[1] >= '0' && x[1] <= '9') ||
            w < 16 || h < 16 || w > 16384 || h > 16384)
            FAIL("--draw needs WIDTHxHEIGHT in pixels, each 16..16384 (got '%s')", v);
        o->draw_w = (int)w;
        o->draw_h = (int)h;
        break;
    }
    case F_GROOM:
        if (v[0] == '\0') FAIL("--groom needs 'curly' or a HAIR file name");
        o->groom = v;
        o->scene.groom = strcmp(v, "curly") == 0 ? HB_GROOM_CURLY : HB_GROOM_FILE;
        break;
    case F_PATH:
        if (v[0] == '\0') FAIL("%s needs a file name", name);
        *(const char **)at = v;
        break;
    case F_WORD: *(const char **)at = v; break;
    case F_SELFTEST:
        if (strcmp(v, "rng") != 0) FAIL("--self-test knows only 'rng' (got '%s')", v);
        o->self_test = v;
        break;
    case F_BATCH: FAIL("--batch FILE takes no other flag (each line of FILE holds a run's flags)");
    default: FAIL("%s: not a run or scene flag", name);
    }
    if (fl->given == HB_GIVEN_SIM) o->dyn_given |= HB_DYN_GIVEN_RUN;
    else o->given |= fl->given;
    return 0;
}

/* The rules between flags, once all are read. */
static int check_combinations(hb_options *o, char *err, size_t errlen)
{
    if (o->warmup < 0) o->warmup = o->repeat > 1 ? 1 : 0;
    /* simulate runs once, last: the paper stages assume a strand in its slice plane */
    int sim = 0;
    for (int i = 0; i < o->n_stages; i++)
        if (o->stages[i] == HB_STAGE_SIMULATE) {
            if (sim || i != o->n_stages - 1) FAIL("--stages: simulate may appear once, as the last stage");
            sim = 1;
        }
    if (!sim && o->motion_track) FAIL("--motion-track belongs to the simulate stage, which --stages does not list");
    if (o->motion_track && o->scene.dyn.motion != HB_MOTION_TRACK) FAIL("--motion-track needs --head-motion track");
    if (o->scene.dyn.motion == HB_MOTION_TRACK && (o->dyn_given & (1ull << hb_dyn_flag_index("--motion-amplitude") |
                                                                   1ull << hb_dyn_flag_index("--motion-frequency"))))
        FAIL("--motion-amplitude and --motion-frequency shape nod, shake and tilt, not --head-motion track");
    if (!sim && o->dyn_given) {
        for (int i = 0; hb_dyn_flag_name(i); i++)
            if (o->dyn_given & (1ull << i))
                FAIL("%s belongs to the simulate stage, which --stages does not list", hb_dyn_flag_name(i));
        FAIL("--frames, --output-every, --velocities and --draw belong to the simulate stage, which --stages does not "
             "list");
    }
    if (!o->scene.dyn.guided && (o->dyn_given & (1ull << hb_dyn_flag_index("--follow"))))
        FAIL("--follow needs --guides (every strand is simulated unless --guides is given)");
    if ((o->given & HB_GIVEN_CURL) && o->scene.groom != HB_GROOM_CURLY)
        FAIL("--curl-radius and --curl-pitch need --groom curly");
    if ((o->given & HB_GIVEN_CENTER) && o->scene.groom != HB_GROOM_FILE)
        FAIL("--head-center needs --groom FILE (a HAIR file; the drape and the curly groom have their head at 0,0,0)");
    o->scene.dyn.per_segment = o->groom != NULL;
    if (o->scene.dyn.sag_free && !o->scene.dyn.shape)
        FAIL("--sag-free needs --shape-compliance (it moves the shape targets)");
    if (o->scene.dyn.shape == 0 && (o->dyn_given & (1ull << hb_dyn_flag_index("--shape-range"))))
        FAIL("--shape-range needs --shape-compliance (shape is off unless its compliance is given)");
    {
        static const char *const needs_grid[] = {"--grid-rebuild", "--grid-box", "--grid-padding", "--grid-friction",
                                                 "--grid-volume"};
        for (size_t i = 0; i < sizeof needs_grid / sizeof needs_grid[0]; i++)
            if (!o->scene.dyn.grid && (o->dyn_given & (1ull << hb_dyn_flag_index(needs_grid[i]))))
                FAIL("%s needs --grid N (the hair-hair grid is off unless its size is given)", needs_grid[i]);
        static const char *const needs_body[] = {"--body-amplitude", "--body-frequency"};
        for (size_t i = 0; i < sizeof needs_body / sizeof needs_body[0]; i++)
            if (o->scene.dyn.body_motion == HB_BODY_STILL &&
                (o->dyn_given & (1ull << hb_dyn_flag_index(needs_body[i]))))
                FAIL("%s needs --body-motion sway or rise", needs_body[i]);
        if (o->scene.dyn.friction_declared && !o->scene.dyn.collider)
            FAIL("--friction is the head sphere's friction, and --no-collider removes the head sphere");
    }
    return 0;
}

int hb_parse_args(int argc, char **argv, const char *backend, hb_options *o, char *err, size_t errlen)
{
    hb_default_options(o);
    for (int i = 1; i < argc; i++) {
        const char *a = argv[i];
        if (strcmp(a, "--help") == 0 || strcmp(a, "-h") == 0) {
            hb_print_usage(stdout, argv[0], backend);
            return 1;
        }
        if (strcmp(a, "--version") == 0) {
            printf("hairbench %s (%s backend)\n", HB_VERSION, backend);
            return 1;
        }
        if (strcmp(a, "--limits") == 0) {
            hb_print_limits(stdout, backend);
            return 1;
        }
        if (strncmp(a, "--", 2) != 0) FAIL("unexpected argument '%s' (see --help)", a);
        /* --flag V or --flag=V */
        const char *eq = strchr(a, '=');
        char name[64];
        const size_t n = eq ? (size_t)(eq - a) : strlen(a);
        if (n >= sizeof name) FAIL("unknown flag '%s' (see --help)", a);
        memcpy(name, a, n);
        name[n] = '\0';
        const flag_spec *fl = find_flag(name);
        if (!fl) FAIL("unknown flag '%s' (see --help)", name);
        const char *v = eq ? eq + 1 : "";
        if (takes_no_value(fl)) {
            if (eq && fl->kind != DF_OPTREAL) FAIL("%s takes no value", name);
            /* DF_OPTREAL: an optional value follows when the next word is a number */
            char *end = NULL;
            if (fl->kind == DF_OPTREAL && !eq && i + 1 < argc && strncmp(argv[i + 1], "--", 2) != 0) {
                (void)strtod(argv[i + 1], &end);
                if (end != argv[i + 1] && *end == '\0') v = argv[++i];
            }
        } else if (!eq) {
            if (i + 1 >= argc || strncmp(argv[i + 1], "--", 2) == 0) FAIL("%s needs a value", name);
            v = argv[++i];
        }
        if (is_dyn(fl) ? parse_dyn(fl, v, o, err, errlen) : parse_run_flag(fl, v, backend, o, err, errlen)) return -1;
    }
    return check_combinations(o, err, errlen);
}

void hb_print_limits(FILE *f, const char *backend)
{
    const flag_spec *block = find_flag("--block-size"), *threads = find_flag("--threads");
    fprintf(f, "{\"backend\": \"%s\", ", backend);
    fprintf(f, "\"strands_min\": %lld, \"points_min\": %lld, \"stages_max\": %d, ",
            (long long)find_flag("--strands")->lo, (long long)find_flag("--points")->lo, HB_MAX_STAGES);
    fprintf(f, "\"substeps_max\": %d, \"iterations_max\": %d, ", HB_COUNT_MAX, HB_COUNT_MAX);
    fprintf(f, "\"substep_s\": [%.15g, %.15g], ", HB_SUBSTEP_MIN_S, HB_SUBSTEP_MAX_S);
    fprintf(f, "\"grid_n\": [%d, %d], \"grid_points_max\": %llu, ", HB_GRID_N_MIN, HB_GRID_N_MAX,
            (unsigned long long)HB_GRID_POINTS_MAX);
    fprintf(f, "\"collider_sweeps\": [1, %d], ", HB_COLLIDER_SWEEPS_MAX);
    fprintf(f, "\"block_size\": {\"min\": %lld, \"max\": %lld, \"multiple\": %d}, ", (long long)block->lo,
            (long long)block->hi, HB_BLOCK_MULTIPLE);
    fprintf(f, "\"threads\": [%lld, %lld]}\n", (long long)threads->lo, (long long)threads->hi);
}

/* The stage-list rule shared with the harness (harness/core/scenes.py parse_stages): no empty
 * item, so "init,,wind", ",init" and "init," are refused instead of skipped. */
int hb_stage_list_has_empty_item(const char *v)
{
    size_t n = strlen(v);
    return n == 0 || v[0] == ',' || v[n - 1] == ',' || strstr(v, ",,") != NULL;
}
