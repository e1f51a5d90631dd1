/* dynamics_impl.h — the dynamic model (docs/model.md §3), written once for a floating
 * type REAL; dynamics_f32.c and dynamics_f64.c include it for float and for double (SFX,
 * DMODEL, SQRT, SIN).
 *
 * One call advances one strand by one frame of S substeps. The feature set F is a
 * compile-time constant in every instantiation of frame_body (see the dispatch at the
 * end), so an undeclared feature leaves no code in the loop (§3.9). Every expression is
 * evaluated in the order written here; §3.10 states that order for the other backends.
 *
 * Layout: point k of a strand at s[3k + 0..2] = (x, y, z).
 */

#include "dynamic/obs_point.h"    /* hb_obs_point: §3.8 per point, shared with cuda/dynamic/model.cuh */
#include "dynamic/contact_impl.h" /* §3.16 grid, §3.17 colliders: shared with cuda/ */

#define HB_ALWAYS_INLINE static inline __attribute__((always_inline))
#if HB_PLANT == 8 /* judge test: the root given weight 1 in its stretch constraint */
#define ROOT_MOVES(k) 1
#else
#define ROOT_MOVES(k) ((k)-1 != 0)
#endif
#if HB_PLANT == 6 /* judge test: the collider skips point P/2 */
#define PLANT_SKIPPED(k) ((k) == m->points / 2)
#else
#define PLANT_SKIPPED(k) 0
#endif

/* r = Q·a, row-major Q, each row summed left to right. */
HB_ALWAYS_INLINE void SFX(rotate)(const REAL *q, const REAL *a, REAL *r)
{
    r[0] = q[0] * a[0] + q[1] * a[1] + q[2] * a[2];
    r[1] = q[3] * a[0] + q[4] * a[1] + q[5] * a[2];
    r[2] = q[6] * a[0] + q[7] * a[1] + q[8] * a[2];
}

/* r = Q·a when the head moves, else a: a rest point carried with the head. */
HB_ALWAYS_INLINE void SFX(rest_pose)(const REAL *q, const REAL *a, REAL *r, const unsigned moves)
{
    if (moves) SFX(rotate)(q, a, r);
    else {
        r[0] = a[0];
        r[1] = a[1];
        r[2] = a[2];
    }
}

/* §3.5 distance constraint between a = p[3ia] and b = p[3ib] with rest length r and
 * α̃ = at. `move_a` is 0 when a is the root (inverse mass 0), else 1; b is never the root. */
HB_ALWAYS_INLINE void SFX(distance)(REAL *pa, REAL *pb, int move_a, REAL r, REAL at, REAL *lambda)
{
    const REAL ex = pb[0] - pa[0], ey = pb[1] - pa[1], ez = pb[2] - pa[2];
    const REAL len = SQRT(ex * ex + ey * ey + ez * ez);
    if (len == (REAL)0) return; /* no direction: nothing moves */
    const REAL c = len - r;
    const REAL wsum = move_a ? (REAL)2 : (REAL)1;
    const REAL dl = (-c - at * *lambda) / (wsum + at);
    *lambda = *lambda + dl;
    const REAL nx = ex / len, ny = ey / len, nz = ez / len;
    if (move_a) {
        pa[0] = pa[0] - dl * nx;
        pa[1] = pa[1] - dl * ny;
        pa[2] = pa[2] - dl * nz;
    }
    pb[0] = pb[0] + dl * nx;
    pb[1] = pb[1] + dl * ny;
    pb[2] = pb[2] + dl * nz;
}

/* §3.5 shape: a zero-length spring from p to the target t. */
HB_ALWAYS_INLINE void SFX(shape_pull)(REAL *p, const REAL *t, REAL at, REAL *lambda)
{
    const REAL ex = p[0] - t[0], ey = p[1] - t[1], ez = p[2] - t[2];
    const REAL c = SQRT(ex * ex + ey * ey + ez * ez);
    if (c == (REAL)0) return;
    const REAL dl = (-c - at * *lambda) / ((REAL)1 + at);
    *lambda = *lambda + dl;
    p[0] = p[0] + dl * (ex / c);
    p[1] = p[1] + dl * (ey / c);
    p[2] = p[2] + dl * (ez / c);
}

