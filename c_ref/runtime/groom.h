/* groom.h — the init stage's strands from a groom instead of the drape (docs/model.md §3.15):
 * the procedural curly groom, or a HAIR file resampled by arc length to P points. The state
 * is computed in double on the host and rounded once to the working precision. */
#ifndef HB_GROOM_H
#define HB_GROOM_H

#include <stddef.h>
#include <stdint.h>

#include "runtime/params.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct {
    double *pos;           /* HB_GROOM_FILE: [N][P][3] in cm, the head centre at the origin */
    int64_t file_strands;  /* strands in the file (N may take the first of them) */
    double resample_error; /* most a file point lies off the resampled strand, cm */
    double length_min, length_max;
    double fit_offset;     /* most a root lies off the sphere fitted to the roots, cm (fitted head) */
    int head_given;        /* the head centre came from --head-center, not the fit */
    double head_center[3]; /* the head centre in the file's coordinates, cm */
} hb_groom;

/* Reads and checks the groom of o->groom and sets the scene's strands, head radius and
 * hair length from it (a file groom); 0, or one line in err and the exit status: HB_EXIT_USAGE
 * for a bad groom, HB_EXIT_MEMORY for one whose resampled state does not fit in memory. */
int hb_groom_prepare(hb_options *o, hb_groom *g, char *err, size_t errlen);
/* The groom's state, canonical [N·P][3] in the scene's precision. */
void hb_groom_state(const hb_scene *s, const hb_groom *g, void *out);
void hb_groom_free(hb_groom *g);

#ifdef __cplusplus
}
#endif
#endif
