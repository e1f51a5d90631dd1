/* cli.c — strict command-line parsing: every number is checked whole (no trailing junk,
 * no NaN, no overflow) and every error names its flag. */
#include "cli.h"

#include <errno.h>
#include <inttypes.h>
#include <math.h>
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
}

void hb_print_usage(FILE *f, const char *prog, const char *backend)
{
    int cuda = strcmp(backend, "cuda") == 0;
    fprintf(f,
            "usage: %s [options]\n"
            "Hair-strand simulation, DESIGN §3 paper model (%s backend). Writes HDF5 states (docs/interfaces.md).\n"
            "\nscene:\n"
            "  --strands N          number of strands (default 1000)\n"
            "  --points P           points per strand incl. the root, >= 2 (default 32)\n"
            "  --seed S             64-bit RNG seed (default 1)\n"
            "  --head-radius R      head sphere radius (default 10)\n"
            "  --hair-offset H      shell offset above the head (default 0.1)\n"
            "  --hair-length L      strand length; L/(P-1) must be >= H (default 30)\n"
            "  --face-margin M      face margin of the root draw (default 1)\n"
            "  --wind-strength W    wind strength in [0, 1] (default 0.5)\n"
            "  --wind-angle PSI     wind direction, radians from +z toward +y (default pi)\n"
            "  --stages LIST        ordered stages from init,collide,wind (default init,collide,wind,collide)\n"
            "  --precision P        fp32 or fp64 (default fp32)\n"
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
            "  --help, --version\n",
            prog, backend, "kernel variant (--list-variants names them)",
            cuda ? "  --block-size B       threads per block, 32..1024 (default 256)\n"
                 : "  --threads T          OpenMP threads over strands (default: all cores)\n",
            cuda ? "device-to-device" : "all-core memory");
}

#define FAIL(...) do { snprintf(err, errlen, __VA_ARGS__); return -1; } while (0)

static int parse_i64(const char *flag, const char *v, int64_t lo, int64_t *out, char *err, size_t errlen)
{
    char *end;
    errno = 0;
    long long x = strtoll(v, &end, 10);
    if (end == v || *end != '\0') {
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
    errno = 0;
    if (v[0] == '-') FAIL("%s needs a non-negative whole number (got '%s')", flag, v);
    unsigned long long x = strtoull(v, &end, 10); /* base 10: 010 is ten */
    if (end == v || *end != '\0') FAIL("%s needs a whole number (got '%s')", flag, v);
    if (errno == ERANGE) FAIL("%s is out of range (got '%s')", flag, v);
    *out = x;
    return 0;
}

static int parse_f64(const char *flag, const char *v, double *out, char *err, size_t errlen)
{
    char *end;
    errno = 0;
    double x = strtod(v, &end);
    if (end == v || *end != '\0') FAIL("%s needs a number (got '%s')", flag, v);
    if (!isfinite(x)) FAIL("%s must be finite (got '%s')", flag, v);
    *out = x;
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
        else FAIL("--stages: unknown stage '%s' (known: init, collide, wind)", tok);
        if (o->n_stages == HB_MAX_STAGES) FAIL("--stages: at most %d stages", HB_MAX_STAGES);
        if (s == HB_STAGE_INIT && o->n_stages > 0) FAIL("--stages: init may only come first (it would replace the state)");
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
        if (strcmp(a, "--force") == 0) { o->force = 1; continue; }
        if (strcmp(a, "--json") == 0) { o->json = 1; continue; }
        if (strcmp(a, "--quiet") == 0) { o->quiet = 1; continue; }
        if (strcmp(a, "--end-to-end") == 0) { o->end_to_end = 1; continue; }
        if (strcmp(a, "--measure-bandwidth") == 0) { o->measure_bandwidth = 1; continue; }
        if (strcmp(a, "--list-variants") == 0) { o->list_variants = 1; continue; }
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
        if (strcmp(name, "--strands") == 0) {
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
    return 0;
}

/* The stage-list rule shared with the harness (harness/scenes.py parse_stages): no empty
 * item, so "init,,wind", ",init" and "init," are refused instead of skipped. */
int hb_stage_list_has_empty_item(const char *v)
{
    size_t n = strlen(v);
    return n == 0 || v[0] == ',' || v[n - 1] == ',' || strstr(v, ",,") != NULL;
}
