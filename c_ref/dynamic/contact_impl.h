/* contact_impl.h — the per-point math of the hair–hair grid (docs/model.md §3.16) and of the
 * colliders with friction (§3.17), written once for a floating type REAL (SFX, SQRT,
 * WORLD, as precision_f32.h / precision_f64.h name them) in the common subset of C and CUDA
 * C++: the C reference (dynamics_impl.h) and the CUDA port (cuda/dyn_contact.cuh) include this
 * same text, so the strict CUDA build performs these operations exactly as the reference.
 * Every expression is evaluated in the order written (docs/model.md §3.10).
 */
#include <math.h>
#include <stdint.h>
#include <string.h> /* memcpy */

#include "runtime/philox.h" /* HB_HD */

#ifndef HB_CONTACT_ONCE
#define HB_CONTACT_ONCE
/* rint to a 64-bit integer, ties to even (the value is within ±2^62 by construction) */
#if defined(__CUDA_ARCH__)
#define HB_RINT64(x) __double2ll_rn((double)(x))
#else
#define HB_RINT64(x) ((int64_t)llrint((double)(x)))
#endif
#define HB_GRID_MASS_SCALE 16777216.0                 /* 2^24 */
#define HB_GRID_MOM_SCALE 1024.0                      /* 2^10 */
#define HB_GRID_VEL_SCALE 16384.0                     /* 2^14 = 2^24 / 2^10 */
#define HB_GRID_VEL_CLAMP 1048576.0                   /* 2^20 cm/s */
#define HB_GRID_INV_MASS_SCALE 5.9604644775390625e-08 /* 2^-24 */
/* §3.17 the head sphere in a sweep (hb_collide_sweeps): none (undeclared, or a judge's plant), its
 * plain projection of §3.5, or with its friction or a bounded depenetration (hb_collide_head) */
enum { HB_HEAD_NONE = 0, HB_HEAD_PLAIN = 1, HB_HEAD_WORLD = 2 };
/* HB_HD, inlined where the C compiler would call it (the collision step, in every feature set's loop) */
#ifdef __CUDACC__
#define HB_HD_INLINE HB_HD
#else
#define HB_HD_INLINE static inline __attribute__((always_inline))
#endif
#endif

/* §3.16 the grid cell of x (u = Q_gᵀ·x, or x with qg = NULL): 1 and its integer coordinates i and
 * the fractions f of x within it when x is in the grid. */
HB_HD int SFX(hb_grid_cell)(const REAL *qg, const REAL *glo, const REAL *gsc, int64_t gn, const REAL *x, int64_t *i,
                            REAL *f)
{
    REAL u[3];
    for (int c = 0; c < 3; c++) u[c] = qg ? (qg[c] * x[0] + qg[3 + c] * x[1]) + qg[6 + c] * x[2] : x[c];
    for (int c = 0; c < 3; c++) {
        const REAL g = (u[c] - glo[c]) * gsc[c];
        if (!(g >= (REAL)0 && g < (REAL)(gn - 1))) return 0;
        i[c] = (int64_t)g;
        f[c] = g - (REAL)i[c];
    }
    return 1;
}

/* §3.16 the eight corner weights (corner a + 2b + 4c) of the fractions f */
HB_HD void SFX(hb_grid_weights)(const REAL *f, REAL *w)
{
    for (int k = 0; k < 8; k++) {
        const REAL wx = (k & 1) ? f[0] : (REAL)1 - f[0];
        const REAL wy = (k & 2) ? f[1] : (REAL)1 - f[1];
        const REAL wz = (k & 4) ? f[2] : (REAL)1 - f[2];
        w[k] = (wx * wy) * wz;
    }
}

/* §3.16 the grid coordinates of x: 1 and the index of its lowest corner and the eight corner
 * weights when x is in the grid. */
HB_HD int SFX(hb_grid_locate)(const REAL *qg, const REAL *glo, const REAL *gsc, int64_t gn, const REAL *x,
                              int64_t *base, REAL *w)
{
    REAL f[3];
    int64_t i[3];
    if (!SFX(hb_grid_cell)(qg, glo, gsc, gn, x, i, f)) return 0;
    *base = i[0] + gn * (i[1] + gn * i[2]);
    SFX(hb_grid_weights)(f, w);
    return 1;
}

/* The node index of corner k of the cell whose lowest corner is `base`. */
HB_HD int64_t SFX(hb_grid_corner)(int64_t base, int64_t gn, int k)
{
    return base + ((k & 1) ? 1 : 0) + ((k & 2) ? gn : 0) + ((k & 4) ? gn * gn : 0);
}

/* §3.16 one point's splat: its fixed-point mass and momentum at its eight corners. Returns 0
 * (nothing to add) for a point outside the grid or not finite. v may be NULL (mass only). */
