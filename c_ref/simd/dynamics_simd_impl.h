/* dynamics_simd_impl.h — the dynamic model on the point-major layout, one strand per SIMD
 * lane (dynamics_simd.h), written once for a floating type REAL; dynamics_simd.c includes
 * it for float and for double (SFX, DMODEL, SQRT, SIN, QTABLE, PHASE, INV_SQRT_ROW, TINY).
 *
 * The model is dynamics_impl.h's (docs/model.md §3): the same steps, constraints, groups
 * and order. The arithmetic is free (docs/cpu_simd.md, "Free arithmetic"): a length's
 * reciprocal comes from INV_SQRT_ROW (fp32: rsqrt and one Newton step), every constant
 * denominator (h, the drag factor, w_a + w_b + α̃) is a reciprocal computed once per block
 * and frame, and products replace divisions. So the result is not the oracle's bits; it is
 * judged by the one-frame rule (tests/test_cpu_simd_dynamic.py). What stays exact: the
 * roots (the oracle's rotation), the bend rest lengths and the observables' arithmetic.
 *
 * Every step of the oracle (one constraint, one point's prediction …) is one loop over the
 * DB lanes of the block, so the strands of a block advance together, constraint by
 * constraint. A branch of the oracle (|e| = 0, the collision test, the ftl direction)
 * becomes a select. The feature set is a compile-time constant in every loop; the frame is
 * cut into two phases that each depend on a few features (velocities: wind, gust, drag,
 * motion; constraints: bend, shape, collide, motion), each instantiated for its own
 * features only.
 *
 * Scratch of a block, rows of DB lanes: p [P][3] (predicted positions), λ [3P] (stretch at
 * row 0, bend at row P, shape at row 2P; a kind with α̃ = 0 needs none), d [3] (the ftl
 * correction of the current point), and 5 rows for one constraint's |e|², 1/|e| and e.
 */

#define HB_ALWAYS_INLINE static inline __attribute__((always_inline))
#define DB HB_SIMD_DYN_BLOCK
#define ROWP(a, k) ((a) + (int64_t)(k)*stride)
#define SROW(r) HB_ASSUME_ALIGNED(scratch + (int64_t)(r)*DB)
#define AL(p) HB_ASSUME_ALIGNED(p)
/* row k of a block's contact planes [P][DB][HB_CONTACT_POINT] (NULL without --contact-planes) */
#define CON_ROW(c, k) ((c) ? (c) + (int64_t)(k)*DB * HB_CONTACT_POINT : NULL)
#define TMP(m, i) SROW(6 * (m)->points + 3 + (i))    /* 0: |e|², 1: 1/|e|, 2–4: e */
#define HS_ROW(m, k) (6 * (m)->points + 8 + 8 * (k)) /* §3.16 `held`: point k's sample, 8 rows */

/* The constant denominators' reciprocals and the constants beside them. */
typedef struct {
    REAL h, ih, iden;         /* h, 1/h, 1/(1 + h(c_d + β)) */
    REAL st_at, st_w1, st_w2; /* stretch α̃, 1/(1 + α̃) (one end the root), 1/(2 + α̃) */
    REAL bd_at, bd_w1, bd_w2; /* the same for bend */
    REAL sh_at, sh_w1;        /* shape α̃, 1/(1 + α̃) */
    REAL rc, rc2, ell, s_ih;  /* R_c, R_c², ℓ, s/h */
} SFX(dyn_consts);

/* §3.5 distance constraint between rows a and b of p, lane by lane: rest length rr[j]
 * (per_lane) or rs, α̃ = at, rw = 1/(w_a + w_b + α̃); lam = NULL when α̃ = 0 (the
 * multiplier then never enters Δλ). a moves unless it is the root. */
HB_ALWAYS_INLINE void SFX(distance_solve)(REAL *restrict ax, REAL *restrict ay, REAL *restrict az, REAL *restrict bx,
                                          REAL *restrict by, REAL *restrict bz, const int move_a, const int per_lane,
                                          const REAL *restrict rr, const REAL rs, const REAL at, const REAL rw,
                                          REAL *restrict lam, const int use_lam, const REAL *restrict l2r,
                                          const REAL *restrict inv)
{
#pragma omp simd
    for (int j = 0; j < DB; j++) {
        const REAL pax = ax[j], pay = ay[j], paz = az[j], pbx = bx[j], pby = by[j], pbz = bz[j];
        const REAL ex = pbx - pax, ey = pby - pay, ez = pbz - paz;
        const REAL l2 = l2r[j], iv = inv[j];
        const int zero = l2 < TINY; /* no direction: nothing moves */
        const REAL c = l2 * iv - (per_lane ? rr[j] : rs);
        REAL dl;
        if (use_lam) {
            const REAL l0 = lam[j];
            dl = (-c - at * l0) * rw;
            lam[j] = zero ? l0 : l0 + dl;
        } else {
            dl = -c * rw;
        }
        const REAL g = zero ? (REAL)0 : dl * iv; /* Δλ/|e|: the step along e */
        if (move_a) {
            ax[j] = pax - g * ex;
            ay[j] = pay - g * ey;
            az[j] = paz - g * ez;
        }
        bx[j] = pbx + g * ex;
        by[j] = pby + g * ey;
        bz[j] = pbz + g * ez;
    }
}

