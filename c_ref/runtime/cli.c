/* cli.c — strict command-line parsing: every number is checked whole (no trailing junk,
 * no NaN, no overflow) and every error names its flag. */
#include "runtime/cli.h"

#include <errno.h>
#include <inttypes.h>
#include <math.h>
#include <stddef.h>
#include <stdlib.h>
#include <string.h>

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

/* ---- the dynamic model's flags (docs/model.md §3), one table -------------------------- */
typedef enum { DF_REAL, DF_COUNT, DF_SOLVER, DF_MOTION, DF_SWITCH, DF_FOLLOW, DF_OPTREAL, DF_FLAG } dyn_kind;
typedef struct {
    const char *flag;
    dyn_kind kind;
    size_t offset;   /* into hb_dynamics */
    size_t declares; /* an int in hb_dynamics set to 1 when the flag is given (0: none) */
    const char *help;
} dyn_flag;

#define DYN(field) offsetof(hb_dynamics, field)
static const dyn_flag dyn_flags[] = {
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
};
#undef DYN
#define N_DYN_FLAGS (sizeof dyn_flags / sizeof dyn_flags[0])

const char *hb_dyn_flag_name(int i)
{
    return i >= 0 && i < (int)N_DYN_FLAGS ? dyn_flags[i].flag : NULL;
}

int hb_dyn_flag_differs(int i, const hb_dynamics *a, const hb_dynamics *b)
{
    const dyn_flag *df = &dyn_flags[i];
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
    }
    return 0;
}

int hb_dyn_flag_index(const char *flag)
{
    for (size_t i = 0; i < N_DYN_FLAGS; i++)
        if (strcmp(dyn_flags[i].flag, flag) == 0) return (int)i;
    return -1;
}

void hb_print_usage(FILE *f, const char *prog, const char *backend)
{
    int cuda = strcmp(backend, "cuda") == 0;
    fprintf(f,
            "usage: %s [options]\n"
            "Hair-strand simulation (%s backend) with two models (docs/model.md): the paper model's one-shot\n"
            "stages init, collide and wind, and the dynamic model's time-stepped simulate stage. Writes HDF5\n"
            "states and a JSON record (docs/interfaces.md).\n"
            "\nscene:\n"
            "  --strands N          number of strands (default 1000)\n"
            "  --points P           points per strand incl. the root, >= 2 (default 32)\n"
            "  --seed S             64-bit RNG seed (default 1)\n"
            "  --head-radius R      head sphere radius (default 10; with --groom FILE only with --head-center)\n"
            "  --head-center X,Y,Z  with --groom FILE: the head sphere's centre in the file's cm, not fitted\n"
            "                       to the roots; R then defaults to the smallest root distance from it\n"
            "  --hair-offset H      shell offset above the head (default 0.1)\n"
            "  --hair-length L      strand length; L/(P-1) must be >= H (default 30)\n"
            "  --face-margin M      face margin of the root draw (default 1)\n"
            "  --wind-strength W    wind strength in [0, 1] (default 0.5)\n"
            "  --wind-angle PSI     wind direction, radians from +z toward +y (default pi)\n"
            "  --stages LIST        comma-separated, in order: init,collide,wind of the paper model (repeats\n"
            "                       allowed, init first), then simulate of the dynamic model, once and last\n"
            "                       (default init,collide,wind,collide)\n"
            "  --precision P        fp32 or fp64 (default fp32)\n"
            "  --groom G            init places a groom, not the drape: 'curly' (helices) or a HAIR file\n"
            "                       (docs/model.md §3.15; per-segment rest lengths, stages init,simulate)\n"
            "  --curl-radius C      with --groom curly: helix radius, cm (default 1)\n"
            "  --curl-pitch Q       with --groom curly: advance per turn along the root normal, cm (default 2)\n"
            "\nrun:\n"
            "  --variant NAME       %s\n"
            "%s"
            "  --input FILE         resume from the last frame of FILE\n"
            "  --output FILE        write the HDF5 state (refuses an existing file unless --force)\n"
            "  --force              allow replacing --output\n"
            "  --repeat K           time each stage K times from the same input (default 1)\n"
            "  --warmup W           untimed runs before the timed ones (default 1 if K > 1, else 0)\n"
            "  --end-to-end         also time one whole pass (transfers included)\n"
            "  --json               print the run record as one JSON object on stdout\n"
            "  --quiet              no summary on stderr\n"
            "  --measure-bandwidth  only measure the %s copy bandwidth (GB/s, read + write)\n"
            "  --self-test rng      print the Philox4x32-10 known-answer checks and exit\n"
            "  --list-variants      print this binary's variants, the stages each runs and its build as JSON\n"
            "  --batch FILE         run each line of FILE (a run's flags, separated by tabs) in this one\n"
            "                       process, in order, until one fails; no other flag with it\n"
            "  --input-frame K      with --input: resume after frame K of the file (default: its last)\n"
            "  --help, --version\n",
            prog, backend, "kernel variant (--list-variants names them)",
            cuda ? "  --block-size B       threads per block, 32..1024 (default 256)\n"
                 : "  --threads T          OpenMP threads over strands (default: all cores)\n",
            cuda ? "device-to-device" : "all-core memory");
    fprintf(f, "\nthe simulate stage (docs/model.md §3; a feature left undeclared is not evaluated):\n"
               "  --frames F           frames to simulate (default 1)\n"
               "  --output-every K     write every K-th simulated frame; the last always (default 1)\n"
               "  --velocities W       last | all: write the velocities of the last or of every written frame\n"
               "  --frame-loop         after the run, time F more frames back to back as an application's frame\n"
               "                       loop would (launches and the frame's tables included; cuda only)\n"
               "  --motion-track FILE  with --head-motion track: the head's transform track, a CSV file\n"
               "                       (docs/interfaces.md, \"Motion tracks\"; translation must be zero)\n");
    for (size_t i = 0; i < N_DYN_FLAGS; i++) {
        char name[64];
        snprintf(name, sizeof name, "%s%s", dyn_flags[i].flag,
                 dyn_flags[i].kind == DF_SWITCH || dyn_flags[i].kind == DF_FLAG ? ""
                 : dyn_flags[i].kind == DF_OPTREAL                              ? " [S]"
                                                                                : " V");
        fprintf(f, "  %-20s %s\n", name, dyn_flags[i].help);
    }
}

