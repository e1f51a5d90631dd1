/* run.h — one run's state, which the driver (driver.c) and the dynamic model's frame loop
 * (simulate.c) share. */
#ifndef HB_RUN_H
#define HB_RUN_H

#include <stddef.h>
#include <stdint.h>

#include "app/backend.h"
#include "app/record.h"
#include "app/state_io.h"
#include "dynamic/head_track.h"
#include "dynamic/world.h"
#include "runtime/groom.h"
#include "runtime/params.h"

typedef struct {
    hb_backend *b;
    hb_options *o;
    hb_record *rec;
    hb_writer *w;
    void *host;                     /* canonical host frame (output, end-to-end) */
    void *input;                    /* the input's last frame */
    void *render, *vrender, *vhost; /* --render-points: a rendered frame and its velocities; simulated velocities */
    hb_input in;
    int have_input;
    hb_groom groom;      /* --groom: what init places (docs/model.md §3.15) */
    hb_colliders cols;   /* --colliders (docs/model.md §3.17) */
    hb_head_track track; /* --motion-track: the head's transform track (motion_track.h) */
    double *times;       /* all stages' timed runs */
    struct {             /* the simulation, for the file's /parameters */
        int dynamic;
        int64_t paper_frames, last_frame;
        char features[192];
    } sim;
} hb_run;


/* Returns `status` from the enclosing function when `call` returns non-zero (err says why). */
#define HB_TRY(call, status)                                                                                           \
    do {                                                                                                               \
        if ((call) != 0) return (status);                                                                              \
    } while (0)

/* A frame's metadata for stage `st`: its name, the backend/variant, the wind where it blew. */
void hb_frame_meta_init(hb_frame_meta *m, hb_stage st, const hb_scene *s, const char *backend, const char *variant);

/* The frame as the file holds it: the state itself, or with --render-points its rendered
 * points (docs/model.md §3.14, the C reference's spline on the host). */
const void *hb_run_as_written(hb_run *r, const void *state);

/* The simulate stage (docs/model.md §3), the run's last, from the state the stages before it
 * left (frame `frame`); its frame times into `times`. An exit status (HB_EXIT_*). */
int hb_run_simulate(hb_run *r, hb_stage_record *sr, int frame, double *times, char *err, size_t errlen);

#endif
