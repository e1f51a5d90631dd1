/* cuda/dynamic/model.cuh — the dynamic model (docs/model.md §3) for the CUDA port: c_ref/dynamic/dynamics_impl.h
 * written as `__host__ __device__` templates over the floating type T, the feature set, the
 * memory layout of the strand and the way a loop over points or constraints is executed.
 *
 * This file follows c_ref/dynamic/dynamics_impl.h operation by operation: the same expressions in
 * the same order (no reassociation, the same divisions, the same branches). A build without
 * FMA contraction and with IEEE division and square root (hairsim-cuda-strict) therefore
 * differs from the C reference only where CUDA's sinf/sin differ from glibc's (gusts only;
 * the rest uses +, −, ×, ÷ and sqrt, all correctly rounded). Compiled for the host
 * (cuda/hostcheck/dyn_hostcheck.cu) the same templates call glibc and must reproduce
 * c_ref/dynamic/dynamics_f32.c / dynamics_f64.c bit for bit. The normal build contracts a·b + c into
 * FMAs and the fast-math build uses approximate sinf, division and square root: both differ.
 *
 * The three policies:
 *   Feat  the feature set (docs/model.md §3.9): StaticF<F> folds every `has(bit)` at compile
 *         time, so an undeclared feature leaves no code; DynF keeps the set as a run-time mask
 *         (the generic fallback of cuda/dynamic/kernels.cu).
 *   Arr   where coordinate c of point k of the strand is: base[k·ks + c·cs]. One type covers
 *         the canonical array (ks = 3, cs = 1), the point-major planes X|Y|Z [P][N]
 *         (ks = N, cs = N·P), a warp's shared-memory planes [3][P] (ks = 1, cs = P) and a
 *         thread's interleaved scratch (ks = T, cs = P·T for T threads).
 *   Exec  how a loop runs: Seq runs it in order on one thread (the strand variant, and the
 *         C reference's order); Lanes (cuda/dynamic/kernels.cu) spreads its iterations over
 *         the 32 lanes of a warp and ends with __syncwarp(). Only loops whose iterations
 *         touch disjoint data are handed to Exec::each (a group of §3.6, the per-point
 *         velocity and position steps, the multiplier reset); the follow-the-leader chain
 *         and the root step run through Exec::one (one lane). So every point sees the same
 *         operations on the same inputs in any Exec, and the bits are the same.
 */
#ifndef HB_DYN_MODEL_CUH
#define HB_DYN_MODEL_CUH

#include <math.h>
#include <stdint.h>

#include "dynamic/dynamics.h"  /* HB_F_*, hb_dyn_model_f32/f64 */
#include "dynamic/obs_point.h" /* hb_obs_point: §3.8 per point, shared with the reference */
#include "runtime/params.h"    /* HB_SOLVER_* */
#include "tmath.cuh"           /* m_sqrt, m_sin: the float overloads for float */
#include "dynamic/world.cuh"   /* §3.16 grid, §3.17 colliders: contact_impl.h for float and double */

#if defined(__CUDACC__)
#define HB_DHD __host__ __device__ __forceinline__
#else
#define HB_DHD inline
#endif

