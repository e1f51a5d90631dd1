/* backend.h — what a backend (cpu, cuda) gives the shared driver (driver.c).
 *
 * The driver owns the command line, the stage loop, repeats and their statistics, the
 * HDF5 file and the JSON record; a backend owns the state memory and the model's
 * arithmetic. States cross this interface in the canonical layout [N·P][3] of the run's
 * precision.
 */
#ifndef HB_BACKEND_H
#define HB_BACKEND_H

#include <stddef.h>
#include <stdint.h>

#include "dynamic/dynamics.h"
#include "runtime/params.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct hb_backend hb_backend;

/* The declared features of docs/model.md §3.14, §3.16 and §3.17, as a variant's `lacks` names them. */
enum {
    HB_X_GUIDES = 1u << 0,
    HB_X_LRA = 1u << 1,
    HB_X_SAGFREE = 1u << 2,
    HB_X_LOD = 1u << 3,
    HB_X_GRID = 1u << 4,      /* §3.16 the hair–hair grid */
    HB_X_COLLIDERS = 1u << 5, /* §3.17 colliders beyond the head sphere */
    HB_X_FRICTION = 1u << 6,  /* §3.17 friction and a bounded depenetration */
    HB_X_PLANES = 1u << 7,    /* §3.17 the colliders as contact planes found once a frame */
    HB_X_ONCE = 1u << 8,      /* §3.6 xpbd's collision step in the last iteration of a substep alone */
    HB_X_COUNT = 9
};

/* One kernel variant of a backend: its name, the stages it runs (bit 1 << hb_stage), a
 * one-line summary, the most points per strand it can simulate (0: no limit), the most
 * threads a block its simulate kernel launches with (0: the backend's limit), its solvers
 * and the §3.14 features it does not run. Declared once, in the backend; `--list-variants`
 * prints the table as JSON, the driver refuses what a variant lacks, and the harness reads
 * the table from there. */
typedef struct {
    const char *name;
    unsigned stages;
    const char *summary;
    int64_t max_points;
    int max_block;
    unsigned solvers; /* the dynamic solvers it runs, bit 1 << hb_solver (0: xpbd and ftl) */
    int per_segment;  /* simulates a groom's per-segment rest lengths (docs/model.md §3.15) */
    unsigned lacks;   /* the §3.14 features it does not run, HB_X_* bits (0: all of them) */
} hb_variant;

/* The solvers a variant runs (its `solvers`, or xpbd and ftl where it declares none). */
static inline unsigned hb_variant_solvers(const hb_variant *v)
{
    return v->solvers ? v->solvers : (1u << HB_SOLVER_XPBD) | (1u << HB_SOLVER_FTL);
}

/* --draw: F frames simulated and drawn on the device, each path timed (docs/interfaces.md,
 * "Drawing on the GPU"). Times are per frame, the mean over the frames after a warm-up
 * frame; NaN where not measured. */
typedef struct {
    int width, height, frames;
    double simulate_ms;      /* the simulation kernel (CUDA events), the compute path's frames */
    double compute_ms;       /* the compute rasteriser: clear with the head, strands, resolve (CUDA events) */
    double compute_frame_ms; /* simulation and compute drawing back to back, first event to last / F */
    double gl_write_ms;      /* OpenGL path: CUDA writing the GL vertex buffer (map, kernel, unmap) */
    double gl_ms;            /* OpenGL path: the draw's GPU time (GL_TIME_ELAPSED) */
    double gl_frame_ms;      /* OpenGL path: simulation, write and draw, host wall time per frame */
    char gl[160];            /* the GL renderer and version, "" where the GL path did not run */
    char gl_missing[256];    /* why the GL path did not run, "" where it did */
} hb_draw_result;

/* The result of running one stage (or a fused group) once. */
typedef struct {
    double ms;            /* the stage's own time: kernels only (cuda events) or the loop (cpu) */
    int64_t moved_points; /* collide: points changed; −1 otherwise */
    int consumed;         /* stages this call ran: 1, or 2 for a fused wind+collide */
} hb_stage_result;

struct hb_backend {
    const char *name; /* "cpu" | "cuda" */
    const char *default_variant;
    const hb_variant *variants; /* terminated by a NULL name */
    const char *build;          /* "default" | "strict" | "fastmath" (the math mode) */
    const char *flags;          /* build flags, recorded in every output */
    const char *compiler;       /* NULL: the host C compiler that built the driver */
    void *impl;                 /* backend's private state */
    int threads, block_size;    /* what the run uses, set by setup (0 where not used) */
    /* cuda lanes: the simulate kernel's points a lane, lanes a strand, threads a block and strands a
     * wave (its blocks every SM holds at once), set by dyn_load (zeros: none; docs/interfaces.md) */
    int layout[4];

