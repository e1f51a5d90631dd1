/* model_impl.h — the paper model (docs/model.md §2), written once for a floating type REAL.
 *
 * Included twice by model.c (REAL = float, then double) with the math functions named by
 * SQRT, SIN, COS, ASIN, ATAN2 and the machine epsilon EPS. The CUDA port (cuda/model.cuh)
 * follows this file operation by operation, so that a strict GPU build differs from it
 * only where the platforms' sin/cos/asin/atan2 differ.
 *
 * Coordinates: s[3k+0] = x (depth, never changes), s[3k+1] = y (up), s[3k+2] = z (toward
 * the face). Angles θ are measured from +z toward +y.
 */

#define PI_R ((REAL)3.14159265358979323846)
#define HALF_PI_R ((REAL)1.57079632679489661923)
#define TWO_PI_R ((REAL)6.28318530717958647692)

/* ---- docs/model.md §2.2 roots (SetStartPoint) ----------------------------------------- */
static void SFX(place_root)(const MODEL *m, uint64_t strand, REAL *s)
{
    uint32_t r[4];
    hb_draw_block(m->seed, strand, 0u, r); /* draws 0, 1, 2 of this strand */
    const REAL u1 = (REAL)hb_u01(r[0]);
    const REAL u2 = (REAL)hb_u01(r[1]);
    const REAL u3 = (REAL)hb_u01(r[2]);
    const REAL R = m->head_radius;

    /* z = clamp((2u1 − 1)R − m, −R, R): the clamp keeps the square roots real. */
    REAL z = ((REAL)2 * u1 - (REAL)1) * R - m->face_margin;
    if (z < -R) z = -R;
    if (z > R) z = R;
    REAL dd = R * R - z * z;
    const REAL d = SQRT(dd > (REAL)0 ? dd : (REAL)0);
    /* Face side (z > 0): y in [0.3d, d), so no root sits on the lower face. */
    const REAL y = z > (REAL)0 ? d * ((REAL)0.3 + (REAL)0.7 * u2) : ((REAL)2 * u2 - (REAL)1) * d;
    REAL xx = R * R - z * z - y * y;
    REAL x = SQRT(xx > (REAL)0 ? xx : (REAL)0);
    if (u3 >= (REAL)0.5) x = -x;
    s[0] = x;
    s[1] = y;
    s[2] = z;
}

/* ---- docs/model.md §2.3 drape (SetEndPoint, interpolated points, slerp) -------------- */
void SFX(hb_drape_strand)(const MODEL *m, REAL *s)
{
    const int64_t P = m->points;
    const REAL ell = m->seg_len;
    const REAL x0 = s[0];
    REAL py = s[1], pz = s[2];                  /* the predecessor, in the slice plane */
    const REAL r0 = SQRT(py * py + pz * pz);    /* head circle of the slice */
    const REAL rc = r0 + m->hair_offset;        /* shell circle */
    REAL theta = ATAN2(py, pz);                 /* (−π, π] … */
    if (theta <= -HALF_PI_R) theta += TWO_PI_R; /* … taken in (−π/2, 3π/2] */
    /* A root on the lower back (θ0 > π) hangs straight down from the root. */
    int hanging = theta > PI_R;
    REAL rho = r0; /* slice radius of the predecessor: r0 for the first step, rc after */

    for (int64_t k = 1; k < P; k++) {
        REAL *q = s + 3 * k;
        if (!hanging) {
            /* Step onto the shell circle: the angle α of the triangle (origin,
             * predecessor, new point) has cos α = (ρ² + rc² − ℓ²) / (2ρ rc). Evaluated in
             * the equivalent half-angle form sin²(α/2) = (ℓ − g)(ℓ + g) / (4ρ rc), g = rc − ρ,
             * which keeps its accuracy for short segments where cos α is near 1
             * (docs/decisions/paper-model.md, "drape_short_segment"). cos α < −1 is s² > 1, cos α > 1
             * is s² < 0. */
            int fits = 0;
            REAL s2 = 0;
            if (rho > (REAL)0) {
                const REAL g = rc - rho;
                s2 = ((ell - g) * (ell + g)) / ((REAL)4 * rho * rc);
                fits = s2 <= (REAL)1; /* cos α < −1: the step does not fit the circle */
            }
            if (fits) {
                if (s2 < (REAL)0) s2 = (REAL)0; /* the shell is out of reach only by rounding */
                const REAL next = theta + (REAL)2 * ASIN(SQRT(s2));
                if (next <= PI_R) {
                    theta = next;
                    pz = rc * COS(next);
                    py = rc * SIN(next);
#if HB_PLANT == 13 /* judge test: every drape step from the head circle, not the shell */
                    rho = r0;
#else
                    rho = rc;
#endif
                    q[0] = x0;
                    q[1] = py;
                    q[2] = pz;
                    continue;
                }
            }
            /* The strand starts to hang: the first hanging point goes onto the vertical
             * tangent line z = −rc, at distance ℓ below its predecessor. */
            const REAL dz = pz + rc;
            const REAL dy2 = ell * ell - dz * dz;
            py = py - SQRT(dy2 > (REAL)0 ? dy2 : (REAL)0);
            pz = -rc;
            hanging = 1;
        } else {
            /* Every later point hangs straight down: p_k = p_{k−1} − ℓŷ. */
            py = py - ell;
        }
        q[0] = x0;
        q[1] = py;
        q[2] = pz;
    }
}

void SFX(hb_init_strand)(const MODEL *m, uint64_t strand, REAL *s)
{
    SFX(place_root)(m, strand, s);
    SFX(hb_drape_strand)(m, s);
}

