/* dynamics_simd_impl.h — the dynamic model on the point-major layout, one strand per SIMD
 * lane (dynamics_simd.h), written once for a floating type REAL; dynamics_simd.c includes
 * it for float and for double (SFX, DMODEL, SQRT, SIN, QTABLE, PHASE).
 *
 * The normative text is dynamics_impl.h (docs/model.md §3.10): every value here is computed
 * by the same operations in the same order; what changes is the loop nest. The oracle runs
 * one strand through a substep point by point; here every step of it (one constraint, one
 * point's prediction …) is one loop over the DB lanes of the block, so the strands of a
 * block advance together, constraint by constraint. A branch of the oracle (|e| = 0, the
 * collision test, the ftl direction) becomes a select: every lane computes the branch
 * (perhaps an Inf or NaN that is then discarded) and keeps the oracle's value.
 *
 * The feature set is a compile-time constant in every loop, as in the oracle; the frame is
 * cut into two phases that each depend on a few features (velocities: wind, gust, drag,
 * motion; constraints: bend, shape, collide, motion), each instantiated for its own
 * features only (16 + 16 bodies per precision instead of the oracle's 96).
 *
 * Scratch of a block, rows of DB lanes: p [P][3] (predicted positions), λ [3P] (stretch at
 * row 0, bend at row P, shape at row 2P, as the oracle's), d [3] (the ftl correction of the
 * current point: the velocity update of point k−1 is done as soon as d_k is known, which
 * is the oracle's arithmetic in another order of independent values).
 */

#define HB_ALWAYS_INLINE static inline __attribute__((always_inline))
#define DB HB_SIMD_DYN_BLOCK
#define ROWP(a, k) ((a) + (int64_t)(k)*stride)
#define SROW(r) HB_ASSUME_ALIGNED(scratch + (int64_t)(r)*DB)
#define AL(p) HB_ASSUME_ALIGNED(p)

/* §3.5 distance constraint between rows a and b of p, lane by lane (dynamics_impl.h
 * distance): rest length rr[j] (per_lane) or rs, α̃ = at; a moves unless it is the root. */
HB_ALWAYS_INLINE void SFX(distance_lanes)(REAL *restrict ax, REAL *restrict ay, REAL *restrict az, REAL *restrict bx,
                                          REAL *restrict by, REAL *restrict bz, const int move_a, const int per_lane,
                                          const REAL *restrict rr, const REAL rs, const REAL at, REAL *restrict lam)
{
    ax = AL(ax);
    ay = AL(ay);
    az = AL(az);
    bx = AL(bx);
    by = AL(by);
    bz = AL(bz);
    lam = AL(lam);
    const REAL wsum = move_a ? (REAL)2 : (REAL)1;
    const REAL wa = wsum + at;
#pragma omp simd
    for (int j = 0; j < DB; j++) {
        const REAL pax = ax[j], pay = ay[j], paz = az[j], pbx = bx[j], pby = by[j], pbz = bz[j];
        const REAL ex = pbx - pax, ey = pby - pay, ez = pbz - paz;
        const REAL len = SQRT(ex * ex + ey * ey + ez * ez);
        const REAL r = per_lane ? rr[j] : rs;
        const REAL c = len - r;
        const REAL l0 = lam[j];
        const REAL dl = (-c - at * l0) / wa;
        const REAL nx = ex / len, ny = ey / len, nz = ez / len;
        const int zero = len == (REAL)0; /* no direction: nothing moves */
        lam[j] = zero ? l0 : l0 + dl;
        if (move_a) {
            ax[j] = zero ? pax : pax - dl * nx;
            ay[j] = zero ? pay : pay - dl * ny;
            az[j] = zero ? paz : paz - dl * nz;
        }
        bx[j] = zero ? pbx : pbx + dl * nx;
        by[j] = zero ? pby : pby + dl * ny;
        bz[j] = zero ? pbz : pbz + dl * nz;
    }
}