HB_HD int SFX(hb_grid_splat_point)(const REAL *qg, const REAL *glo, const REAL *gsc, int64_t gn, const REAL *x,
                                   const REAL *v, int64_t *base, int64_t *mass, int64_t *mom)
{
    REAL w[8], vc[3] = {(REAL)0, (REAL)0, (REAL)0};
    for (int c = 0; c < 3; c++)
        if (!isfinite(x[c]) || (v && !isfinite(v[c]))) return 0;
    if (!SFX(hb_grid_locate)(qg, glo, gsc, gn, x, base, w)) return 0;
    if (v)
        for (int c = 0; c < 3; c++)
            vc[c] = v[c] < (REAL)-HB_GRID_VEL_CLAMP  ? (REAL)-HB_GRID_VEL_CLAMP
                    : v[c] > (REAL)HB_GRID_VEL_CLAMP ? (REAL)HB_GRID_VEL_CLAMP
                                                     : v[c];
    for (int k = 0; k < 8; k++) {
        mass[k] = HB_RINT64(w[k] * (REAL)HB_GRID_MASS_SCALE);
        for (int c = 0; c < 3; c++) mom[3 * k + c] = v ? HB_RINT64((w[k] * vc[c]) * (REAL)HB_GRID_MOM_SCALE) : 0;
    }
    return 1;
}

/* §3.16 the excess density e of node j (volume): max(ρ − T, 0)·(1/ρ̄₀). */
HB_HD REAL SFX(hb_grid_excess)(const int64_t *mass, const REAL *target, REAL inv_rho0, int64_t j)
{
    const REAL e = (REAL)mass[j] * (REAL)HB_GRID_INV_MASS_SCALE - target[j];
    return (e > (REAL)0 ? e : (REAL)0) * inv_rho0;
}

/* §3.16 node j's fields from the sums: out_v = (o·V, o), and with volume out_a = (A, 0),
 * A = Q_g·(−K_v·G) (qg = NULL: not turned). */
HB_HD void SFX(hb_grid_node)(int64_t j, int64_t gn, const int64_t *mass, const int64_t *mom, const REAL *target,
                             REAL inv_rho0, REAL neg_kv, const REAL *gsc, const REAL *qg, REAL *out_v, REAL *out_a)
{
    if (out_v) {
        const int64_t m = mass[j];
        for (int c = 0; c < 3; c++)
            out_v[4 * j + c] = m > 0 ? ((REAL)mom[3 * j + c] / (REAL)m) * (REAL)HB_GRID_VEL_SCALE : (REAL)0;
        out_v[4 * j + 3] = m > 0 ? (REAL)1 : (REAL)0;
    }
    if (out_a) {
        const int64_t idx[3] = {j % gn, (j / gn) % gn, j / (gn * gn)};
        const int64_t step[3] = {1, gn, gn * gn};
        REAL g[3], a[3];
        for (int c = 0; c < 3; c++) {
            const int lo = idx[c] > 0, hi = idx[c] + 1 < gn;
            const REAL ep = SFX(hb_grid_excess)(mass, target, inv_rho0, hi ? j + step[c] : j);
            const REAL em = SFX(hb_grid_excess)(mass, target, inv_rho0, lo ? j - step[c] : j);
            g[c] = (lo && hi) ? (ep - em) * (gsc[c] * (REAL)0.5) : (ep - em) * gsc[c];
        }
        for (int c = 0; c < 3; c++) a[c] = neg_kv * g[c];
        for (int r = 0; r < 3; r++)
            out_a[4 * j + r] = qg ? (qg[3 * r] * a[0] + qg[3 * r + 1] * a[1]) + qg[3 * r + 2] * a[2] : a[r];
        out_a[4 * j + 3] = (REAL)0;
    }
}

/* §3.16 the grid's sample at x (the correction's inputs): s[0..2] = v̄ and s[3] = 1 where
 * friction applies (S_w > 0), else s[3] = 0; s[4..6] = ā (volume); s[7] = 1 when x is in the
 * grid, else 0 (then nothing else is written). */
HB_HD void SFX(hb_grid_sample)(const WORLD *w, const REAL *qg, const REAL *x, REAL *s)
{
    int64_t base;
    REAL wt[8];
    s[7] = (REAL)0;
    if (!SFX(hb_grid_locate)(qg, w->glo, w->gsc, w->gn, x, &base, wt)) return;
    s[7] = (REAL)1;
    s[3] = (REAL)0;
    if (w->grid_friction) {
        REAL sw = (REAL)0, sv[3] = {(REAL)0, (REAL)0, (REAL)0};
        for (int c8 = 0; c8 < 8; c8++) {
            const REAL *nv = w->node_v + 4 * SFX(hb_grid_corner)(base, w->gn, c8);
            if (nv[3] != (REAL)0) {
                sw = sw + wt[c8];
                for (int c = 0; c < 3; c++) sv[c] = sv[c] + wt[c8] * nv[c];
            }
        }
        if (sw > (REAL)0) {
            for (int c = 0; c < 3; c++) s[c] = sv[c] / sw;
            s[3] = (REAL)1;
        }
    }
    if (w->grid_volume) {
        REAL a[3] = {(REAL)0, (REAL)0, (REAL)0};
        for (int c8 = 0; c8 < 8; c8++) {
            const REAL *na = w->node_a + 4 * SFX(hb_grid_corner)(base, w->gn, c8);
            for (int c = 0; c < 3; c++) a[c] = a[c] + wt[c8] * na[c];
        }
        for (int c = 0; c < 3; c++) s[4 + c] = a[c];
    }
}

