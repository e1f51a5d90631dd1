/* params.h — the scene parameters and run options shared by every backend (DESIGN §3, §8;
 * the flags are documented in docs/interfaces.md). */
#ifndef HB_PARAMS_H
#define HB_PARAMS_H

#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

#define HB_VERSION "0.1.0"
#define HB_MAX_STAGES 64
#define HB_ERRLEN 512

/* Exit statuses (docs/interfaces.md). */
enum { HB_EXIT_OK = 0, HB_EXIT_USAGE = 2, HB_EXIT_MEMORY = 3, HB_EXIT_RUNTIME = 4 };

typedef enum { HB_FP32 = 0, HB_FP64 = 1 } hb_precision;
typedef enum { HB_STAGE_INIT = 0, HB_STAGE_WIND = 1, HB_STAGE_COLLIDE = 2 } hb_stage;

/* The scene: everything that decides the bits of a state. */
typedef struct {
    int64_t n_strands;       /* N */
    int64_t points;          /* P, including the root */
    uint64_t seed;
    double head_radius;      /* R */
    double hair_offset;      /* h */
    double hair_length;      /* L */
    double face_margin;      /* m */
    double wind_strength;    /* w in [0, 1] */
    double wind_angle;       /* psi, radians from +z toward +y */
    hb_precision precision;
} hb_scene;

/* How a run is carried out: which stages, how timed, where written. */
typedef struct {
    hb_scene scene;
    hb_stage stages[HB_MAX_STAGES];
    int n_stages;
    const char *variant;     /* NULL: the backend's default */
    int threads;             /* cpu: 0 = all cores */
    int block_size;          /* cuda */
    const char *input;       /* NULL: start with init */
    const char *output;      /* NULL: no file */
    int force;
    int repeat;
    int warmup;              /* -1: default (1 if repeat > 1, else 0) */
    int json;
    int quiet;
    int end_to_end;          /* measure one extra untimed-by-stage pass */
    int measure_bandwidth;   /* only measure the copy bandwidth */
    const char *self_test;   /* "rng": print the known-answer checks */
    int list_variants;       /* print the backend's variants as JSON and exit */
    /* which scene flags the user gave explicitly (for --input consistency checks) */
    unsigned given;
} hb_options;

/* Bits of hb_options.given. */
enum {
    HB_GIVEN_STRANDS = 1u << 0, HB_GIVEN_POINTS = 1u << 1, HB_GIVEN_SEED = 1u << 2,
    HB_GIVEN_RADIUS = 1u << 3, HB_GIVEN_OFFSET = 1u << 4, HB_GIVEN_LENGTH = 1u << 5,
    HB_GIVEN_MARGIN = 1u << 6, HB_GIVEN_PRECISION = 1u << 7,
};

/* Derived values, computed once in double on the host and rounded once to the working
 * precision by each backend (docs/decisions.md). */
static inline double hb_segment_length(const hb_scene *s)
{
    return s->hair_length / (double)(s->points - 1);
}

static inline size_t hb_real_size(hb_precision p) { return p == HB_FP64 ? 8 : 4; }

const char *hb_stage_name(hb_stage s);
const char *hb_precision_name(hb_precision p);

/* Checks a scene against DESIGN §3/§8; on failure writes one line naming the flag. */
int hb_scene_validate(const hb_scene *s, char *err, size_t errlen);

/* Bytes of one state [N·P][3] in the scene's precision; 0 on overflow. */
uint64_t hb_state_bytes(const hb_scene *s);

/* The wind angle reduced to (−π, π], in double. */
double hb_wind_angle_reduced(const hb_scene *s);

#ifdef __cplusplus
}
#endif
#endif