/* ---- docs/model.md §2.4 wind ------------------------------------------------------------ */
/* Each segment's direction φk turns toward ψ by t = w·k/(P−1) of the shorter arc (a 2-D
 * slerp); the strand is rebuilt from the root with segments of length ℓ. The caller does
 * not call this when w = 0 (the identity). */
void SFX(hb_wind_strand)(const MODEL *m, REAL *s)
{
    const int64_t P = m->points;
    const REAL ell = m->seg_len;
    const REAL w = m->wind_strength;
    const REAL psi = m->wind_angle; /* already reduced to (−π, π] */
    const REAL last = (REAL)(P - 1);
    REAL oy = s[1], oz = s[2]; /* the predecessor before the wind */
    REAL ny = oy, nz = oz;     /* the predecessor after the wind (the root never moves) */

    for (int64_t k = 1; k < P; k++) {
        REAL *q = s + 3 * k;
        const REAL cy = q[1], cz = q[2];
        const REAL dy = cy - oy, dz = cz - oz;
        const REAL phi = ATAN2(dy, dz);
        REAL delta = psi - phi; /* in [−2π, 2π]: wrap to (−π, π] */
        if (delta > PI_R) delta -= TWO_PI_R;
        else if (delta <= -PI_R) delta += TWO_PI_R;
        /* Exactly opposite: take the arc through +y. Turning by +π passes through the
         * direction φ + π/2, whose y component has the sign of cos φ, i.e. of dz. */
        if (delta == PI_R) delta = dz >= (REAL)0 ? PI_R : -PI_R;
#if HB_PLANT == 11 /* judge test: the wind's blend of segment k taken at k − 1 */
        const REAL t = (w * (REAL)(k - 1)) / last;
#else
        const REAL t = (w * (REAL)k) / last;
#endif
        const REAL turned = phi + t * delta;
        nz = nz + ell * COS(turned);
        ny = ny + ell * SIN(turned);
        q[1] = ny;
        q[2] = nz;
        oy = cy;
        oz = cz;
    }
}

/* ---- docs/model.md §2.5 collide --------------------------------------------------------- */
/* Walk from the root. A point inside the shell (beyond the rounding allowance) moves to
 * the intersection of the shell circle with the circle of radius ℓ around its
 * predecessor that is closest to where it was (a tie takes the upper one); once a point
 * has moved, every later point is pulled follow-the-leader style and checked in turn.
 * Returns the number of points changed. */
int64_t SFX(hb_collide_strand)(const MODEL *m, REAL *s)
{
    const int64_t P = m->points;
    const REAL ell = m->seg_len;
    const REAL r0 = SQRT(s[1] * s[1] + s[2] * s[2]);
    const REAL rc = r0 + m->hair_offset;
    const REAL inner = rc - rc * ((REAL)HB_SHELL_ULPS * EPS); /* rounding allowance */
    const REAL inner2 = inner * inner;
    int moved = 0;
    int64_t changed = 0;
    REAL py = s[1], pz = s[2];

    for (int64_t k = 1; k < P; k++) {
        REAL *q = s + 3 * k;
        REAL cy = q[1], cz = q[2];
#if HB_PLANT == 12 /* judge test: no follow-the-leader pull after a move */
        if (0) {
#else
        if (moved) {
#endif
            /* Follow the leader: p_k ← p_{k−1} + ℓ·unit(p_k − p_{k−1}). */
            const REAL dy = cy - py, dz = cz - pz;
            const REAL len = SQRT(dy * dy + dz * dz);
            if (len > (REAL)0) {
                cy = py + ell * (dy / len);
                cz = pz + ell * (dz / len);
            } else { /* no direction left: hang down */
                cy = py - ell;
                cz = pz;
            }
        }
        if (cy * cy + cz * cz < inner2) {
            /* Intersect the shell (radius rc, centre 0) with the circle of radius ℓ around
             * the predecessor at distance d from the centre: the chord's foot lies at
             * a = (d² + rc² − ℓ²) / 2d along the unit u towards the predecessor, the
             * candidates at a·u ± hh·u⊥ with hh = √(rc² − a²). Evaluated through
             * t = d − a = ((d − rc)(d + rc) + ℓ²) / 2d and hh² = (rc − a)(rc + a), which
             * avoid the cancellation of rc² − a² when ℓ ≪ rc (docs/decisions/paper-model.md,
             * "collide_short_segment"). */
            const REAL d2 = py * py + pz * pz;
            const REAL d = SQRT(d2);
            if (d > (REAL)0) {
                const REAL t = ((d - rc) * (d + rc) + ell * ell) / ((REAL)2 * d);
                const REAL a = d - t;
                const REAL h2 = ((rc - d) + t) * (rc + a);
                const REAL hh = SQRT(h2 > (REAL)0 ? h2 : (REAL)0);
                const REAL uy = py / d, uz = pz / d;
                const REAL fy = a * uy, fz = a * uz;
                const REAL y1 = fy + hh * uz, z1 = fz - hh * uy;
                const REAL y2 = fy - hh * uz, z2 = fz + hh * uy;
                const REAL e1 = (y1 - cy) * (y1 - cy) + (z1 - cz) * (z1 - cz);
                const REAL e2 = (y2 - cy) * (y2 - cy) + (z2 - cz) * (z2 - cz);
                if (e1 < e2 || (e1 == e2 && y1 >= y2)) {
                    cy = y1;
                    cz = z1;
                } else {
                    cy = y2;
                    cz = z2;
                }
                moved = 1;
            }
        }
        if (moved) {
            q[1] = cy;
            q[2] = cz;
            changed++;
        }
        py = cy;
        pz = cz;
    }
    return changed;
}

#undef PI_R
#undef HALF_PI_R
#undef TWO_PI_R
