/* head_track.h — the head's rotation from a recorded transform track (docs/model.md §3.2,
 * --head-motion track): K samples (time, unit quaternion, translation), the rotation between
 * two samples by spherical linear interpolation along the shorter arc, held at the first
 * sample before the track and at the last after it. Computed in double on the host, as the
 * sinusoidal motions are; header-only, so that every object that plans a frame links it. */
#ifndef HB_HEAD_TRACK_H
#define HB_HEAD_TRACK_H

#include <math.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

typedef struct hb_head_track {
    int64_t n;  /* samples, ≥ 1 */
    double *t;  /* [n] s, strictly increasing */
    double *q;  /* [n][4] unit quaternions (w, x, y, z): the rotation from the rest pose */
    double *tr; /* [n][3] translation, cm (read and stored; not yet applied: docs/model.md §3.2) */
} hb_head_track;

/* The row-major rotation matrix of the unit quaternion (w, x, y, z). */
static inline void hb_quat_matrix(const double *q, double m[9])
{
    const double w = q[0], x = q[1], y = q[2], z = q[3];
    m[0] = 1.0 - 2.0 * (y * y + z * z);
    m[1] = 2.0 * (x * y - z * w);
    m[2] = 2.0 * (x * z + y * w);
    m[3] = 2.0 * (x * y + z * w);
    m[4] = 1.0 - 2.0 * (x * x + z * z);
    m[5] = 2.0 * (y * z - x * w);
    m[6] = 2.0 * (x * z - y * w);
    m[7] = 2.0 * (y * z + x * w);
    m[8] = 1.0 - 2.0 * (x * x + y * y);
}

/* The sample index i with t[i] <= t < t[i + 1] (0 < t − t[0], t < t[n − 1]). */
static inline int64_t hb_track_segment(const hb_head_track *k, double t)
{
    int64_t lo = 0, hi = k->n - 1;
    while (hi - lo > 1) {
        const int64_t mid = lo + (hi - lo) / 2;
        if (k->t[mid] <= t) lo = mid;
        else hi = mid;
    }
    return lo;
}

/* Q(t) of the track as a row-major matrix. The angle between the two samples' quaternions is
 * 2·atan2(|a − b|, |a + b|), accurate at every angle; the result is normalised once. */
static inline void hb_track_rotation(const hb_head_track *k, double t, double m[9])
{
    if (k->n == 1 || !(t > k->t[0])) {
        hb_quat_matrix(k->q, m);
        return;
    }
    if (t >= k->t[k->n - 1]) {
        hb_quat_matrix(k->q + 4 * (k->n - 1), m);
        return;
    }
    const int64_t i = hb_track_segment(k, t);
    const double *a = k->q + 4 * i, *b0 = k->q + 4 * (i + 1);
    const double u = (t - k->t[i]) / (k->t[i + 1] - k->t[i]);
    double dot = 0.0, b[4];
    for (int c = 0; c < 4; c++) dot += a[c] * b0[c];
    const double sign = dot < 0.0 ? -1.0 : 1.0; /* q and −q are one rotation: the shorter arc */
    double dm = 0.0, dp = 0.0;
    for (int c = 0; c < 4; c++) {
        b[c] = sign * b0[c];
        dm += (a[c] - b[c]) * (a[c] - b[c]);
        dp += (a[c] + b[c]) * (a[c] + b[c]);
    }
    const double theta = 2.0 * atan2(sqrt(dm), sqrt(dp)); /* the angle between a and b in R^4 */
    double wa = 1.0 - u, wb = u;
    if (theta > 1e-12) {
        const double s = sin(theta);
        wa = sin((1.0 - u) * theta) / s;
        wb = sin(u * theta) / s;
    }
    double q[4], n2 = 0.0;
    for (int c = 0; c < 4; c++) {
        q[c] = wa * a[c] + wb * b[c];
        n2 += q[c] * q[c];
    }
    const double inv = 1.0 / sqrt(n2);
    for (int c = 0; c < 4; c++) q[c] *= inv;
    hb_quat_matrix(q, m);
}

#ifdef __cplusplus
}
#endif
#endif
