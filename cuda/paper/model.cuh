/* model.cuh — the paper model (docs/model.md §2) for the CUDA port: c_ref/paper/model_impl.h written as
 * `__host__ __device__` templates over the floating type T and the memory layout.
 *
 * Two arithmetics, chosen when the file is compiled (the builds of docs/cuda.md):
 *   - the reference arithmetic (HB_REFERENCE_ARITHMETIC=1, the strict build): every point is
 *     computed by the C reference's own per-point steps (c_ref/paper/points_impl.h, included
 *     below as float and double overloads), and the walks around them follow
 *     c_ref/paper/model_impl.h. Without FMA contraction and with IEEE division and square root
 *     it therefore differs from the C reference only where CUDA's sinf/cosf/asinf/atan2f
 *     (sin/cos/asin/atan2) differ from glibc's; compiled for the host
 *     (cuda/hostcheck/paper_hostcheck.cu) it must reproduce c_ref/paper/model.c bit for bit;
 *   - the free arithmetic (the default: normal and fast-math builds): the same model and
 *     the same decisions (hanging, the wind's wrap and exactly-opposite rule, collide's
 *     threshold and tie), computed more cheaply, judged by the paper model's tolerances
 *     (harness/tolerances.py) instead of bits. Per point it has no IEEE division, no asin
 *     and no library atan2/sincos in fp32: drape steps by an angle computed once per strand,
 *     wind uses c_ref/paper/fast_trig.h's polynomials and t = k·(w/(P−1)), collide uses
 *     reciprocal square roots (see each stage's `if constexpr (kFree)`).
 *
 * The only departures of the reference arithmetic from the C file are in *when memory is
 * read*, never in arithmetic:
 *   - with a prefetch depth D ≥ 1 (walk_points; the soa and fused variants) the walks load
 *     point k+D before they compute point k (the addresses differ from the ones written,
 *     so the values are the same); D = 0 (the paper variant) loads as the C code does;
 *   - init keeps the root in registers instead of reading it back for the drape;
 *   - point-major wind and collide never read or write x (it never changes);
 *   - the fused walk (wind_collide_strand) runs wind and collide in one pass over the
 *     points, keeping both running predecessors, see there.
 *
 * Layouts (element (i, k, c) = coordinate c of point k of strand i; c: 0 = x, 1 = y, 2 = z):
 *   StrandMajor<T>: the canonical array [N][P][3], element at (i·P + k)·3 + c;
 *   PointMajor<T>:  three arrays X, Y, Z of [P][N], element (i, k) at k·N + i, so the
 *                   consecutive strands of a warp load consecutive words.
 * All indices are 64-bit (N·P·3 passes 2^31).
 */
#ifndef HB_MODEL_CUH
#define HB_MODEL_CUH

#include <math.h>
#include <stdint.h>

#include "paper/fast_trig.h" /* hb_atan2_fast, hb_sincos_fast (the free arithmetic, fp32) */
#include "paper/model.h"     /* HB_SHELL_ULPS, hb_model_f32/f64 */
#include "runtime/philox.h"  /* hb_draw_block, hb_u01, HB_HD = __host__ __device__ __forceinline__ */
#include "tmath.cuh"         /* m_sqrt, m_asin, m_atan2: the float overloads for float */

/* The reference arithmetic's per-point steps, written once with the C reference: instantiated
 * here as float and double overloads of one name (SFX(name) = name) at global scope,
 * with the same math functions as model.c (SQRT = sqrtf/sqrt, …; SINCOS on the device). */
#include "paper/precision_f32.h"
#undef SFX
#define SFX(name) name
#include "paper/points_impl.h"
#include "paper/precision_end.h"
#include "paper/precision_f64.h"
#undef SFX
#define SFX(name) name
#include "paper/points_impl.h"
#include "paper/precision_end.h"

/* #pragma unroll for the device pass only (the host compiler does not know it) */
#if defined(__CUDA_ARCH__)
#define HB_UNROLL _Pragma("unroll")
#define HB_NO_UNROLL _Pragma("unroll 1")
#else
#define HB_UNROLL
#define HB_NO_UNROLL
#endif

