/* cuda/dynamic/held.cuh — a point's sample of the hair–hair grid (docs/model.md §3.16) on the device,
 * for the lanes kernel's gather (`frame`, `substep`) and the `held` kernel of world.cu: the strict
 * build runs the reference (contact_impl.h) itself; the free builds the same sums from registers,
 * the eight corners' nodes read as vectors through the read-only cache. */
#ifndef HB_DYN_HELD_CUH
#define HB_DYN_HELD_CUH

#include "dynamic/world.cuh"

namespace hb {
namespace dyn {

#if defined(HB_REFERENCE_ARITHMETIC)
constexpr bool kGridFree = false;
#else
constexpr bool kGridFree = true;
#endif

template <typename T> struct Node4 {
    T x, y, z, w;
};
template <typename T> __device__ __forceinline__ Node4<T> load_node4(const T *p)
{
    if constexpr (sizeof(T) == sizeof(float)) {
        const float4 a = __ldg(reinterpret_cast<const float4 *>(p));
        return Node4<T>{a.x, a.y, a.z, a.w};
    } else {
        const double2 a = __ldg(reinterpret_cast<const double2 *>(p)),
                      b = __ldg(reinterpret_cast<const double2 *>(p) + 1);
        return Node4<T>{a.x, a.y, b.x, b.y};
    }
}
/* §3.16 a point's grid sample as contact_impl.h's hb_grid_sample lays it out: a = (v̄, 1 where
 * friction applies, else 0), b = (ā, 1 when x is in the grid, else 0). */
template <typename T> struct Sample {
    Node4<T> a, b;
};
__device__ __forceinline__ float grid_recip(float x)
{
    return __fdividef(1.0f, x);
}
__device__ __forceinline__ double grid_recip(double x)
{
    return 1.0 / x;
}
/* the sample at (x, y, z) with the grid rotation qg (nullptr: still) */
template <typename T>
__device__ __forceinline__ Sample<T> grid_sample_xyz(const World<T> &w, const T *qg, T x, T y, T z)
{
    Sample<T> s{{(T)0, (T)0, (T)0, (T)0}, {(T)0, (T)0, (T)0, (T)0}};
    if constexpr (!kGridFree) {
        const T xx[3] = {x, y, z};
        T r[8] = {};
        grid_sample(w, qg, xx, r);
        s.a = Node4<T>{r[0], r[1], r[2], r[3]};
        s.b = Node4<T>{r[4], r[5], r[6], r[7]};
    } else {
        T ux = x, uy = y, uz = z;
        if (qg) {
            ux = (qg[0] * x + qg[3] * y) + qg[6] * z;
            uy = (qg[1] * x + qg[4] * y) + qg[7] * z;
            uz = (qg[2] * x + qg[5] * y) + qg[8] * z;
        }
        const T gx = (ux - w.glo[0]) * w.gsc[0], gy = (uy - w.glo[1]) * w.gsc[1], gz = (uz - w.glo[2]) * w.gsc[2];
        const T top = (T)(w.gn - 1);
        if (!(gx >= (T)0 && gx < top && gy >= (T)0 && gy < top && gz >= (T)0 && gz < top)) return s;
        const int ix = (int)gx, iy = (int)gy, iz = (int)gz;
        const T fx = gx - (T)ix, fy = gy - (T)iy, fz = gz - (T)iz;
        const int64_t n = w.gn, b = ix + n * (iy + n * (int64_t)iz);
        T sw = 0, svx = 0, svy = 0, svz = 0, ax = 0, ay = 0, az = 0;
#pragma unroll
        for (int c = 0; c < 8; c++) {
            const T wx = (c & 1) ? fx : (T)1 - fx, wy = (c & 2) ? fy : (T)1 - fy, wz = (c & 4) ? fz : (T)1 - fz;
            const T wt = (wx * wy) * wz;
            const int64_t j = b + ((c & 1) ? 1 : 0) + ((c & 2) ? n : 0) + ((c & 4) ? n * n : 0);
            if (w.grid_friction) {
                const auto nv = load_node4<T>(w.node_v + 4 * j);
                const T wo = wt * nv.w; /* o ∈ {0, 1}; V is 0 where o is */
                sw += wo;
                svx += wt * nv.x;
                svy += wt * nv.y;
                svz += wt * nv.z;
            }
            if (w.grid_volume) {
                const auto na = load_node4<T>(w.node_a + 4 * j);
                ax += wt * na.x;
                ay += wt * na.y;
                az += wt * na.z;
            }
        }
        if (w.grid_friction && sw > (T)0) {
            const T inv = grid_recip(sw);
            s.a = Node4<T>{svx * inv, svy * inv, svz * inv, (T)1};
        }
        s.b = Node4<T>{ax, ay, az, (T)1};
    }
    return s;
}

/* §3.16 `held`: what a point keeps for the frame, kHeldReals reals. The strict build keeps the
 * sample itself (a, then b) and applies it with the reference's operations; the free builds keep
 * the correction: friction then volume, v + f·(v̄ − v) + h·ā, is v·(1 − f) + (f·v̄ + h·ā), kept as
 * (f·v̄ + h·ā, 1 − f). */
constexpr int kHeldReals = kGridFree ? 4 : 8;
template <typename T>
__device__ __forceinline__ Node4<T> held_correction(const World<T> &w, T h, int k, const Sample<T> &s)
{
    Node4<T> c{(T)0, (T)0, (T)0, (T)1};
    if (s.b.w == (T)0) return c;
    if (w.grid_friction && s.a.w != (T)0) {
        const T f = w.ftab[k];
        c = Node4<T>{f * s.a.x, f * s.a.y, f * s.a.z, (T)1 - f};
    }
    if (w.grid_volume) c = Node4<T>{c.x + h * s.b.x, c.y + h * s.b.y, c.z + h * s.b.z, c.w};
    return c;
}

} /* namespace dyn */
} /* namespace hb */

#endif