HB_ALWAYS_INLINE void SFX(distance_lanes)(const DMODEL *m, REAL *scratch, const int64_t a, const int64_t b,
                                          const int per_lane, const REAL *rr, const REAL rs, const REAL at,
                                          const REAL rw, REAL *lam)
{
    REAL *restrict ax = SROW(3 * a), *restrict ay = SROW(3 * a + 1), *restrict az = SROW(3 * a + 2);
    REAL *restrict bx = SROW(3 * b), *restrict by = SROW(3 * b + 1), *restrict bz = SROW(3 * b + 2);
    REAL *restrict l2r = TMP(m, 0), *restrict inv = TMP(m, 1);
#pragma omp simd
    for (int j = 0; j < DB; j++) {
        const REAL ex = bx[j] - ax[j], ey = by[j] - ay[j], ez = bz[j] - az[j];
        l2r[j] = ex * ex + ey * ey + ez * ez;
    }
    INV_SQRT_ROW(l2r, inv);
    const int move_a = a != 0;
    if (lam && move_a) SFX(distance_solve)(ax, ay, az, bx, by, bz, 1, per_lane, rr, rs, at, rw, AL(lam), 1, l2r, inv);
    else if (lam) SFX(distance_solve)(ax, ay, az, bx, by, bz, 0, per_lane, rr, rs, at, rw, AL(lam), 1, l2r, inv);
    else if (move_a) SFX(distance_solve)(ax, ay, az, bx, by, bz, 1, per_lane, rr, rs, at, rw, NULL, 0, l2r, inv);
    else SFX(distance_solve)(ax, ay, az, bx, by, bz, 0, per_lane, rr, rs, at, rw, NULL, 0, l2r, inv);
}

/* §3.5 head collision of row k of p (dynamics_impl.h collide_sphere): inside when
 * |p|² < R_c²; the centre itself (|p|² below TINY) goes to (0, R_c, 0). */
/* docs/model.md §3.13 long-range attachment of point k to the root (row 0), every lane:
 * |p_k − p_0| ≤ (s_L·ℓ)·k, the oracle's lra_all for one point. */
HB_ALWAYS_INLINE void SFX(lra_lanes)(const DMODEL *m, REAL *scratch, const int64_t k)
{
    REAL *restrict px = SROW(3 * k), *restrict py = SROW(3 * k + 1), *restrict pz = SROW(3 * k + 2);
    const REAL *restrict ox = SROW(0), *restrict oy = SROW(1), *restrict oz = SROW(2);
    const REAL r = m->lra_len * (REAL)k;
#pragma omp simd
    for (int j = 0; j < DB; j++) {
        const REAL ex = px[j] - ox[j], ey = py[j] - oy[j], ez = pz[j] - oz[j];
        const REAL d = SQRT(ex * ex + ey * ey + ez * ez);
        const int over = d > r;
        const REAL sc = r / (over ? d : r + (REAL)1);
        px[j] = over ? ox[j] + ex * sc : px[j];
        py[j] = over ? oy[j] + ey * sc : py[j];
        pz[j] = over ? oz[j] + ez * sc : pz[j];
    }
}

HB_ALWAYS_INLINE void SFX(collide_lanes)(const DMODEL *m, REAL *scratch, const int64_t k, const SFX(dyn_consts) * K)
{
    REAL *restrict px = SROW(3 * k), *restrict py = SROW(3 * k + 1), *restrict pz = SROW(3 * k + 2);
    REAL *restrict l2r = TMP(m, 0), *restrict inv = TMP(m, 1);
    const REAL rc = K->rc, rc2 = K->rc2;
#pragma omp simd
    for (int j = 0; j < DB; j++) {
        const REAL x = px[j], y = py[j], z = pz[j];
        l2r[j] = x * x + y * y + z * z;
    }
    INV_SQRT_ROW(l2r, inv);
#pragma omp simd
    for (int j = 0; j < DB; j++) {
        const REAL x = px[j], y = py[j], z = pz[j], l2 = l2r[j];
        const int in = l2 < rc2, zero = l2 < TINY;
        const REAL sc = rc * inv[j];
        const REAL nx = zero ? (REAL)0 : x * sc, ny = zero ? rc : y * sc, nz = zero ? (REAL)0 : z * sc;
        px[j] = in ? nx : x;
        py[j] = in ? ny : y;
        pz[j] = in ? nz : z;
    }
}