/* §3.5 head collision of row k of p (dynamics_impl.h collide_sphere). */
HB_ALWAYS_INLINE void SFX(collide_lanes)(REAL *restrict px, REAL *restrict py, REAL *restrict pz, const REAL rc)
{
    px = AL(px);
    py = AL(py);
    pz = AL(pz);
#pragma omp simd
    for (int j = 0; j < DB; j++) {
        const REAL x = px[j], y = py[j], z = pz[j];
        const REAL len = SQRT(x * x + y * y + z * z);
        const int in = len < rc, zero = len == (REAL)0;
        const REAL sc = rc / len;
        const REAL nx = zero ? (REAL)0 : x * sc, ny = zero ? rc : y * sc, nz = zero ? (REAL)0 : z * sc;
        px[j] = in ? nx : x;
        py[j] = in ? ny : y;
        pz[j] = in ? nz : z;
    }
}

/* Phase 1 of a substep (steps 1 and 2 of dynamics_impl.h frame_body): the root on the head,
 * the velocities, the prediction p. Features: WIND, GUST, DRAG, MOTION. */
HB_ALWAYS_INLINE void SFX(vel_phase)(const DMODEL *m, const REAL *q, const REAL phase, REAL *X, REAL *Y, REAL *Z,
                                     REAL *VX, REAL *VY, REAL *VZ, const REAL *RX, const REAL *RY, const REAL *RZ,
                                     const int64_t stride, REAL *scratch, const unsigned F)
{
    const int64_t P = m->points;
    const REAL h = m->h;
    if (F & HB_F_MOTION) {
        REAL *restrict x = AL(X), *restrict y = AL(Y), *restrict z = AL(Z);
        REAL *restrict vx = AL(VX), *restrict vy = AL(VY), *restrict vz = AL(VZ);
        const REAL *restrict rx = AL(RX), *restrict ry = AL(RY), *restrict rz = AL(RZ);
        const REAL q0 = q[0], q1 = q[1], q2 = q[2], q3 = q[3], q4 = q[4], q5 = q[5], q6 = q[6], q7 = q[7], q8 = q[8];
#pragma omp simd
        for (int j = 0; j < DB; j++) {
            const REAL a0 = rx[j], a1 = ry[j], a2 = rz[j];
            const REAL r0 = q0 * a0 + q1 * a1 + q2 * a2;
            const REAL r1 = q3 * a0 + q4 * a1 + q5 * a2;
            const REAL r2 = q6 * a0 + q7 * a1 + q8 * a2;
            vx[j] = (r0 - x[j]) / h;
            x[j] = r0;
            vy[j] = (r1 - y[j]) / h;
            y[j] = r1;
            vz[j] = (r2 - z[j]) / h;
            z[j] = r2;
        }
    }
    {
        const REAL *restrict x = AL(X), *restrict y = AL(Y), *restrict z = AL(Z);
        REAL *restrict px = SROW(0), *restrict py = SROW(1), *restrict pz = SROW(2);
#pragma omp simd
        for (int j = 0; j < DB; j++) {
            px[j] = x[j];
            py[j] = y[j];
            pz[j] = z[j];
        }
    }
    const REAL gy = m->gravity_y, wy = m->wind_y, wz = m->wind_z, den = m->den;
    const REAL gust = m->gust, kappa = m->kappa, dy = m->dir_y, dz = m->dir_z;
    (void)wy;
    (void)wz;
    (void)den;
    (void)gust;
    (void)kappa;
    (void)dy;
    (void)dz;
    (void)phase;
    for (int64_t k = 1; k < P; k++) {
        const REAL *restrict x = AL(ROWP(X, k)), *restrict y = AL(ROWP(Y, k)), *restrict z = AL(ROWP(Z, k));
        REAL *restrict vxr = AL(ROWP(VX, k)), *restrict vyr = AL(ROWP(VY, k)), *restrict vzr = AL(ROWP(VZ, k));
        REAL *restrict px = SROW(3 * k), *restrict py = SROW(3 * k + 1), *restrict pz = SROW(3 * k + 2);
#pragma omp simd
        for (int j = 0; j < DB; j++) {
            REAL vx = vxr[j], vy = vyr[j], vz = vzr[j];
            const REAL xx = x[j], xy = y[j], xz = z[j];
            if (F & HB_F_WIND) {
                REAL gam = (REAL)1;
                if (F & HB_F_GUST) gam = (REAL)1 + gust * SIN(phase - kappa * (dy * xy + dz * xz));
                vy = vy + h * (gy + wy * gam);
                vz = vz + h * (wz * gam);
            } else {
                vy = vy + h * gy;
            }
            if (F & HB_F_DRAG) {
                vx = vx / den;
                vy = vy / den;
                vz = vz / den;
            }
            vxr[j] = vx;
            vyr[j] = vy;
            vzr[j] = vz;
            px[j] = xx + h * vx;
            py[j] = xy + h * vy;
            pz[j] = xz + h * vz;
        }
    }
}

