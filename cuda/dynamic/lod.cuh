/* cuda/dynamic/lod.cuh — simulated-point LOD (docs/model.md §3.14, --render-points): the rendered points
 * of a strand, a centripetal Catmull–Rom spline through its simulated points, as
 * `__host__ __device__` code that follows c_ref/dynamic/dyn_lod_impl.h operation by operation;
 * cuda/dynamic/lod.cu launches it one thread per rendered point. */
#ifndef HB_DYN_LOD_CUH
#define HB_DYN_LOD_CUH

#include <cuda_runtime.h>
#include <stdint.h>

#include "dynamic/kernels.cuh"
#include "dynamic/model.cuh"

namespace hb {
namespace dyn {

/* Simulated point j = −1 … ps of strand i (in layout l), coordinate c; the phantom ends are
 * the reflections x_{−1} = x_0 + (x_0 − x_1), x_ps = x_{ps−1} + (x_{ps−1} − x_{ps−2}) (lod_at). */
template <typename T> HB_DHD T lod_at(const T *b, Layout l, int64_t i, int64_t ps, int64_t j, int c)
{
    const T *s = b + i * l.is + (int64_t)c * l.cs;
    if (j < 0) return s[0] + (s[0] - s[l.ks]);
    if (j >= ps) return s[(ps - 1) * l.ks] + (s[(ps - 1) * l.ks] - s[(ps - 2) * l.ks]);
    return s[j * l.ks];
}

/* sqrt(|x_b − x_a|), the centripetal knot interval (lod_knot). */
template <typename T> HB_DHD T lod_knot(const T *x, Layout l, int64_t i, int64_t ps, int64_t a, int64_t b)
{
    T e[3];
    for (int c = 0; c < 3; c++) e[c] = lod_at(x, l, i, ps, b, c) - lod_at(x, l, i, ps, a, c);
    return m_sqrt(m_sqrt(e[0] * e[0] + e[1] * e[1] + e[2] * e[2]));
}

/* Rendered point j (0 ≤ j < pr) of strand i: the values y (positions x, or velocities with
 * x's knots) of segment k = j / m at i = j mod m (lod_point; rows k·m copy y_k). */
template <typename T>
HB_DHD void lod_render_point(const T *x, const T *y, Layout l, int64_t i, int64_t ps, int64_t pr, int64_t j, T *out)
{
    const int64_t m = (pr - 1) / (ps - 1), k = j / m, r = j - k * m;
    if (r == 0) { /* a simulated point (the tip included: k = ps − 1) */
        for (int c = 0; c < 3; c++) out[c] = lod_at(y, l, i, ps, k, c);
        return;
    }
    const T s = (T)r / (T)m;
    const T da = lod_knot(x, l, i, ps, k - 1, k), db = lod_knot(x, l, i, ps, k, k + 1),
            dc = lod_knot(x, l, i, ps, k + 1, k + 2);
    for (int c = 0; c < 3; c++) {
        const T p0 = lod_at(y, l, i, ps, k - 1, c), p1 = lod_at(y, l, i, ps, k, c), p2 = lod_at(y, l, i, ps, k + 1, c),
                p3 = lod_at(y, l, i, ps, k + 2, c);
        if (da > (T)0 && db > (T)0 && dc > (T)0) {
            const T t = s * db;
            const T ua = (t + da) / da, ub = t / db, uc = (t - db) / dc, ud = (t + da) / (da + db), ue = t / (db + dc);
            const T a1 = p0 + ua * (p1 - p0), a2 = p1 + ub * (p2 - p1), a3 = p2 + uc * (p3 - p2);
            const T b1 = a1 + ud * (a2 - a1), b2 = a2 + ue * (a3 - a2);
            out[c] = b1 + ub * (b2 - b1);
        } else {
            out[c] = p1 + s * (p2 - p1);
        }
    }
}

/* Every strand's pr rendered points of x (layout lay) into canonical xr [N·pr][3], and of the
 * velocities v into vr when v is not null; one thread per rendered point. */
template <typename T>
cudaError_t launch_lod_render(const T *x, const T *v, Layout lay, int64_t n, int64_t ps, int64_t pr, T *xr, T *vr,
                              cudaStream_t stream);

} /* namespace dyn */
} /* namespace hb */
#endif