/* §3.5 head collision: a point inside the sphere R_c goes to its surface along the ray
 * from the centre; the centre itself goes to (0, R_c, 0) (contact_impl.h hb_head_sphere). */
HB_ALWAYS_INLINE void SFX(collide_sphere)(REAL *p, REAL rc)
{
    SFX(hb_head_sphere)(p, rc);
}

#if HB_PLANT == 5 /* judge test: the bend rest length from the current shape, not the rest shape */
HB_ALWAYS_INLINE REAL SFX(dist)(const REAL *a, const REAL *b)
{
    return SQRT((b[0] - a[0]) * (b[0] - a[0]) + (b[1] - a[1]) * (b[1] - a[1]) + (b[2] - a[2]) * (b[2] - a[2]));
}
#define BEND_REST(p, k) SFX(dist)(p + 3 * ((k)-1), p + 3 * ((k) + 1))
#else
#define BEND_REST(p, k) bend_rest[(k)-1]
#endif

/* §3.15 the stretch rest length of segment k: the groom's ℓ_k, else the scene's ℓ */
#define SEG_REST(k) (seg_rest ? seg_rest[(k)-1] : m->seg_len)

/* §3.6 bend constraints (k−1, k+1), k = 1…P−2, of one parity group: ⌊(k−1)/2⌋ even
 * (parity 0) or odd (parity 1). */
HB_ALWAYS_INLINE void SFX(bend_group)(const DMODEL *m, REAL *p, const REAL *bend_rest, REAL *lam, int parity)
{
    const int64_t P = m->points;
    for (int64_t k = 1; k + 1 < P; k++)
        if ((((k - 1) / 2) & 1) == parity)
            SFX(distance)(p + 3 * (k - 1), p + 3 * (k + 1), k - 1 != 0, BEND_REST(p, k), m->bend_at, &lam[k - 1]);
}