/* §3.6 bend constraints of one parity group (dynamics_impl.h bend_group). */
HB_ALWAYS_INLINE void SFX(bend_lanes)(const DMODEL *m, REAL *scratch, const REAL *BR, const int64_t stride,
                                      const int parity)
{
    const int64_t P = m->points;
    for (int64_t k = 1; k + 1 < P; k++)
        if ((((k - 1) / 2) & 1) == parity) {
            const int64_t a = k - 1, b = k + 1;
            SFX(distance_lanes)
            (SROW(3 * a), SROW(3 * a + 1), SROW(3 * a + 2), SROW(3 * b), SROW(3 * b + 1), SROW(3 * b + 2), a != 0, 1,
             ROWP(BR, k - 1), (REAL)0, m->bend_at, SROW(3 * P + P + (k - 1)));
        }
}

/* §3.5 shape pulls toward T_k = Q·X̄_k (X̄_k without motion), k = 1…K. */
HB_ALWAYS_INLINE void SFX(shape_lanes)(const DMODEL *m, REAL *scratch, const REAL *q, const REAL *RX, const REAL *RY,
                                       const REAL *RZ, const int64_t stride, const unsigned F)
{
    const int64_t P = m->points;
    const REAL at = m->shape_at, wa = (REAL)1 + at;
    for (int64_t k = 1; k <= m->shape_count; k++) {
        REAL *restrict px = SROW(3 * k), *restrict py = SROW(3 * k + 1), *restrict pz = SROW(3 * k + 2);
        REAL *restrict lam = SROW(3 * P + 2 * P + (k - 1));
        const REAL *restrict rx = AL(ROWP(RX, k)), *restrict ry = AL(ROWP(RY, k)), *restrict rz = AL(ROWP(RZ, k));
#pragma omp simd
        for (int j = 0; j < DB; j++) {
            const REAL a0 = rx[j], a1 = ry[j], a2 = rz[j];
            REAL t0, t1, t2;
            if (F & HB_F_MOTION) {
                t0 = q[0] * a0 + q[1] * a1 + q[2] * a2;
                t1 = q[3] * a0 + q[4] * a1 + q[5] * a2;
                t2 = q[6] * a0 + q[7] * a1 + q[8] * a2;
            } else {
                t0 = a0;
                t1 = a1;
                t2 = a2;
            }
            const REAL x = px[j], y = py[j], z = pz[j];
            const REAL ex = x - t0, ey = y - t1, ez = z - t2;
            const REAL c = SQRT(ex * ex + ey * ey + ez * ez);
            const REAL l0 = lam[j];
            const REAL dl = (-c - at * l0) / wa;
            const int zero = c == (REAL)0;
            lam[j] = zero ? l0 : l0 + dl;
            px[j] = zero ? x : x + dl * (ex / c);
            py[j] = zero ? y : y + dl * (ey / c);
            pz[j] = zero ? z : z + dl * (ez / c);
        }
    }
}

/* Phase 2 of a substep (steps 3 and 4): the constraints of the solver, then the velocities
 * from the motion and the positions. Features: BEND, SHAPE, COLLIDE, MOTION (for shape). */
