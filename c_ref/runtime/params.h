/* params.h — the scene parameters and run options shared by every backend (docs/model.md §2;
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
/* HB_EXIT_BLOWN_UP: the run ended and wrote everything, but a simulated frame blew up (§3.8) */
enum { HB_EXIT_OK = 0, HB_EXIT_USAGE = 2, HB_EXIT_MEMORY = 3, HB_EXIT_RUNTIME = 4, HB_EXIT_BLOWN_UP = 5 };

typedef enum { HB_FP32 = 0, HB_FP64 = 1 } hb_precision;
typedef enum { HB_STAGE_INIT = 0, HB_STAGE_WIND = 1, HB_STAGE_COLLIDE = 2, HB_STAGE_SIMULATE = 3 } hb_stage;
/* rigid: no dynamics, every point carried with the head (docs/model.md §3.13) */
typedef enum { HB_SOLVER_XPBD = 0, HB_SOLVER_FTL = 1, HB_SOLVER_RIGID = 2, HB_SOLVER_COUNT = 3 } hb_solver;
/* track: a recorded transform track (--motion-track FILE, dynamic/head_track.h) */
typedef enum {
    HB_MOTION_STILL = 0,
    HB_MOTION_NOD = 1,
    HB_MOTION_SHAKE = 2,
    HB_MOTION_TILT = 3,
    HB_MOTION_TRACK = 4
} hb_motion;
typedef enum { HB_FOLLOW_BLEND3 = 0, HB_FOLLOW_ONE = 1 } hb_follow;

/* The dynamic model's physics (docs/model.md §3): everything that decides the bits of a
 * simulated frame. Units: cm, s. Bend and shape exist only when declared (their
 * compliance given); the wind only when U > 0 and c_d > 0 (§3.9). */
typedef struct {
    double frame_dt;    /* Δt, s */
    int64_t substeps;   /* S */
    int64_t iterations; /* I */
    hb_solver solver;
    double gravity;            /* g0, cm/s² */
    double drag, damping;      /* c_d, β, 1/s */
    int drag_declared;         /* --drag or --damping given: the implicit divide runs (§3.9) */
    double stretch_compliance; /* α_s */
    int bend;                  /* declared */
    double bend_compliance;    /* α_b */
    int shape;                 /* declared */
    double shape_compliance;   /* α_g */
    double shape_range;        /* ρ_g in (0, 1] */
    double ftl_damping;        /* s */
    int collider;
    double collision_margin;                                /* c_m */
    double wind_speed;                                      /* U, cm/s; direction ψ is hb_scene.wind_angle */
    double gust_amplitude, gust_frequency, gust_wavelength; /* A_g, f_g (Hz), λ_g (cm) */
    hb_motion motion;
    double motion_amplitude;           /* A, radians */
    double motion_frequency;           /* f, Hz */
    const struct hb_head_track *track; /* HB_MOTION_TRACK: the samples (owned by the run or its --input) */
    /* docs/model.md §3.13: guides and followers, long-range attachments */
    int guided;            /* --guides given: only the guides are simulated */
    double guides;         /* a fraction in (0, 1] of the strands, or a count > 1 */
    hb_follow follow;      /* how followers are placed from their guides */
    int lra;               /* --lra given */
    double lra_scale;      /* s_L ≥ 1: the bound is s_L times the rest arc length */
    int sag_free;          /* --sag-free: shape targets that hold the rest shape against gravity */
    int64_t render_points; /* --render-points P_r: strands written with P_r points (§3.14); 0: as simulated */
    int per_segment;       /* §3.15: stretch rest lengths per segment from X̄ (a groom), not ℓ = L/(P−1) */
    /* §3.16 the hair–hair grid (run-time switches: not among the compiled feature sets) */
    int grid;                   /* --grid given */
    int64_t grid_n;             /* n_g, nodes per axis */
    int grid_rebuild;           /* hb_grid_rebuild */
    int grid_box_given;         /* --grid-box given, else derived from the rest shape */
    double grid_box[6];         /* lo x, y, z, hi x, y, z in the head frame, cm */
    double grid_padding;        /* b, cm */
    int grid_friction_declared; /* --grid-friction given */
    double grid_friction[2];    /* f_r, f_t in [0, 1] */
    int grid_volume_declared;   /* --grid-volume given */
    double grid_volume;         /* K_v, cm²/s² */
    /* §3.17 colliders and friction */
    const char *colliders_path;      /* --colliders FILE (NULL: none) */
    const struct hb_colliders *cols; /* the loaded colliders (runtime/colliders.c), NULL: none */
    int friction_declared;           /* --friction given: the head sphere's friction */
    double friction[2];              /* μ_s, μ_k of the head sphere */
    int depen_declared;              /* --depenetration-speed given */
    double depen_speed;              /* V, cm/s */
    int64_t collider_sweeps;         /* --collider-sweeps: the collision sweep a point, at most (1: once) */
    int planes_declared;             /* --contact-planes given: the colliders as one contact plane a point a frame */
    int collide_once;                /* --collide-once: xpbd's collision step in a substep's last iteration alone */
    double contact_margin;           /* M, cm: how near a collider a point finds its plane */
    int body_motion;                 /* hb_body_motion */
    double body_amplitude, body_frequency; /* A_b (cm), f_b (Hz) */
} hb_dynamics;

typedef enum { HB_GRID_FRAME = 0, HB_GRID_SUBSTEP = 1, HB_GRID_HELD = 2 } hb_grid_rebuild;
typedef enum { HB_BODY_STILL = 0, HB_BODY_SWAY = 1, HB_BODY_RISE = 2 } hb_body_motion;

