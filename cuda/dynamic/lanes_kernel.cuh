/* cuda/dynamic/lanes_kernel.cuh — the lanes variant's kernel k_lanes and its steps (docs/cuda.md "The lanes
 * variant"): a half-warp of 16 lanes per strand (two strands a warp), lane l holding the G
 * consecutive points G·l … G·l + G − 1 in registers for the whole frame, G = 2, 4 or 8
 * (P ≤ 32, 64, 128). Every group of docs/model.md §3.6 keeps nearly every lane busy:
 *   stretch, k odd      (G·l+2m, G·l+2m+1): inside the lane;
 *   stretch, k even     inside the lane, and (G·l − 1, G·l) across, computed by the upper lane;
 *   bend                inside the lane where both ends are; across a boundary (l, l+1) the
 *                       two constraints (G·l+G−2, G·l+G) and (G·l+G−1, G·l+G+1) are split:
 *                       the lower lane computes the first, the upper lane the second.
 * A lane that computes a constraint across lanes receives the other end by a shuffle and
 * sends its new position back, so every point is written by one lane.
 *
 * Arithmetic (docs/cuda.md "Builds and arithmetic"): the strict build (HB_REFERENCE_ARITHMETIC)
 * calls cuda/dynamic/model.cuh's reference helpers, the same operations as c_ref/dynamic/dynamics_impl.h, so
 * it gives the CPU's bits; the normal and fast-math builds use reciprocal square roots and
 * the scene's precomputed reciprocals (DModel::inv_*), judged by the one-frame rule.
 */
#ifndef HB_DYN_LANES_KERNEL_CUH
#define HB_DYN_LANES_KERNEL_CUH

#include <utility>

#include "dynamic/chain.cuh"
#include "dynamic/held.cuh"
#include "dynamic/kernels.cuh"
#include "runtime/approx.h" /* hb_rsqrt_fast, HB_FAST_FLOOR */