/* §3.16 the correction of point k (≥ 1), velocity v, from its sample s (hb_grid_sample). */
HB_HD void SFX(hb_grid_apply)(const WORLD *w, REAL h, int64_t k, const REAL *s, REAL *v)
{
    if (s[7] == (REAL)0) return;
    if (w->grid_friction && s[3] != (REAL)0) {
        const REAL f = w->ftab[k];
        for (int c = 0; c < 3; c++) v[c] = v[c] + f * (s[c] - v[c]);
    }
    if (w->grid_volume)
        for (int c = 0; c < 3; c++) v[c] = v[c] + h * s[4 + c];
}

/* §3.16 the hair–hair correction of point k (≥ 1) at x, velocity v, in step 2 of §3.4. */
HB_HD void SFX(hb_grid_correct)(const WORLD *w, const REAL *qg, REAL h, int64_t k, const REAL *x, REAL *v)
{
    REAL s[8];
    SFX(hb_grid_sample)(w, qg, x, s);
    SFX(hb_grid_apply)(w, h, k, s, v);
}

/* ---- §3.17 colliders ---- */

/* Friction after a projection that removed depth m along the unit normal n: the motion of p
 * relative to the collider's surface since x (the start of the substep), made tangential and
 * removed (static) or shortened by μ_k·m (kinetic). turn: the frame turned (back = its
 * Q(t)·Q(t+h)ᵀ); sway: it moved (back + 9 = b(t) − b(t+h)). */
HB_HD void SFX(hb_friction)(REAL *p, const REAL *x, const REAL *n, REAL m, REAL mu_s, REAL mu_k, int turn, int sway,
                            const REAL *back)
{
    REAL r[3], t[3];
    for (int c = 0; c < 3; c++) {
        const REAL bp = turn   ? (back[3 * c] * p[0] + back[3 * c + 1] * p[1]) + back[3 * c + 2] * p[2]
                        : sway ? p[c] + back[9 + c]
                               : p[c];
        r[c] = bp - x[c];
    }
    const REAL rn = (r[0] * n[0] + r[1] * n[1]) + r[2] * n[2];
    for (int c = 0; c < 3; c++) t[c] = r[c] - rn * n[c];
    const REAL tau = SQRT((t[0] * t[0] + t[1] * t[1]) + t[2] * t[2]);
    if (tau < mu_s * m) {
        for (int c = 0; c < 3; c++) p[c] = p[c] - t[c];
    } else if (tau > (REAL)0) {
        REAL k = (mu_k * m) / tau;
        if (k > (REAL)1) k = (REAL)1;
        for (int c = 0; c < 3; c++) p[c] = p[c] - k * t[c];
    }
}

/* The depth of p in the sphere of radius rc about c, rc − ρ > 0 with the outward normal in n
 * (ρ = 0: nperp, or ŷ without one), or 0 outside (n unset). */
HB_HD REAL SFX(hb_sphere_depth)(const REAL *p, const REAL *c, REAL rc, const REAL *nperp, REAL *n)
{
    const REAL e[3] = {p[0] - c[0], p[1] - c[1], p[2] - c[2]};
    const REAL rho = SQRT((e[0] * e[0] + e[1] * e[1]) + e[2] * e[2]);
    if (!(rho < rc)) return (REAL)0;
    if (rho == (REAL)0) {
        for (int k = 0; k < 3; k++) n[k] = nperp ? nperp[k] : (k == 1 ? (REAL)1 : (REAL)0);
    } else {
        for (int k = 0; k < 3; k++) n[k] = e[k] / rho;
    }
    return rc - rho;
}

/* p moved out of the sphere (c, rc) along n: by m, or with exact = 1 (unbounded) onto the
 * surface as c + (rc/ρ)·e (ρ = 0: c + rc·n). */
HB_HD void SFX(hb_sphere_move)(REAL *p, const REAL *c, REAL rc, const REAL *n, REAL m, int exact)
{
    if (!exact) {
        for (int k = 0; k < 3; k++) p[k] = p[k] + m * n[k];
        return;
    }
    const REAL e[3] = {p[0] - c[0], p[1] - c[1], p[2] - c[2]};
    const REAL rho = SQRT((e[0] * e[0] + e[1] * e[1]) + e[2] * e[2]);
    if (rho == (REAL)0) {
        for (int k = 0; k < 3; k++) p[k] = c[k] + rc * n[k];
    } else {
        const REAL sg = rc / rho;
        for (int k = 0; k < 3; k++) p[k] = c[k] + e[k] * sg;
    }
}

/* The bounded depenetration: of the depth d found at t + h, a point keeps what it had at the
 * substep's start (d0) less one step V·h (depen), never more than d; returns the depth to
 * remove, d − min(d, max(d0 − V·h, 0)). A point that was outside at the start (d0 ≤ V·h)
 * leaves in full, whatever pushed it in. */