#define FAIL(...)                                                                                                      \
    do {                                                                                                               \
        snprintf(err, errlen, __VA_ARGS__);                                                                            \
        return -1;                                                                                                     \
    } while (0)

/* The one grammar of every number on the command line (docs/interfaces.md, "Numbers"):
 * [+-]digits[.digits][(e|E)[+-]digits] or [+-].digits[…], decimal only; no spaces, hex,
 * inf or nan. Returns 1 when v matches it, and *plain = 1 when it is [+-]digits alone. */
static int decimal_syntax(const char *v, int *plain)
{
    const char *c = v;
    if (*c == '+' || *c == '-') c++;
    int digits = 0, dot = 0, expo = 0;
    for (; *c >= '0' && *c <= '9'; c++) digits++;
    if (*c == '.') {
        dot = 1;
        for (c++; *c >= '0' && *c <= '9'; c++) digits++;
    }
    if (!digits) return 0;
    if (*c == 'e' || *c == 'E') {
        expo = 1;
        c++;
        if (*c == '+' || *c == '-') c++;
        if (!(*c >= '0' && *c <= '9')) return 0;
        while (*c >= '0' && *c <= '9') c++;
    }
    *plain = !dot && !expo;
    return *c == '\0';
}

static int parse_i64(const char *flag, const char *v, int64_t lo, int64_t *out, char *err, size_t errlen)
{
    char *end;
    int plain;
    if (!decimal_syntax(v, &plain)) FAIL("%s needs a whole number (got '%s')", flag, v);
    errno = 0;
    long long x = strtoll(v, &end, 10);
    if (!plain) {
        /* accept 1e6-style integers */
        double d = strtod(v, &end);
        if (end == v || *end != '\0' || !isfinite(d) || d != floor(d) || fabs(d) > 9.2e18)
            FAIL("%s needs a whole number (got '%s')", flag, v);
        x = (long long)d;
    } else if (errno == ERANGE) {
        FAIL("%s is out of range (got '%s')", flag, v);
    }
    if (x < lo) FAIL("%s must be at least %lld (got %lld)", flag, (long long)lo, x);
    *out = x;
    return 0;
}