HB_ALWAYS_INLINE void SFX(con_phase)(const DMODEL *m, const REAL *q, REAL *X, REAL *Y, REAL *Z, REAL *VX, REAL *VY,
                                     REAL *VZ, const REAL *RX, const REAL *RY, const REAL *RZ, const REAL *BR,
                                     const int64_t stride, REAL *scratch, const unsigned F)
{
    const int64_t P = m->points;
    const REAL h = m->h, ell = m->seg_len;
    /* every multiplier in use starts the substep at 0 */
    {
        REAL *restrict lam = SROW(3 * P);
        const int64_t rows = (F & HB_F_SHAPE) ? 3 * P : (F & HB_F_BEND) ? 2 * P : P;
        for (int64_t i = 0; i < rows * DB; i++) lam[i] = (REAL)0;
    }
    if (m->solver == HB_SOLVER_XPBD) {
        for (int64_t it = 0; it < m->iterations; it++) {
            // clang-format off
            for (int64_t k = 1; k < P; k += 2) /* stretch, k odd */
                SFX(distance_lanes)(SROW(3 * (k - 1)), SROW(3 * (k - 1) + 1), SROW(3 * (k - 1) + 2), SROW(3 * k),
                                    SROW(3 * k + 1), SROW(3 * k + 2), k - 1 != 0, 0, NULL, ell, m->stretch_at,
                                    SROW(3 * P + (k - 1)));
            for (int64_t k = 2; k < P; k += 2) /* stretch, k even */
                SFX(distance_lanes)(SROW(3 * (k - 1)), SROW(3 * (k - 1) + 1), SROW(3 * (k - 1) + 2), SROW(3 * k),
                                    SROW(3 * k + 1), SROW(3 * k + 2), 1, 0, NULL, ell, m->stretch_at,
                                    SROW(3 * P + (k - 1)));
            // clang-format on
            if (F & HB_F_BEND) {
                SFX(bend_lanes)(m, scratch, BR, stride, 0);
                SFX(bend_lanes)(m, scratch, BR, stride, 1);
            }
            if (F & HB_F_SHAPE) SFX(shape_lanes)(m, scratch, q, RX, RY, RZ, stride, F);
            if (F & HB_F_COLLIDE)
                for (int64_t k = 1; k < P; k++)
                    SFX(collide_lanes)(SROW(3 * k), SROW(3 * k + 1), SROW(3 * k + 2), m->collide_r);
        }
        /* 4. v = (p − x)/h, then x = p */
        for (int64_t k = 1; k < P; k++) {
            REAL *restrict x = AL(ROWP(X, k)), *restrict y = AL(ROWP(Y, k)), *restrict z = AL(ROWP(Z, k));
            REAL *restrict vx = AL(ROWP(VX, k)), *restrict vy = AL(ROWP(VY, k)), *restrict vz = AL(ROWP(VZ, k));
            const REAL *restrict px = SROW(3 * k), *restrict py = SROW(3 * k + 1), *restrict pz = SROW(3 * k + 2);
#pragma omp simd
            for (int j = 0; j < DB; j++) {
                const REAL nx = px[j], ny = py[j], nz = pz[j];
                vx[j] = (nx - x[j]) / h;
                vy[j] = (ny - y[j]) / h;
                vz[j] = (nz - z[j]) / h;
                x[j] = nx;
                y[j] = ny;
                z[j] = nz;
            }
        }
        return;
    }
    for (int64_t it = 0; it < m->iterations; it++) {
        if (F & HB_F_BEND) {
            SFX(bend_lanes)(m, scratch, BR, stride, 0);
            SFX(bend_lanes)(m, scratch, BR, stride, 1);
        }
        if (F & HB_F_SHAPE) SFX(shape_lanes)(m, scratch, q, RX, RY, RZ, stride, F);
    }
    /* §3.7 follow the leader, point by point; as soon as d_k is known, point k − 1 is final:
     * v_{k−1} = (p − x)/h − (s·d_k)/h and x_{k−1} = p (the oracle's step 4 for that point) */
    const REAL s = m->ftl_s, rc = m->collide_r;
    (void)rc;
    REAL *restrict dx = SROW(6 * P), *restrict dy = SROW(6 * P + 1), *restrict dz = SROW(6 * P + 2);
    for (int64_t k = 1; k < P; k++) {
        {
            REAL *restrict px = SROW(3 * k), *restrict py = SROW(3 * k + 1), *restrict pz = SROW(3 * k + 2);
            const REAL *restrict ppx = SROW(3 * (k - 1)), *restrict ppy = SROW(3 * (k - 1) + 1),
                                 *restrict ppz = SROW(3 * (k - 1) + 2);
#pragma omp simd
            for (int j = 0; j < DB; j++) {
                const REAL ax = ppx[j], ay = ppy[j], az = ppz[j], bx = px[j], by = py[j], bz = pz[j];
                const REAL ex = bx - ax, ey = by - ay, ez = bz - az;
                const REAL len = SQRT(ex * ex + ey * ey + ez * ez);
                const int pos = len > (REAL)0;
                const REAL fx = ax + ell * (ex / len), fy = ay + ell * (ey / len), fz = az + ell * (ez / len);
                const REAL down = ay - ell;
                REAL qx = pos ? fx : ax, qy = pos ? fy : down, qz = pos ? fz : az;
                dx[j] = qx - bx;
                dy[j] = qy - by;
                dz[j] = qz - bz;
                if (F & HB_F_COLLIDE) {
                    const REAL cl = SQRT(qx * qx + qy * qy + qz * qz);
                    const int in = cl < rc, zero = cl == (REAL)0;
                    const REAL sc = rc / cl;
                    const REAL nx = zero ? (REAL)0 : qx * sc, ny = zero ? rc : qy * sc, nz = zero ? (REAL)0 : qz * sc;
                    qx = in ? nx : qx;
                    qy = in ? ny : qy;
                    qz = in ? nz : qz;
                }
                px[j] = qx;
                py[j] = qy;
                pz[j] = qz;
            }
        }
        if (k >= 2) {
            const int64_t k1 = k - 1;
            REAL *restrict x = AL(ROWP(X, k1)), *restrict y = AL(ROWP(Y, k1)), *restrict z = AL(ROWP(Z, k1));
            REAL *restrict vx = AL(ROWP(VX, k1)), *restrict vy = AL(ROWP(VY, k1)), *restrict vz = AL(ROWP(VZ, k1));
            const REAL *restrict px = SROW(3 * k1), *restrict py = SROW(3 * k1 + 1), *restrict pz = SROW(3 * k1 + 2);
#pragma omp simd
            for (int j = 0; j < DB; j++) {
                const REAL nx = px[j], ny = py[j], nz = pz[j];
                REAL wx = (nx - x[j]) / h, wy = (ny - y[j]) / h, wz = (nz - z[j]) / h;
                wx = wx - (s * dx[j]) / h;
                wy = wy - (s * dy[j]) / h;
                wz = wz - (s * dz[j]) / h;
                vx[j] = wx;
                vy[j] = wy;
                vz[j] = wz;
                x[j] = nx;
                y[j] = ny;
                z[j] = nz;
            }
        }
    }
    { /* the last point: no correction */
        const int64_t k1 = P - 1;
        REAL *restrict x = AL(ROWP(X, k1)), *restrict y = AL(ROWP(Y, k1)), *restrict z = AL(ROWP(Z, k1));
        REAL *restrict vx = AL(ROWP(VX, k1)), *restrict vy = AL(ROWP(VY, k1)), *restrict vz = AL(ROWP(VZ, k1));
        const REAL *restrict px = SROW(3 * k1), *restrict py = SROW(3 * k1 + 1), *restrict pz = SROW(3 * k1 + 2);
#pragma omp simd
        for (int j = 0; j < DB; j++) {
            const REAL nx = px[j], ny = py[j], nz = pz[j];
            vx[j] = (nx - x[j]) / h;
            vy[j] = (ny - y[j]) / h;
            vz[j] = (nz - z[j]) / h;
            x[j] = nx;
            y[j] = ny;
            z[j] = nz;
        }
    }
}