/* The scene: everything that decides the bits of a state. */
typedef struct {
    int64_t n_strands; /* N */
    int64_t points;    /* P, including the root */
    uint64_t seed;
    double head_radius;   /* R */
    double hair_offset;   /* h */
    double hair_length;   /* L */
    double face_margin;   /* m */
    double wind_strength; /* w in [0, 1] */
    double wind_angle;    /* psi, radians from +z toward +y */
    hb_precision precision;
    hb_dynamics dyn; /* used by the simulate stage only */
    /* §3.15: the init stage's strands from a groom instead of the drape (HB_GROOM_DRAPE) */
    int groom;                      /* hb_groom_kind */
    double curl_radius, curl_pitch; /* HB_GROOM_CURLY: helix radius and advance per turn, cm */
} hb_scene;

typedef enum { HB_GROOM_DRAPE = 0, HB_GROOM_CURLY = 1, HB_GROOM_FILE = 2 } hb_groom_kind;

/* How a run is carried out: which stages, how timed, where written. */
typedef struct {
    hb_scene scene;
    hb_stage stages[HB_MAX_STAGES];
    int n_stages;
    const char *variant;      /* NULL: the backend's default */
    int threads;              /* cpu: 0 = all cores */
    int block_size;           /* cuda */
    const char *input;        /* NULL: start with init */
    const char *groom;        /* --groom: "curly" or a HAIR file; NULL: the drape */
    const char *motion_track; /* --motion-track: a CSV head transform track; NULL: none */
    const char *output;       /* NULL: no file */
    int force;
    int repeat;
    int warmup; /* -1: default (1 if repeat > 1, else 0) */
    int json;
    int quiet;
    int end_to_end;         /* measure one extra untimed-by-stage pass */
    int measure_bandwidth;  /* only measure the copy bandwidth */
    const char *self_test;  /* "rng": print the known-answer checks */
    int list_variants;      /* print the backend's variants as JSON and exit */
    int input_frame;        /* --input-frame: resume after this frame of --input; −1 = its last */
    int64_t frames;         /* simulate: frames to advance (F) */
    int64_t output_every;   /* simulate: write every K-th frame (the last always) */
    int all_velocities;     /* simulate: write the velocities of every written frame */
    int frame_loop;         /* simulate: also time F more frames back to back (backend dyn_loop) */
    int draw_w, draw_h;     /* --draw WxH: also simulate and draw F more frames on the GPU (backend dyn_draw) */
    const char *draw_image; /* --draw-image PREFIX: the last drawn frame of each path as PREFIX-PATH.ppm */
    uint64_t dyn_given;     /* which dynamic flags were given: bit i = entry i of cli.c's table */
    /* which scene flags the user gave explicitly (for --input consistency checks) */
    unsigned given;
    /* --head-center: a groom file's head centre, cm (HB_GIVEN_CENTER) */
    double head_center[3];
} hb_options;

/* Bits of hb_options.given. */
enum {
    HB_GIVEN_STRANDS = 1u << 0,
    HB_GIVEN_POINTS = 1u << 1,
    HB_GIVEN_SEED = 1u << 2,
    HB_GIVEN_RADIUS = 1u << 3,
    HB_GIVEN_OFFSET = 1u << 4,
    HB_GIVEN_LENGTH = 1u << 5,
    HB_GIVEN_MARGIN = 1u << 6,
    HB_GIVEN_PRECISION = 1u << 7,
    HB_GIVEN_ANGLE = 1u << 8,
    HB_GIVEN_CURL = 1u << 9,
    HB_GIVEN_CENTER = 1u << 10,
};

/* Derived values, computed once in double on the host and rounded once to the working
 * precision by each backend (docs/model.md §1.3). */
static inline double hb_segment_length(const hb_scene *s)
{
    return s->hair_length / (double)(s->points - 1);
}

static inline size_t hb_real_size(hb_precision p)
{
    return p == HB_FP64 ? 8 : 4;
}

const char *hb_stage_name(hb_stage s);
const char *hb_precision_name(hb_precision p);

/* Checks a scene against docs/model.md §2.6; on failure writes one line naming the flag. */
int hb_scene_validate(const hb_scene *s, char *err, size_t errlen);
/* Checks the dynamic parameters (docs/model.md §3); one line naming the flag on failure. */
int hb_dynamics_validate(const hb_dynamics *d, char *err, size_t errlen);
/* Checks that the dynamic model's derived constants fit the scene's precision and that the
 * lengths it squares stay in range; one line naming the flags on failure. */
int hb_dynamics_validate_scene(const hb_scene *s, char *err, size_t errlen);
/* Checks that the head motion's phase 2πf·t and the gust's f_g·t stay finite up to t_end
 * seconds, for the features the run evaluates; one line naming the flag on failure. */
int hb_dynamics_validate_time(const hb_scene *s, double t_end, char *err, size_t errlen);
void hb_dynamics_defaults(hb_dynamics *d);
const char *hb_solver_name(hb_solver s);
const char *hb_motion_name(hb_motion m);
const char *hb_follow_name(hb_follow f);

/* The lengths precision p can square without underflow or overflow (docs/decisions/paper-model.md,
 * "Representable scenes"). */
double hb_length_min(hb_precision p);
double hb_length_max(hb_precision p);

/* Bytes of one state [N·P][3] in the scene's precision; 0 on overflow. */
uint64_t hb_state_bytes(const hb_scene *s);

/* The wind angle reduced to (−π, π], in double. */
double hb_wind_angle_reduced(const hb_scene *s);

#ifdef __cplusplus
}
#endif
#endif
