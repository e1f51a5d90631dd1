/* points_impl.h — one point's step of the paper model's stages (docs/model.md §2) in the
 * reference arithmetic, written once for a floating type REAL and shared by the C reference
 * (paper/model_impl.h, whose loops call these) and the CUDA port's strict build
 * (cuda/paper/model.cuh's reference branches), so the two agree bit for bit by construction
 * wherever the platforms' sqrt/sin/cos/asin/atan2 agree.
 *
 * Included between precision_f32.h / precision_f64.h and precision_end.h (the names REAL,
 * SFX, SQRT, SIN, COS, SINCOS, ASIN, ATAN2, EPS). Plain C99 that nvcc also compiles: every
 * function is HB_HD (runtime/philox.h). A point's state lives in the caller's variables,
 * passed by pointer. The planted defects 11-13 (docs/judge.md) sit here, so they reach the C
 * reference only (nothing else defines HB_PLANT).
 */

#define PI_R ((REAL)3.14159265358979323846)
#define HALF_PI_R ((REAL)1.57079632679489661923)
#define TWO_PI_R ((REAL)6.28318530717958647692)

/* sin and cos of one angle: on the device one call (SINCOS, sharing the range reduction;
 * the same bits as SIN and COS, docs/cuda.md), on the host SIN and COS as glibc has them. */
HB_HD void SFX(hb_sin_cos)(const REAL x, REAL *s, REAL *c)
{
#if defined(__CUDA_ARCH__)
    SINCOS(x, s, c);
#else
    *s = SIN(x);
    *c = COS(x);
#endif
}

/* ---- docs/model.md §2.2 roots (SetStartPoint): p = the root (x, y, z) of `strand` ------ */
HB_HD void SFX(hb_root_place)(const uint64_t seed, const uint64_t strand, const REAL R, const REAL face_margin,
                              REAL p[3])
{
    uint32_t r[4];
    hb_draw_block(seed, strand, 0u, r); /* draws 0, 1, 2 of this strand */
    const REAL u1 = (REAL)hb_u01(r[0]);
    const REAL u2 = (REAL)hb_u01(r[1]);
    const REAL u3 = (REAL)hb_u01(r[2]);

    /* z = clamp((2u1 − 1)R − m, −R, R): the clamp keeps the square roots real. */
    REAL z = ((REAL)2 * u1 - (REAL)1) * R - face_margin;
    if (z < -R) z = -R;
    if (z > R) z = R;
    const REAL dd = R * R - z * z;
    const REAL d = SQRT(dd > (REAL)0 ? dd : (REAL)0);
    /* Face side (z > 0): y in [0.3d, d), so no root sits on the lower face. */
    const REAL y = z > (REAL)0 ? d * ((REAL)0.3 + (REAL)0.7 * u2) : ((REAL)2 * u2 - (REAL)1) * d;
    const REAL xx = R * R - z * z - y * y;
    REAL x = SQRT(xx > (REAL)0 ? xx : (REAL)0);
    if (u3 >= (REAL)0.5) x = -x;
    p[0] = x;
    p[1] = y;
    p[2] = z;
}

/* ---- docs/model.md §2.3 drape (SetEndPoint, interpolated points, slerp) --------------- */
/* From the root (py, pz): the head circle r0 and shell circle rc of the slice, the root's
 * angle θ; returns whether the strand hangs from the root. */
HB_HD int SFX(hb_drape_begin)(const REAL py, const REAL pz, const REAL hair_offset, REAL *r0, REAL *rc, REAL *theta)
{
    *r0 = SQRT(py * py + pz * pz);        /* head circle of the slice */
    *rc = *r0 + hair_offset;              /* shell circle */
    REAL th = ATAN2(py, pz);              /* (−π, π] … */
    if (th <= -HALF_PI_R) th += TWO_PI_R; /* … taken in (−π/2, 3π/2] */
    *theta = th;
    /* A root on the lower back (θ0 > π) hangs straight down from the root. */
    return th > PI_R;
}

/* Point k from its predecessor (py, pz), in place; ρ = the predecessor's slice radius (r0 for
 * the first step, rc after). */