namespace hb {
namespace dyn {

/* The run's constants in T: the fields of hb_dyn_model_f32/f64 (hb_dyn_round made them). */
template <typename T> struct DModel {
    int64_t points, substeps, iterations, shape_count;
    int64_t collide_from; /* xpbd: the first iteration with a collision step (0; I − 1: --collide-once) */
    int solver;
    unsigned features;
    T h, seg_len, gravity_y, wind_y, wind_z, dir_y, dir_z, kappa, gust, den, stretch_at, bend_at, shape_at, collide_r,
        ftl_s;
    /* the normal build's constant reciprocals (docs/cuda.md "Builds and arithmetic"), each
     * computed once in double from the rounded constants and rounded once: 1/h, 1/D,
     * 1/(W + α̃) for W = 1 (root) and 2 of stretch and bend, 1/(1 + α̃_g), R_c² */
    T inv_h, inv_den, inv_s1, inv_s2, inv_b1, inv_b2, inv_g, rc2;
    int lra; /* §3.14 long-range attachments: a run-time switch */
    T lra_len;
    /* §3.15 a groom's stretch rest lengths ℓ_k on the device (nullptr: ℓ = seg_len); strand i's
     * ℓ_k at seg_rest[i·seg_is + (k − 1)·seg_s] (point-major for strand, [N][P−1] for the others) */
    const T *seg_rest = nullptr;
    int64_t seg_is = 0, seg_s = 0;
    /* §3.16 the grid and §3.17 the colliders (has_world = 0: none); the frame's device tables:
     * the colliders' poses [S][max(ncol, 1)][HB_COL_POSE], back-transforms [S][HB_COL_BACK] and
     * Q at the frame's start (the frame's first grid build) */
    int has_world = 0;
    World<T> world{};
    const int64_t *perm = nullptr; /* the strands' order (lanes with a world): slot s runs strand perm[s] */
    const T *pose = nullptr, *back = nullptr, *qs = nullptr;
    /* §3.16 `held`: each point's sample for the frame ([N][P][kHeldReals], cuda/dynamic/held.cuh) */
    const T *held = nullptr;
    /* §3.16 `held` without colliders: the held lanes kernel samples its block's own points before its
     * strand loop (hold_block; k_grid_hold not launched, m.held unused) */
    int hold_self = 0;
    /* lanes: the one-wave layout (lanes_wave, decided once a run) */
    bool wave = false;
    /* §3.17 --contact-planes: each point's planes [N][P][HB_CONTACT_POINT] (strands as stored), where a
     * frame runs in several launches (lanes: kept between them; nullptr: the frame in one launch) */
    T *contacts = nullptr;
    /* the substeps a launch runs: j0 … j1 − 1 (j1 < 0: all of the frame's) */
    int j0 = 0, j1 = -1;
};

template <typename T, typename M> inline DModel<T> dmodel_from(const M &m)
{
    DModel<T> r;
    r.points = m.points;
    r.substeps = m.substeps;
    r.iterations = m.iterations;
    r.collide_from = m.collide_from;
    r.shape_count = m.shape_count;
    r.solver = m.solver;
    r.features = m.features;
    r.h = m.h;
    r.seg_len = m.seg_len;
    r.gravity_y = m.gravity_y;
    r.wind_y = m.wind_y;
    r.wind_z = m.wind_z;
    r.dir_y = m.dir_y;
    r.dir_z = m.dir_z;
    r.kappa = m.kappa;
    r.gust = m.gust;
    r.den = m.den;
    r.stretch_at = m.stretch_at;
    r.bend_at = m.bend_at;
    r.shape_at = m.shape_at;
    r.collide_r = m.collide_r;
    r.ftl_s = m.ftl_s;
    r.lra = m.lra;
    r.lra_len = m.lra_len;
    r.inv_h = (T)(1.0 / (double)r.h);
    r.inv_den = (T)(1.0 / (double)r.den);
    r.inv_s1 = (T)(1.0 / (1.0 + (double)r.stretch_at));
    r.inv_s2 = (T)(1.0 / (2.0 + (double)r.stretch_at));
    r.inv_b1 = (T)(1.0 / (1.0 + (double)r.bend_at));
    r.inv_b2 = (T)(1.0 / (2.0 + (double)r.bend_at));
    r.inv_g = (T)(1.0 / (1.0 + (double)r.shape_at));
    r.rc2 = (T)((double)r.collide_r * (double)r.collide_r);
    return r;
}

/* The observables' scene numbers, in double, as hb_dyn_observe_strand computes them. */
struct ObsScene {
    int64_t points;
    double ell, far2, rc;
    int collider;
    const double *seg64 = nullptr; /* §3.15 a groom's ℓ_k in double, [N][P−1] on the device; nullptr: ell */
    /* §3.17 the colliders at the frame's end (the depth of a point in each), one precision's */
    int ncol = 0;
    const World<float> *w32 = nullptr;
    const World<double> *w64 = nullptr;
    const float *pose32 = nullptr;
    const double *pose64 = nullptr;
};

inline ObsScene obs_scene(const hb_scene *s)
{
    ObsScene o;
    o.points = s->points;
    o.ell = hb_segment_length(s);
    o.far2 = 4.0 * s->hair_length * s->hair_length;
    o.rc = s->head_radius + s->dyn.collision_margin;
    o.collider = s->dyn.collider;
    return o;
}

/* ---- policies ---- */
template <unsigned F> struct StaticF {
    HB_DHD constexpr bool operator()(unsigned bit) const { return (F & bit) != 0u; }
};
struct DynF {
    unsigned f;
    HB_DHD bool operator()(unsigned bit) const { return (f & bit) != 0u; }
};

template <typename T> struct Arr {
    T *b;
    int64_t ks, cs;
    HB_DHD T &operator()(int64_t k, int c) const { return b[k * ks + (int64_t)c * cs]; }
};
template <typename T> struct Arr1 {
    T *b;
    int64_t s;
    HB_DHD T &operator()(int64_t i) const { return b[i * s]; }
};

/* One strand: x, v (state), rest X̄, bend rest lengths, and the frame's working arrays:
 * predicted positions p, multipliers λ (stretch P−1 | bend P−2 | shape K at 0, P, 2P) and
 * the ftl corrections d. */
template <typename T> struct Strand {
    Arr<T> x, v;
    Arr<const T> rest;
    Arr1<const T> bend_rest;
    Arr<T> p, d;
    Arr1<T> lam;
    Arr1<const T> seg_rest = {nullptr, 0}; /* §3.15 a groom's ℓ_k (b = nullptr: m.seg_len) */
};

/* The warp variant's strand in one warp's shared memory (cuda/dynamic/kernels.cu k_warp, and its
 * host check): x, v, p, d [3][P], λ [3P] from base; rest and bend_rest are the caller's. */
template <typename T> HB_DHD constexpr int64_t warp_reals(int64_t P)
{
    return 15 * P;
}
template <typename T> HB_DHD Strand<T> warp_strand(T *base, int64_t P)
{
    Strand<T> s;
    s.x = Arr<T>{base, 1, P};
    s.v = Arr<T>{base + 3 * P, 1, P};
    s.p = Arr<T>{base + 6 * P, 1, P};
    s.d = Arr<T>{base + 9 * P, 1, P};
    s.lam = Arr1<T>{base + 12 * P, 1};
    return s;
}

struct Seq {
    template <class Fn> HB_DHD void each(int64_t b, int64_t e, int64_t step, Fn f) const
    {
        for (int64_t k = b; k < e; k += step) f(k);
    }
    template <class Fn> HB_DHD void one(Fn f) const { f(); }
};

/* ---- the constraints (§3.5) on scalars ---- */

/* r = Q·a, row-major Q, each row summed left to right. */
template <typename T> HB_DHD void rotate(const T *q, T a0, T a1, T a2, T *r)
{
    r[0] = q[0] * a0 + q[1] * a1 + q[2] * a2;
    r[1] = q[3] * a0 + q[4] * a1 + q[5] * a2;
    r[2] = q[6] * a0 + q[7] * a1 + q[8] * a2;
}

/* The math of the constraints and steps on scalars, once: the kernels that hold a strand in
 * memory (frame_body below) and the one that holds a point per lane in registers
 * (cuda/dynamic/kernels.cu k_warpreg) both call these, so every variant does the same
 * operations in the same order. */

/* §3.5 distance constraint between a and b (dynamics_impl.h distance): the multiplier step.
 * Returns false when |e| = 0 (nothing moves, λ unchanged); else the caller moves
 * a ← a − dl·n (unless a is the root) and b ← b + dl·n. */
template <typename T>
HB_DHD bool distance_step(T ax, T ay, T az, T bx, T by, T bz, int move_a, T r, T at, T &lambda, T &dl, T &nx, T &ny,
                          T &nz)
{
    const T ex = bx - ax, ey = by - ay, ez = bz - az;
    const T len = m_sqrt(ex * ex + ey * ey + ez * ez);
    if (len == (T)0) return false;
    const T c = len - r;
    const T wsum = move_a ? (T)2 : (T)1;
    dl = (-c - at * lambda) / (wsum + at);
    lambda = lambda + dl;
    nx = ex / len;
    ny = ey / len;
    nz = ez / len;
    return true;
}

/* distance constraint between point a and point b of `p` */
template <typename T> HB_DHD void distance(const Arr<T> &p, int64_t ia, int64_t ib, int move_a, T r, T at, T &lambda)
{
    T dl, nx, ny, nz;
    if (!distance_step(p(ia, 0), p(ia, 1), p(ia, 2), p(ib, 0), p(ib, 1), p(ib, 2), move_a, r, at, lambda, dl, nx, ny,
                       nz))
        return;
    if (move_a) {
        p(ia, 0) = p(ia, 0) - dl * nx;
        p(ia, 1) = p(ia, 1) - dl * ny;
        p(ia, 2) = p(ia, 2) - dl * nz;
    }
    p(ib, 0) = p(ib, 0) + dl * nx;
    p(ib, 1) = p(ib, 1) + dl * ny;
    p(ib, 2) = p(ib, 2) + dl * nz;
}

/* §3.5 shape: a zero-length spring from (p0, p1, p2) to the target t (dynamics_impl.h shape_pull). */
template <typename T> HB_DHD void shape_pull(T &p0, T &p1, T &p2, const T *t, T at, T &lambda)
{
    const T ex = p0 - t[0], ey = p1 - t[1], ez = p2 - t[2];
    const T c = m_sqrt(ex * ex + ey * ey + ez * ez);
    if (c == (T)0) return;
    const T dl = (-c - at * lambda) / ((T)1 + at);
    lambda = lambda + dl;
    p0 = p0 + dl * (ex / c);
    p1 = p1 + dl * (ey / c);
    p2 = p2 + dl * (ez / c);
}

/* head collision on a point held in three scalars */
template <typename T> HB_DHD void collide_sphere(T &p0, T &p1, T &p2, T rc)
{
    const T len = m_sqrt(p0 * p0 + p1 * p1 + p2 * p2);
    if (!(len < rc)) return;
    if (len == (T)0) {
        p0 = (T)0;
        p1 = rc;
        p2 = (T)0;
        return;
    }
    const T sc = rc / len;
    p0 = p0 * sc;
    p1 = p1 * sc;
    p2 = p2 * sc;
}

/* §3.14 long-range attachment of point k to its root a: |p − a| ≤ (s_L·ℓ)·k */
template <typename T> HB_DHD void lra_point(T a0, T a1, T a2, T &p0, T &p1, T &p2, T len, int64_t k)
{
    const T ex = p0 - a0, ey = p1 - a1, ez = p2 - a2;
    const T d = m_sqrt(ex * ex + ey * ey + ez * ez);
    const T r = len * (T)k;
    if (d > r) {
        const T sc = r / d;
        p0 = a0 + ex * sc;
        p1 = a1 + ey * sc;
        p2 = a2 + ez * sc;
    }
}

/* §3.4 step 1: the root on the head, x0 ← Q·X̄0, v0 ← (x0_new − x0_old)/h. */
template <typename T> HB_DHD void root_step(const T *q, T r0, T r1, T r2, T h, T &x0, T &x1, T &x2, T &v0, T &v1, T &v2)
{
    T r[3];
    rotate(q, r0, r1, r2, r);
    v0 = (r[0] - x0) / h;
    x0 = r[0];
    v1 = (r[1] - x1) / h;
    x1 = r[1];
    v2 = (r[2] - x2) / h;
    x2 = r[2];
}

/* §3.4 step 2 for one point k ≥ 1: the velocity, implicit in drag and damping, then the
 * prediction p = x + h·v. */
template <typename T, class Feat>
HB_DHD void velocity_predict(const DModel<T> &m, Feat has, T phase, T x0, T x1, T x2, T &v0, T &v1, T &v2, T &p0, T &p1,
                             T &p2)
{
    const T h = m.h;
    T vx = v0, vy = v1, vz = v2;
    if (has(HB_F_WIND)) {
        T gam = (T)1;
        if (has(HB_F_GUST)) gam = (T)1 + m.gust * m_sin(phase - m.kappa * (m.dir_y * x1 + m.dir_z * x2));
        vy = vy + h * (m.gravity_y + m.wind_y * gam);
        vz = vz + h * (m.wind_z * gam);
    } else {
        vy = vy + h * m.gravity_y;
    }
    if (has(HB_F_DRAG)) {
        vx = vx / m.den;
        vy = vy / m.den;
        vz = vz / m.den;
    }
    v0 = vx;
    v1 = vy;
    v2 = vz;
    p0 = x0 + h * vx;
    p1 = x1 + h * vy;
    p2 = x2 + h * vz;
}

/* §3.7 one follow-the-leader step: (p0, p1, p2) follows its corrected predecessor a; d is
 * the correction before the collision, then the collision (if on) moves the point. */
template <typename T>
HB_DHD void follow(T a0, T a1, T a2, T &p0, T &p1, T &p2, T seg, bool collide, T rc, T &d0, T &d1, T &d2)
{
    const T ex = p0 - a0, ey = p1 - a1, ez = p2 - a2;
    const T len = m_sqrt(ex * ex + ey * ey + ez * ez);
    T nq0, nq1, nq2;
    if (len > (T)0) {
        nq0 = a0 + seg * (ex / len);
        nq1 = a1 + seg * (ey / len);
        nq2 = a2 + seg * (ez / len);
    } else {
        nq0 = a0;
        nq1 = a1 - seg;
        nq2 = a2;
    }
    d0 = nq0 - p0;
    d1 = nq1 - p1;
    d2 = nq2 - p2;
    if (collide) collide_sphere(nq0, nq1, nq2, rc);
    p0 = nq0;
    p1 = nq1;
    p2 = nq2;
}

/* §3.4 step 4 for one coordinate of a point k ≥ 1: v = (p − x)/h, less s·d(k+1)/h for ftl
 * (corr: the point has a successor and the solver is ftl). */
template <typename T> HB_DHD T update_velocity(T p, T x, T h, bool corr, T s, T dnext)
{
    T vk = (p - x) / h;
    if (corr) vk = vk - (s * dnext) / h;
    return vk;
}

/* k of the g-th member of bend group `parity`: ⌊(k−1)/2⌋ ≡ parity (mod 2), k ascending. */
HB_DHD int64_t bend_k(int64_t g, int parity)
{
    return 1 + 4 * (g >> 1) + (g & 1) + 2 * parity;
}

template <typename T, class Exec>
HB_DHD void bend_group(const DModel<T> &m, const Strand<T> &s, const Exec &ex, int parity)
{
    const int64_t P = m.points;
    const Arr<T> p = s.p;
    const Arr1<const T> br = s.bend_rest;
    const Arr1<T> lam = s.lam;
    const T at = m.bend_at;
    /* members g = 0, 1, …: at most P/2 + 2 of them; k + 1 < P bounds the group */
    ex.each(0, P / 2 + 2, 1, [&](int64_t g) {
        const int64_t k = bend_k(g, parity);
        if (k + 1 < P) distance(p, k - 1, k + 1, k - 1 != 0, br(k - 1), at, lam(P + k - 1));
    });
}

template <typename T, class Feat, class Exec>
HB_DHD void shape_all(const DModel<T> &m, const Strand<T> &s, const T *q, const Exec &ex, Feat has)
{
    const int64_t P = m.points;
    const Arr<T> p = s.p;
    const Arr<const T> rest = s.rest;
    const Arr1<T> lam = s.lam;
    const T at = m.shape_at;
    ex.each(1, m.shape_count + 1, 1, [&](int64_t k) {
        T t[3];
        if (has(HB_F_MOTION)) rotate(q, rest(k, 0), rest(k, 1), rest(k, 2), t);
        else {
            t[0] = rest(k, 0);
            t[1] = rest(k, 1);
            t[2] = rest(k, 2);
        }
        shape_pull(p(k, 0), p(k, 1), p(k, 2), t, at, lam(2 * P + k - 1));
    });
}

/* One frame of one strand: S substeps of §3.4 with the solver of §3.6 or §3.7.
 * qtab: [S][9] rotations Q(t+h); phtab: [S] gust phases φ(t) (hb_dyn_frame_plan). */
template <typename T, class Feat, class Exec>
HB_DHD void frame_body(const DModel<T> &m, const T *qtab, const T *phtab, const Strand<T> &s, const Exec &ex, Feat has)
{
    const int64_t P = m.points;
    const T h = m.h;
    const Arr<T> x = s.x, v = s.v, p = s.p, d = s.d;
    const Arr<const T> rest = s.rest;
    const Arr1<T> lam = s.lam;
    const Arr1<const T> sr = s.seg_rest;
    auto seg = [&](int64_t k) { return sr.b ? sr(k - 1) : m.seg_len; }; /* §3.15 */

    for (int64_t j = 0; j < m.substeps; j++) {
        const T *q = qtab + 9 * j;
        const T phase = phtab[j];

        /* 1. root on the head, then p0 = x0 */
        ex.one([&]() {
            if (has(HB_F_MOTION))
                root_step(q, rest(0, 0), rest(0, 1), rest(0, 2), h, x(0, 0), x(0, 1), x(0, 2), v(0, 0), v(0, 1),
                          v(0, 2));
            p(0, 0) = x(0, 0);
            p(0, 1) = x(0, 1);
            p(0, 2) = x(0, 2);
        });

        /* 2. velocities, implicit in drag and damping, then the prediction */
        ex.each(1, P, 1, [&](int64_t k) {
            velocity_predict(m, has, phase, x(k, 0), x(k, 1), x(k, 2), v(k, 0), v(k, 1), v(k, 2), p(k, 0), p(k, 1),
                             p(k, 2));
        });

        /* 3. constraints; every multiplier starts the substep at 0 */
        /* one iteration's bend, shape and LRA constraints, in the order both solvers apply them */
        auto bend_shape_lra = [&]() {
            if (has(HB_F_BEND)) {
                bend_group(m, s, ex, 0);
                bend_group(m, s, ex, 1);
            }
            if (has(HB_F_SHAPE)) shape_all(m, s, q, ex, has);
            if (m.lra)
                ex.each(1, P, 1, [&](int64_t k) {
                    lra_point(p(0, 0), p(0, 1), p(0, 2), p(k, 0), p(k, 1), p(k, 2), m.lra_len, k);
                });
        };
        ex.each(0, 3 * P, 1, [&](int64_t i) { lam(i) = (T)0; });
        if (m.solver == HB_SOLVER_XPBD) {
            for (int64_t it = 0; it < m.iterations; it++) {
                ex.each(1, P, 2, [&](int64_t k) { /* stretch, k odd */
                                                  distance(p, k - 1, k, k - 1 != 0, seg(k), m.stretch_at, lam(k - 1));
                });
                ex.each(2, P, 2, [&](int64_t k) { /* stretch, k even */
                                                  distance(p, k - 1, k, 1, seg(k), m.stretch_at, lam(k - 1));
                });
                bend_shape_lra();
                if (has(HB_F_COLLIDE))
                    ex.each(1, P, 1, [&](int64_t k) { collide_sphere(p(k, 0), p(k, 1), p(k, 2), m.collide_r); });
            }
        } else {
            for (int64_t it = 0; it < m.iterations; it++) { bend_shape_lra(); }
            /* §3.7 follow the leader, k ascending: each point follows its corrected predecessor */
            ex.one([&]() {
                for (int64_t k = 1; k < P; k++)
                    follow(p(k - 1, 0), p(k - 1, 1), p(k - 1, 2), p(k, 0), p(k, 1), p(k, 2), seg(k), has(HB_F_COLLIDE),
                           m.collide_r, d(k, 0), d(k, 1), d(k, 2));
            });
        }

        /* 4. velocities from the motion (ftl: less s·d_{k+1}/h), then the positions. Per
         * point the same operations as the reference's three loops, in the same order. */
        const int ftl = m.solver == HB_SOLVER_FTL;
        ex.each(1, P, 1, [&](int64_t k) {
            const bool corr = ftl && k + 1 < P;
            for (int c = 0; c < 3; c++) {
                v(k, c) = update_velocity(p(k, c), x(k, c), h, corr, m.ftl_s, corr ? d(k + 1, c) : (T)0);
                x(k, c) = p(k, c);
            }
        });
    }
}

/* §3.5 bend rest lengths |X̄_{k+1} − X̄_{k−1}| (dynamics_impl.h hb_dyn_bend_rest). */
template <typename T> HB_DHD void bend_rest(int64_t P, const Arr<const T> &rest, const Arr1<T> &out)
{
    for (int64_t k = 1; k + 1 < P; k++) {
        const T ex = rest(k + 1, 0) - rest(k - 1, 0), ey = rest(k + 1, 1) - rest(k - 1, 1),
                ez = rest(k + 1, 2) - rest(k - 1, 2);
        out(k - 1) = m_sqrt(ex * ex + ey * ey + ez * ez);
    }
}

/* Per-strand partial observables (§3.8), in double: hb_obs_partial's fields. */
struct ObsPartial {
    double stretch_max, penetration_max, v2_sum;
    long long blown;
};

HB_DHD int finite_d(double a)
{
    return isfinite(a) ? 1 : 0;
}

template <typename T>
HB_DHD void observe_strand(const ObsScene &sc, const Arr<const T> &x, const Arr<const T> &v, ObsPartial *o)
{
    const int64_t P = sc.points;
    const double ell = sc.ell, far2 = sc.far2, rc = sc.rc;
    double smax = 0.0, pmax = 0.0, v2 = 0.0;
    long long blown = 0;
    for (int64_t k = 0; k < P; k++)
        for (int c = 0; c < 3; c++) blown |= !finite_d((double)x(k, c)) || !finite_d((double)v(k, c));
    const double x0[3] = {(double)x(0, 0), (double)x(0, 1), (double)x(0, 2)};
    for (int64_t k = 1; k < P; k++) {
        const double xk[3] = {(double)x(k, 0), (double)x(k, 1), (double)x(k, 2)};
        const double xp[3] = {(double)x(k - 1, 0), (double)x(k - 1, 1), (double)x(k - 1, 2)};
        const double vk[3] = {(double)v(k, 0), (double)v(k, 1), (double)v(k, 2)};
        if (hb_obs_point(xk, xp, x0, vk, sc.seg64 ? sc.seg64[k - 1] : ell, sc.collider, rc, far2, &smax, &pmax, &v2))
            blown = 1;
        for (int i = 0; i < sc.ncol; i++) { /* §3.17 */
            const double dep = sc.w32 ? collider_depth(*sc.w32, i, sc.pose32 + i * HB_COL_POSE, xk)
                                      : collider_depth(*sc.w64, i, sc.pose64 + i * HB_COL_POSE, xk);
            if (dep > pmax) pmax = dep;
        }
    }
    o->stretch_max = smax;
    o->penetration_max = pmax;
    o->v2_sum = v2;
    o->blown = blown;
}

/* acc ← acc combined with o (hb_dyn_reduce_into). */
HB_DHD void reduce_into(ObsPartial *acc, const ObsPartial *o)
{
    if (o->stretch_max > acc->stretch_max) acc->stretch_max = o->stretch_max;
    if (o->penetration_max > acc->penetration_max) acc->penetration_max = o->penetration_max;
    acc->v2_sum += o->v2_sum;
    acc->blown += o->blown;
}

} /* namespace dyn */
} /* namespace hb */

#endif