    /* Check memory and allocate for the run (saving a copy for repeats when `need_save`;
     * the driver's own host buffers take `driver_host_bytes`). Returns HB_EXIT_OK or an
     * exit status with one line in err. */
    int (*setup)(hb_backend *b, const hb_options *o, int need_save, uint64_t driver_host_bytes, char *err,
                 size_t errlen);
    /* Load a canonical host state as the current state; *ms gets the transfer time (cuda). */
    int (*load)(hb_backend *b, const void *canonical, double *ms, char *err, size_t errlen);
    /* Run stages[i] (and, for a fusing variant, possibly stages[i+1]) on the current state. */
    int (*run_stage)(hb_backend *b, const hb_stage *stages, int i, int n, hb_stage_result *r, char *err, size_t errlen);
    /* Keep a copy of the current state / make the copy current again (for repeats). */
    int (*save)(hb_backend *b, char *err, size_t errlen);
    int (*restore)(hb_backend *b, char *err, size_t errlen);
    /* Copy the current state into a canonical host buffer; *ms gets the transfer time. */
    int (*fetch)(hb_backend *b, void *canonical, double *ms, char *err, size_t errlen);
    /* After a fused call with consumed == 2: the state between the two stages (the wind
     * frame), canonical. Only asked for when a file is written. */
    int (*fetch_intermediate)(hb_backend *b, void *canonical, char *err, size_t errlen);
    /* Tell the backend whether fused calls must keep the intermediate state. */
    void (*keep_intermediate)(hb_backend *b, int keep);
    /* Measure copy bandwidth (bytes read + bytes written per second, GB/s). */
    int (*measure_bandwidth)(hb_backend *b, const hb_options *o, double *gbps, double *bytes, char *err, size_t errlen);
    /* Optional (NULL: not measured): a STREAM-style triad a = b + q·c, bytes = 2 reads + 1 write. */
    int (*measure_triad)(hb_backend *b, const hb_options *o, double *gbps, double *bytes, char *err, size_t errlen);
    /* The dynamic model (the simulate stage; NULL where no variant runs it). The positions
     * come through load; this gives their velocities (NULL: all zero) and the rest shape,
     * canonical, and computes what the run derives from the rest shape once. */
    int (*dyn_load)(hb_backend *b, const void *velocity, const void *rest, char *err, size_t errlen);
    /* Advance the current state by one frame; r->ms is the frame's own time. */
    int (*dyn_frame)(hb_backend *b, const hb_dyn_frame *f, hb_stage_result *r, char *err, size_t errlen);
    /* The observables of the current state (docs/model.md §3.8). */
    int (*dyn_observe)(hb_backend *b, hb_observables *obs, char *err, size_t errlen);
    int (*dyn_fetch_velocity)(hb_backend *b, void *canonical, char *err, size_t errlen);
    /* Optional (NULL: the driver fetches the state and renders it on the host): the current
     * state's rendered points (docs/model.md §3.14, --render-points) into a canonical host
     * buffer [N·P_r][3], and its velocities when `velocity` is not NULL; *ms the rendering's
     * own time (kernel time, transfers not counted). */
    int (*dyn_render)(hb_backend *b, void *position, void *velocity, double *ms, char *err, size_t errlen);
    /* Optional (NULL: not measured): advance the current state by n frames back to back, as
     * an application's frame loop would (each frame's tables uploaded and its kernel
     * launched, no observables, no fetch); *ms = host wall time per frame after one
     * synchronisation at the end; *graph_ms the same n frames captured once as a CUDA graph
     * and replayed (NaN where not measured). */
    int (*dyn_loop)(hb_backend *b, const hb_dyn_frame *plans, int n, double *ms, double *graph_ms, char *err,
                    size_t errlen);
    /* Descriptions for the metadata. */
    void (*describe)(hb_backend *b, char *device, size_t dlen, char *driver, size_t vlen);
    void (*teardown)(hb_backend *b);
    /* Optional (NULL: --draw refused): advance the current state by n frames, drawing each
     * into a W×H image on the device through each path (OpenGL through EGL from a vertex
     * buffer CUDA writes, and a CUDA compute rasteriser), nothing copied through the host;
     * with `image` (a path prefix) the last frame of each path is written as PREFIX-PATH.ppm
     * after the timing. A missing EGL or GL fills out->gl_missing and is not an error. */
    int (*dyn_draw)(hb_backend *b, const hb_dyn_frame *plans, int n, int width, int height, const char *image,
                    hb_draw_result *out, char *err, size_t errlen);
};

/* Runs the whole command line with this backend; returns the process exit status. */
int hb_main(int argc, char **argv, hb_backend *b);

#ifdef __cplusplus
}
#endif
#endif