HB_HD REAL SFX(hb_bounded_move)(REAL d, REAL d0, REAL depen)
{
    REAL keep = d0 - depen;
    keep = keep > (REAL)0 ? keep : (REAL)0;
    return d - (keep < d ? keep : d);
}

/* y = β⁻¹(x): the start of the substep carried with the collider frame's motion to t + h, where
 * the collider's pose is: turn, back's transpose (Q(t+h)·Q(t)ᵀ); sway, less its shift. */
HB_HD void SFX(hb_carry)(const REAL *back, int turn, int sway, const REAL *x, REAL *y)
{
    for (int c = 0; c < 3; c++)
        y[c] = turn ? (back[c] * x[0] + back[3 + c] * x[1]) + back[6 + c] * x[2] : sway ? x[c] - back[9 + c] : x[c];
}

/* The point of capsule a–b (pose) nearest to p. */
HB_HD void SFX(hb_capsule_centre)(const REAL *pose, const REAL *p, REAL *c)
{
    const REAL ab[3] = {pose[3] - pose[0], pose[4] - pose[1], pose[5] - pose[2]};
    const REAL ap[3] = {p[0] - pose[0], p[1] - pose[1], p[2] - pose[2]};
    REAL t = ((ap[0] * ab[0] + ap[1] * ab[1]) + ap[2] * ab[2]) / pose[10];
    t = t < (REAL)0 ? (REAL)0 : t > (REAL)1 ? (REAL)1 : t;
    for (int k = 0; k < 3; k++) c[k] = pose[k] + t * ab[k];
}

/* A mesh's SDF at the mesh-frame point u: 1, the value φ and the (unnormalised) gradient g in
 * grid units when u is inside the cube. geo: lo x, y, z and the scale 1/Δ_s. */
HB_HD int SFX(hb_sdf_sample)(const REAL *sdf, int64_t n, const REAL *geo, const REAL *u, REAL *phi, REAL *g)
{
    REAL f[3];
    int64_t i[3];
    for (int c = 0; c < 3; c++) {
        const REAL gc = (u[c] - geo[c]) * geo[3];
        if (!(gc >= (REAL)0 && gc < (REAL)(n - 1))) return 0;
        i[c] = (int64_t)gc;
        f[c] = gc - (REAL)i[c];
    }
    const int64_t b = i[0] + n * (i[1] + n * i[2]);
    REAL v[8], w[8];
    for (int k = 0; k < 8; k++) {
        v[k] = sdf[SFX(hb_grid_corner)(b, n, k)];
        const REAL wx = (k & 1) ? f[0] : (REAL)1 - f[0];
        const REAL wy = (k & 2) ? f[1] : (REAL)1 - f[1];
        const REAL wz = (k & 4) ? f[2] : (REAL)1 - f[2];
        w[k] = (wx * wy) * wz;
    }
    REAL s = (REAL)0;
    for (int k = 0; k < 8; k++) s = s + w[k] * v[k];
    *phi = s;
    /* ∂/∂g_c of the trilinear interpolant: the four edges along c, each weighted by the other two */
    for (int c = 0; c < 3; c++) {
        const int a1 = c == 0 ? 1 : 0, a2 = c == 2 ? 1 : 2; /* the other two axes */
        const int bit = 1 << c, b1 = 1 << a1, b2 = 1 << a2;
        REAL acc = (REAL)0;
        for (int e = 0; e < 4; e++) {
            const int k0 = ((e & 1) ? b1 : 0) | ((e & 2) ? b2 : 0);
            const REAL w1 = (e & 1) ? f[a1] : (REAL)1 - f[a1];
            const REAL w2 = (e & 2) ? f[a2] : (REAL)1 - f[a2];
            acc = acc + (w1 * w2) * (v[k0 | bit] - v[k0]);
        }
        g[c] = acc;
    }
    return 1;
}

/* The mesh-frame point of p (a head mesh: Qᵀ·p, pose's rows; a body mesh: p − b). */
HB_HD void SFX(hb_mesh_local)(const REAL *pose, int turn, int sway, const REAL *p, REAL *u)
{
    for (int c = 0; c < 3; c++)
        u[c] = turn ? (pose[c] * p[0] + pose[3 + c] * p[1]) + pose[6 + c] * p[2] : sway ? p[c] - pose[9 + c] : p[c];
}

/* The depth at t + h of y (the substep's start carried, hb_carry) in collider i (kind, pose):
 * positive inside; 0 or less outside (a sphere or capsule: 0; a mesh outside its cube: 0). */
