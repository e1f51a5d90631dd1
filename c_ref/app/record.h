/* record.h — what one run did and how long it took: the JSON record of docs/interfaces.md
 * and the human summary. */
#ifndef HB_RECORD_H
#define HB_RECORD_H

#include <stdio.h>

#include "app/backend.h"
#include "runtime/groom.h"
#include "runtime/params.h"
#include "app/state_io.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct {
    int frame;
    hb_stage stage;
    hb_frame_meta meta; /* stage, skipped, fused, moved points, median/min/max */
    double *times_ms;   /* repeat entries (NULL when skipped or fused into the previous) */
    int n_times;
    /* simulate: frames advanced (the times are per frame), the features compiled in, the
     * last frame's observables and the frames that blew up */
    int64_t frames;
    char features[192];
    int layout[4]; /* hb_backend's layout (zeros: none) */
    hb_observables last;
    int64_t blown_frames;
    double observe_ms;             /* computing the observables, all frames, apart from the frame times */
    double loop_ms, loop_graph_ms; /* --frame-loop: per frame, back to back / as a graph (NaN: not run) */
    double render_ms;              /* --render-points: median time to render a written frame (NaN: none) */
    int drawn;                     /* --draw ran: `draw` holds its result */
    hb_draw_result draw;
} hb_stage_record;

typedef struct {
    const hb_options *opt;
    const char *backend, *variant, *flags, *compiler, *git_revision;
    char device[256], driver[128];
    int threads, block_size;
    hb_stage_record stages[HB_MAX_STAGES];
    int n_stages;
    double end_to_end_ms, h2d_ms, d2h_ms, hdf5_write_ms; /* NaN: not measured */
    const hb_groom *groom;                               /* with --groom: its numbers */
} hb_record;

void hb_record_json(FILE *f, const hb_record *r);
/* Frames of the run's simulation that blew up (docs/model.md §3.8); 0 without one. */
int64_t hb_record_blown_frames(const hb_record *r);
void hb_record_summary(FILE *f, const hb_record *r);

/* Statistics of n times: median (mean of the middle two for even n), min, max. */
void hb_time_stats(const double *t, int n, double *median, double *min, double *max);

/* Build facts compiled in by the Makefile, and the CPU model of this machine. */
const char *hb_git_revision(void);
const char *hb_compiler(void);
void hb_cpu_model(char *out, size_t n);

#ifdef __cplusplus
}
#endif
#endif