/* The two phases, one function per feature subset (the switches' constants specialise). */
#define VEL_F(i)                                                                                                       \
    ((((i)&1) ? HB_F_WIND : 0u) | (((i)&2) ? HB_F_GUST : 0u) | (((i)&4) ? HB_F_DRAG : 0u) |                            \
     (((i)&8) ? HB_F_MOTION : 0u))
#define CON_F(i)                                                                                                       \
    ((((i)&1) ? HB_F_BEND : 0u) | (((i)&2) ? HB_F_SHAPE : 0u) | (((i)&4) ? HB_F_COLLIDE : 0u) |                        \
     (((i)&8) ? HB_F_MOTION : 0u))
#define CASE16(C) C(0) C(1) C(2) C(3) C(4) C(5) C(6) C(7) C(8) C(9) C(10) C(11) C(12) C(13) C(14) C(15)

static void SFX(vel_dispatch)(unsigned idx, const DMODEL *m, const REAL *q, const REAL phase, REAL *X, REAL *Y, REAL *Z,
                              REAL *VX, REAL *VY, REAL *VZ, const REAL *RX, const REAL *RY, const REAL *RZ,
                              const int64_t stride, REAL *scratch)
{
#define VCASE(i)                                                                                                       \
    case (i):                                                                                                          \
        if (((i)&2) && !((i)&1)) break; /* no gusts without wind (hb_dyn_features) */                                  \
        SFX(vel_phase)(m, q, phase, X, Y, Z, VX, VY, VZ, RX, RY, RZ, stride, scratch, VEL_F(i));                       \
        break;
    switch (idx) {
        CASE16(VCASE)
    default: break;
    }
#undef VCASE
}

