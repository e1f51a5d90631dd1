/* motion_track.h — a recorded head transform track (docs/model.md §3.2, docs/interfaces.md
 * "Motion tracks"): read from a CSV file for --motion-track, stored in and read back from the
 * HDF5 state's /parameters/motion_track so that a resumed run sees the same samples. */
#ifndef HB_MOTION_TRACK_H
#define HB_MOTION_TRACK_H

#include <stddef.h>
#include <stdint.h>

#include "dynamic/head_track.h"

#ifdef __cplusplus
extern "C" {
#endif

/* Reads a CSV track (header time,qw,qx,qy,qz,tx,ty,tz or time,axis_x,axis_y,axis_z,angle,tx,ty,tz);
 * the quaternions normalised once. A translation that is not zero is refused. 0, or −1 with one
 * line in err. */
int hb_track_load_csv(const char *path, hb_head_track *k, char *err, size_t errlen);
/* /parameters/motion_track [K][8] (time, qw, qx, qy, qz, tx, ty, tz) in the group `params`. */
int hb_track_write_h5(int64_t params, const hb_head_track *k);
/* Reads /parameters/motion_track of the open file `file` (0), or −1 with one line in err. */
int hb_track_read_h5(int64_t file, const char *path, hb_head_track *k, char *err, size_t errlen);
/* 1 when a and b hold the same samples bit for bit. */
int hb_track_same(const hb_head_track *a, const hb_head_track *b);
void hb_track_free(hb_head_track *k);

#ifdef __cplusplus
}
#endif
#endif
