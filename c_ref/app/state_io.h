/* state_io.h — the HDF5 state (layout in docs/interfaces.md): a writer that
 * appends frames to a temporary file and renames it when complete, and a reader that
 * validates an --input file before any work. */
#ifndef HB_STATE_IO_H
#define HB_STATE_IO_H

#include <stddef.h>
#include <stdint.h>

#include "dynamic/dynamics.h"
#include "dynamic/head_track.h"
#include "runtime/params.h"

#ifdef __cplusplus
extern "C" {
#endif

/* What each frame records beside its positions. */
typedef struct {
    char stage[16];
    char fused[16];
    char backend[48]; /* "cpu/ref", "cuda/fused", … */
    int skipped;
    int64_t moved_points; /* −1 where not a collide frame */
    double wind_strength; /* NaN where not a wind frame */
    double wind_angle;
    double median_ms, min_ms, max_ms;
    int64_t step; /* /particles/hair/position/step (docs/interfaces.md) */
    double time;  /* s: 0 for the paper stages' frames, f·Δt for simulated frame f */
} hb_frame_meta;

/* Run-wide metadata written as attributes of /parameters. */
typedef struct {
    const char *backend, *variant, *git_revision, *compiler, *flags, *device, *driver;
    int threads, block_size, repeat, warmup;
    double end_to_end_ms, hdf5_write_ms;
    /* the dynamic model (docs/model.md §3): 0 for a paper-model run */
    int dynamic;
    int64_t paper_frames;     /* frames of the paper stages before the simulation */
    int64_t simulated_frames; /* simulated frames from the start of the simulation to the last */
    int output_every;
    const char *features;
    /* a groom file's head (docs/model.md §3.15): "fitted" or "given", NULL otherwise */
    const char *groom_head;
    double groom_head_center[3]; /* in the file's coordinates, cm */
} hb_run_meta;

typedef struct hb_writer hb_writer;

/* Opens a marked temporary file beside `path` (safe_write.h); refuses an existing `path`
 * unless `force`. NULL on failure, with *status the exit status: 2 for the user's path, 4 for
 * the machine's fault (a full disk). */
hb_writer *hb_writer_open(const char *path, int force, const hb_scene *scene, int *status, char *err, size_t errlen);
int hb_writer_append(hb_writer *w, const void *frame, const hb_frame_meta *fm, char *err, size_t errlen);
/* Writes /parameters, closes, renames to the final name (HB_SAFE_EXISTS when the name was
 * taken during the run and `force` was not given). Frees w in every case. */
int hb_writer_close(hb_writer *w, const hb_run_meta *rm, char *err, size_t errlen);
/* Closes and deletes the temporary file. Frees w. */
void hb_writer_abort(hb_writer *w);
double hb_writer_seconds(const hb_writer *w); /* time spent writing so far */
/* The dynamic model's datasets: the rest shape (once), velocities (per written frame) and
 * the per-frame observables (kept in memory, written at close). */
int hb_writer_rest(hb_writer *w, const void *rest, char *err, size_t errlen);
int hb_writer_velocity(hb_writer *w, const void *v, int64_t step, double time, char *err, size_t errlen);
int hb_writer_observables(hb_writer *w, const hb_observables *o, int64_t step, double time, char *err, size_t errlen);

/* An --input file, validated. */
typedef struct {
    hb_scene scene;
    int n_frames;
    hb_frame_meta *frames; /* n_frames entries (step and time included) */
    int64_t hid;           /* the open file */
    /* a dynamic file: the rest shape, velocity frames and observables */
    int dynamic;
    int64_t paper_frames;
    int n_vel;
    int64_t *vel_step;
    double *vel_time;
    int n_obs;
    hb_observables *obs;
    int64_t *obs_step;
    double *obs_time;
    /* §3.17 a dynamic file's colliders (scene.dyn.cols points here) and their file's name */
    hb_colliders cols;
    char colliders_file[1024];
    hb_head_track track; /* head_motion = track: /parameters/motion_track (scene.dyn.track points here) */
} hb_input;

/* Opens and checks the layout and the scene; one line in err on failure. */
int hb_input_open(const char *path, hb_input *in, char *err, size_t errlen);
/* Reads frame f into buf (canonical, the file's precision); checks for NaN/Inf. */
int hb_input_read_frame(hb_input *in, int f, void *buf, char *err, size_t errlen);
void hb_input_close(hb_input *in);
int hb_input_read_rest(hb_input *in, void *buf, char *err, size_t errlen);
int hb_input_read_velocity(hb_input *in, int index, void *buf, char *err, size_t errlen);

#ifdef __cplusplus
}
#endif
#endif