static void SFX(con_dispatch)(unsigned idx, const DMODEL *m, const REAL *q, REAL *X, REAL *Y, REAL *Z, REAL *VX,
                              REAL *VY, REAL *VZ, const REAL *RX, const REAL *RY, const REAL *RZ, const REAL *BR,
                              const int64_t stride, REAL *scratch)
{
#define CCASE(i)                                                                                                       \
    case (i):                                                                                                          \
        if (((i)&8) && !((i)&2)) break; /* motion matters here only through shape */                                   \
        SFX(con_phase)(m, q, X, Y, Z, VX, VY, VZ, RX, RY, RZ, BR, stride, scratch, CON_F(i));                          \
        break;
    switch (idx) {
        CASE16(CCASE)
    default: break;
    }
#undef CCASE
}

void SFX(hb_simd_dyn_frame_block)(const DMODEL *m, const hb_dyn_frame *fr, REAL *X, REAL *Y, REAL *Z, REAL *VX,
                                  REAL *VY, REAL *VZ, const REAL *RX, const REAL *RY, const REAL *RZ, const REAL *BR,
                                  int64_t stride, REAL *scratch)
{
    const unsigned F = m->features;
    const unsigned vi = ((F & HB_F_WIND) ? 1u : 0u) | ((F & HB_F_WIND) && (F & HB_F_GUST) ? 2u : 0u) |
                        ((F & HB_F_DRAG) ? 4u : 0u) | ((F & HB_F_MOTION) ? 8u : 0u);
    const unsigned ci = ((F & HB_F_BEND) ? 1u : 0u) | ((F & HB_F_SHAPE) ? 2u : 0u) | ((F & HB_F_COLLIDE) ? 4u : 0u) |
                        ((F & HB_F_SHAPE) && (F & HB_F_MOTION) ? 8u : 0u);
    for (int64_t j = 0; j < m->substeps; j++) {
        const REAL *q = QTABLE(fr) + 9 * j; /* Q(t + h) */
        const REAL phase = PHASE(fr)[j];    /* φ(t) */
        SFX(vel_dispatch)(vi, m, q, phase, X, Y, Z, VX, VY, VZ, RX, RY, RZ, stride, scratch);
        SFX(con_dispatch)(ci, m, q, X, Y, Z, VX, VY, VZ, RX, RY, RZ, BR, stride, scratch);
    }
}

/* §3.5 bend rest lengths, lane by lane (dynamics_impl.h hb_dyn_bend_rest). */
void SFX(hb_simd_dyn_bend_rest_block)(const DMODEL *m, const REAL *RX, const REAL *RY, const REAL *RZ, REAL *BR,
                                      int64_t stride)
{
    for (int64_t k = 1; k + 1 < m->points; k++) {
        const REAL *restrict ax = AL(ROWP(RX, k - 1)), *restrict ay = AL(ROWP(RY, k - 1)),
                             *restrict az = AL(ROWP(RZ, k - 1));
        const REAL *restrict bx = AL(ROWP(RX, k + 1)), *restrict by = AL(ROWP(RY, k + 1)),
                             *restrict bz = AL(ROWP(RZ, k + 1));
        REAL *restrict br = AL(ROWP(BR, k - 1));
#pragma omp simd
        for (int j = 0; j < DB; j++) {
            const REAL ex = bx[j] - ax[j], ey = by[j] - ay[j], ez = bz[j] - az[j];
            br[j] = SQRT(ex * ex + ey * ey + ez * ez);
        }
    }
}

/* §3.8 observables of strands first … first + count − 1 (dynamics_impl.h
 * hb_dyn_observe_strand, lane by lane; the same operations, so the same bits per strand). */
