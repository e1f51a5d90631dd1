/* model_impl.h — the paper model (docs/model.md §2), written once for a floating type REAL.
 *
 * Included twice by model.c (REAL = float, then double), after paper/points_impl.h, with the
 * math functions named by SQRT, SIN, COS, ASIN, ATAN2 and the machine epsilon EPS. Each
 * stage walks a strand from the root and computes every point by points_impl.h's step, which
 * the CUDA port's strict build (cuda/paper/model.cuh) calls too; so a strict GPU build differs from
 * this file only where the platforms' sin/cos/asin/atan2 differ.
 *
 * Coordinates: s[3k+0] = x (depth, never changes), s[3k+1] = y (up), s[3k+2] = z (toward
 * the face). Angles θ are measured from +z toward +y.
 */

/* ---- docs/model.md §2.3 drape (SetEndPoint, interpolated points, slerp) -------------- */
void SFX(hb_drape_strand)(const MODEL *m, REAL *s)
{
    const int64_t P = m->points;
    const REAL ell = m->seg_len;
    const REAL x0 = s[0];
    REAL py = s[1], pz = s[2]; /* the predecessor, in the slice plane */
    REAL r0, rc, theta;
    int hanging = SFX(hb_drape_begin)(py, pz, m->hair_offset, &r0, &rc, &theta);
    REAL rho = r0; /* slice radius of the predecessor: r0 for the first step, rc after */

    for (int64_t k = 1; k < P; k++) {
        REAL *q = s + 3 * k;
        SFX(hb_drape_step)(ell, r0, rc, &theta, &rho, &hanging, &py, &pz);
        q[0] = x0;
        q[1] = py;
        q[2] = pz;
    }
}

/* ---- docs/model.md §2.2 roots (SetStartPoint), then the drape ---------------------------- */
void SFX(hb_init_strand)(const MODEL *m, uint64_t strand, REAL *s)
{
    SFX(hb_root_place)(m->seed, strand, m->head_radius, m->face_margin, s);
    SFX(hb_drape_strand)(m, s);
}

/* ---- docs/model.md §2.4 wind ------------------------------------------------------------ */
/* Each segment's direction φk turns toward ψ by t = w·k/(P−1) of the shorter arc (a 2-D
 * slerp); the strand is rebuilt from the root with segments of length ℓ. The caller does
 * not call this when w = 0 (the identity). */
void SFX(hb_wind_strand)(const MODEL *m, REAL *s)
{
    const int64_t P = m->points;
    const REAL last = (REAL)(P - 1);
    REAL oy = s[1], oz = s[2]; /* the predecessor before the wind */
    REAL ny = oy, nz = oz;     /* the predecessor after the wind (the root never moves) */

    for (int64_t k = 1; k < P; k++) {
        REAL *q = s + 3 * k;
        SFX(hb_wind_step)(m->seg_len, m->wind_strength, m->wind_angle, last, k, q[1], q[2], &oy, &oz, &ny, &nz);
        q[1] = ny;
        q[2] = nz;
    }
}

/* ---- docs/model.md §2.5 collide --------------------------------------------------------- */
/* Walk from the root; a point is written back only when collide changed it. Returns the
 * number of points changed. */
int64_t SFX(hb_collide_strand)(const MODEL *m, REAL *s)
{
    const int64_t P = m->points;
    REAL rc, inner2;
    SFX(hb_collide_begin)(s[1], s[2], m->hair_offset, &rc, &inner2);
    int moved = 0;
    int64_t changed = 0;
    REAL py = s[1], pz = s[2];

    for (int64_t k = 1; k < P; k++) {
        REAL *q = s + 3 * k;
        REAL cy = q[1], cz = q[2];
        if (SFX(hb_collide_step)(m->seg_len, rc, inner2, &moved, &py, &pz, &cy, &cz)) {
            q[1] = cy;
            q[2] = cz;
            changed++;
        }
    }
    return changed;
}