HB_HD REAL SFX(hb_start_depth)(const WORLD *w, int i, int kind, int turn, int sway, const REAL *pose, const REAL *y)
{
    REAL n[3];
    if (kind == HB_COL_SPHERE) return SFX(hb_sphere_depth)(y, pose, pose[3], NULL, n);
    if (kind == HB_COL_CAPSULE) {
        REAL c[3];
        SFX(hb_capsule_centre)(pose, y, c);
        return SFX(hb_sphere_depth)(y, c, pose[6], pose + 7, n);
    }
    if (kind == HB_COL_PLANE)
        return pose[6] - (((y[0] - pose[0]) * pose[3] + (y[1] - pose[1]) * pose[4]) + (y[2] - pose[2]) * pose[5]);
    REAL u[3], phi, g[3];
    SFX(hb_mesh_local)(pose, turn, sway, y, u);
    if (!SFX(hb_sdf_sample)(w->sdf[i], w->sdf_n[i], w->sdf_geo + 4 * i, u, &phi, g)) return (REAL)0;
    return pose[12] - phi;
}

/* Collider i (kind, pose) on p: its projection and friction. x: the point at the start of the
 * substep; back: the substep's back-transforms. */
HB_HD void SFX(hb_collide_one)(const WORLD *w, int i, const REAL *pose, const REAL *back, REAL *p, const REAL *x)
{
    { /* outside the bounding sphere nothing can happen: skipped (the same bits as testing) */
        const REAL bx = p[0] - pose[16], by = p[1] - pose[17], bz = p[2] - pose[18];
        if (!((bx * bx + by * by) + bz * bz < pose[19])) return;
    }
    const int kind = w->col_kind[i], frame = w->col_frame[i];
    const int turn = frame == HB_FRAME_HEAD && w->motion, sway = frame == HB_FRAME_BODY && w->sway;
    REAL n[3], c[3] = {(REAL)0, (REAL)0, (REAL)0}, d; /* c: a sphere's or capsule's centre */
    if (kind == HB_COL_SPHERE || kind == HB_COL_CAPSULE) {
        if (kind == HB_COL_SPHERE) {
            for (int k = 0; k < 3; k++) c[k] = pose[k];
            d = SFX(hb_sphere_depth)(p, c, pose[3], NULL, n);
        } else {
            SFX(hb_capsule_centre)(pose, p, c);
            d = SFX(hb_sphere_depth)(p, c, pose[6], pose + 7, n);
        }
        if (!(d > (REAL)0)) return;
    } else if (kind == HB_COL_PLANE) {
        const REAL rho = ((p[0] - pose[0]) * pose[3] + (p[1] - pose[1]) * pose[4]) + (p[2] - pose[2]) * pose[5];
        if (!(rho < pose[6])) return;
        d = pose[6] - rho;
        for (int k = 0; k < 3; k++) n[k] = pose[3 + k];
    } else { /* mesh */
        REAL u[3], phi, g[3];
        SFX(hb_mesh_local)(pose, turn, sway, p, u);
        if (!SFX(hb_sdf_sample)(w->sdf[i], w->sdf_n[i], w->sdf_geo + 4 * i, u, &phi, g)) return;
        const REAL gl = SQRT((g[0] * g[0] + g[1] * g[1]) + g[2] * g[2]);
        if (!(phi < pose[12] && gl > (REAL)0)) return;
        d = pose[12] - phi;
        REAL nl[3];
        for (int k = 0; k < 3; k++) nl[k] = g[k] / gl;
        for (int r = 0; r < 3; r++)
            n[r] = turn ? (pose[3 * r] * nl[0] + pose[3 * r + 1] * nl[1]) + pose[3 * r + 2] * nl[2] : nl[r];
    }
    REAL m = d;
    if (w->bounded) {
        REAL y[3];
        SFX(hb_carry)(back, turn, sway, x, y);
        m = SFX(hb_bounded_move)(d, SFX(hb_start_depth)(w, i, kind, turn, sway, pose, y), w->depen);
    }
    if (kind == HB_COL_SPHERE || kind == HB_COL_CAPSULE) {
        SFX(hb_sphere_move)(p, c, kind == HB_COL_SPHERE ? pose[3] : pose[6], n, m, !w->bounded);
    } else {
        for (int k = 0; k < 3; k++) p[k] = p[k] + m * n[k];
    }
    const REAL mu_s = w->col_mu[2 * i];
    if (m > (REAL)0 && mu_s > (REAL)0) SFX(hb_friction)(p, x, n, m, mu_s, w->col_mu[2 * i + 1], turn, sway, back);
}

/* The head sphere of §3.5 with friction or a bounded depenetration (§3.17); its depth does not
 * change as it turns, so x's own depth is its start's. */
HB_HD void SFX(hb_collide_head)(const WORLD *w, REAL rc, const REAL *back, REAL *p, const REAL *x)
{
    const REAL origin[3] = {(REAL)0, (REAL)0, (REAL)0};
    REAL n[3], n0[3];
    const REAL d = SFX(hb_sphere_depth)(p, origin, rc, NULL, n);
    if (!(d > (REAL)0)) return;
    const REAL m = w->bounded ? SFX(hb_bounded_move)(d, SFX(hb_sphere_depth)(x, origin, rc, NULL, n0), w->depen) : d;
    SFX(hb_sphere_move)(p, origin, rc, n, m, !w->bounded);
    if (m > (REAL)0 && w->head_friction && w->head_mu_s > (REAL)0)
        SFX(hb_friction)(p, x, n, m, w->head_mu_s, w->head_mu_k, w->motion, 0, back);
}