static int parse_u64(const char *flag, const char *v, uint64_t *out, char *err, size_t errlen)
{
    char *end;
    int plain;
    if (!decimal_syntax(v, &plain)) FAIL("%s needs a whole number (got '%s')", flag, v);
    if (v[0] == '-') FAIL("%s needs a non-negative whole number (got '%s')", flag, v);
    errno = 0;
    if (!plain) { /* 1e6-style, as for the other whole numbers */
        double d = strtod(v, &end);
        if (d != floor(d) || !(d < 18446744073709551616.0)) FAIL("%s needs a whole number (got '%s')", flag, v);
        *out = (uint64_t)d;
        return 0;
    }
    unsigned long long x = strtoull(v, &end, 10); /* base 10: 010 is ten */
    if (errno == ERANGE) FAIL("%s is out of range (got '%s')", flag, v);
    *out = x;
    return 0;
}

static int parse_f64(const char *flag, const char *v, double *out, char *err, size_t errlen)
{
    char *end;
    int plain;
    errno = 0;
    double x = strtod(v, &end);
    if (end != v && *end == '\0' && !isfinite(x)) FAIL("%s must be finite (got '%s')", flag, v);
    if (!decimal_syntax(v, &plain)) FAIL("%s needs a decimal number (got '%s')", flag, v);
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

static int parse_dyn(const dyn_flag *df, const char *v, hb_options *o, char *err, size_t errlen)
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
        if (parse_i64(df->flag, v, 1, &iv, err, errlen)) return -1;
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
    }
    if (df->declares) *(int *)(base + df->declares) = 1;
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