namespace hb {

#if defined(HB_REFERENCE_ARITHMETIC) && HB_REFERENCE_ARITHMETIC
constexpr bool kFree = false;
#else
constexpr bool kFree = true;
#endif

/* The scene's numbers rounded once to the working precision (the fields of hb_model_f32/
 * hb_model_f64, as backend_cpu.c's round_scene makes them). Passed to kernels by value. */
template <typename T> struct Model {
    uint64_t seed;
    int64_t points;
    T head_radius, hair_offset, face_margin, seg_len, wind_strength, wind_angle;
};

template <typename M, typename T> inline Model<T> model_from(const M &m)
{
    Model<T> r;
    r.seed = m.seed;
    r.points = m.points;
    r.head_radius = m.head_radius;
    r.hair_offset = m.hair_offset;
    r.face_margin = m.face_margin;
    r.seg_len = m.seg_len;
    r.wind_strength = m.wind_strength;
    r.wind_angle = m.wind_angle;
    return r;
}

/* ---- the free arithmetic's functions: fp32 fast_trig.h, fp64 the library's ---------- */
#ifndef HB_PAPER_MUFU
#define HB_PAPER_MUFU 1
#endif
HB_HD float m_atan2_free(float y, float x)
{
    return hb_atan2_fast(y, x);
}
HB_HD double m_atan2_free(double y, double x)
{
    return atan2(y, x);
}
HB_HD void m_sincos_free(float x, float *s, float *c)
{
#if defined(__CUDA_ARCH__) && HB_PAPER_MUFU
    __sincosf(x, s, c);
#else
    hb_sincos_fast(x, s, c);
#endif
}
HB_HD void m_sincos_free(double x, double *s, double *c)
{
    hb_sin_cos(x, s, c); /* the reference's (points_impl.h) */
}
/* 1/√x: the device's approximate rsqrt (fast_trig.h; fp64: rsqrt, 1 ulp); 1/sqrt on the host */
HB_HD float m_rsqrt(float x)
{
    return hb_rsqrt_fast(x);
}
HB_HD double m_rsqrt(double x)
{
#if defined(__CUDA_ARCH__)
    return rsqrt(x);
#else
    return 1.0 / sqrt(x);
#endif
}
/* the least input m_rsqrt takes as positive: fp32 HB_FAST_FLOOR, fp64 any */
template <typename T> HB_HD constexpr T rsqrt_floor()
{
    return sizeof(T) == 4 ? (T)HB_FAST_FLOOR : (T)0;
}

/* PI_R, HALF_PI_R, TWO_PI_R of model_impl.h: the double literals rounded to T */
template <typename T> HB_HD T pi_r()
{
    return (T)3.14159265358979323846;
}
template <typename T> HB_HD T half_pi_r()
{
    return (T)1.57079632679489661923;
}
template <typename T> HB_HD T two_pi_r()
{
    return (T)6.28318530717958647692;
}

/* ---- layouts ------------------------------------------------------------------------- */
/* A layout hands out a view of one strand: x(k), y(k), z(k) are references to point k. */
template <typename T> struct StrandMajor {
    T *s;      /* [N][P][3] */
    int64_t P; /* points per strand */
    struct View {
        T *p; /* strand i's first element: s + i·P·3 */
        HB_HD T &x(int64_t k) const { return p[3 * k]; }
        HB_HD T &y(int64_t k) const { return p[3 * k + 1]; }
        HB_HD T &z(int64_t k) const { return p[3 * k + 2]; }
        /* the walks' cursors: &y(k), &z(k), and the distance from point k to point k+1 */
        HB_HD T *yp(int64_t k) const { return p + 3 * k + 1; }
        HB_HD T *zp(int64_t k) const { return p + 3 * k + 2; }
        HB_HD int64_t stride() const { return 3; }
    };
    HB_HD View strand(int64_t i) const { return View{s + i * P * 3}; }
    /* from a kernel's pointer arguments (a = the array; b, c unused) */
    HB_HD static StrandMajor make(T *a, T *, T *, int64_t, int64_t P) { return StrandMajor{a, P}; }
};

template <typename T> struct PointMajor {
    T *X, *Y, *Z; /* each [P][N] */
    int64_t N;    /* strands */
    struct View {
        T *px, *py, *pz; /* X + i, Y + i, Z + i */
        int64_t n;       /* the stride between points: N */
        HB_HD T &x(int64_t k) const { return px[k * n]; }
        HB_HD T &y(int64_t k) const { return py[k * n]; }
        HB_HD T &z(int64_t k) const { return pz[k * n]; }
        HB_HD T *yp(int64_t k) const { return py + k * n; }
        HB_HD T *zp(int64_t k) const { return pz + k * n; }
        HB_HD int64_t stride() const { return n; }
    };
    HB_HD View strand(int64_t i) const { return View{X + i, Y + i, Z + i, N}; }
    /* from a kernel's pointer arguments (a, b, c = X, Y, Z) */
    HB_HD static PointMajor make(T *a, T *b, T *c, int64_t N, int64_t) { return PointMajor{a, b, c, N}; }
};

/* ---- docs/model.md §2.3 drape (model_impl.h: hb_drape_strand) ------------------------------------ */
/* The root (x0, py, pz) is already stored; writes points 1 … P−1 by points_impl.h's step. */
template <typename T, class V> HB_HD void drape_reference(const Model<T> &m, const V &s, const T x0, T py, T pz)
{
    const int64_t P = m.points;
    const T ell = m.seg_len;
    T r0, rc, theta;
    int hanging = hb_drape_begin(py, pz, m.hair_offset, &r0, &rc, &theta);
    T rho = r0; /* slice radius of the predecessor: r0 for the first step, rc after */
    for (int64_t k = 1; k < P; k++) {
        hb_drape_step(ell, r0, rc, &theta, &rho, &hanging, &py, &pz);
        s.x(k) = x0;
        s.y(k) = py;
        s.z(k) = pz;
    }
}

/* The free arithmetic's drape: the reference's decisions on the reference's angles, fewer
 * operations. Only the first step starts off the shell (ρ = r0); every later one goes from
 * the shell to the shell (ρ = rc, g = 0), so its s² and its angle 2·asin(√s²) are the same
 * at every point: both angles are computed once, with the reference's expressions, and
 * θ advances by additions exactly as in the reference (so the step that starts the hanging
 * is the reference's). A point on the shell is rc·(cos θ, sin θ) through m_sincos_free. */
template <typename T, class V> HB_HD void drape_free(const Model<T> &m, const V &s, const T x0, T py, T pz)
{
    const int64_t P = m.points;
    const T ell = m.seg_len;
    const T r0 = m_sqrt(py * py + pz * pz);
    const T rc = r0 + m.hair_offset;
    T theta = m_atan2(py, pz);
    if (theta <= -half_pi_r<T>()) theta += two_pi_r<T>();
    int hanging = theta > pi_r<T>();
    /* the step angle from slice radius rho onto the shell; fits: the step exists (s² ≤ 1) */
    auto step_angle = [&](const T rho, int *fits) {
        *fits = 0;
        T s2 = 0;
        if (rho > (T)0) {
            const T g = rc - rho;
            s2 = ((ell - g) * (ell + g)) / ((T)4 * rho * rc);
            *fits = s2 <= (T)1;
        }
        if (s2 < (T)0) s2 = (T)0;
        return (T)2 * m_asin(m_sqrt(*fits ? s2 : (T)0));
    };
    int fits_first, fits_shell;
    const T alpha_first = step_angle(r0, &fits_first);
    const T alpha_shell = step_angle(rc, &fits_shell);

    /* One path for every thread (the reference's branches as selects, so a warp whose strands
     * are partly on the shell and partly hanging does not run both): the shell candidate is
     * computed at every point, the first hanging point's square root only where a strand
     * starts to hang. */
    HB_NO_UNROLL
    for (int64_t k = 1; k < P; k++) {
        const int fits = k == 1 ? fits_first : fits_shell;
        const T next = theta + (k == 1 ? alpha_first : alpha_shell);
        const int shell = !hanging && fits && next <= pi_r<T>();
        T sin_n = (T)0, cos_n = (T)0;
        if (sizeof(T) == 4 || shell) m_sincos_free(next, &sin_n, &cos_n); /* fp32: the MUFU's, cheap */
        T drop = ell;             /* a hanging point: ℓ below its predecessor */
        if (!hanging && !shell) { /* the first hanging point, on the vertical tangent z = −rc */
            const T dz = pz + rc;
            const T dy2 = ell * ell - dz * dz;
            drop = m_sqrt(dy2 > (T)0 ? dy2 : (T)0);
        }
        theta = shell ? next : theta;
        py = shell ? rc * sin_n : py - drop;
        pz = shell ? rc * cos_n : hanging ? pz : -rc;
        hanging = !shell;
        s.x(k) = x0;
        s.y(k) = py;
        s.z(k) = pz;
    }
}

template <typename T, class V> HB_HD void drape(const Model<T> &m, const V &s, const T x0, T py, T pz)
{
    if constexpr (kFree) drape_free(m, s, x0, py, pz);
    else drape_reference(m, s, x0, py, pz);
}

/* ---- docs/model.md §2.2, §2.3 init: roots (points_impl.h: hb_root_place) then the drape --- */
/* The root is IEEE arithmetic on integer draws, the reference's in every build. */
template <typename T, class Layout> HB_HD void init_strand(const Model<T> &m, const Layout &lay, int64_t i)
{
    const typename Layout::View s = lay.strand(i);
    T p[3];
    hb_root_place(m.seed, (uint64_t)i, m.head_radius, m.face_margin, p);
    s.x(0) = p[0];
    s.y(0) = p[1];
    s.z(0) = p[2];
    drape(m, s, p[0], p[1], p[2]);
}

/* Re-drapes strand i from its stored root (model.h: hb_drape_strand). */
template <typename T, class Layout> HB_HD void drape_strand(const Model<T> &m, const Layout &lay, int64_t i)
{
    const typename Layout::View s = lay.strand(i);
    drape(m, s, s.x(0), s.y(0), s.z(0));
}

/* ---- docs/model.md §2.4 wind: one step of the walk (model_impl.h: hb_wind_strand) ------- */
/* Keeps the predecessor before the wind (oy, oz) and after it (ny, nz). */
template <typename T> struct WindWalk {
    T ell, w, psi, last;
    T w_per_point, kf; /* free arithmetic: w/(P−1), and k as a T (exact while k < 2^24) */
    T oy, oz;          /* the predecessor before the wind */
    T ny, nz;          /* the predecessor after the wind (the root never moves) */

    WindWalk() = default;
    HB_HD WindWalk(const Model<T> &m, T y0, T z0)
    {
        ell = m.seg_len;
        w = m.wind_strength;
        psi = m.wind_angle; /* already reduced to (−π, π] */
        last = (T)(m.points - 1);
        w_per_point = w / last;
        kf = (T)0;
        oy = y0;
        oz = z0;
        ny = oy;
        nz = oz;
    }

    /* Point k was (cy, cz) before the wind; afterwards it is (ny, nz). The free arithmetic
     * keeps the reference's angles, wrap and exactly-opposite rule (m_atan2_free returns
     * the axes' angles exactly), with the polynomial atan2 and sincos, and t by a product. */
    HB_HD void step(int64_t k, const T cy, const T cz)
    {
        if constexpr (kFree) {
            const T dy = cy - oy, dz = cz - oz;
            const T phi = m_atan2_free(dy, dz);
            const T d0 = psi - phi;
            /* the wrap as two selects and one add (d0 + 0 is d0): no branch in the walk */
            const T up = d0 <= -pi_r<T>() ? two_pi_r<T>() : (T)0;
            const T wrap = d0 > pi_r<T>() ? -two_pi_r<T>() : up;
            T delta = d0 + wrap;
            delta = delta == pi_r<T>() && dz < (T)0 ? -pi_r<T>() : delta;
            kf += (T)1;
            const T turned = phi + (kf * w_per_point) * delta;
            T sin_t, cos_t;
            m_sincos_free(turned, &sin_t, &cos_t);
            nz = nz + ell * cos_t;
            ny = ny + ell * sin_t;
            oy = cy;
            oz = cz;
            return;
        }
        hb_wind_step(ell, w, psi, last, k, cy, cz, &oy, &oz, &ny, &nz); /* the reference's */
    }
};

/* ---- docs/model.md §2.5 collide: one step of the walk (model_impl.h: hb_collide_strand)  */
/* Count: the type of the points-changed count (int where the strand's points fit one) */
template <typename T, class Count = int64_t> struct CollideWalk {
    T ell, ell2, rc, inner2;
    T py, pz; /* the predecessor, after collision */
    int moved;
    Count changed;

    CollideWalk() = default;
    HB_HD CollideWalk(const Model<T> &m, T y0, T z0)
    {
        ell = m.seg_len;
        ell2 = ell * ell;
        hb_collide_begin(y0, z0, m.hair_offset, &rc, &inner2); /* the shell and its rounding allowance */
        moved = 0;
        changed = 0;
        py = y0;
        pz = z0;
    }

    /* Point k is (cy, cz) on entry and its collided position on return; returns whether
     * the point changed (the C code writes it back exactly then). */
    HB_HD int step(T &cy, T &cz)
    {
        if constexpr (kFree) return step_free(cy, cz);
        const int write = hb_collide_step(ell, rc, inner2, &moved, &py, &pz, &cy, &cz); /* the reference's */
        if (write) changed++;
        return write;
    }

    /* The free arithmetic: the same decisions, reciprocal square roots instead of square
     * roots and divisions; the pull is written as selects (no branch inside it). */
    HB_HD int step_free(T &cy, T &cz)
    {
        {
            /* the pull, evaluated by every thread and kept where the strand has moved */
            const T dy = cy - py, dz = cz - pz;
            const T len2 = dy * dy + dz * dz;
            const int dir = len2 > rsqrt_floor<T>();
            const T scale = ell * m_rsqrt(dir ? len2 : (T)1);
            const T fy = dir ? py + dy * scale : py - ell;
            const T fz = dir ? pz + dz * scale : pz;
            cy = moved ? fy : cy;
            cz = moved ? fz : cz;
        }
        if (cy * cy + cz * cz < inner2) {
            const T d2 = py * py + pz * pz;
            if (d2 > rsqrt_floor<T>()) {
                const T inv_d = m_rsqrt(d2);
                const T d = d2 * inv_d;
                const T t = ((d - rc) * (d + rc) + ell2) * ((T)0.5 * inv_d);
                const T a = d - t;
                const T h2 = ((rc - d) + t) * (rc + a);
                const T hh = h2 > rsqrt_floor<T>() ? h2 * m_rsqrt(h2) : (T)0;
                const T uy = py * inv_d, uz = pz * inv_d;
                const T fy = a * uy, fz = a * uz;
                int upper;
                if constexpr (sizeof(T) == 4) {
                    /* e1 − e2 = 4·hh·(uy·cz − uz·cy): the nearer candidate from one cross product
                     * (fp32; fp64, whose rule allows no decision to differ, compares e1, e2) */
                    const T cross = uy * cz - uz * cy;
                    upper = hh == (T)0 || cross < (T)0 || (cross == (T)0 && uz >= (T)0);
                } else {
                    const T y1 = fy + hh * uz, z1 = fz - hh * uy;
                    const T y2 = fy - hh * uz, z2 = fz + hh * uy;
                    const T e1 = (y1 - cy) * (y1 - cy) + (z1 - cz) * (z1 - cz);
                    const T e2 = (y2 - cy) * (y2 - cy) + (z2 - cz) * (z2 - cz);
                    upper = e1 < e2 || (e1 == e2 && y1 >= y2);
                }
                const T sh = upper ? hh : -hh;
                cy = fy + sh * uz;
                cz = fz - sh * uy;
                moved = 1;
            }
        }
        if (moved) changed++;
        py = cy;
        pz = cz;
        return moved;
    }
};

/* ---- the walk over a strand's points ------------------------------------------------------ */
/* Calls f(k, cy, cz, y, z) for k = 1 … P−1 in order: (cy, cz) = point k's y and z as loaded,
 * y and z = references to where they are stored (f writes the point back through them).
 * D = 0: each point is loaded when its turn comes, as the C code does (the paper variant).
 * D ≥ 1: the load of point k + D is issued before point k is computed, so every thread keeps
 * D points' loads in flight while it computes (the per-strand walk is sequential, so this is
 * where the memory-level parallelism of one thread comes from). The loads wait in a queue
 * of D registers that shifts by one each step (the loop is not unrolled: one copy of the
 * step's code, and the queue is indexed with constants only, so it stays in registers).
 * The offsets from point 0 advance by the layout's stride (in Idx: int where they all fit).
 * Loading early is safe: point k + D is not written before its turn. */
template <int D, typename T, class Idx = int64_t, class V, class F>
HB_HD void walk_points(const V &s, const int64_t P, F &&f)
{
    if constexpr (D == 0) {
        for (int64_t k = 1; k < P; k++) {
            const T cy = s.y(k), cz = s.z(k);
            f(k, cy, cz, s.y(k), s.z(k));
        }
    } else {
        /* Idx: the offsets' type (int where every offset fits, which saves the 64-bit adds) */
        const Idx step = (Idx)s.stride(), ahead = (Idx)D * step;
        T *const y0 = s.yp(0), *const z0 = s.zp(0);
        Idx at = step;            /* point k's offset from point 0 */
        T qy[D] = {}, qz[D] = {}; /* q[j] = point k + j, loaded */
        HB_UNROLL
        for (int j = 0; j < D; j++)
            if (1 + j < P) {
                qy[j] = y0[at + (Idx)j * step];
                qz[j] = z0[at + (Idx)j * step];
            }
        const Idx last = (Idx)P;
        HB_NO_UNROLL
        for (Idx k = 1; k < last; k++) {
            const T cy = qy[0], cz = qz[0];
            HB_UNROLL
            for (int j = 0; j + 1 < D; j++) {
                qy[j] = qy[j + 1];
                qz[j] = qz[j + 1];
            }
            if (k + D < last) {
                qy[D - 1] = y0[at + ahead];
                qz[D - 1] = z0[at + ahead];
            }
            f((int64_t)k, cy, cz, y0[at], z0[at]);
            at += step;
        }
    }
}

/* ---- the per-strand stages ------------------------------------------------------------ */
/* Wind on strand i, in place. The caller does not call it when w = 0 (the identity).
 * D: the prefetch depth of walk_points. */
template <int D, typename T, class Layout> HB_HD void wind_strand(const Model<T> &m, const Layout &lay, int64_t i)
{
    const int64_t P = m.points;
    if (P < 2) return;
    const typename Layout::View s = lay.strand(i);
    WindWalk<T> wind(m, s.y(0), s.z(0));
    walk_points<D, T>(s, P, [&](int64_t k, T cy, T cz, T &y, T &z) {
        wind.step(k, cy, cz);
        y = wind.ny;
        z = wind.nz;
    });
}

/* Collide on strand i, in place; returns the number of points changed. */
template <int D, typename T, class Layout> HB_HD int64_t collide_strand(const Model<T> &m, const Layout &lay, int64_t i)
{
    const int64_t P = m.points;
    if (P < 2) return 0;
    const typename Layout::View s = lay.strand(i);
    CollideWalk<T> col(m, s.y(0), s.z(0));
    walk_points<D, T>(s, P, [&](int64_t, T cy, T cz, T &y, T &z) {
        if (col.step(cy, cz)) {
            y = cy;
            z = cz;
        }
    });
    return col.changed;
}

/* Wind immediately followed by collide on strand i, in one walk over the points: wind
 * rebuilds point k from the wind-rotated predecessor, and collide at once checks (and
 * pulls) it against the collided predecessor. Both running predecessors are kept (the
 * wind walk needs the one before the wind and the one after the wind, the collide walk
 * the collided one), so the result is bit for bit wind_strand then collide_strand. Each
 * point is read once and written once; with Keep the post-wind state (the frame between
 * the two stages) is also stored, canonically, into `inter` (x included, so then x is read
 * too); without Keep x is neither read nor written. Returns the points collide changed. */
template <bool Keep, int D, typename T, class Layout, class Idx = int64_t>
HB_HD int64_t wind_collide_strand(const Model<T> &m, const Layout &lay, int64_t i, const StrandMajor<T> &inter)
{
    const int64_t P = m.points;
    if (P < 2) return 0;
    const typename Layout::View s = lay.strand(i);
    const T y0 = s.y(0), z0 = s.z(0);
    typename StrandMajor<T>::View q = {nullptr};
    if (Keep) {
        q = inter.strand(i);
        q.x(0) = s.x(0); /* the root: wind does not move it */
        q.y(0) = y0;
        q.z(0) = z0;
    }
    WindWalk<T> wind(m, y0, z0);
    CollideWalk<T, Idx> col(m, y0, z0);
    walk_points<D, T, Idx>(s, P, [&](int64_t k, T cy, T cz, T &y, T &z) {
        wind.step(k, cy, cz);
        T wy = wind.ny, wz = wind.nz;
        if (Keep) {
            q.x(k) = s.x(k);
            q.y(k) = wy;
            q.z(k) = wz;
        }
        col.step(wy, wz); /* unchanged when collide leaves the point alone */
        y = wy;
        z = wz;
    });
    return col.changed;
}

} /* namespace hb */

#endif