#define OBS_LANES 256
void SFX(hb_simd_dyn_observe)(const hb_scene *s, const REAL *X, const REAL *Y, const REAL *Z, const REAL *VX,
                              const REAL *VY, const REAL *VZ, int64_t stride, int64_t first, int64_t count,
                              hb_obs_partial *out)
{
    const int64_t P = s->points;
    const double ell = hb_segment_length(s), far2 = 4.0 * s->hair_length * s->hair_length;
    const double rc = s->head_radius + s->dyn.collision_margin;
    const int collider = s->dyn.collider;
    const double big = 1.7976931348623157e308; /* |a| ≤ DBL_MAX: finite (false for NaN) */
    double smax[OBS_LANES], pmax[OBS_LANES], v2[OBS_LANES];
    int64_t blown[OBS_LANES];
    for (int64_t c0 = 0; c0 < count; c0 += OBS_LANES) {
        const int n = (int)(count - c0 < OBS_LANES ? count - c0 : OBS_LANES);
        const int64_t base = first + c0;
        {
            const REAL *x = X + base, *y = Y + base, *z = Z + base, *vx = VX + base, *vy = VY + base, *vz = VZ + base;
#pragma omp simd
            for (int j = 0; j < n; j++) {
                const int fin = (fabs((double)x[j]) <= big) & (fabs((double)y[j]) <= big) &
                                (fabs((double)z[j]) <= big) & (fabs((double)vx[j]) <= big) &
                                (fabs((double)vy[j]) <= big) & (fabs((double)vz[j]) <= big);
                blown[j] = !fin;
                smax[j] = 0.0;
                pmax[j] = 0.0;
                v2[j] = 0.0;
            }
        }
        for (int64_t k = 1; k < P; k++) {
            const REAL *x0 = X + base, *y0 = Y + base, *z0 = Z + base;
            const REAL *xp = ROWP(X, k - 1) + base, *yp = ROWP(Y, k - 1) + base, *zp = ROWP(Z, k - 1) + base;
            const REAL *x = ROWP(X, k) + base, *y = ROWP(Y, k) + base, *z = ROWP(Z, k) + base;
            const REAL *vx = ROWP(VX, k) + base, *vy = ROWP(VY, k) + base, *vz = ROWP(VZ, k) + base;
#pragma omp simd
            for (int j = 0; j < n; j++) {
                const double a0 = (double)x[j], a1 = (double)y[j], a2 = (double)z[j];
                const double w0 = (double)vx[j], w1 = (double)vy[j], w2v = (double)vz[j];
                const double e0 = a0 - (double)xp[j], e1 = a1 - (double)yp[j], e2 = a2 - (double)zp[j];
                const double r0 = a0 - (double)x0[j], r1 = a1 - (double)y0[j], r2v = a2 - (double)z0[j];
                double l2 = 0.0, r2 = 0.0, n2 = 0.0, w2 = 0.0;
                l2 += e0 * e0;
                r2 += r0 * r0;
                n2 += a0 * a0;
                w2 += w0 * w0;
                l2 += e1 * e1;
                r2 += r1 * r1;
                n2 += a1 * a1;
                w2 += w1 * w1;
                l2 += e2 * e2;
                r2 += r2v * r2v;
                n2 += a2 * a2;
                w2 += w2v * w2v;
                const int fin = (fabs(a0) <= big) & (fabs(a1) <= big) & (fabs(a2) <= big) & (fabs(w0) <= big) &
                                (fabs(w1) <= big) & (fabs(w2v) <= big);
                const double st = fabs(sqrt(l2) / ell - 1.0);
                smax[j] = st > smax[j] ? st : smax[j];
                const double pen = rc - sqrt(n2);
                if (collider) pmax[j] = pen > pmax[j] ? pen : pmax[j];
                v2[j] += w2;
                blown[j] |= (!fin) | (r2 > far2);
            }
        }
        for (int j = 0; j < n; j++) {
            out[c0 + j].stretch_max = smax[j];
            out[c0 + j].penetration_max = pmax[j];
            out[c0 + j].v2_sum = v2[j];
            out[c0 + j].blown = blown[j];
        }
    }
}
#undef OBS_LANES

#undef VEL_F
#undef CON_F
#undef CASE16
#undef HB_ALWAYS_INLINE
#undef DB
#undef ROWP
#undef SROW
#undef AL
