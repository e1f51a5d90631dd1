/* obs_point.h — one point k >= 1 of a strand's observables (docs/model.md §3.8), in double:
 * the reference (dynamics_impl.h) and the CUDA port (cuda/dynamic/model.cuh) share it, so both
 * compute the same operations in the same order.
 */
#ifndef HB_OBS_POINT_H
#define HB_OBS_POINT_H

#include <math.h>

#include "runtime/philox.h" /* HB_HD */

/* xk, xp, x0: points k, k − 1 and the root; vk: the velocity of point k; seg: the segment's
 * rest length. Raises *smax (stretch) and, with a collider, *pmax (penetration), adds |v_k|²
 * to *v2; returns 1 when point k lies farther than √far2 from the root. */
HB_HD int hb_obs_point(const double xk[3], const double xp[3], const double x0[3], const double vk[3], double seg,
                       int collider, double rc, double far2, double *smax, double *pmax, double *v2)
{
    double e[3], r[3], r2 = 0.0, l2 = 0.0, n2 = 0.0, w2 = 0.0;
    for (int c = 0; c < 3; c++) {
        e[c] = xk[c] - xp[c];
        r[c] = xk[c] - x0[c];
        l2 += e[c] * e[c];
        r2 += r[c] * r[c];
        n2 += xk[c] * xk[c];
        w2 += vk[c] * vk[c];
    }
    const double st = fabs(sqrt(l2) / seg - 1.0);
    if (st > *smax) *smax = st;
    if (collider) {
        const double pen = rc - sqrt(n2);
        if (pen > *pmax) *pmax = pen;
    }
    *v2 += w2;
    return r2 > far2;
}

#endif