int hb_parse_args(int argc, char **argv, const char *backend, hb_options *o, char *err, size_t errlen)
{
    int cuda = strcmp(backend, "cuda") == 0;
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
        if (strcmp(a, "--force") == 0) {
            o->force = 1;
            continue;
        }
        if (strcmp(a, "--json") == 0) {
            o->json = 1;
            continue;
        }
        if (strcmp(a, "--quiet") == 0) {
            o->quiet = 1;
            continue;
        }
        if (strcmp(a, "--end-to-end") == 0) {
            o->end_to_end = 1;
            continue;
        }
        if (strcmp(a, "--frame-loop") == 0) {
            o->frame_loop = 1;
            continue;
        }
        if (strcmp(a, "--measure-bandwidth") == 0) {
            o->measure_bandwidth = 1;
            continue;
        }
        if (strcmp(a, "--list-variants") == 0) {
            o->list_variants = 1;
            continue;
        }
        {
            int di = hb_dyn_flag_index(a);
            if (di >= 0 && (dyn_flags[di].kind == DF_SWITCH || dyn_flags[di].kind == DF_FLAG ||
                            dyn_flags[di].kind == DF_OPTREAL)) {
                /* an optional value follows when the next word is a number */
                const char *v = "";
                char *end = NULL;
                if (dyn_flags[di].kind == DF_OPTREAL && i + 1 < argc && strncmp(argv[i + 1], "--", 2) != 0) {
                    (void)strtod(argv[i + 1], &end);
                    if (end != argv[i + 1] && *end == '\0') v = argv[++i];
                }
                if (parse_dyn(&dyn_flags[di], v, o, err, errlen)) return -1;
                o->dyn_given |= 1ull << di;
                continue;
            }
        }
        if (strncmp(a, "--", 2) != 0) FAIL("unexpected argument '%s' (see --help)", a);
        /* every other flag takes a value: --flag V or --flag=V */
        const char *eq = strchr(a, '=');
        char name[64];
        const char *v;
        if (eq) {
            size_t n = (size_t)(eq - a);
            if (n >= sizeof name) FAIL("unknown flag '%s' (see --help)", a);
            memcpy(name, a, n);
            name[n] = '\0';
            v = eq + 1;
        } else {
            if (strlen(a) >= sizeof name) FAIL("unknown flag '%s' (see --help)", a);
            strcpy(name, a);
            if (i + 1 >= argc || strncmp(argv[i + 1], "--", 2) == 0) FAIL("%s needs a value", name);
            v = argv[++i];
        }
        int64_t iv;
        hb_scene *s = &o->scene;
        const int di = hb_dyn_flag_index(name);
        if (di >= 0) {
            if (dyn_flags[di].kind == DF_SWITCH || dyn_flags[di].kind == DF_FLAG) FAIL("%s takes no value", name);
            if (parse_dyn(&dyn_flags[di], v, o, err, errlen)) return -1;
            o->dyn_given |= 1ull << di;
        } else if (strcmp(name, "--frames") == 0) {
            if (parse_i64(name, v, 1, &o->frames, err, errlen)) return -1;
            o->dyn_given |= HB_DYN_GIVEN_RUN;
        } else if (strcmp(name, "--output-every") == 0) {
            if (parse_i64(name, v, 1, &o->output_every, err, errlen)) return -1;
            o->dyn_given |= HB_DYN_GIVEN_RUN;
        } else if (strcmp(name, "--velocities") == 0) {
            if (strcmp(v, "all") == 0) o->all_velocities = 1;
            else if (strcmp(v, "last") == 0) o->all_velocities = 0;
            else FAIL("--velocities must be last or all (got '%s')", v);
            o->dyn_given |= HB_DYN_GIVEN_RUN;
        } else if (strcmp(name, "--input-frame") == 0) {
            if (parse_i64(name, v, 0, &iv, err, errlen)) return -1;
            if (iv > INT32_MAX) FAIL("--input-frame is out of range (got %lld)", (long long)iv);
            o->input_frame = (int)iv;
        } else if (strcmp(name, "--strands") == 0) {
            if (parse_i64(name, v, 1, &s->n_strands, err, errlen)) return -1;
            o->given |= HB_GIVEN_STRANDS;
        } else if (strcmp(name, "--points") == 0) {
            if (parse_i64(name, v, 2, &s->points, err, errlen)) return -1;
            o->given |= HB_GIVEN_POINTS;
        } else if (strcmp(name, "--seed") == 0) {
            if (parse_u64(name, v, &s->seed, err, errlen)) return -1;
            o->given |= HB_GIVEN_SEED;
        } else if (strcmp(name, "--head-radius") == 0) {
            if (parse_f64(name, v, &s->head_radius, err, errlen)) return -1;
            o->given |= HB_GIVEN_RADIUS;
        } else if (strcmp(name, "--head-center") == 0) {
            if (parse_vec3(name, v, o->head_center, err, errlen)) return -1;
            o->given |= HB_GIVEN_CENTER;
        } else if (strcmp(name, "--hair-offset") == 0) {
            if (parse_f64(name, v, &s->hair_offset, err, errlen)) return -1;
            o->given |= HB_GIVEN_OFFSET;
        } else if (strcmp(name, "--hair-length") == 0) {
            if (parse_f64(name, v, &s->hair_length, err, errlen)) return -1;
            o->given |= HB_GIVEN_LENGTH;
        } else if (strcmp(name, "--face-margin") == 0) {
            if (parse_f64(name, v, &s->face_margin, err, errlen)) return -1;
            o->given |= HB_GIVEN_MARGIN;
        } else if (strcmp(name, "--wind-strength") == 0) {
            if (parse_f64(name, v, &s->wind_strength, err, errlen)) return -1;
        } else if (strcmp(name, "--wind-angle") == 0) {
            if (parse_f64(name, v, &s->wind_angle, err, errlen)) return -1;
            o->given |= HB_GIVEN_ANGLE;
        } else if (strcmp(name, "--stages") == 0) {
            if (parse_stages(v, o, err, errlen)) return -1;
        } else if (strcmp(name, "--precision") == 0) {
            if (strcmp(v, "fp32") == 0) s->precision = HB_FP32;
            else if (strcmp(v, "fp64") == 0) s->precision = HB_FP64;
            else FAIL("--precision must be fp32 or fp64 (got '%s')", v);
            o->given |= HB_GIVEN_PRECISION;
        } else if (strcmp(name, "--variant") == 0) {
            o->variant = v;
        } else if (strcmp(name, "--threads") == 0) {
            if (cuda) FAIL("--threads is a flag of hairsim-cpu; the cuda backend takes --block-size");
            if (parse_i64(name, v, 1, &iv, err, errlen)) return -1;
            if (iv > 4096) FAIL("--threads must be at most 4096 (got %lld)", (long long)iv);
            o->threads = (int)iv;
        } else if (strcmp(name, "--block-size") == 0) {
            if (!cuda) FAIL("--block-size is a flag of hairsim-cuda; the cpu backend takes --threads");
            if (parse_i64(name, v, 1, &iv, err, errlen)) return -1;
            if (iv < 32 || iv > 1024 || iv % 32 != 0)
                FAIL("--block-size must be a multiple of 32 from 32 to 1024 (got %lld)", (long long)iv);
            o->block_size = (int)iv;
        } else if (strcmp(name, "--input") == 0) {
            o->input = v;
        } else if (strcmp(name, "--groom") == 0) {
            if (v[0] == '\0') FAIL("--groom needs 'curly' or a HAIR file name");
            o->groom = v;
            s->groom = strcmp(v, "curly") == 0 ? HB_GROOM_CURLY : HB_GROOM_FILE;
        } else if (strcmp(name, "--motion-track") == 0) {
            if (v[0] == '\0') FAIL("--motion-track needs a CSV file name");
            o->motion_track = v;
        } else if (strcmp(name, "--curl-radius") == 0) {
            if (parse_f64(name, v, &s->curl_radius, err, errlen)) return -1;
            if (!(s->curl_radius >= 0.0)) FAIL("--curl-radius must be >= 0 (got %s)", v);
            o->given |= HB_GIVEN_CURL;
        } else if (strcmp(name, "--curl-pitch") == 0) {
            if (parse_f64(name, v, &s->curl_pitch, err, errlen)) return -1;
            if (!(s->curl_pitch >= 0.0)) FAIL("--curl-pitch must be >= 0 (got %s)", v);
            o->given |= HB_GIVEN_CURL;
        } else if (strcmp(name, "--output") == 0) {
            if (v[0] == '\0') FAIL("--output needs a file name");
            o->output = v;
        } else if (strcmp(name, "--repeat") == 0) {
            if (parse_i64(name, v, 1, &iv, err, errlen)) return -1;
            if (iv > 100000) FAIL("--repeat must be at most 100000 (got %lld)", (long long)iv);
            o->repeat = (int)iv;
        } else if (strcmp(name, "--warmup") == 0) {
            if (parse_i64(name, v, 0, &iv, err, errlen)) return -1;
            if (iv > 1000) FAIL("--warmup must be at most 1000 (got %lld)", (long long)iv);
            o->warmup = (int)iv;
        } else if (strcmp(name, "--self-test") == 0) {
            if (strcmp(v, "rng") != 0) FAIL("--self-test knows only 'rng' (got '%s')", v);
            o->self_test = v;
        } else {
            FAIL("unknown flag '%s' (see --help)", name);
        }
    }
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
        for (size_t i = 0; i < N_DYN_FLAGS; i++)
            if (o->dyn_given & (1ull << i))
                FAIL("%s belongs to the simulate stage, which --stages does not list", dyn_flags[i].flag);
        FAIL("--frames, --output-every and --velocities belong to the simulate stage, which --stages does not list");
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
    return 0;
}

/* The stage-list rule shared with the harness (harness/core/scenes.py parse_stages): no empty
 * item, so "init,,wind", ",init" and "init," are refused instead of skipped. */
int hb_stage_list_has_empty_item(const char *v)
{
    size_t n = strlen(v);
    return n == 0 || v[0] == ',' || v[n - 1] == ',' || strstr(v, ",,") != NULL;
}