/* The head sphere of §3.5 alone (no friction, unbounded): a point inside R_c goes to its surface
 * along the ray from the centre; the centre itself goes to (0, R_c, 0). */
HB_HD void SFX(hb_head_sphere)(REAL *p, REAL rc)
{
    const REAL len = SQRT(p[0] * p[0] + p[1] * p[1] + p[2] * p[2]);
    if (!(len < rc)) return;
    if (len == (REAL)0) {
        p[0] = (REAL)0;
        p[1] = rc;
        p[2] = (REAL)0;
        return;
    }
    const REAL sc = rc / len;
    p[0] = p[0] * sc;
    p[1] = p[1] * sc;
    p[2] = p[2] * sc;
}

/* Whether any bit of p differs from q's (a sweep that changes no bit of p would change none again),
 * and q ← p. */
HB_HD int SFX(hb_moved)(const REAL *p, REAL *q)
{
    int moved = 0;
    for (int c = 0; c < 3; c++) {
        RBITS a, b;
        memcpy(&a, &p[c], sizeof a);
        memcpy(&b, &q[c], sizeof b);
        moved |= a != b;
        q[c] = p[c];
    }
    return moved;
}

/* §3.17 --contact-planes: the signed distance of x from collider i (pose) at its margin-grown surface,
 * outside positive, with the outward unit normal in n; 0 where it has none (a mesh outside its cube
 * or at a flat spot of its field), else 1. */
HB_HD int SFX(hb_contact_distance)(const WORLD *w, int i, const REAL *pose, const REAL *x, REAL *rho, REAL *n)
{
    const int kind = w->col_kind[i], frame = w->col_frame[i];
    const int turn = frame == HB_FRAME_HEAD && w->motion, sway = frame == HB_FRAME_BODY && w->sway;
    if (kind == HB_COL_SPHERE || kind == HB_COL_CAPSULE) {
        REAL c[3];
        const REAL rc = kind == HB_COL_SPHERE ? pose[3] : pose[6];
        if (kind == HB_COL_SPHERE) {
            for (int k = 0; k < 3; k++) c[k] = pose[k];
        } else {
            SFX(hb_capsule_centre)(pose, x, c);
        }
        const REAL e[3] = {x[0] - c[0], x[1] - c[1], x[2] - c[2]};
        const REAL len = SQRT((e[0] * e[0] + e[1] * e[1]) + e[2] * e[2]);
        if (len == (REAL)0) {
            for (int k = 0; k < 3; k++) n[k] = kind == HB_COL_CAPSULE ? pose[7 + k] : (k == 1 ? (REAL)1 : (REAL)0);
        } else {
            for (int k = 0; k < 3; k++) n[k] = e[k] / len;
        }
        *rho = len - rc;
        return 1;
    }
    if (kind == HB_COL_PLANE) {
        for (int k = 0; k < 3; k++) n[k] = pose[3 + k];
        *rho = (((x[0] - pose[0]) * pose[3] + (x[1] - pose[1]) * pose[4]) + (x[2] - pose[2]) * pose[5]) - pose[6];
        return 1;
    }
    REAL u[3], phi, g[3];
    SFX(hb_mesh_local)(pose, turn, sway, x, u);
    if (!SFX(hb_sdf_sample)(w->sdf[i], w->sdf_n[i], w->sdf_geo + 4 * i, u, &phi, g)) return 0;
    const REAL gl = SQRT((g[0] * g[0] + g[1] * g[1]) + g[2] * g[2]);
    if (!(gl > (REAL)0)) return 0;
    REAL nl[3];
    for (int k = 0; k < 3; k++) nl[k] = g[k] / gl;
    for (int r = 0; r < 3; r++)
        n[r] = turn ? (pose[3 * r] * nl[0] + pose[3 * r + 1] * nl[1]) + pose[3 * r + 2] * nl[2] : nl[r];
    *rho = phi - pose[12];
    return 1;
}

/* §3.17 --contact-planes: the contacts of the point x at the frame's first substep (pose: every
 * collider's at its t + h): among the colliders whose surface lies nearer than the margin M (signed
 * distance ρ < M, inside too), the HB_CONTACT_K nearest (at a tie the first in the file), each kept as
 * the plane through its surface point x − ρ·n with the normal n, (n, n·x − ρ, i), in the file's order;
 * an unused slot has i = −1. */