HB_HD void SFX(hb_drape_step)(const REAL ell, const REAL r0, const REAL rc, REAL *theta, REAL *rho, int *hanging,
                              REAL *py, REAL *pz)
{
    if (*hanging) {
        /* Every later point hangs straight down: p_k = p_{k−1} − ℓŷ. */
        *py = *py - ell;
        return;
    }
    /* Step onto the shell circle: the angle α of the triangle (origin, predecessor, new
     * point) has cos α = (ρ² + rc² − ℓ²) / (2ρ rc). Evaluated in the equivalent half-angle
     * form sin²(α/2) = (ℓ − g)(ℓ + g) / (4ρ rc), g = rc − ρ, which keeps its accuracy for
     * short segments where cos α is near 1 (docs/decisions/paper-model.md,
     * "drape_short_segment"). cos α < −1 is s² > 1, cos α > 1 is s² < 0. */
    int fits = 0;
    REAL s2 = 0;
    if (*rho > (REAL)0) {
        const REAL g = rc - *rho;
        s2 = ((ell - g) * (ell + g)) / ((REAL)4 * *rho * rc);
        fits = s2 <= (REAL)1; /* cos α < −1: the step does not fit the circle */
    }
    if (fits) {
        if (s2 < (REAL)0) s2 = (REAL)0; /* the shell is out of reach only by rounding */
        const REAL next = *theta + (REAL)2 * ASIN(SQRT(s2));
        if (next <= PI_R) {
            REAL sin_n, cos_n;
            SFX(hb_sin_cos)(next, &sin_n, &cos_n);
            *theta = next;
            *pz = rc * cos_n;
            *py = rc * sin_n;
#if HB_PLANT == 13 /* judge test: every drape step from the head circle, not the shell */
            *rho = r0;
#else
            (void)r0;
            *rho = rc;
#endif
            return;
        }
    }
    /* The strand starts to hang: the first hanging point goes onto the vertical tangent line
     * z = −rc, at distance ℓ below its predecessor. */
    const REAL dz = *pz + rc;
    const REAL dy2 = ell * ell - dz * dz;
    *py = *py - SQRT(dy2 > (REAL)0 ? dy2 : (REAL)0);
    *pz = -rc;
    *hanging = 1;
}

/* ---- docs/model.md §2.4 wind ------------------------------------------------------------ */
/* Point k was (cy, cz) before the wind; (oy, oz) is its predecessor before the wind and
 * (ny, nz) after it, and both move on to point k. Segment k's direction φ turns toward ψ by
 * t = w·k/(P−1) (last = P − 1) of the shorter arc. */
HB_HD void SFX(hb_wind_step)(const REAL ell, const REAL w, const REAL psi, const REAL last, const int64_t k,
                             const REAL cy, const REAL cz, REAL *oy, REAL *oz, REAL *ny, REAL *nz)
{
    const REAL dy = cy - *oy, dz = cz - *oz;
    const REAL phi = ATAN2(dy, dz);
    REAL delta = psi - phi; /* in [−2π, 2π]: wrap to (−π, π] */
    if (delta > PI_R) delta -= TWO_PI_R;
    else if (delta <= -PI_R) delta += TWO_PI_R;
    /* Exactly opposite: take the arc through +y. Turning by +π passes through the direction
     * φ + π/2, whose y component has the sign of cos φ, i.e. of dz. */
    if (delta == PI_R) delta = dz >= (REAL)0 ? PI_R : -PI_R;
#if HB_PLANT == 11 /* judge test: the wind's blend of segment k taken at k − 1 */
    const REAL t = (w * (REAL)(k - 1)) / last;
#else
    const REAL t = (w * (REAL)k) / last;
#endif
    const REAL turned = phi + t * delta;
    REAL sin_t, cos_t;
    SFX(hb_sin_cos)(turned, &sin_t, &cos_t);
    *nz = *nz + ell * cos_t;
    *ny = *ny + ell * sin_t;
    *oy = cy;
    *oz = cz;
}

/* ---- docs/model.md §2.5 collide --------------------------------------------------------- */
/* From the root (y0, z0): the shell radius rc and the square of the radius below which a
 * point counts as inside (the rounding allowance of HB_SHELL_ULPS). */