/* §3.6 step 7 / §3.7 with the colliders of §3.17 on row k (≥ 1) of p, lane by lane: the
 * reference's collision step itself (contact_impl.h hb_collide_sweeps: the head sphere as `head`
 * says, HB_HEAD_NONE where collide_lanes projected it already, then each collider with its
 * friction, in sweeps, or the row's contact planes con, NULL without --contact-planes); x: the row
 * at the substep's start. */
HB_ALWAYS_INLINE void SFX(world_row)(const WORLD *w, const REAL *pose, const REAL *back, const REAL rc, const int head,
                                     REAL *px, REAL *py, REAL *pz, const REAL *x, const REAL *y, const REAL *z,
                                     const REAL *con)
{
    for (int l = 0; l < DB; l++) {
        REAL p[3] = {px[l], py[l], pz[l]};
        const REAL xs[3] = {x[l], y[l], z[l]};
        SFX(hb_collide_sweeps)(w, rc, head, pose, back, p, xs, con ? con + HB_CONTACT_POINT * l : NULL);
        px[l] = p[0];
        py[l] = p[1];
        pz[l] = p[2];
    }
}

/* §3.16 the hair–hair correction of row k (≥ 1) in step 2, lane by lane with the reference's
 * operations (contact_impl.h): the frame's held sample, taken at its first substep into the
 * block's rows hs (8 a point), or a sample taken now. */
HB_ALWAYS_INLINE void SFX(grid_row)(const WORLD *w, const REAL *qg, const REAL h, const int64_t k, const int64_t j,
                                    const REAL *x, const REAL *y, const REAL *z, REAL *vx, REAL *vy, REAL *vz, REAL *hs)
{
    const int held = w->grid_rebuild == HB_GRID_HELD;
    for (int l = 0; l < DB; l++) {
        const REAL xk[3] = {x[l], y[l], z[l]};
        REAL vk[3] = {vx[l], vy[l], vz[l]},
             sm[8] = {(REAL)0, (REAL)0, (REAL)0, (REAL)0, (REAL)0, (REAL)0, (REAL)0, (REAL)0};
        if (held) {
            if (j == 0) {
                SFX(hb_grid_sample)(w, qg, xk, sm);
                for (int c = 0; c < 8; c++) hs[c * DB + l] = sm[c];
            } else {
                for (int c = 0; c < 8; c++) sm[c] = hs[c * DB + l];
            }
            SFX(hb_grid_apply)(w, h, k, sm, vk);
        } else {
            SFX(hb_grid_correct)(w, qg, h, k, xk, vk);
        }
        vx[l] = vk[0];
        vy[l] = vk[1];
        vz[l] = vk[2];
    }
}

/* Phase 1 of a substep (steps 1 and 2 of dynamics_impl.h frame_body): the root on the head,
 * the velocities, the prediction p. Features: WIND, GUST, DRAG, MOTION. With `prefetch`,
 * the rows of the next block's x and v are requested (into L2) row by row, so that they
 * arrive while this block computes. */