HB_HD void SFX(hb_contact_find)(const WORLD *w, const REAL *pose, const REAL *x, REAL *con)
{
    REAL near[HB_CONTACT_K];
    int at[HB_CONTACT_K];
    for (int s = 0; s < HB_CONTACT_K; s++) near[s] = w->margin, at[s] = -1;
    for (int i = 0; i < w->ncol; i++) { /* the K nearest, nearest first (a later one only when nearer) */
        REAL rho, n[3];
        if (!SFX(hb_contact_distance)(w, i, pose + (size_t)i * HB_COL_POSE, x, &rho, n) ||
            !(rho < near[HB_CONTACT_K - 1]))
            continue;
        int s = HB_CONTACT_K - 1;
        for (; s > 0 && rho < near[s - 1]; s--) near[s] = near[s - 1], at[s] = at[s - 1];
        near[s] = rho, at[s] = i;
    }
    for (int s = 1; s < HB_CONTACT_K; s++) /* the file's order: indices ascending, the unused last */
        for (int t = s; t > 0 && at[t] >= 0 && (at[t - 1] < 0 || at[t] < at[t - 1]); t--) {
            const int a = at[t];
            at[t] = at[t - 1], at[t - 1] = a;
        }
    for (int s = 0; s < HB_CONTACT_K; s++) {
        REAL *c = con + HB_CONTACT * s, rho = (REAL)0, n[3] = {(REAL)0, (REAL)0, (REAL)0};
        c[4] = (REAL)at[s];
        if (at[s] < 0) continue;
        SFX(hb_contact_distance)(w, at[s], pose + (size_t)at[s] * HB_COL_POSE, x, &rho, n); /* found above */
        for (int k = 0; k < 3; k++) c[k] = n[k];
        c[3] = ((n[0] * x[0] + n[1] * x[1]) + n[2] * x[2]) - rho;
    }
}

/* §3.17 --contact-planes: a point's plane carried with its collider's frame over the substep (t to
 * t + h, the inverse of back's transform): a turning head frame turns n (about the origin, so d
 * stays); a swaying body frame shifts the plane by s = b(t + h) − b(t) = −back[9..11], d ← d + n·s. */
HB_HD void SFX(hb_contact_carry)(const WORLD *w, const REAL *back, REAL *con)
{
    if (!(con[4] >= (REAL)0)) return; /* an unused slot */
    const int frame = w->col_frame[(int)con[4]];
    if (frame == HB_FRAME_HEAD && w->motion) {
        REAL n[3];
        SFX(hb_carry)(back, 1, 0, con, n);
        for (int k = 0; k < 3; k++) con[k] = n[k];
    } else if (frame == HB_FRAME_BODY && w->sway) {
        con[3] = con[3] - ((con[0] * back[9] + con[1] * back[10]) + con[2] * back[11]);
    }
}

/* §3.17 --contact-planes: point x's planes con at substep j of a frame, before the substep's first
 * step: found from x at the frame's first substep, carried with their colliders at the others */
HB_HD void SFX(hb_contact_step)(const WORLD *w, const REAL *pose, const REAL *back, int64_t j, const REAL *x, REAL *con)
{
    if (j == 0) SFX(hb_contact_find)(w, pose, x, con);
    else
        for (int s = 0; s < HB_CONTACT_K; s++) SFX(hb_contact_carry)(w, back, con + HB_CONTACT * s);
}

/* §3.17 --contact-planes: the point's plane on p, as a plane collider: the depth δ = d − n·p > 0
 * (bounded: δ₀ = d − n·y of the substep's start carried, hb_carry), p ← p + m·n, then the collider's
 * friction. x: the point at the substep's start; back: the substep's back-transforms. The collider's
 * frame and friction are looked up only for a plane that p is behind: most planes a point keeps
 * are not met in an iteration (docs/cuda.md "Contact planes in the lanes kernel"). */
HB_HD void SFX(hb_contact_one)(const WORLD *w, const REAL *con, const REAL *back, REAL *p, const REAL *x)
{
    if (!(con[4] >= (REAL)0)) return;
    const REAL d = con[3] - ((con[0] * p[0] + con[1] * p[1]) + con[2] * p[2]);
    if (!(d > (REAL)0)) return;
    const int i = (int)con[4], frame = w->col_frame[i];
    const int turn = frame == HB_FRAME_HEAD && w->motion, sway = frame == HB_FRAME_BODY && w->sway;
    REAL m = d;
    if (w->bounded) {
        REAL y[3];
        SFX(hb_carry)(back, turn, sway, x, y);
        m = SFX(hb_bounded_move)(d, con[3] - ((con[0] * y[0] + con[1] * y[1]) + con[2] * y[2]), w->depen);
    }
    for (int k = 0; k < 3; k++) p[k] = p[k] + m * con[k];
    const REAL mu_s = w->col_mu[2 * i];
    if (m > (REAL)0 && mu_s > (REAL)0) SFX(hb_friction)(p, x, con, m, mu_s, w->col_mu[2 * i + 1], turn, sway, back);
}

/* §3.17 the collision step of one point p (x: where it was at the substep's start): the sweep,
 * the head sphere (head: HB_HEAD_*) then each collider in order with its friction, run again
 * while it moves p (any of them changes a bit of it), w->sweeps sweeps at most. One sweep (w->sweeps = 1)
 * is the collision step as it was before sweeps, the same operations. pose: collider i's at
 * pose + i·HB_COL_POSE; back: the substep's back-transforms. The C reference (dynamics_impl.h)
 * and the SIMD backend (dynamics_simd_impl.h) call this; the CUDA port's lanes kernel takes the
 * same steps a warp at a time (cuda/dynamic/lanes_kernel.cuh collide_points). con: the point's contact plane
 * (--contact-planes), met in place of the colliders; NULL: every collider (the reference's default). */