/* §3.5 shape targets T_k = Q(t+h)·X̄_k (X̄_k itself when the head does not move). */
HB_ALWAYS_INLINE void SFX(shape_all)(const DMODEL *m, REAL *p, const REAL *rest, const REAL *q, REAL *lam,
                                     const unsigned F)
{
#if HB_PLANT == 10 /* judge test: the shape range one point too long */
    for (int64_t k = 1; k <= m->shape_count + (m->shape_count + 1 < m->points); k++) {
#else
    for (int64_t k = 1; k <= m->shape_count; k++) {
#endif
        REAL t[3];
        SFX(rest_pose)(q, rest + 3 * k, t, F & HB_F_MOTION);
        SFX(shape_pull)(p + 3 * k, t, m->shape_at, &lam[k - 1]);
    }
}

/* §3.14 long-range attachments: |p_k − p_0| ≤ s_L·ℓ·k, a unilateral projection toward the
 * root (whose inverse mass is 0); each touches only p_k, so the group's order is free. */
HB_ALWAYS_INLINE void SFX(lra_all)(const DMODEL *m, REAL *p)
{
    for (int64_t k = 1; k < m->points; k++) {
        REAL *pk = p + 3 * k;
        const REAL ex = pk[0] - p[0], ey = pk[1] - p[1], ez = pk[2] - p[2];
        const REAL d = SQRT(ex * ex + ey * ey + ez * ez);
        const REAL r = m->lra_len * (REAL)k;
        if (d > r) {
            const REAL sc = r / d;
            pk[0] = p[0] + ex * sc;
            pk[1] = p[1] + ey * sc;
            pk[2] = p[2] + ez * sc;
        }
    }
}

/* §3.6 step 7 / §3.7's collision of one point p (x: where it was at the substep's start): the
 * head sphere, then the colliders of §3.17, each with its friction, in sweeps (contact_impl.h
 * hb_collide_sweeps, which the SIMD backend calls too). */
HB_ALWAYS_INLINE void SFX(collide_point)(const DMODEL *m, const WORLD *w, const REAL *pose, const REAL *back, REAL *p,
                                         const REAL *x, const REAL *con, int64_t k, const unsigned F)
{
    const int64_t P = m->points; /* PLANT_SKIPPED's */
    (void)P;
    const int head = !(F & HB_F_COLLIDE) || PLANT_SKIPPED(k) ? HB_HEAD_NONE
                     : w->head_friction || w->bounded        ? HB_HEAD_WORLD
                                                             : HB_HEAD_PLAIN;
    SFX(hb_collide_sweeps)(w, m->collide_r, head, pose, back, p, x, con ? con + HB_CONTACT_POINT * k : NULL);
}

/* Substeps j0 … j1 − 1 of a frame of one strand: §3.4, the solver of §3.6, §3.7 or §3.13 (rigid).
 * w: the grid and colliders (§3.16, §3.17), NULL without them. */
HB_ALWAYS_INLINE void SFX(frame_body)(const DMODEL *m, const WORLD *w, const hb_dyn_frame *fr, int64_t j0, int64_t j1,
                                      REAL *x, REAL *v, const REAL *rest, const REAL *bend_rest, const REAL *seg_rest,
                                      REAL *scratch, REAL *con, const unsigned F)
{
    const int64_t P = m->points;
    const REAL h = m->h;
    REAL *p = scratch;           /* predicted positions, 3P */
    REAL *lam = scratch + 3 * P; /* multipliers: stretch P−1 | bend P−2 | shape K */
    REAL *lam_s = lam, *lam_b = lam + P, *lam_g = lam + 2 * P;
    REAL *d = scratch + 6 * P;  /* ftl corrections d_k, 3P */
    REAL *hs = scratch + 9 * P; /* §3.16 `held`: the points' grid samples of the frame, 8P */

    const int wgrid = w && w->grid && (w->grid_friction || w->grid_volume);
    const int held = wgrid && w->grid_rebuild == HB_GRID_HELD;
    (void)hs;
    const int wcol = w && (w->ncol > 0 || w->head_friction || w->bounded);
    for (int64_t j = j0; j < j1; j++) {
        const REAL *q = QTABLE(fr) + 9 * j; /* Q(t + h) */
        const REAL phase = PHASE(fr)[j];    /* φ(t) */
        /* §3.16 the rotation of the grid in use (NULL: still), §3.17 this substep's poses */
        const REAL *qg = !(F & HB_F_MOTION)                                   ? NULL
                         : (w && w->grid_rebuild == HB_GRID_SUBSTEP && j > 0) ? QTABLE(fr) + 9 * (j - 1)
                                                                              : QSTART(fr);
        const REAL *pose = wcol ? POSES(fr) + (size_t)j * (size_t)(w->ncol > 0 ? w->ncol : 1) * HB_COL_POSE : NULL;
        const REAL *back = wcol ? BACKS(fr) + HB_COL_BACK * j : NULL;
        (void)q;
        (void)phase;
        (void)qg;
        /* §3.17 --contact-planes: each point's plane found from x at the frame's first substep,
         * carried with its collider at the others */
        if (con && m->solver != HB_SOLVER_RIGID)
            for (int64_t k = 1; k < P; k++)
                SFX(hb_contact_step)(w, pose, back, j, x + 3 * k, con + HB_CONTACT_POINT * k);

        /* 1. root on the head: x0 ← Q(t+h)·X̄0, v0 ← (x0_new − x0_old)/h */
        if (F & HB_F_MOTION) {
            REAL r[3];
            SFX(rotate)(q, rest, r);
            for (int c = 0; c < 3; c++) {
                v[c] = (r[c] - x[c]) / h;
                x[c] = r[c];
            }
        }
        /* rigid (no dynamics): every point is carried with the head like the root,
         * x_k ← Q(t+h)·X̄_k (X̄_k when still), v_k ← (x_k_new − x_k_old)/h */
        if (m->solver == HB_SOLVER_RIGID) {
            for (int64_t k = 1; k < P; k++) {
                REAL r[3];
                SFX(rest_pose)(q, rest + 3 * k, r, F & HB_F_MOTION);
                for (int c = 0; c < 3; c++) {
                    v[3 * k + c] = (r[c] - x[3 * k + c]) / h;
                    x[3 * k + c] = r[c];
                }
            }
            continue;
        }
        p[0] = x[0];
        p[1] = x[1];
        p[2] = x[2];

        /* 2. velocities, implicit in drag and damping, then the prediction */
        for (int64_t k = 1; k < P; k++) {
            REAL *vk = v + 3 * k;
            const REAL *xk = x + 3 * k;
            if (held) { /* §3.16 the sample taken at the frame's first substep, applied at each */
                if (j == 0) SFX(hb_grid_sample)(w, qg, xk, hs + 8 * k);
                SFX(hb_grid_apply)(w, h, k, hs + 8 * k, vk);
            } else if (wgrid) {
                SFX(hb_grid_correct)(w, qg, h, k, xk, vk); /* §3.16 friction, then volume */
            }
            REAL vx = vk[0], vy = vk[1], vz = vk[2];
            if (F & HB_F_WIND) {
                REAL gam = (REAL)1;
                if (F & HB_F_GUST)
                    gam = (REAL)1 + m->gust * SIN(phase - m->kappa * (m->dir_y * xk[1] + m->dir_z * xk[2]));
#if HB_PLANT == 1 /* judge test: gravity dropped from the velocity update */
                vy = vy + h * (m->wind_y * gam);
#else
                vy = vy + h * (m->gravity_y + m->wind_y * gam);
#endif
                vz = vz + h * (m->wind_z * gam);
            } else {
#if HB_PLANT != 1
                vy = vy + h * m->gravity_y;
#endif
            }
            if (F & HB_F_DRAG) {
                vx = vx / m->den;
                vy = vy / m->den;
                vz = vz / m->den;
            }
            vk[0] = vx;
            vk[1] = vy;
            vk[2] = vz;
            p[3 * k + 0] = xk[0] + h * vx;
            p[3 * k + 1] = xk[1] + h * vy;
            p[3 * k + 2] = xk[2] + h * vz;
        }

        /* 3. constraints; every multiplier starts the substep at 0 */
#if HB_PLANT == 4 /* judge test: the multipliers kept from the last substep */
        if (j == 0)
#endif
            for (int64_t i = 0; i < 3 * P; i++) lam[i] = (REAL)0;
        if (m->solver == HB_SOLVER_XPBD) {
            for (int64_t it = 0; it < m->iterations; it++) {
#if HB_PLANT == 3 /* judge test: the even stretch group before the odd */
                for (int64_t k = 2; k < P; k += 2)
                    SFX(distance)(p + 3 * (k - 1), p + 3 * k, 1, SEG_REST(k), m->stretch_at, &lam_s[k - 1]);
#endif
                for (int64_t k = 1; k < P; k += 2) /* stretch, k odd */
                    SFX(distance)(p + 3 * (k - 1), p + 3 * k, ROOT_MOVES(k), SEG_REST(k), m->stretch_at, &lam_s[k - 1]);
#if HB_PLANT != 3
                for (int64_t k = 2; k < P; k += 2) /* stretch, k even */
                    SFX(distance)(p + 3 * (k - 1), p + 3 * k, 1, SEG_REST(k), m->stretch_at, &lam_s[k - 1]);
#endif
                if (F & HB_F_BEND) {
                    SFX(bend_group)(m, p, bend_rest, lam_b, 0);
                    SFX(bend_group)(m, p, bend_rest, lam_b, 1);
                }
                if (F & HB_F_SHAPE) SFX(shape_all)(m, p, rest, q, lam_g, F);
                if (m->lra) SFX(lra_all)(m, p);
                if (it < m->collide_from) continue; /* --collide-once: the last iteration's alone */
                if (wcol)
                    for (int64_t k = 1; k < P; k++)
                        SFX(collide_point)(m, w, pose, back, p + 3 * k, x + 3 * k, con, k, F);
                else if (F & HB_F_COLLIDE)
                    for (int64_t k = 1; k < P; k++)
                        if (!PLANT_SKIPPED(k)) SFX(collide_sphere)(p + 3 * k, m->collide_r);
            }
        } else {
            for (int64_t it = 0; it < m->iterations; it++) {
                if (F & HB_F_BEND) {
                    SFX(bend_group)(m, p, bend_rest, lam_b, 0);
                    SFX(bend_group)(m, p, bend_rest, lam_b, 1);
                }
                if (F & HB_F_SHAPE) SFX(shape_all)(m, p, rest, q, lam_g, F);
                if (m->lra) SFX(lra_all)(m, p);
            }
            /* §3.7 follow the leader: q = p_{k−1} + ℓ·(p_k − p_{k−1})/|p_k − p_{k−1}| */
            for (int64_t k = 1; k < P; k++) {
                REAL *pk = p + 3 * k;
                const REAL *pp = p + 3 * (k - 1);
                const REAL ex = pk[0] - pp[0], ey = pk[1] - pp[1], ez = pk[2] - pp[2];
                const REAL len = SQRT(ex * ex + ey * ey + ez * ez);
                const REAL ell = SEG_REST(k);
                REAL nq[3];
                if (len > (REAL)0) {
                    nq[0] = pp[0] + ell * (ex / len);
                    nq[1] = pp[1] + ell * (ey / len);
                    nq[2] = pp[2] + ell * (ez / len);
                } else {
                    nq[0] = pp[0];
                    nq[1] = pp[1] - ell;
                    nq[2] = pp[2];
                }
                for (int c = 0; c < 3; c++) d[3 * k + c] = nq[c] - pk[c];
                if (wcol) SFX(collide_point)(m, w, pose, back, nq, x + 3 * k, con, k, F);
                else if ((F & HB_F_COLLIDE) && !PLANT_SKIPPED(k)) SFX(collide_sphere)(nq, m->collide_r);
                for (int c = 0; c < 3; c++) pk[c] = nq[c];
            }
        }

        /* 4. velocities from the motion (ftl: less s·d_{k+1}/h), then the positions */
        for (int64_t k = 1; k < P; k++)
            for (int c = 0; c < 3; c++) v[3 * k + c] = (p[3 * k + c] - x[3 * k + c]) / h;
        if (m->solver == HB_SOLVER_FTL)
            for (int64_t k = 1; k + 1 < P; k++)
#if HB_PLANT == 9 /* judge test: the ftl correction of the point's own d_k, not d_{k+1} */
                for (int c = 0; c < 3; c++) v[3 * k + c] = v[3 * k + c] - (m->ftl_s * d[3 * k + c]) / h;
#else
                for (int c = 0; c < 3; c++) v[3 * k + c] = v[3 * k + c] - (m->ftl_s * d[3 * (k + 1) + c]) / h;
#endif
        for (int64_t i = 3; i < 3 * P; i++) x[i] = p[i];
    }
}

/* One function per feature set: the switch's constant F specialises frame_body. */
void SFX(hb_dyn_frame_strand)(const DMODEL *m, const WORLD *w, const hb_dyn_frame *fr, int64_t j0, int64_t j1, REAL *x,
                              REAL *v, const REAL *rest, const REAL *bend_rest, const REAL *seg_rest, REAL *scratch,
                              REAL *con)
{
// clang-format off
#define HB_F_CASE(n)                                                                         \
    case (n):                                                                                \
        if (((n) & HB_F_GUST) && !((n) & HB_F_WIND)) break; /* no gusts without wind */     \
        SFX(frame_body)(m, w, fr, j0, j1, x, v, rest, bend_rest, seg_rest, scratch,          \
                        w && w->planes ? con : NULL, (n));                                   \
        break;
#define HB_F_CASE8(n) HB_F_CASE(n) HB_F_CASE(n + 1) HB_F_CASE(n + 2) HB_F_CASE(n + 3)      \
    HB_F_CASE(n + 4) HB_F_CASE(n + 5) HB_F_CASE(n + 6) HB_F_CASE(n + 7)
    switch (m->features) {
        HB_F_CASE8(0) HB_F_CASE8(8) HB_F_CASE8(16) HB_F_CASE8(24)
        HB_F_CASE8(32) HB_F_CASE8(40) HB_F_CASE8(48) HB_F_CASE8(56)
        HB_F_CASE8(64) HB_F_CASE8(72) HB_F_CASE8(80) HB_F_CASE8(88)
        HB_F_CASE8(96) HB_F_CASE8(104) HB_F_CASE8(112) HB_F_CASE8(120)
    default: break;
    }
// clang-format on
#undef HB_F_CASE8
#undef HB_F_CASE
}

/* §3.5 bend rest lengths |X̄_{k+1} − X̄_{k−1}|, once per run in the working precision. */
void SFX(hb_dyn_bend_rest)(const DMODEL *m, const REAL *rest, REAL *bend_rest)
{
    for (int64_t k = 1; k + 1 < m->points; k++) {
        const REAL *a = rest + 3 * (k - 1), *b = rest + 3 * (k + 1);
        const REAL ex = b[0] - a[0], ey = b[1] - a[1], ez = b[2] - a[2];
        bend_rest[k - 1] = SQRT(ex * ex + ey * ey + ez * ez);
    }
}

/* §3.8 observables of one strand, in double. */
void SFX(hb_dyn_observe_strand)(const hb_scene *s, const WORLD *w, const REAL *pose, const REAL *x, const REAL *v,
                                const double *seg64, hb_obs_partial *o)
{
    const int64_t P = s->points;
    const double ell = hb_segment_length(s), far2 = 4.0 * s->hair_length * s->hair_length;
    const double rc = s->head_radius + s->dyn.collision_margin;
    double smax = 0.0, pmax = 0.0, v2 = 0.0;
    int64_t blown = 0;
    for (int64_t k = 0; k < P; k++)
        for (int c = 0; c < 3; c++) blown |= !isfinite((double)x[3 * k + c]) || !isfinite((double)v[3 * k + c]);
    const double x0[3] = {(double)x[0], (double)x[1], (double)x[2]};
    for (int64_t k = 1; k < P; k++) {
        const double xk[3] = {(double)x[3 * k], (double)x[3 * k + 1], (double)x[3 * k + 2]};
        const double xp[3] = {(double)x[3 * k - 3], (double)x[3 * k - 2], (double)x[3 * k - 1]};
        const double vk[3] = {(double)v[3 * k], (double)v[3 * k + 1], (double)v[3 * k + 2]};
        if (hb_obs_point(xk, xp, x0, vk, seg64 ? seg64[k - 1] : ell, s->dyn.collider, rc, far2, &smax, &pmax, &v2))
            blown = 1;
        for (int i = 0; w && pose && i < w->ncol; i++) { /* §3.17: the depth in each collider */
            const double dep = SFX(hb_collider_depth)(w, i, pose + (size_t)i * HB_COL_POSE, xk);
            if (dep > pmax) pmax = dep;
        }
    }
    o->stretch_max = smax;
    o->penetration_max = pmax;
    o->v2_sum = v2;
    o->blown = blown;
}

#undef HB_ALWAYS_INLINE
#undef ROOT_MOVES
#undef PLANT_SKIPPED
#undef BEND_REST
#undef SEG_REST