HB_HD void SFX(hb_collide_begin)(const REAL y0, const REAL z0, const REAL hair_offset, REAL *rc, REAL *inner2)
{
    const REAL r0 = SQRT(y0 * y0 + z0 * z0);
    *rc = r0 + hair_offset;
    const REAL inner = *rc - *rc * ((REAL)HB_SHELL_ULPS * EPS); /* rounding allowance */
    *inner2 = inner * inner;
}

/* docs/model.md §2.5: the point (y, z) inside the shell moved onto the intersection of the shell
 * (radius rc, centre 0) with the circle of radius ℓ around the predecessor (qy, qz) at distance
 * d > 0 from the centre, the candidate closest to (y, z) (ties: the upper one). The chord's foot
 * lies at a = (d² + rc² − ℓ²) / 2d along the unit u towards the predecessor, the candidates at
 * a·u ± hh·u⊥ with hh = √(rc² − a²), evaluated through t = d − a = ((d − rc)(d + rc) + ℓ²) / 2d
 * and hh² = (rc − a)(rc + a), which avoid the cancellation of rc² − a² when ℓ ≪ rc
 * (docs/decisions/paper-model.md, "collide_short_segment"). Shared by the simd variant's lanes. */
HB_HD void SFX(hb_shell_chord)(const REAL qy, const REAL qz, const REAL d, const REAL rc, const REAL ell, REAL *y,
                               REAL *z)
{
    const REAL t = ((d - rc) * (d + rc) + ell * ell) / ((REAL)2 * d);
    const REAL a = d - t;
    const REAL h2 = ((rc - d) + t) * (rc + a);
    const REAL hh = SQRT(h2 > (REAL)0 ? h2 : (REAL)0);
    const REAL uy = qy / d, uz = qz / d;
    const REAL fy = a * uy, fz = a * uz;
    const REAL y1 = fy + hh * uz, z1 = fz - hh * uy;
    const REAL y2 = fy - hh * uz, z2 = fz + hh * uy;
    const REAL e1 = (y1 - *y) * (y1 - *y) + (z1 - *z) * (z1 - *z);
    const REAL e2 = (y2 - *y) * (y2 - *y) + (z2 - *z) * (z2 - *z);
    const int upper = (e1 < e2) | ((e1 == e2) & (y1 >= y2));
    *y = upper ? y1 : y2;
    *z = upper ? z1 : z2;
}

/* Point (cy, cz), in place, after its predecessor (py, pz), which then moves on to it. A
 * point inside the shell moves to the intersection of the shell circle with the circle of
 * radius ℓ around its predecessor that is closest to where it was (a tie takes the upper
 * one); once a point has moved (`moved`), every later point is pulled follow-the-leader
 * style and checked in turn. Returns whether the point changed (= moved). */
HB_HD int SFX(hb_collide_step)(const REAL ell, const REAL rc, const REAL inner2, int *moved, REAL *py, REAL *pz,
                               REAL *cy, REAL *cz)
{
    const REAL qy = *py, qz = *pz;
    REAL y = *cy, z = *cz;
#if HB_PLANT == 12 /* judge test: no follow-the-leader pull after a move */
    if (0) {
#else
    if (*moved) {
#endif
        /* Follow the leader: p_k ← p_{k−1} + ℓ·unit(p_k − p_{k−1}). */
        const REAL dy = y - qy, dz = z - qz;
        const REAL len = SQRT(dy * dy + dz * dz);
        if (len > (REAL)0) {
            y = qy + ell * (dy / len);
            z = qz + ell * (dz / len);
        } else { /* no direction left: hang down */
            y = qy - ell;
            z = qz;
        }
    }
    if (y * y + z * z < inner2) {
        /* onto the shell's intersection with the circle of radius ℓ around the predecessor */
        const REAL d2 = qy * qy + qz * qz;
        const REAL d = SQRT(d2);
        if (d > (REAL)0) {
            SFX(hb_shell_chord)(qy, qz, d, rc, ell, &y, &z);
            *moved = 1;
        }
    }
    *cy = y;
    *cz = z;
    *py = y;
    *pz = z;
    return *moved;
}

#undef PI_R
#undef HALF_PI_R
#undef TWO_PI_R