HB_HD_INLINE void SFX(hb_collide_sweeps)(const WORLD *w, REAL rc, int head, const REAL *pose, const REAL *back, REAL *p,
                                         const REAL *x, const REAL *con)
{
    if (w->sweeps <= 1) { /* one sweep: nothing to compare */
        if (head == HB_HEAD_PLAIN) SFX(hb_head_sphere)(p, rc);
        else if (head == HB_HEAD_WORLD) SFX(hb_collide_head)(w, rc, back, p, x);
        for (int s = 0; con && s < HB_CONTACT_K; s++) SFX(hb_contact_one)(w, con + HB_CONTACT * s, back, p, x);
        if (!con)
            for (int i = 0; i < w->ncol; i++) SFX(hb_collide_one)(w, i, pose + (size_t)i * HB_COL_POSE, back, p, x);
        return;
    }
    for (int s = 1;; s++) {
        const int track = s < w->sweeps; /* whether another sweep may follow */
        int moved = 0;
        REAL q[3] = {p[0], p[1], p[2]};
        if (head == HB_HEAD_PLAIN) SFX(hb_head_sphere)(p, rc);
        else if (head == HB_HEAD_WORLD) SFX(hb_collide_head)(w, rc, back, p, x);
        if (track && head != HB_HEAD_NONE) moved |= SFX(hb_moved)(p, q);
        for (int s = 0; con && s < HB_CONTACT_K; s++) {
            SFX(hb_contact_one)(w, con + HB_CONTACT * s, back, p, x);
            if (track) moved |= SFX(hb_moved)(p, q);
        }
        for (int i = 0; !con && i < w->ncol; i++) {
            SFX(hb_collide_one)(w, i, pose + (size_t)i * HB_COL_POSE, back, p, x);
            if (track) moved |= SFX(hb_moved)(p, q);
        }
        if (!moved) return;
    }
}

/* The depth of x (double) inside collider i with pose `pose` (§3.8 penetration_max), or 0. */
HB_HD double SFX(hb_collider_depth)(const WORLD *w, int i, const REAL *pose, const double *x)
{
    const int kind = w->col_kind[i], frame = w->col_frame[i];
    const int turn = frame == HB_FRAME_HEAD && w->motion, sway = frame == HB_FRAME_BODY && w->sway;
    double d = 0.0;
    if (kind == HB_COL_SPHERE || kind == HB_COL_CAPSULE) {
        double c[3] = {(double)pose[0], (double)pose[1], (double)pose[2]};
        double rc = (double)pose[3];
        if (kind == HB_COL_CAPSULE) {
            const double ab[3] = {(double)pose[3] - c[0], (double)pose[4] - c[1], (double)pose[5] - c[2]};
            double t = (((x[0] - c[0]) * ab[0] + (x[1] - c[1]) * ab[1]) + (x[2] - c[2]) * ab[2]) / (double)pose[10];
            t = t < 0.0 ? 0.0 : t > 1.0 ? 1.0 : t;
            for (int k = 0; k < 3; k++) c[k] = c[k] + t * ab[k];
            rc = (double)pose[6];
        }
        const double e[3] = {x[0] - c[0], x[1] - c[1], x[2] - c[2]};
        d = rc - sqrt((e[0] * e[0] + e[1] * e[1]) + e[2] * e[2]);
    } else if (kind == HB_COL_PLANE) {
        d = (double)pose[6] -
            (((x[0] - (double)pose[0]) * (double)pose[3] + (x[1] - (double)pose[1]) * (double)pose[4]) +
             (x[2] - (double)pose[2]) * (double)pose[5]);
    } else {
        double u[3], f[3];
        int64_t ii[3];
        const int64_t n = w->sdf_n[i];
        const REAL *geo = w->sdf_geo + 4 * i;
        for (int c = 0; c < 3; c++)
            u[c] = turn   ? ((double)pose[c] * x[0] + (double)pose[3 + c] * x[1]) + (double)pose[6 + c] * x[2]
                   : sway ? x[c] - (double)pose[9 + c]
                          : x[c];
        for (int c = 0; c < 3; c++) {
            const double g = (u[c] - (double)geo[c]) * (double)geo[3];
            if (!(g >= 0.0 && g < (double)(n - 1))) return 0.0;
            ii[c] = (int64_t)g;
            f[c] = g - (double)ii[c];
        }
        const int64_t b = ii[0] + n * (ii[1] + n * ii[2]);
        double phi = 0.0;
        for (int k = 0; k < 8; k++) {
            const double wx = (k & 1) ? f[0] : 1.0 - f[0];
            const double wy = (k & 2) ? f[1] : 1.0 - f[1];
            const double wz = (k & 4) ? f[2] : 1.0 - f[2];
            phi = phi + ((wx * wy) * wz) * (double)w->sdf[i][SFX(hb_grid_corner)(b, n, k)];
        }
        d = (double)pose[12] - phi;
    }
    return d > 0.0 ? d : 0.0;
}