HB_ALWAYS_INLINE void SFX(vel_phase)(const DMODEL *m, const SFX(dyn_consts) * K, const REAL *q, const REAL phase,
                                     REAL *X, REAL *Y, REAL *Z, REAL *VX, REAL *VY, REAL *VZ, const REAL *RX,
                                     const REAL *RY, const REAL *RZ, const int64_t stride, REAL *scratch,
                                     const WORLD *w, const REAL *qg, const int64_t jj, const int prefetch,
                                     const unsigned F)
{
    const int64_t P = m->points;
    const REAL h = K->h, ih = K->ih;
    if (F & HB_F_MOTION) {
        REAL *restrict x = AL(X), *restrict y = AL(Y), *restrict z = AL(Z);
        REAL *restrict vx = AL(VX), *restrict vy = AL(VY), *restrict vz = AL(VZ);
        const REAL *restrict rx = AL(RX), *restrict ry = AL(RY), *restrict rz = AL(RZ);
        const REAL q0 = q[0], q1 = q[1], q2 = q[2], q3 = q[3], q4 = q[4], q5 = q[5], q6 = q[6], q7 = q[7], q8 = q[8];
#pragma omp simd
        for (int j = 0; j < DB; j++) {
            const REAL a0 = rx[j], a1 = ry[j], a2 = rz[j];
            const REAL r0 = q0 * a0 + q1 * a1 + q2 * a2; /* the oracle's rotation: roots stay exact */
            const REAL r1 = q3 * a0 + q4 * a1 + q5 * a2;
            const REAL r2 = q6 * a0 + q7 * a1 + q8 * a2;
            vx[j] = (r0 - x[j]) * ih;
            x[j] = r0;
            vy[j] = (r1 - y[j]) * ih;
            y[j] = r1;
            vz[j] = (r2 - z[j]) * ih;
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
    const REAL gy = m->gravity_y, wy = m->wind_y, wz = m->wind_z, iden = K->iden;
    const REAL gust = m->gust, kappa = m->kappa, dy = m->dir_y, dz = m->dir_z;
    (void)wy;
    (void)wz;
    (void)iden;
    (void)gust;
    (void)kappa;
    (void)dy;
    (void)dz;
    (void)phase;
    for (int64_t k = 0; k < P; k++) {
        if (prefetch) {
            /* addresses as integers: past the last block they point nowhere, and a prefetch
             * of nowhere is harmless */
            const REAL *rows[6] = {ROWP(X, k), ROWP(Y, k), ROWP(Z, k), ROWP(VX, k), ROWP(VY, k), ROWP(VZ, k)};
            for (int a = 0; a < 6; a++)
                for (uintptr_t b = DB * sizeof(REAL); b < 2 * DB * sizeof(REAL); b += 64)
                    __builtin_prefetch((const void *)((uintptr_t)rows[a] + b), 0, HB_SIMD_DYN_PREFETCH_HINT);
        }
        if (k == 0) continue;
        const REAL *restrict x = AL(ROWP(X, k)), *restrict y = AL(ROWP(Y, k)), *restrict z = AL(ROWP(Z, k));
        REAL *restrict vxr = AL(ROWP(VX, k)), *restrict vyr = AL(ROWP(VY, k)), *restrict vzr = AL(ROWP(VZ, k));
        REAL *restrict px = SROW(3 * k), *restrict py = SROW(3 * k + 1), *restrict pz = SROW(3 * k + 2);
        if (w) SFX(grid_row)(w, qg, h, k, jj, x, y, z, vxr, vyr, vzr, SROW(HS_ROW(m, k)));
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
                vx = vx * iden;
                vy = vy * iden;
                vz = vz * iden;
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
HB_ALWAYS_INLINE void SFX(bend_lanes)(const DMODEL *m, const SFX(dyn_consts) * K, REAL *scratch, const REAL *BR,
                                      const int64_t stride, const int parity)
{
    const int64_t P = m->points;
    for (int64_t k = 1; k + 1 < P; k++) {
        if ((((k - 1) / 2) & 1) != parity) continue;
        const REAL rw = k - 1 != 0 ? K->bd_w2 : K->bd_w1;
        REAL *lam = K->bd_at != (REAL)0 ? SROW(3 * P + P + (k - 1)) : NULL;
        SFX(distance_lanes)(m, scratch, k - 1, k + 1, 1, AL(ROWP(BR, k - 1)), (REAL)0, K->bd_at, rw, lam);
    }
}

/* §3.5 shape pulls toward T_k = Q·X̄_k (X̄_k without motion), k = 1…K. */
HB_ALWAYS_INLINE void SFX(shape_lanes)(const DMODEL *m, const SFX(dyn_consts) * K, REAL *scratch, const REAL *q,
                                       const REAL *RX, const REAL *RY, const REAL *RZ, const int64_t stride,
                                       const unsigned F)
{
    const int64_t P = m->points;
    const REAL at = K->sh_at, rw = K->sh_w1;
    REAL *restrict l2r = TMP(m, 0), *restrict inv = TMP(m, 1);
    REAL *restrict exr = TMP(m, 2), *restrict eyr = TMP(m, 3), *restrict ezr = TMP(m, 4);
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
            const REAL ex = px[j] - t0, ey = py[j] - t1, ez = pz[j] - t2;
            exr[j] = ex;
            eyr[j] = ey;
            ezr[j] = ez;
            l2r[j] = ex * ex + ey * ey + ez * ez;
        }
        INV_SQRT_ROW(l2r, inv);
#pragma omp simd
        for (int j = 0; j < DB; j++) {
            const REAL l2 = l2r[j], iv = inv[j];
            const int zero = l2 < TINY;
            const REAL l0 = lam[j];
            const REAL dl = (-(l2 * iv) - at * l0) * rw;
            lam[j] = zero ? l0 : l0 + dl;
            const REAL g = zero ? (REAL)0 : dl * iv;
            px[j] = px[j] + g * exr[j];
            py[j] = py[j] + g * eyr[j];
            pz[j] = pz[j] + g * ezr[j];
        }
    }
}

/* x ← p and v ← (p − x)/h − (s/h)·d (d = NULL: no correction) for row k. */
HB_ALWAYS_INLINE void SFX(update_row)(const SFX(dyn_consts) * K, REAL *scratch, REAL *X, REAL *Y, REAL *Z, REAL *VX,
                                      REAL *VY, REAL *VZ, const int64_t stride, const int64_t k,
                                      const REAL *restrict dx, const REAL *restrict dy, const REAL *restrict dz)
{
    REAL *restrict x = AL(ROWP(X, k)), *restrict y = AL(ROWP(Y, k)), *restrict z = AL(ROWP(Z, k));
    REAL *restrict vx = AL(ROWP(VX, k)), *restrict vy = AL(ROWP(VY, k)), *restrict vz = AL(ROWP(VZ, k));
    const REAL *restrict px = SROW(3 * k), *restrict py = SROW(3 * k + 1), *restrict pz = SROW(3 * k + 2);
    const REAL ih = K->ih, s_ih = K->s_ih;
    (void)s_ih;
#pragma omp simd
    for (int j = 0; j < DB; j++) {
        const REAL nx = px[j], ny = py[j], nz = pz[j];
        REAL wx = (nx - x[j]) * ih, wy = (ny - y[j]) * ih, wz = (nz - z[j]) * ih;
        if (dx) {
            wx = wx - s_ih * dx[j];
            wy = wy - s_ih * dy[j];
            wz = wz - s_ih * dz[j];
        }
        vx[j] = wx;
        vy[j] = wy;
        vz[j] = wz;
        x[j] = nx;
        y[j] = ny;
        z[j] = nz;
    }
}

/* One iteration's bend, shape and LRA constraints (those the features and the model use),
 * in the order both solvers apply them. */
HB_ALWAYS_INLINE void SFX(bend_shape_lra_lanes)(const DMODEL *m, const SFX(dyn_consts) * K, const REAL *q,
                                                const REAL *RX, const REAL *RY, const REAL *RZ, const REAL *BR,
                                                const int64_t stride, REAL *scratch, const unsigned F)
{
    if (F & HB_F_BEND) {
        SFX(bend_lanes)(m, K, scratch, BR, stride, 0);
        SFX(bend_lanes)(m, K, scratch, BR, stride, 1);
    }
    if (F & HB_F_SHAPE) SFX(shape_lanes)(m, K, scratch, q, RX, RY, RZ, stride, F);
    if (m->lra)
        for (int64_t k = 1; k < m->points; k++) SFX(lra_lanes)(m, scratch, k);
}

/* Phase 2 of a substep (steps 3 and 4): the constraints of the solver, then the velocities
 * from the motion and the positions. Features: BEND, SHAPE, COLLIDE, MOTION (for shape). */
HB_ALWAYS_INLINE void SFX(con_phase)(const DMODEL *m, const SFX(dyn_consts) * K, const REAL *q, REAL *X, REAL *Y,
                                     REAL *Z, REAL *VX, REAL *VY, REAL *VZ, const REAL *RX, const REAL *RY,
                                     const REAL *RZ, const REAL *BR, const REAL *SR, const int64_t stride,
                                     REAL *scratch, const WORLD *wc, const REAL *pose, const REAL *back,
                                     const REAL *con, const unsigned F)
{
    /* §3.17 (wc: the colliders, or the head sphere's friction or bounded depenetration): the head
     * sphere's plain projection stays collide_lanes' where the world does not take it, and where
     * its sweep is not repeated (a repeated sweep holds the head sphere: hb_collide_sweeps) */
    const int head_world = wc && (F & HB_F_COLLIDE) && (wc->head_friction || wc->bounded);
    const int head_swept = wc && (F & HB_F_COLLIDE) && !head_world && wc->sweeps > 1;
    const int plain = (F & HB_F_COLLIDE) && !head_world && !head_swept;
    const int head = head_world ? HB_HEAD_WORLD : head_swept ? HB_HEAD_PLAIN : HB_HEAD_NONE;
    const int64_t P = m->points;
    const REAL ell = K->ell;
    const int per_seg = SR != NULL; /* §3.15: a groom's ℓ_k, row k − 1 of SR */
    /* every multiplier in use starts the substep at 0 (stretch rows P…, bend 2P…, shape 3P…) */
    {
        const int64_t from = K->st_at != (REAL)0 ? 0 : (F & HB_F_BEND) && K->bd_at != (REAL)0 ? P : 2 * P;
        const int64_t to = (F & HB_F_SHAPE) ? 3 * P : (F & HB_F_BEND) ? 2 * P : P;
        REAL *restrict lam = SROW(3 * P);
        for (int64_t i = from * DB; i < to * DB; i++) lam[i] = (REAL)0;
    }
    REAL *const lam_s = K->st_at != (REAL)0 ? SROW(3 * P) : NULL;
    if (m->solver == HB_SOLVER_XPBD) {
        for (int64_t it = 0; it < m->iterations; it++) {
            // clang-format off
            for (int64_t k = 1; k < P; k += 2) /* stretch, k odd */
                SFX(distance_lanes)(m, scratch, k - 1, k, per_seg, per_seg ? AL(ROWP(SR, k - 1)) : NULL, ell, K->st_at,
                                    k - 1 != 0 ? K->st_w2 : K->st_w1, lam_s ? lam_s + (k - 1) * DB : NULL);
            for (int64_t k = 2; k < P; k += 2) /* stretch, k even */
                SFX(distance_lanes)(m, scratch, k - 1, k, per_seg, per_seg ? AL(ROWP(SR, k - 1)) : NULL, ell, K->st_at,
                                    K->st_w2, lam_s ? lam_s + (k - 1) * DB : NULL);
            // clang-format on
            SFX(bend_shape_lra_lanes)(m, K, q, RX, RY, RZ, BR, stride, scratch, F);
            if (it < m->collide_from) continue; /* --collide-once: the last iteration's alone */
            for (int64_t k = 1; k < P && (plain || wc); k++) {
                if (plain) SFX(collide_lanes)(m, scratch, k, K);
                if (wc) {
                    const REAL *xr = AL(ROWP(X, k)), *yr = AL(ROWP(Y, k)), *zr = AL(ROWP(Z, k));
                    REAL *qx = SROW(3 * k), *qy = SROW(3 * k + 1), *qz = SROW(3 * k + 2);
                    SFX(world_row)(wc, pose, back, K->rc, head, qx, qy, qz, xr, yr, zr, CON_ROW(con, k));
                }
            }
        }
        /* 4. v = (p − x)/h, then x = p */
        for (int64_t k = 1; k < P; k++) SFX(update_row)(K, scratch, X, Y, Z, VX, VY, VZ, stride, k, NULL, NULL, NULL);
        return;
    }
    for (int64_t it = 0; it < m->iterations; it++) {
        SFX(bend_shape_lra_lanes)(m, K, q, RX, RY, RZ, BR, stride, scratch, F);
    }
    /* §3.7 follow the leader, point by point; as soon as d_k is known, point k − 1 is final:
     * v_{k−1} = (p − x)/h − (s/h)·d_k and x_{k−1} = p (the oracle's step 4 for that point) */
    REAL *restrict dx = SROW(6 * P), *restrict dy = SROW(6 * P + 1), *restrict dz = SROW(6 * P + 2);
    REAL *restrict l2r = TMP(m, 0), *restrict inv = TMP(m, 1);
    for (int64_t k = 1; k < P; k++) {
        REAL *restrict px = SROW(3 * k), *restrict py = SROW(3 * k + 1), *restrict pz = SROW(3 * k + 2);
        const REAL *restrict ppx = SROW(3 * (k - 1)), *restrict ppy = SROW(3 * (k - 1) + 1),
                             *restrict ppz = SROW(3 * (k - 1) + 2);
#pragma omp simd
        for (int j = 0; j < DB; j++) {
            const REAL ex = px[j] - ppx[j], ey = py[j] - ppy[j], ez = pz[j] - ppz[j];
            l2r[j] = ex * ex + ey * ey + ez * ez;
        }
        INV_SQRT_ROW(l2r, inv);
        const REAL *restrict sr = per_seg ? AL(ROWP(SR, k - 1)) : NULL;
#pragma omp simd
        for (int j = 0; j < DB; j++) {
            const REAL ax = ppx[j], ay = ppy[j], az = ppz[j], bx = px[j], by = py[j], bz = pz[j];
            const REAL ex = bx - ax, ey = by - ay, ez = bz - az;
            const int pos = l2r[j] >= TINY; /* the oracle's |e| > 0 */
            const REAL lk = per_seg ? sr[j] : ell;
            const REAL g = lk * inv[j];
            const REAL qx = pos ? ax + g * ex : ax, qy = pos ? ay + g * ey : ay - lk, qz = pos ? az + g * ez : az;
            dx[j] = qx - bx;
            dy[j] = qy - by;
            dz[j] = qz - bz;
            px[j] = qx;
            py[j] = qy;
            pz[j] = qz;
        }
        if (plain) SFX(collide_lanes)(m, scratch, k, K);
        if (wc) {
            const REAL *xr = AL(ROWP(X, k)), *yr = AL(ROWP(Y, k)), *zr = AL(ROWP(Z, k));
            SFX(world_row)(wc, pose, back, K->rc, head, px, py, pz, xr, yr, zr, CON_ROW(con, k));
        }
        if (k >= 2) SFX(update_row)(K, scratch, X, Y, Z, VX, VY, VZ, stride, k - 1, dx, dy, dz);
    }
    /* the last point: no correction */
    SFX(update_row)(K, scratch, X, Y, Z, VX, VY, VZ, stride, P - 1, NULL, NULL, NULL);
}

/* The two phases, one function per feature subset (the switches' constants specialise). */
#define VEL_F(i)                                                                                                       \
    ((((i)&1) ? HB_F_WIND : 0u) | (((i)&2) ? HB_F_GUST : 0u) | (((i)&4) ? HB_F_DRAG : 0u) |                            \
     (((i)&8) ? HB_F_MOTION : 0u))
#define CON_F(i)                                                                                                       \
    ((((i)&1) ? HB_F_BEND : 0u) | (((i)&2) ? HB_F_SHAPE : 0u) | (((i)&4) ? HB_F_COLLIDE : 0u) |                        \
     (((i)&8) ? HB_F_MOTION : 0u))
#define CASE16(C) C(0) C(1) C(2) C(3) C(4) C(5) C(6) C(7) C(8) C(9) C(10) C(11) C(12) C(13) C(14) C(15)

static void SFX(vel_dispatch)(unsigned idx, const DMODEL *m, const SFX(dyn_consts) * K, const REAL *q, const REAL phase,
                              REAL *X, REAL *Y, REAL *Z, REAL *VX, REAL *VY, REAL *VZ, const REAL *RX, const REAL *RY,
                              const REAL *RZ, const int64_t stride, REAL *scratch, const WORLD *w, const REAL *qg,
                              const int64_t j, const int prefetch)
{
#define VCASE(i)                                                                                                       \
    case (i):                                                                                                          \
        if (((i)&2) && !((i)&1)) break; /* no gusts without wind (hb_dyn_features) */                                  \
        if (prefetch)                                                                                                  \
            SFX(vel_phase)(m, K, q, phase, X, Y, Z, VX, VY, VZ, RX, RY, RZ, stride, scratch, w, qg, j, 1, VEL_F(i));   \
        else SFX(vel_phase)(m, K, q, phase, X, Y, Z, VX, VY, VZ, RX, RY, RZ, stride, scratch, w, qg, j, 0, VEL_F(i));  \
        break;
    switch (idx) {
        CASE16(VCASE)
    default: break;
    }
#undef VCASE
}

static void SFX(con_dispatch)(unsigned idx, const DMODEL *m, const SFX(dyn_consts) * K, const REAL *q, REAL *X, REAL *Y,
                              REAL *Z, REAL *VX, REAL *VY, REAL *VZ, const REAL *RX, const REAL *RY, const REAL *RZ,
                              const REAL *BR, const REAL *SR, const int64_t stride, REAL *scratch, const WORLD *wc,
                              const REAL *pose, const REAL *back, const REAL *con)
{
#define CCASE(i)                                                                                                       \
    case (i):                                                                                                          \
        if (((i)&8) && !((i)&2)) break; /* motion matters here only through shape */                                   \
        SFX(con_phase)                                                                                                 \
        (m, K, q, X, Y, Z, VX, VY, VZ, RX, RY, RZ, BR, SR, stride, scratch, wc, pose, back, con, CON_F(i));            \
        break;
    switch (idx) {
        CASE16(CCASE)
    default: break;
    }
#undef CCASE
}

void SFX(hb_simd_dyn_frame_block)(const DMODEL *m, const hb_dyn_frame *fr, const WORLD *w, int64_t j0, int64_t j1,
                                  REAL *X, REAL *Y, REAL *Z, REAL *VX, REAL *VY, REAL *VZ, const REAL *RX,
                                  const REAL *RY, const REAL *RZ, const REAL *BR, const REAL *SR, int64_t stride,
                                  REAL *scratch, REAL *con)
{
    const unsigned F = m->features;
    const unsigned vi = ((F & HB_F_WIND) ? 1u : 0u) | ((F & HB_F_WIND) && (F & HB_F_GUST) ? 2u : 0u) |
                        ((F & HB_F_DRAG) ? 4u : 0u) | ((F & HB_F_MOTION) ? 8u : 0u);
    const unsigned ci = ((F & HB_F_BEND) ? 1u : 0u) | ((F & HB_F_SHAPE) ? 2u : 0u) | ((F & HB_F_COLLIDE) ? 4u : 0u) |
                        ((F & HB_F_SHAPE) && (F & HB_F_MOTION) ? 8u : 0u);
    const REAL one = (REAL)1, two = (REAL)2;
    SFX(dyn_consts) K;
    K.h = m->h;
    K.ih = one / m->h;
    K.iden = one / m->den;
    K.st_at = m->stretch_at;
    K.st_w1 = one / (one + m->stretch_at);
    K.st_w2 = one / (two + m->stretch_at);
    K.bd_at = m->bend_at;
    K.bd_w1 = one / (one + m->bend_at);
    K.bd_w2 = one / (two + m->bend_at);
    K.sh_at = m->shape_at;
    K.sh_w1 = one / (one + m->shape_at);
    K.rc = m->collide_r;
    K.rc2 = m->collide_r * m->collide_r;
    K.ell = m->seg_len;
    K.s_ih = m->ftl_s / m->h;
    /* §3.16 the grid where it corrects (w: NULL otherwise), and the rotation of the build in use */
    const WORLD *wg = w && w->grid && (w->grid_friction || w->grid_volume) ? w : NULL;
    /* §3.17 the colliders, or the head sphere's friction or bounded depenetration */
    const WORLD *wc = w && (w->ncol > 0 || w->head_friction || w->bounded) ? w : NULL;
    for (int64_t j = j0; j < j1; j++) {
        const REAL *q = QTABLE(fr) + 9 * j;                            /* Q(t + h) */
        const REAL phase = PHASE(fr)[j];                               /* φ(t) */
        const int last = HB_SIMD_DYN_PREFETCH && j + 1 == m->substeps; /* the next block's rows arrive meanwhile */
        const REAL *qg = !(F & HB_F_MOTION)                                     ? NULL
                         : (wg && wg->grid_rebuild == HB_GRID_SUBSTEP && j > 0) ? QTABLE(fr) + 9 * (j - 1)
                                                                                : QSTART(fr);
        const REAL *pose = wc ? POSES(fr) + (size_t)j * (size_t)(wc->ncol > 0 ? wc->ncol : 1) * HB_COL_POSE : NULL;
        const REAL *back = wc ? BACKS(fr) + HB_COL_BACK * j : NULL;
        /* §3.17 --contact-planes: each point's planes found from x at the frame's first substep,
         * carried with their colliders at the others (dynamics_impl.h frame_body) */
        if (con && wc)
            for (int64_t k = 1; k < m->points; k++)
                for (int l = 0; l < DB; l++) {
                    const REAL xs[3] = {ROWP(X, k)[l], ROWP(Y, k)[l], ROWP(Z, k)[l]};
                    SFX(hb_contact_step)(wc, pose, back, j, xs, CON_ROW(con, k) + HB_CONTACT_POINT * l);
                }
        SFX(vel_dispatch)(vi, m, &K, q, phase, X, Y, Z, VX, VY, VZ, RX, RY, RZ, stride, scratch, wg, qg, j, last);
        SFX(con_dispatch)(ci, m, &K, q, X, Y, Z, VX, VY, VZ, RX, RY, RZ, BR, SR, stride, scratch, wc, pose, back, con);
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
void SFX(hb_simd_dyn_observe)(const hb_scene *s, const WORLD *w, const REAL *pose, const REAL *X, const REAL *Y,
                              const REAL *Z, const REAL *VX, const REAL *VY, const REAL *VZ, int64_t stride,
                              int64_t first, int64_t count, const double *seg64, hb_obs_partial *out)
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
                const double xk[3] = {(double)x[j], (double)y[j], (double)z[j]};
                const double vk[3] = {(double)vx[j], (double)vy[j], (double)vz[j]};
                const double xq[3] = {(double)xp[j], (double)yp[j], (double)zp[j]};
                const double xr[3] = {(double)x0[j], (double)y0[j], (double)z0[j]};
                const int fin = (fabs(xk[0]) <= big) & (fabs(xk[1]) <= big) & (fabs(xk[2]) <= big) &
                                (fabs(vk[0]) <= big) & (fabs(vk[1]) <= big) & (fabs(vk[2]) <= big);
                const double seg = seg64 ? seg64[(base + j) * (P - 1) + k - 1] : ell;
                double sm = smax[j], pm = pmax[j], w2 = v2[j];
                const int far = hb_obs_point(xk, xq, xr, vk, seg, collider, rc, far2, &sm, &pm, &w2);
                smax[j] = sm;
                pmax[j] = pm;
                v2[j] = w2;
                blown[j] |= (!fin) | far;
            }
            for (int j = 0; w && pose && j < n; j++) { /* §3.17: the depth in each collider */
                const double xk[3] = {(double)x[j], (double)y[j], (double)z[j]};
                for (int i = 0; i < w->ncol; i++) {
                    const double dep = SFX(hb_collider_depth)(w, i, pose + (size_t)i * HB_COL_POSE, xk);
                    if (dep > pmax[j]) pmax[j] = dep;
                }
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
#undef HS_ROW
#undef HB_ALWAYS_INLINE
#undef DB
#undef ROWP
#undef CON_ROW
#undef SROW
#undef AL
#undef TMP