namespace hb {
namespace dyn {
namespace {

#if defined(HB_REFERENCE_ARITHMETIC)
constexpr bool kFree = false;
#else
constexpr bool kFree = true;
#endif
/* the colliders of §3.17 in free arithmetic (contact_free.cuh) where the build is free;
 * HB_LANES_REF_COLLIDE=1 keeps contact_impl.h's operations there (a measured alternative) */
#ifndef HB_LANES_REF_COLLIDE
#define HB_LANES_REF_COLLIDE 0
#endif
constexpr bool kFreeCollide = kFree && !HB_LANES_REF_COLLIDE;
/* a collision step of one sweep (--collider-sweeps 1, the default) compiled apart, without the
 * comparisons that decide whether another sweep follows; HB_LANES_ONE_SWEEP=0: one loop for every
 * count (a measured alternative, docs/cuda.md) */
#ifndef HB_LANES_ONE_SWEEP
#define HB_LANES_ONE_SWEEP 1
#endif

/* Blocks of kLanesMaxBlock an SM must hold (__launch_bounds__'s second argument, which caps
 * the registers a thread): fp32 at P ≤ 32 HB_LANES_MINB for xpbd and HB_LANES_FTL_MINB for
 * ftl, with the world's code HB_LANES_WORLD_MINB (all of it), HB_LANES_COL_MINB (colliders alone),
 * HB_LANES_PLANES_MINB (colliders as contact planes alone), HB_LANES_HELD_MINB (the held grid alone) or
 * HB_LANES_GATHER_MINB (the grid's gather alone) (measured, docs/cuda.md), 1 (up to 255 registers)
 * otherwise. */
#ifndef HB_LANES_MINB
#define HB_LANES_MINB 4
#endif
#ifndef HB_LANES_FTL_MINB
#define HB_LANES_FTL_MINB 3
#endif
#ifndef HB_LANES_WORLD_MINB
#define HB_LANES_WORLD_MINB 2
#endif
#ifndef HB_LANES_COL_MINB
#define HB_LANES_COL_MINB 3
#endif
#ifndef HB_LANES_PLANES_MINB
#define HB_LANES_PLANES_MINB 3
#endif
#ifndef HB_LANES_HELD_MINB
#define HB_LANES_HELD_MINB HB_LANES_MINB
#endif
#ifndef HB_LANES_GATHER_MINB
#define HB_LANES_GATHER_MINB 3
#endif
/* The one-wave layout (lanes.cu's lanes_wave): xpbd at P ≤ 32 in fp32, the default scene's
 * feature set with no world or the held grid alone, kWaveG points a lane on kWaveL lanes a strand
 * in blocks of half the threads (the same strands a block), HB_LANES_WAVE_MINB blocks an SM
 * (96 registers), so that one wave holds more strands than G = 2's */
constexpr int kWaveG = 4, kWaveL = 8;
#ifndef HB_LANES_WAVE_MINB
#define HB_LANES_WAVE_MINB 5
#endif
#ifndef HB_LANES_FTL_G
#define HB_LANES_FTL_G 4
#endif
constexpr int kFtlG = HB_LANES_FTL_G, kFtlL = 32 / HB_LANES_FTL_G;
static_assert(kFtlG == 4 || kFtlG == 8, "ftl at P ≤ 32 runs 4 or 8 points a lane");
constexpr unsigned kAll = 0xffffffffu;

/* maybe_unused: each object is one precision, and the strict build calls neither */
[[maybe_unused]] __device__ __forceinline__ float rsq(float x)
{
    return hb_rsqrt_fast(x);
}
[[maybe_unused]] __device__ __forceinline__ double rsq(double x)
{
    return rsqrt(x);
}
/* the least input rsq takes as positive (free arithmetic: below it a length counts as zero) */
template <typename T> __device__ __forceinline__ constexpr T floor_of()
{
    return sizeof(T) == 4 ? (T)HB_FAST_FLOOR : (T)0;
}
/* the gust's sine: the phase table is reduced to [0, 2π) on the host (§3.3), so the argument
 * stays within a few radians, where __sinf is within 2^-21 of sin */
[[maybe_unused]] __device__ __forceinline__ float gust_sin(float x)
{
    return __sinf(x);
}
[[maybe_unused]] __device__ __forceinline__ double gust_sin(double x)
{
    return sin(x);
}
/* a / b in free arithmetic */
[[maybe_unused]] __device__ __forceinline__ float fdiv(float a, float b)
{
    return __fdividef(a, b);
}
[[maybe_unused]] __device__ __forceinline__ double fdiv(double a, double b)
{
    return a / b;
}
#include "dynamic/contact_free.cuh" /* templates only: inside this file's namespace, after rsq, floor_of, fdiv */
/* The world's code a kernel carries (its W, a set of these): the grid's gather every substep
 * (`frame`, `substep`), the held sample (`held`), the colliders of §3.17 and the head sphere's
 * friction or bounded depenetration; with kWCol, kWPlanes: the colliders as contact planes alone
 * (--contact-planes; the kernel with all the world's code runs them too). A run takes the smallest
 * kernel that holds what it declares. */
constexpr int kWGather = 1, kWHeld = 2, kWCol = 4, kWPlanes = 8, kWAll = kWGather | kWHeld | kWCol;
template <typename T, int G, int L, bool Ftl, int W = 0> constexpr int lanes_min_blocks()
{
    return sizeof(T) != 4                       ? 1
           : !Ftl && G == kWaveG && L == kWaveL ? HB_LANES_WAVE_MINB /* the one-wave layout */
           : W == kWHeld && !Ftl && G == 2      ? HB_LANES_HELD_MINB /* the held grid alone */
           : W == kWCol                         ? HB_LANES_COL_MINB
           : W == (kWCol | kWPlanes)            ? HB_LANES_PLANES_MINB
           : W == kWGather && !Ftl && G == 2    ? HB_LANES_GATHER_MINB /* the grid's gather alone */
           : W                                  ? HB_LANES_WORLD_MINB  /* everything: 2, up to 128 registers */
           : (!Ftl && G == 2)                   ? HB_LANES_MINB
           : (Ftl && G == kFtlG && L == kFtlL)  ? HB_LANES_FTL_MINB
                                                : 1;
}

/* __launch_bounds__'s threads a block: half kLanesMaxBlock for the one-wave layout */
template <typename T, int G, int L, bool Ftl> constexpr int lanes_max_threads()
{
    return sizeof(T) == 4 && !Ftl && G == kWaveG && L == kWaveL ? kLanesMaxBlock / 2 : kLanesMaxBlock;
}

template <typename T> struct V3 {
    T x, y, z;
};
/* c ? a : b by components (a selected array element would force the array into local memory) */
template <typename T> __device__ __forceinline__ V3<T> pick(bool c, const V3<T> &a, const V3<T> &b)
{
    return V3<T>{c ? a.x : b.x, c ? a.y : b.y, c ? a.z : b.z};
}
/* shuffles within a strand's L lanes */
template <int L, typename T> __device__ __forceinline__ V3<T> up(const V3<T> &a)
{
    return V3<T>{__shfl_up_sync(kAll, a.x, 1, L), __shfl_up_sync(kAll, a.y, 1, L), __shfl_up_sync(kAll, a.z, 1, L)};
}
template <int L, typename T> __device__ __forceinline__ V3<T> down(const V3<T> &a)
{
    return V3<T>{__shfl_down_sync(kAll, a.x, 1, L), __shfl_down_sync(kAll, a.y, 1, L),
                 __shfl_down_sync(kAll, a.z, 1, L)};
}
template <int L, typename T> __device__ __forceinline__ V3<T> from(const V3<T> &a, int src)
{
    return V3<T>{__shfl_sync(kAll, a.x, src, L), __shfl_sync(kAll, a.y, src, L), __shfl_sync(kAll, a.z, src, L)};
}

/* §3.5 distance constraint with rest r, written from one end: e = other − own; own moves by
 * −Δλ·n (unless it is the root, which is always the lower end), other by +Δλ·n. Called with
 * own = the lower end a, or (the G = 2 bend pairs) with own = b: e and n change sign exactly,
 * so every value is the same bit for bit, and both lanes of a pair run this one path on their
 * own operands, so the warp does not diverge. inv1, inv2: 1/(1 + α̃) and 1/(2 + α̃) (free
 * arithmetic only). */
template <typename T>
__device__ __forceinline__ void dist(V3<T> &own, V3<T> &other, bool own_root, T r, T at, T inv1, T inv2, T &lam)
{
    if constexpr (kFree) {
        const T ex = other.x - own.x, ey = other.y - own.y, ez = other.z - own.z;
        const T q = ex * ex + ey * ey + ez * ez;
        if (!(q > floor_of<T>())) return;
        const T inv = rsq(q);
        const T dl = ((r - q * inv) - at * lam) * (own_root ? inv1 : inv2);
        lam = lam + dl;
        const T s = dl * inv;
        if (!own_root) own = V3<T>{own.x - s * ex, own.y - s * ey, own.z - s * ez};
        other = V3<T>{other.x + s * ex, other.y + s * ey, other.z + s * ez};
    } else {
        T dl, nx, ny, nz;
        if (!distance_step(own.x, own.y, own.z, other.x, other.y, other.z, !own_root, r, at, lam, dl, nx, ny, nz))
            return;
        if (!own_root) own = V3<T>{own.x - dl * nx, own.y - dl * ny, own.z - dl * nz};
        other = V3<T>{other.x + dl * nx, other.y + dl * ny, other.z + dl * nz};
    }
}

template <typename T> __device__ __forceinline__ void collide(const DModel<T> &m, V3<T> &p)
{
    if constexpr (kFree) {
        const T q = p.x * p.x + p.y * p.y + p.z * p.z;
        if (!(q < m.rc2)) return;
        if (!(q > floor_of<T>())) {
            p = V3<T>{(T)0, m.collide_r, (T)0};
            return;
        }
        const T s = m.collide_r * rsq(q);
        p = V3<T>{p.x * s, p.y * s, p.z * s};
    } else {
        collide_sphere(p.x, p.y, p.z, m.collide_r);
    }
}

template <typename T> __device__ __forceinline__ void shape(const DModel<T> &m, V3<T> &p, const V3<T> &t, T &lam)
{
    if constexpr (kFree) {
        const T ex = p.x - t.x, ey = p.y - t.y, ez = p.z - t.z;
        const T q = ex * ex + ey * ey + ez * ez;
        if (!(q > floor_of<T>())) return;
        const T inv = rsq(q);
        const T dl = (-(q * inv) - m.shape_at * lam) * m.inv_g;
        lam = lam + dl;
        const T s = dl * inv;
        p = V3<T>{p.x + s * ex, p.y + s * ey, p.z + s * ez};
    } else {
        const T tt[3] = {t.x, t.y, t.z};
        shape_pull(p.x, p.y, p.z, tt, m.shape_at, lam);
    }
}

/* §3.4 step 2 for a point k ≥ 1: the velocity (implicit in drag and damping) and the prediction. */
template <typename T, class Feat>
__device__ __forceinline__ void predict(const DModel<T> &m, Feat has, T phase, const V3<T> &x, V3<T> &v, V3<T> &p)
{
    if constexpr (kFree) {
        const T h = m.h;
        T vx = v.x, vy = v.y, vz = v.z;
        if (has(HB_F_WIND)) {
            T gam = (T)1;
            if (has(HB_F_GUST)) gam = (T)1 + m.gust * gust_sin(phase - m.kappa * (m.dir_y * x.y + m.dir_z * x.z));
            vy = vy + h * (m.gravity_y + m.wind_y * gam);
            vz = vz + h * (m.wind_z * gam);
        } else {
            vy = vy + h * m.gravity_y;
        }
        if (has(HB_F_DRAG)) {
            vx = vx * m.inv_den;
            vy = vy * m.inv_den;
            vz = vz * m.inv_den;
        }
        v = V3<T>{vx, vy, vz};
        p = V3<T>{x.x + h * vx, x.y + h * vy, x.z + h * vz};
    } else {
        velocity_predict(m, has, phase, x.x, x.y, x.z, v.x, v.y, v.z, p.x, p.y, p.z);
    }
}

/* §3.16 the grid's sample at x (cuda/dynamic/held.cuh) */
template <typename T>
__device__ __forceinline__ Sample<T> grid_sample_at(const DModel<T> &m, const T *qg, const V3<T> &x)
{
    return grid_sample_xyz(m.world, qg, x.x, x.y, x.z);
}
/* §3.16 the correction of point k from its sample (hb_grid_apply). */
template <typename T>
__device__ __forceinline__ void grid_apply_at(const DModel<T> &m, int k, const Sample<T> &s, V3<T> &v)
{
    const World<T> &w = m.world;
    if constexpr (!kFree) {
        const T r[8] = {s.a.x, s.a.y, s.a.z, s.a.w, s.b.x, s.b.y, s.b.z, s.b.w};
        T vv[3] = {v.x, v.y, v.z};
        grid_apply(w, m.h, k, r, vv);
        v = V3<T>{vv[0], vv[1], vv[2]};
    } else {
        if (s.b.w == (T)0) return;
        if (w.grid_friction && s.a.w != (T)0) {
            const T f = w.ftab[k];
            v = V3<T>{v.x + f * (s.a.x - v.x), v.y + f * (s.a.y - v.y), v.z + f * (s.a.z - v.z)};
        }
        if (w.grid_volume) v = V3<T>{v.x + m.h * s.b.x, v.y + m.h * s.b.y, v.z + m.h * s.b.z};
    }
}
/* A held sample in shared memory (`held`), stored as vectors so that a warp's loads and stores
 * are conflict-free. The strict build holds contact_impl.h's sample (two vectors a slot, at
 * hs[(2i + 0|1)·32 + lane]) and applies it with the reference's operations; the free builds hold
 * the correction itself (one vector a slot, at hs[i·32 + lane]): friction then volume,
 * v + f·(v̄ − v) + h·ā, is v·(1 − f) + (f·v̄ + h·ā), kept as (f·v̄ + h·ā, 1 − f). */
template <typename T> __device__ __forceinline__ void store_node4(T *p, const Node4<T> &a)
{
    if constexpr (sizeof(T) == sizeof(float)) {
        *reinterpret_cast<float4 *>(p) = make_float4(a.x, a.y, a.z, a.w);
    } else {
        reinterpret_cast<double2 *>(p)[0] = make_double2(a.x, a.y);
        reinterpret_cast<double2 *>(p)[1] = make_double2(a.z, a.w);
    }
}
template <typename T> __device__ __forceinline__ Node4<T> shared_node4(const T *p)
{
    if constexpr (sizeof(T) == sizeof(float)) {
        const float4 a = *reinterpret_cast<const float4 *>(p);
        return Node4<T>{a.x, a.y, a.z, a.w};
    } else {
        const double2 a = reinterpret_cast<const double2 *>(p)[0], b = reinterpret_cast<const double2 *>(p)[1];
        return Node4<T>{a.x, a.y, b.x, b.y};
    }
}
/* vectors a held slot */
constexpr int kHeldVectors = kHeldReals / 4;
/* §3.16 `held`: point k's sample (the frame's first substep), as k_grid_hold left it at src, into
 * slot i of hs */
template <typename T> __device__ __forceinline__ void hold_sample(const T *src, T *hs, int i, int lane)
{
#pragma unroll
    for (int u = 0; u < kHeldVectors; u++)
        store_node4(hs + 4 * ((kHeldVectors * i + u) * 32 + lane), load_node4<T>(src + 4 * u));
}
/* §3.16 `held`: the correction of point k from slot i of hs */
template <typename T>
__device__ __forceinline__ void apply_held(const DModel<T> &m, int k, const T *hs, int i, int lane, V3<T> &v)
{
    if constexpr (!kFree) {
        grid_apply_at(
            m, k,
            Sample<T>{shared_node4(hs + 4 * (2 * i * 32 + lane)), shared_node4(hs + 4 * ((2 * i + 1) * 32 + lane))}, v);
    } else {
        const Node4<T> c = shared_node4(hs + 4 * (i * 32 + lane));
        v = V3<T>{c.w * v.x + c.x, c.w * v.y + c.y, c.w * v.z + c.z};
    }
}

/* §3.17 hb_collide_one's first test, the same operations: outside its bounding sphere a collider
 * leaves p as it is. */
template <typename T> __device__ __forceinline__ bool col_in_bound(const T *pose, const V3<T> &p)
{
    const T bx = p.x - pose[16], by = p.y - pose[17], bz = p.z - pose[18];
    return (bx * bx + by * by) + bz * bz < pose[19];
}

/* A mesh's second test, the one sdf_value_free and sdf_sample make first (the same operations): a
 * point outside the SDF's cube is left as it is. Clears in[s] for such points; true while one is left. */
template <int NP, typename T, class Wd>
__device__ __forceinline__ bool mesh_in_cube(const Wd &w, int i, const T *pose, const V3<T> *p, bool (&in)[NP])
{
    const int frame = w.col_frame[i], n1 = (int)w.sdf_n[i] - 1;
    const bool turn = frame == HB_FRAME_HEAD && w.motion, sway = frame == HB_FRAME_BODY && w.sway;
    const T *geo = w.sdf_geo + 4 * i;
    bool any = false;
#pragma unroll
    for (int s = 0; s < NP; s++) {
        if (!in[s]) continue;
        const T q[3] = {p[s].x, p[s].y, p[s].z};
        T u[3];
        mesh_local_free(pose, turn, sway, q, u);
        for (int c = 0; c < 3; c++) {
            const T gc = (u[c] - geo[c]) * geo[3];
            in[s] = in[s] && gc >= (T)0 && gc < (T)n1;
        }
        any = any || in[s];
    }
    return any;
}

/* Whether any bit of p differs from q's (contact_impl.h hb_moved); maybe_unused: each object is one
 * precision */
[[maybe_unused]] __device__ __forceinline__ bool bits_differ(float a, float b)
{
    return __float_as_uint(a) != __float_as_uint(b);
}
[[maybe_unused]] __device__ __forceinline__ bool bits_differ(double a, double b)
{
    return __double_as_longlong(a) != __double_as_longlong(b);
}
template <typename T> __device__ __forceinline__ bool moved_from(const V3<T> &q, const V3<T> &p)
{
    return bits_differ(p.x, q.x) || bits_differ(p.y, q.y) || bits_differ(p.z, q.z);
}

/* §3.17 --contact-planes in shared memory: a warp's planes, HB_CONTACT_POINT reals a point slot, each
 * real of a slot a row of 32 lanes (conflict-free): from a lane's base pl, slot i's plane c has its
 * real e at pl[((i·K + c)·HB_CONTACT + e)·32]. */
template <int G> __host__ __device__ constexpr int64_t lanes_plane_reals()
{
    return (int64_t)G * HB_CONTACT_POINT * 32;
}
__device__ __forceinline__ constexpr int plane_at(int i, int c, int e)
{
    return ((i * HB_CONTACT_K + c) * HB_CONTACT + e) * 32;
}
/* slot i's plane c's collider index (< 0: unused, and so are the slot's later planes) */
template <typename T> __device__ __forceinline__ T plane_index(const T *pl, int i, int c)
{
    return pl[plane_at(i, c, 4)];
}
template <typename T> __device__ __forceinline__ void plane_load(const T *pl, int i, int c, T (&con)[HB_CONTACT])
{
#pragma unroll
    for (int e = 0; e < HB_CONTACT; e++) con[e] = pl[plane_at(i, c, e)];
}
template <typename T> __device__ __forceinline__ void plane_store(T *pl, int i, int c, const T *con)
{
#pragma unroll
    for (int e = 0; e < HB_CONTACT; e++) pl[plane_at(i, c, e)] = con[e];
}

/* §3.6 step 7 and §3.7 with the colliders of §3.17 on a lane's NP points p (on: those that
 * collide; x: their positions at the substep's start): contact_impl.h hb_collide_sweeps's steps,
 * the sweep (on each point the head sphere, with its friction or a bounded depenetration, then
 * each collider with its friction) run again while it moves a point, w.sweeps sweeps at most.
 * The points are independent, so taking them collider by collider keeps each point's order. A
 * point outside a collider's bound skips it (hb_collide_one would return p as it is: the strict
 * build keeps the CPU's bits), and the lanes of `mask`, which call this together, skip it together
 * when none of theirs is inside. They sweep all their points again while any lane's point moved
 * (a warp vote): a point the CPU has stopped (its last sweep changed no bit of it) goes through a
 * sweep on the same bits, which changes none again, so each point ends with the CPU's bits. No
 * flag a point or a lane: the fewest registers (ptxas, docs/cuda.md "The hair–hair grid and the
 * colliders"). pl (--contact-planes): the points' planes (plane_load), met in place of the colliders;
 * Exact = false: a kernel that runs no collider's own test (kWPlanes). */
template <int NP, bool Exact = true, typename T, class Feat>
__device__ __forceinline__ void collide_points(const DModel<T> &m, Feat has, const T *pose, const T *back, V3<T> *p,
                                               const V3<T> *x, const bool *on, unsigned mask, const T *pl = nullptr)
{
    const World<T> &w = m.world;
    /* one sweep over the points; track: whether another may follow (moved: a bit of a point changed) */
    auto sweep_points = [&](bool track) {
        bool moved = false;
#pragma unroll
        for (int s = 0; s < NP; s++) {
            if (!on[s] || !has(HB_F_COLLIDE)) continue;
            const V3<T> was = p[s];
            if (w.head_friction || w.bounded) {
                T pp[3] = {p[s].x, p[s].y, p[s].z};
                const T xx[3] = {x[s].x, x[s].y, x[s].z};
                if constexpr (kFreeCollide) collide_head_free(w, m.collide_r, back, pp, xx);
                else collide_head(w, m.collide_r, back, pp, xx);
                p[s] = V3<T>{pp[0], pp[1], pp[2]};
            } else {
                collide(m, p[s]);
            }
            moved = moved || (track && moved_from(was, p[s]));
        }
        for (int c = 0; pl && c < HB_CONTACT_K; c++) { /* each point's planes, in their order */
            bool used[NP], any = false;                /* a slot past the last used one is unused (hb_contact_find) */
#pragma unroll
            for (int s = 0; s < NP; s++) {
                used[s] = on[s] && plane_index(pl, s, c) >= (T)0;
                any = any || used[s];
            }
            if (!__any_sync(mask, any)) break;
#pragma unroll
            for (int s = 0; s < NP; s++) {
                if (!used[s]) continue;
                T con[HB_CONTACT];
                plane_load(pl, s, c, con);
                T pp[3] = {p[s].x, p[s].y, p[s].z};
                const T xx[3] = {x[s].x, x[s].y, x[s].z};
                contact_one(w, con, back, pp, xx); /* every build: contact_impl.h's (docs/cuda.md) */
                const V3<T> np{pp[0], pp[1], pp[2]};
                moved = moved || (track && moved_from(p[s], np));
                p[s] = np;
            }
        }
        for (int i = 0; Exact && !pl && i < w.ncol; i++) {
            const T *pi = pose + i * HB_COL_POSE;
            bool in[NP], any = false;
#pragma unroll
            for (int s = 0; s < NP; s++) {
                in[s] = on[s] && col_in_bound(pi, p[s]);
                any = any || in[s];
            }
            if constexpr (kFreeCollide)
                if (any && w.col_kind[i] == HB_COL_MESH) any = mesh_in_cube<NP>(w, i, pi, p, in);
            if (!__any_sync(mask, any)) continue;
#pragma unroll
            for (int s = 0; s < NP; s++) {
                if (!in[s]) continue;
                T pp[3] = {p[s].x, p[s].y, p[s].z};
                const T xx[3] = {x[s].x, x[s].y, x[s].z};
                if constexpr (kFreeCollide) collide_one_free(w, i, pi, back, pp, xx);
                else collide_one(w, i, pi, back, pp, xx);
                const V3<T> np{pp[0], pp[1], pp[2]};
                moved = moved || (track && moved_from(p[s], np));
                p[s] = np;
            }
        }
        return moved;
    };
    if (HB_LANES_ONE_SWEEP && w.sweeps <= 1) { /* nothing to compare: the sweep without its tracking */
        sweep_points(false);
        return;
    }
    for (int sweep = 1;; sweep++) {
        const bool track = sweep < w.sweeps;
        const bool moved = sweep_points(track);
        if (!track || !__any_sync(mask, moved)) return;
    }
}

/* the lanes l = 0 of a warp's strands (L lanes a strand) */
template <int L> __device__ __forceinline__ constexpr unsigned first_lanes()
{
    unsigned r = 0;
    for (int s = 0; s < 32 / L; s++) r |= 1u << (s * L);
    return r;
}

/* The free builds' follow-the-leader target of p: ell from a along a→p (straight down when p is on a). */
template <typename T> __device__ __forceinline__ V3<T> follow_target(T ell, const V3<T> &a, const V3<T> &p)
{
    const T ex = p.x - a.x, ey = p.y - a.y, ez = p.z - a.z;
    const T q = ex * ex + ey * ey + ez * ez;
    if (q > floor_of<T>()) {
        const T f = ell * rsq(q);
        return V3<T>{a.x + f * ex, a.y + f * ey, a.z + f * ez};
    }
    return V3<T>{a.x, a.y - ell, a.z};
}

/* §3.7 one follow-the-leader step of p after its corrected predecessor a, ell its segment's
 * rest length; d: the correction; wc: the colliders of §3.17 (pose, back, x; mask: the lanes that
 * take this step together; pl: p's planes, --contact-planes) instead of the head sphere. */
template <bool Exact = true, typename T, class Feat>
__device__ __forceinline__ void follow_one(const DModel<T> &m, Feat has, T ell, const V3<T> &a, V3<T> &p, V3<T> &d,
                                           bool wc = false, const T *pose = nullptr, const T *back = nullptr,
                                           const V3<T> *x = nullptr, unsigned mask = kAll, const T *pl = nullptr)
{
    if (wc) {
        if constexpr (kFree) {
            const V3<T> n = follow_target(ell, a, p);
            d = V3<T>{n.x - p.x, n.y - p.y, n.z - p.z};
            p = n;
        } else {
            follow(a.x, a.y, a.z, p.x, p.y, p.z, ell, false, m.collide_r, d.x, d.y, d.z);
        }
        const bool on = true;
        collide_points<1, Exact>(m, has, pose, back, &p, x, &on, mask, pl);
        return;
    }
    if constexpr (kFree) {
        V3<T> n = follow_target(ell, a, p);
        d = V3<T>{n.x - p.x, n.y - p.y, n.z - p.z};
        if (has(HB_F_COLLIDE)) collide(m, n);
        p = n;
    } else {
        follow(a.x, a.y, a.z, p.x, p.y, p.z, ell, has(HB_F_COLLIDE), m.collide_r, d.x, d.y, d.z);
    }
}

/* §3.4 step 4 for a point k ≥ 1 (corr: ftl and k < P − 1, dn = d_{k+1}). */
template <typename T>
__device__ __forceinline__ void update(const DModel<T> &m, bool corr, const V3<T> &dn, V3<T> &x, V3<T> &v,
                                       const V3<T> &p)
{
    if constexpr (kFree) {
        if (corr) {
            const T s = m.ftl_s;
            v = V3<T>{((p.x - x.x) - s * dn.x) * m.inv_h, ((p.y - x.y) - s * dn.y) * m.inv_h,
                      ((p.z - x.z) - s * dn.z) * m.inv_h};
        } else {
            v = V3<T>{(p.x - x.x) * m.inv_h, (p.y - x.y) * m.inv_h, (p.z - x.z) * m.inv_h};
        }
    } else {
        v.x = update_velocity(p.x, x.x, m.h, corr, m.ftl_s, dn.x);
        v.y = update_velocity(p.y, x.y, m.h, corr, m.ftl_s, dn.y);
        v.z = update_velocity(p.z, x.z, m.h, corr, m.ftl_s, dn.z);
    }
    x = p;
}

template <typename T> __device__ __forceinline__ V3<T> rotated(const T *q, const V3<T> &a)
{ /* Q·a as cuda/dynamic/model.cuh's rotate: each row summed left to right */
    return V3<T>{q[0] * a.x + q[1] * a.y + q[2] * a.z, q[3] * a.x + q[4] * a.y + q[5] * a.z,
                 q[6] * a.x + q[7] * a.y + q[8] * a.z};
}

/* Shared memory of a warp: its strands' x and v ([N][P][3] rows), their rest shape and their
 * bend rest lengths ([N][P−2]), staged together so that every load is in flight at once. */
template <typename T, int G, int L> __host__ __device__ constexpr int64_t lanes_warp_reals(int64_t P)
{
    return 3 * (32 / L) * 3 * P + (32 / L) * (P - 2);
}
/* With the grid (W): a warp's held samples of §3.16 `held`, kHeldVectors vectors of 4 reals a
 * point slot, before every warp's staging area (so that they stay 16-byte aligned). */
template <typename T, int G> __host__ __device__ constexpr int64_t lanes_held_reals()
{
    return kHeldVectors * 4 * G * 32;
}
/* §3.17 a launch's colliders in shared memory after the warps' areas, staged once a block: the
 * poses of its nj substeps [nj][ncol][HB_COL_POSE], then their back-transforms [nj][HB_COL_BACK];
 * at most kColStageBytes a block (more substeps run in several launches: launch_frame_lanes). */
constexpr int64_t kColStageBytes = 16384;
__host__ __device__ constexpr int64_t lanes_col_reals(int ncol, int nj)
{
    return (int64_t)nj * ((int64_t)ncol * HB_COL_POSE + HB_COL_BACK);
}
/* whether a kernel with the colliders' code (W) stages them: the run has colliders or the head
 * sphere's friction or bounded depenetration */
template <typename T> __host__ __device__ constexpr bool lanes_col_on(int W, const DModel<T> &m)
{
    return (W & kWCol) && world_collides(m.world);
}

/* Slot i of a lane holds point k0 + i, or with two points a lane on an odd lane (sw) k0 + 1 − i:
 * then every lane of a bend pair finds its own point and the one its partner needs in the
 * same slots (the bend groups below). */
template <int G> __device__ __forceinline__ int point_of(int k0, bool sw, int i)
{
    return k0 + (G == 2 && sw ? 1 - i : i);
}

template <typename T, int G>
__device__ __forceinline__ void unpack(const T *s, int k0, bool sw, int P, bool live, V3<T> (&dst)[G])
{
#pragma unroll
    for (int i = 0; i < G; i++) {
        const int k = point_of<G>(k0, sw, i);
        if (live && k < P) dst[i] = V3<T>{s[3 * k], s[3 * k + 1], s[3 * k + 2]};
        else dst[i] = V3<T>{(T)0, (T)0, (T)0};
    }
}

template <typename T, int G>
__device__ __forceinline__ void pack(T *s, int k0, bool sw, int P, bool live, const V3<T> (&src)[G])
{
#pragma unroll
    for (int i = 0; i < G; i++) {
        const int k = point_of<G>(k0, sw, i);
        if (live && k < P) {
            s[3 * k] = src[i].x;
            s[3 * k + 1] = src[i].y;
            s[3 * k + 2] = src[i].z;
        }
    }
}

/* §3.16 `held` (m.hold_self): k_grid_hold's work done by the held kernel's block for its own strands
 * (those of its one pass of the strand loop: launch_frame_lanes' grid covers N) before the loop. A
 * warp takes 32 consecutive (strand, point) pairs, strands fastest, so that it samples one point index
 * across neighbouring strands in the order m.perm as k_grid_hold does, with the same functions; each
 * sample goes to the warp's area where hold_sample would have put it. */
template <typename T, int G, int L>
__device__ __forceinline__ void hold_block(const DModel<T> &m, const T *qtab, const T *x, int64_t N, int wpb,
                                           bool motion)
{
    constexpr int SPW = 32 / L;
    extern __shared__ __align__(16) unsigned char hb_lanes_smem[];
    const int P = (int)m.points;
    const int64_t b0 = (int64_t)blockIdx.x * wpb * SPW;
    const int nbs = N - b0 < (int64_t)wpb * SPW ? (int)(N - b0) : wpb * SPW;
    const T *qg = motion ? m.qs : nullptr; /* the rotation of the frame's first build */
    /* k ≥ 1: point 0 is the root, which takes no sample */
    for (int e = (int)threadIdx.x + nbs; e < nbs * P; e += (int)blockDim.x) {
        const int t = e % nbs, k = e / nbs;
        const T *p = x + (m.perm[b0 + t] * P + k) * 3;
        const Sample<T> s = grid_sample_xyz(m.world, qg, p[0], p[1], p[2]);
        const int ww = t / SPW, l = k / G, lane = (t % SPW) * L + l;
        const int i = G == 2 && (l & 1) ? 1 - (k & 1) : k % G; /* point_of's slot */
        T *hs = (T *)hb_lanes_smem + (int64_t)ww * lanes_held_reals<T, G>();
        if constexpr (kGridFree) { /* kHeldReals: the correction, as k_grid_hold keeps it */
            store_node4(hs + 4 * (i * 32 + lane), held_correction(m.world, m.h, k, s));
        } else {
            store_node4(hs + 4 * (2 * i * 32 + lane), s.a);
            store_node4(hs + 4 * ((2 * i + 1) * 32 + lane), s.b);
        }
    }
    __syncthreads(); /* before the warps read their areas */
}

/* The frame of (32/L) strands a warp, L lanes a strand, G points a lane (G·L ≥ P); Ftl: the
 * solver of §3.7, else §3.6; Seg: a groom's per-segment rest lengths (§3.15, m.seg_rest); W: the
 * grid and colliders of §3.16–3.17 (m.world), with the strands taken in the order m.perm (slot
 * s holds strand perm[s], nearby strands together, so a block's points share grid nodes and
 * colliders) where the kernel reads the grid or tests colliders; the held grid's kernel (W =
 * kWHeld) reads each point's own sample, which no order changes: in the order where it samples
 * them itself (m.hold_self), else as stored (m.perm nullptr). */
template <typename T, class Feat, int G, int L, bool Ftl, bool Seg, int W>
__global__ void __launch_bounds__(lanes_max_threads<T, G, L, Ftl>(), lanes_min_blocks<T, G, L, Ftl, W>())
    k_lanes(DModel<T> m, const T *__restrict__ qtab, const T *__restrict__ phtab, T *x, T *v,
            const T *__restrict__ rest, const T *__restrict__ bend_rest, int64_t N)
{
    wait_for_previous();        /* launched as a programmatic dependent (lanes.cu: launch_chained) */
    constexpr int SPW = 32 / L; /* strands a warp */
    constexpr bool Ordered = (W & (kWGather | kWCol | kWHeld)) != 0; /* strands in the order m.perm */
    extern __shared__ __align__(16) unsigned char hb_lanes_smem[];
    const Feat has = MakeFeat<Feat>::make(m.features);
    const int lane = (int)(threadIdx.x & 31u), w = (int)(threadIdx.x >> 5), wpb = (int)(blockDim.x >> 5);
    const int seg = lane / L, l = lane % L;
    static_assert(G > 2 || !Ftl, "the follow-the-leader pass takes a lane's slots in point order");
    const int P = (int)m.points, K = (int)m.shape_count, k0 = G * l;
    const bool sw = G == 2 && (l & 1); /* slots in reverse point order (point_of) */
    const int row = 3 * P;             /* reals of a strand */
    T *hs = (T *)hb_lanes_smem + (int64_t)w * ((W & kWHeld) ? lanes_held_reals<T, G>() : 0);
    T *xv = (T *)hb_lanes_smem + (int64_t)wpb * ((W & kWHeld) ? lanes_held_reals<T, G>() : 0) +
            (int64_t)w * lanes_warp_reals<T, G, L>(P);
    T *rs = xv + 2 * SPW * row; /* the rest shape of the warp's strands */
    const bool need_rest = has(HB_F_MOTION) || has(HB_F_SHAPE);
    const int stages = (P + G - 1) / G; /* lanes that hold points */
    const int jend = m.j1 < 0 ? (int)m.substeps : m.j1;
    const bool wcol = lanes_col_on<T>(W, m);
    /* §3.17 the launch's poses and back-transforms, staged once a block (lanes_col_reals) */
    const T *cs = (const T *)hb_lanes_smem +
                  (int64_t)wpb * (((W & kWHeld) ? lanes_held_reals<T, G>() : 0) + lanes_warp_reals<T, G, L>(P));
    if constexpr ((W & kWCol) != 0) {
        if (wcol) {
            T *st = (T *)cs;
            const int np = (jend - m.j0) * m.world.ncol * HB_COL_POSE, nb = (jend - m.j0) * HB_COL_BACK;
            const T *gp = m.pose + (int64_t)m.j0 * m.world.ncol * HB_COL_POSE, *gb = m.back + HB_COL_BACK * m.j0;
            for (int e = (int)threadIdx.x; e < np; e += (int)blockDim.x) st[e] = gp[e];
            for (int e = (int)threadIdx.x; e < nb; e += (int)blockDim.x) st[np + e] = gb[e];
        }
        __syncthreads(); /* before any warp's strand loop, whose trip count differs between warps */
    }
    /* §3.17 --contact-planes: each warp's planes after the staged colliders (lanes_plane_reals) */
    const bool planes = (W & kWPlanes) != 0 || (W == kWAll && m.world.planes);
    constexpr bool Exact = (W & kWPlanes) == 0; /* the colliders' own tests in the collision step */
    T *ps = (T *)cs + lanes_col_reals(m.world.ncol, jend - m.j0) + (int64_t)w * lanes_plane_reals<G>() + lane;
    if constexpr (W == kWHeld) { /* §3.16 `held`: the block's samples taken here (hold_block) */
        if (m.hold_self) hold_block<T, G, L>(m, qtab, x, N, wpb, has(HB_F_MOTION));
    }

    /* the loop bound is the same for every lane of a warp: whole warps take each group of strands */
    for (int64_t s0 = SPW * ((int64_t)blockIdx.x * wpb + w); s0 < N; s0 += SPW * (int64_t)gridDim.x * wpb) {
        const int ns = N - s0 >= SPW ? SPW : (int)(N - s0);
        const bool live = seg < ns;
        const int n = ns * row;
        /* where element e of the warp's strands lies (rows of r reals a strand): s0·r + e, or with
         * the world at strand perm[s0 + t], t = ⌊e / r⌋ found by comparisons (SPW ≤ 4); the order
         * is read again at each use, so that it holds no register through the substeps */
        auto at_row = [&](int e, int r) -> int64_t {
            if constexpr (Ordered) {
                if (m.perm) {
                    int t = 0;
#pragma unroll
                    for (int u = 1; u < SPW; u++)
                        if (e >= u * r) t = u;
                    return m.perm[s0 + t] * (int64_t)r + (e - t * r);
                }
            }
            return s0 * r + e;
        };
        auto at = [&](int e) { return at_row(e, row); };
        auto bat = [&](int e) { return at_row(e, P - 2); }; /* the bend rest lengths, P − 2 a strand */
        V3<T> X[G], V[G], Q[G], D[G];
        T *bs = rs + SPW * row; /* the bend rest lengths of the warp's strands */
        const bool need_bend = has(HB_F_BEND) && P > 2;
        const int nb = ns * (P - 2);
        { /* x, v, the rest shape and the bend rest lengths: every load in flight at once */
            T rx[3 * G], rv[3 * G], rr[3 * G], rb[G];
#pragma unroll
            for (int u = 0; u < 3 * G; u++) {
                const int e = lane + 32 * u < n ? lane + 32 * u : n - 1;
                const int64_t a = at(e);
                rx[u] = x[a];
                rv[u] = v[a];
                if (need_rest) rr[u] = rest[a];
            }
#pragma unroll
            for (int u = 0; u < G; u++) /* nb ≤ (32/L)·(G·L − 2) < 32·G */
                if (need_bend) rb[u] = bend_rest[bat(lane + 32 * u < nb ? lane + 32 * u : nb - 1)];
#pragma unroll
            for (int u = 0; u < 3 * G; u++)
                if (lane + 32 * u < n) {
                    xv[lane + 32 * u] = rx[u];
                    xv[SPW * row + lane + 32 * u] = rv[u];
                    if (need_rest) rs[lane + 32 * u] = rr[u];
                }
#pragma unroll
            for (int u = 0; u < G; u++)
                if (need_bend && lane + 32 * u < nb) bs[lane + 32 * u] = rb[u];
        }
        __syncwarp();
        unpack<T, G>(xv + seg * row, k0, sw, P, live, X);
        unpack<T, G>(xv + SPW * row + seg * row, k0, sw, P, live, V);
        T br[G], brp = (T)0;
        if (need_bend) { /* this lane's (k0+i, k0+i+2), i ≤ G−2, and (k0−1, k0+1) */
            const T *sb = bs + seg * (P - 2);
#pragma unroll
            for (int i = 0; i < G; i++) br[i] = live && k0 + i + 2 < P ? sb[k0 + i] : (T)0;
            brp = live && l >= 1 && k0 + 1 < P ? sb[k0 - 1] : (T)0;
        }
        const T *R = rs + seg * row; /* the rest shape X̄ of this lane's strand */
        /* §3.15 (Seg) a groom's ℓ_k of the segment (k − 1, k) ending at this lane's point
         * k = k0 + i; ell(i): it, or ℓ */
        T sl[Seg ? G : 1];
        if constexpr (Seg) {
#pragma unroll
            for (int i = 0; i < G; i++) {
                const int k = k0 + i;
                const int64_t st = Ordered && m.perm ? m.perm[s0 + seg] : s0 + seg;
                sl[i] = live && k >= 1 && k < P ? m.seg_rest[st * m.seg_is + (int64_t)(k - 1) * m.seg_s] : m.seg_len;
            }
        }
        auto ell = [&](int i) {
            if constexpr (Seg) return sl[i];
            else return m.seg_len;
        };
#pragma unroll
        for (int i = 0; i < G; i++) { /* a lane's points past the tip stay defined */
            D[i] = V3<T>{(T)0, (T)0, (T)0};
            Q[i] = X[i];
        }

        const bool wgrid = (W & (kWGather | kWHeld)) && m.world.grid && (m.world.grid_friction || m.world.grid_volume);
        /* lanes_holds_samples: k_grid_hold took them, or hold_block */
        const bool held = (W & kWHeld) && wgrid && (W == kWHeld || m.held);
        if constexpr ((W & kWHeld) != 0) { /* §3.16 `held`: each point's sample, taken by k_grid_hold */
            if (held && live && !(W == kWHeld && m.hold_self)) {
                const int64_t st = Ordered && m.perm ? m.perm[s0 + seg] : s0 + seg;
#pragma unroll
                for (int i = 0; i < G; i++) {
                    const int k = point_of<G>(k0, sw, i);
                    if (k >= 1 && k < P) hold_sample(m.held + (st * P + k) * kHeldReals, hs, i, lane);
                }
            }
        }
        for (int j = m.j0; j < jend; j++) {
            const T *q = qtab + 9 * j;
            /* §3.16 the rotation of the grid in use (nullptr: still); §3.17 this substep's poses */
            const T *qg = !has(HB_F_MOTION)                                    ? nullptr
                          : (m.world.grid_rebuild == HB_GRID_SUBSTEP && j > 0) ? qtab + 9 * (j - 1)
                                                                               : m.qs;
            const T *pose = cs + (j - m.j0) * m.world.ncol * HB_COL_POSE;
            const T *back = cs + (jend - m.j0) * m.world.ncol * HB_COL_POSE + (j - m.j0) * HB_COL_BACK;
            /* §3.17 --contact-planes: each point's planes found from x at the frame's first substep (its
             * poses), carried with their colliders at the others; a launch that starts later in the
             * frame takes them from m.contacts, where the launch before left them */
            if constexpr ((W & kWCol) != 0) {
                if (planes) {
                    const int64_t st = Ordered && m.perm ? m.perm[s0 + seg] : s0 + seg;
#pragma unroll
                    for (int i = 0; i < G; i++) {
                        const int k = point_of<G>(k0, sw, i);
                        const bool own = live && k >= 1 && k < P;
                        if (j > m.j0) { /* carried in place: a plane whose collider's frame stays, as it is */
                            for (int c = 0; own && c < HB_CONTACT_K; c++) {
                                const T at = plane_index(ps, i, c);
                                if (!(at >= (T)0)) break; /* the unused slots are the last */
                                const int fr = m.world.col_frame[(int)at];
                                if (!((fr == HB_FRAME_HEAD && m.world.motion) || (fr == HB_FRAME_BODY && m.world.sway)))
                                    continue;
                                T one[HB_CONTACT];
                                plane_load(ps, i, c, one);
                                contact_carry(m.world, back, one);
                                plane_store(ps, i, c, one);
                            }
                            continue;
                        }
                        T con[HB_CONTACT_POINT];
#pragma unroll
                        for (int e = 0; e < HB_CONTACT_POINT; e++) con[e] = (e % HB_CONTACT == 4) ? (T)-1 : (T)0;
                        if (own && j == 0) {
                            const T xx[3] = {X[i].x, X[i].y, X[i].z};
                            contact_find(m.world, pose, xx, con);
                        } else if (own) { /* a launch's first substep after the frame's first */
#pragma unroll
                            for (int c = 0; c < HB_CONTACT_K; c++) {
                                const T *g = m.contacts + (st * P + k) * HB_CONTACT_POINT + HB_CONTACT * c;
#pragma unroll
                                for (int e = 0; e < HB_CONTACT; e++) con[HB_CONTACT * c + e] = g[e];
                                contact_carry(m.world, back, con + HB_CONTACT * c);
                            }
                        }
#pragma unroll
                        for (int c = 0; c < HB_CONTACT_K; c++) plane_store(ps, i, c, con + HB_CONTACT * c);
                    }
                }
            }
            /* 1. the root on the head, then p0 = x0 */
            if (l == 0) {
                if (has(HB_F_MOTION)) {
                    const V3<T> r0{R[0], R[1], R[2]};
                    if constexpr (kFree) {
                        const V3<T> r = rotated(q, r0);
                        V[0] = V3<T>{(r.x - X[0].x) * m.inv_h, (r.y - X[0].y) * m.inv_h, (r.z - X[0].z) * m.inv_h};
                        X[0] = r;
                    } else {
                        root_step(q, r0.x, r0.y, r0.z, m.h, X[0].x, X[0].y, X[0].z, V[0].x, V[0].y, V[0].z);
                    }
                }
                Q[0] = X[0];
            }
            /* 2. velocities and the prediction */
            const T phase = has(HB_F_GUST) ? phtab[j] : (T)0;
#pragma unroll
            for (int i = 0; i < G; i++) {
                const int k = point_of<G>(k0, sw, i);
                if (k >= 1 && k < P) {
                    /* §3.16 friction, then volume; `held`: sampled at the frame's first substep */
                    if constexpr (W != 0) {
                        if (held) {
                            apply_held(m, k, hs, i, lane, V[i]);
                        } else if constexpr ((W & kWGather) != 0) {
                            if (wgrid) grid_apply_at(m, k, grid_sample_at(m, qg, X[i]), V[i]);
                        }
                    }
                    predict(m, has, phase, X[i], V[i], Q[i]);
                }
            }
            /* the shape targets T_k = Q(t+h)·X̄_k of this substep (the same in every iteration) */
            V3<T> S[G];
#pragma unroll
            for (int i = 0; i < G; i++) {
                const int k = point_of<G>(k0, sw, i);
                S[i] = V3<T>{(T)0, (T)0, (T)0};
                if (has(HB_F_SHAPE) && k >= 1 && k <= K) {
                    S[i] = V3<T>{R[3 * k], R[3 * k + 1], R[3 * k + 2]};
                    if (has(HB_F_MOTION)) S[i] = rotated(q, S[i]);
                }
            }

            /* 3. constraints; every multiplier starts the substep at 0 */
            T lso[G / 2], lse[G / 2], lbi[G], lg[G], lsx = 0, lc1 = 0, lc2 = 0;
#pragma unroll
            for (int i = 0; i < G / 2; i++) lso[i] = lse[i] = (T)0;
#pragma unroll
            for (int i = 0; i < G; i++) lbi[i] = lg[i] = (T)0;

            auto stretch = [&]() {
                if constexpr (G == 2) { /* (k0, k0+1) inside the lane; (k0 − 1, k0) across */
                    if (k0 + 1 < P) dist(Q[0], Q[1], l == 0, ell(1), m.stretch_at, m.inv_s1, m.inv_s2, lso[0]);
                    V3<T> a = up<L>(pick(sw, Q[0], Q[1])); /* the lower lane's last point */
                    V3<T> own = pick(sw, Q[1], Q[0]);      /* this lane's first */
                    if (l >= 1 && k0 < P) dist(a, own, false, ell(0), m.stretch_at, m.inv_s1, m.inv_s2, lsx);
                    Q[0] = pick(sw, Q[0], own);
                    Q[1] = pick(sw, own, Q[1]);
                    const V3<T> na = down<L>(a);
                    const bool back_on = l + 1 < L && k0 + G < P;
                    Q[0] = pick(back_on && sw, na, Q[0]);
                    Q[1] = pick(back_on && !sw, na, Q[1]);
                } else {
#pragma unroll
                    for (int i = 0; i + 1 < G; i += 2) /* k odd: inside the lane */
                        if (k0 + i + 1 < P)
                            dist(Q[i], Q[i + 1], k0 + i == 0, ell(i + 1), m.stretch_at, m.inv_s1, m.inv_s2, lso[i / 2]);
#pragma unroll
                    for (int i = 1; i + 1 < G; i += 2) /* k even: inside the lane … */
                        if (k0 + i + 1 < P)
                            dist(Q[i], Q[i + 1], false, ell(i + 1), m.stretch_at, m.inv_s1, m.inv_s2, lse[i / 2]);
                    V3<T> a = up<L>(Q[G - 1]); /* … and (k0 − 1, k0) on this lane, the lower end sent back */
                    if (l >= 1 && k0 < P) dist(a, Q[0], false, ell(0), m.stretch_at, m.inv_s1, m.inv_s2, lsx);
                    const V3<T> na = down<L>(a);
                    if (l + 1 < L && k0 + G < P) Q[G - 1] = na;
                }
            };
            /* bend group g (⌊(k−1)/2⌋ ≡ g mod 2): the constraints (a, a+2) with (a>>1)&1 = g */
            auto bend = [&](int g) {
#pragma unroll
                for (int i = 0; i + 2 < G; i++)
                    if ((((k0 + i) >> 1) & 1) == g && k0 + i + 2 < P)
                        dist(Q[i], Q[i + 2], k0 + i == 0, br[i], m.bend_at, m.inv_b1, m.inv_b2, lbi[i]);
                if constexpr (G == 2) {
                    /* lanes pair up: l is the lower lane of (2l, 2l+2), (2l+1, 2l+3) when l ≡ g
                     * (mod 2) and computes the first, its partner l+1 the second. With the
                     * slots of point_of, in group 0 every lane's own end is in slot 0 and the
                     * end its partner needs in slot 1; in group 1 the other way round. */
                    const bool lower = (l & 1) == g;
                    const int partner = lower ? (l + 1 < L ? l + 1 : l) : (l >= 1 ? l - 1 : l);
                    const bool act = lower ? l + 1 < L && k0 + 2 < P : l >= 1 && k0 + 1 < P;
                    const bool back_on = lower ? l + 1 < L && k0 + 3 < P : l >= 1 && k0 < P;
                    const T r = lower ? br[0] : brp;
                    V3<T> &own = g == 0 ? Q[0] : Q[1];
                    V3<T> &sent = g == 0 ? Q[1] : Q[0];
                    V3<T> o = from<L>(sent, partner);
                    if (act) dist(own, o, g == 0 && l == 0, r, m.bend_at, m.inv_b1, m.inv_b2, g == 0 ? lc1 : lc2);
                    const V3<T> back = from<L>(o, partner);
                    if (back_on) sent = back;
                } else {
                    /* every boundary (l, l+1) in group 1: (k0+G−2, k0+G) on the lower lane,
                     * (k0+G−1, k0+G+1) on the upper */
                    V3<T> hi0 = down<L>(Q[0]);
                    V3<T> lolast = up<L>(Q[G - 1]);
                    const bool c1 = l + 1 < L && (((k0 + G - 2) >> 1) & 1) == g && k0 + G < P;
                    const bool c2 = l >= 1 && (((k0 - 1) >> 1) & 1) == g && k0 + 1 < P;
                    if (c1) dist(Q[G - 2], hi0, false, br[G - 2], m.bend_at, m.inv_b1, m.inv_b2, lc1);
                    if (c2) dist(lolast, Q[1], false, brp, m.bend_at, m.inv_b1, m.inv_b2, lc2);
                    const V3<T> n0 = up<L>(hi0), nl = down<L>(lolast);
                    if (l >= 1 && (((k0 - 2) >> 1) & 1) == g && k0 < P) Q[0] = n0;
                    if (l + 1 < L && (((k0 + G - 1) >> 1) & 1) == g && k0 + G + 1 < P) Q[G - 1] = nl;
                }
            };
            auto shapes = [&]() {
#pragma unroll
                for (int i = 0; i < G; i++) {
                    const int k = point_of<G>(k0, sw, i);
                    if (k >= 1 && k <= K) shape(m, Q[i], S[i], lg[i]);
                }
            };
            if constexpr (!Ftl) {
                for (int it = 0; it < (int)m.iterations; it++) {
                    stretch();
                    if (has(HB_F_BEND)) {
                        bend(0);
                        bend(1);
                    }
                    if (has(HB_F_SHAPE)) shapes();
                    if (it < (int)m.collide_from) continue; /* --collide-once: the last iteration's alone */
                    if ((W & kWCol) && wcol) {              /* every lane of the warp */
                        bool on[G];
#pragma unroll
                        for (int i = 0; i < G; i++) on[i] = point_of<G>(k0, sw, i) >= 1 && point_of<G>(k0, sw, i) < P;
                        collide_points<G, Exact>(m, has, pose, back, Q, X, on, kAll, planes ? (const T *)ps : nullptr);
                    } else if (has(HB_F_COLLIDE)) {
#pragma unroll
                        for (int i = 0; i < G; i++)
                            if (point_of<G>(k0, sw, i) >= 1 && point_of<G>(k0, sw, i) < P) collide(m, Q[i]);
                    }
                }
            } else {
                for (int it = 0; it < (int)m.iterations; it++) {
                    if (has(HB_F_BEND)) {
                        bend(0);
                        bend(1);
                    }
                    if (has(HB_F_SHAPE)) shapes();
                }
                /* §3.7 follow the leader, k ascending: lane st takes its points after lane st − 1 */
                for (int st = 0; st < stages; st++) {
                    const unsigned smask = first_lanes<L>() << st; /* the lanes l = st */
                    const V3<T> a = up<L>(Q[G - 1]);
                    if (l == st) {
#pragma unroll
                        for (int i = 0; i < G; i++) {
                            const int k = k0 + i;
                            if (k >= 1 && k < P)
                                follow_one<Exact>(m, has, ell(i), i == 0 ? a : Q[i > 0 ? i - 1 : 0], Q[i], D[i],
                                                  (W & kWCol) && wcol, pose, back, &X[i], smask,
                                                  planes ? (const T *)ps + (int64_t)i * HB_CONTACT_POINT * 32
                                                         : nullptr);
                        }
                    }
                }
            }
            /* 4. velocities from the motion (ftl: less s·d(k+1)/h), then the positions */
            V3<T> dn{(T)0, (T)0, (T)0};
            if constexpr (Ftl) dn = down<L>(D[0]);
#pragma unroll
            for (int i = 0; i < G; i++) {
                const int k = point_of<G>(k0, sw, i);
                if (k >= 1 && k < P)
                    update(m, Ftl && k + 1 < P, i + 1 < G ? D[i + 1 < G ? i + 1 : i] : dn, X[i], V[i], Q[i]);
            }
        }
        if constexpr ((W & kWCol) != 0) { /* the planes kept for the frame's next launch */
            if (planes && jend < (int)m.substeps && live) {
                const int64_t st = Ordered && m.perm ? m.perm[s0 + seg] : s0 + seg;
#pragma unroll
                for (int i = 0; i < G; i++) {
                    const int k = point_of<G>(k0, sw, i);
                    if (k < 1 || k >= P) continue;
#pragma unroll
                    for (int c = 0; c < HB_CONTACT_K; c++) {
                        T one[HB_CONTACT];
                        plane_load(ps, i, c, one);
#pragma unroll
                        for (int e = 0; e < HB_CONTACT; e++)
                            m.contacts[(st * P + k) * HB_CONTACT_POINT + HB_CONTACT * c + e] = one[e];
                    }
                }
            }
        }
        __syncwarp();
        pack<T, G>(xv + seg * row, k0, sw, P, live, X);
        pack<T, G>(xv + SPW * row + seg * row, k0, sw, P, live, V);
        __syncwarp();
#pragma unroll
        for (int u = 0; u < 3 * G; u++)
            if (lane + 32 * u < n) {
                const int64_t a = at(lane + 32 * u);
                x[a] = xv[lane + 32 * u];
                v[a] = xv[SPW * row + lane + 32 * u];
            }
        __syncwarp();
    }
}

} /* namespace */

template <typename T>
using LanesFn = void (*)(DModel<T>, const T *, const T *, T *, T *, const T *, const T *, int64_t);

/* The kernels with the world's code (W ≠ 0) of layout (G, L, Ftl), each kind compiled in an object of
 * its own so that make -j compiles them side by side: the grid's (kWHeld, kWGather; wk) in
 * lanes_grid.cu, the colliders' (kWCol) in lanes_colliders.cu, the contact planes' (kWCol | kWPlanes)
 * in lanes_planes.cu and all of the world's (kWAll; seg: a groom's; lanes_world.cuh) in lanes_world_xpbd.cu and
 * lanes_world_ftl.cu, a solver's layouts each. f: the feature mask. */
template <typename T, int G, int L, bool Ftl> LanesFn<T> lanes_grid_kernel(unsigned f, int wk);
template <typename T, int G, int L, bool Ftl> LanesFn<T> lanes_colliders_kernel(unsigned f);
template <typename T, int G, int L, bool Ftl> LanesFn<T> lanes_planes_kernel(unsigned f);
template <typename T, int G, int L, bool Ftl> LanesFn<T> lanes_world_kernel(bool seg);
/* the one-wave layout's kernel with the held grid (lanes_grid.cu; nullptr in fp64) */
template <typename T> LanesFn<T> lanes_wave_held_kernel();

/* each layout of lanes_pick (lanes.cu), for the precision T: ftl's, xpbd's, all of them */
#define HB_LANES_LAYOUTS_FTL(X, T)                                                                                     \
    X(T, kFtlG, kFtlL, true)                                                                                           \
    X(T, 8, 8, true)                                                                                                   \
    X(T, 8, 16, true)
#define HB_LANES_LAYOUTS_XPBD(X, T)                                                                                    \
    X(T, 2, 16, false)                                                                                                 \
    X(T, 4, 16, false)                                                                                                 \
    X(T, 8, 16, false)
#define HB_LANES_LAYOUTS(X, T) HB_LANES_LAYOUTS_FTL(X, T) HB_LANES_LAYOUTS_XPBD(X, T)
/* X(T, G, L, Ftl) for each layout of LAYOUTS in the precision(s) of this object: the Makefile compiles each
 * kind's file once per precision (-DHB_DYN_REAL), side by side */
#ifdef HB_DYN_REAL
#define HB_LANES_INSTANCES(LAYOUTS, X) LAYOUTS(X, HB_DYN_REAL)
#else
#define HB_LANES_INSTANCES(LAYOUTS, X) LAYOUTS(X, float) LAYOUTS(X, double)
#endif

} /* namespace dyn */
} /* namespace hb */

#endif
