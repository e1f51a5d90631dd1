/* cuda/dynamic/post.cuh — what the dynamic model does after a frame's substeps (cuda/dynamic/post.cu):
 * the followers of docs/model.md §3.14, placed from their guides by a kernel of their own.
 * The per-follower math is `__host__ __device__` (place_follower), so
 * cuda/hostcheck/post_hostcheck.cu runs it on the host against c_ref/dynamic/dyn_followers_impl.h. */
#ifndef HB_DYN_POST_CUH
#define HB_DYN_POST_CUH

#include <cuda_runtime.h>
#include <stdint.h>

#include "dynamic/kernels.cuh"
#include "dynamic/model.cuh"

namespace hb {
namespace dyn {

/* Element (strand i, point k, coordinate c) of an array in a layout. */
template <typename T> struct At {
    T *b;
    Layout l;
    HB_DHD T &operator()(int64_t i, int64_t k, int c) const { return b[i * l.is + k * l.ks + (int64_t)c * l.cs]; }
};

/* y = x_g,k + M(a → b)·o: follower f's point k carried by guide g (fl_carry). */
template <typename T>
HB_DHD void carry(const At<T> &x, const At<const T> &rest, int64_t g, int64_t f, int64_t k, const T *q, T *y)
{
    T e[3], t[3], d[3], a[3], o[3];
    for (int c = 0; c < 3; c++) e[c] = rest(g, k, c) - rest(g, k - 1, c);
    const T len = m_sqrt(e[0] * e[0] + e[1] * e[1] + e[2] * e[2]);
    for (int c = 0; c < 3; c++) d[c] = rest(f, k, c) - rest(g, k, c);
    for (int c = 0; c < 3; c++) t[c] = len > (T)0 ? e[c] / len : (T)0;
    if (q) {
        rotate(q, t[0], t[1], t[2], a);
        rotate(q, d[0], d[1], d[2], o);
    } else {
        for (int c = 0; c < 3; c++) {
            a[c] = t[c];
            o[c] = d[c];
        }
    }
    for (int c = 0; c < 3; c++) e[c] = x(g, k, c) - x(g, k - 1, c);
    const T rho = m_sqrt(e[0] * e[0] + e[1] * e[1] + e[2] * e[2]);
    T r[3] = {o[0], o[1], o[2]};
    if (len > (T)0 && rho > (T)0) {
        T b[3];
        for (int c = 0; c < 3; c++) b[c] = e[c] / rho;
        const T cs = a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
        const T den = (T)1 + cs;
        if (den > (T)0) {
            const T u[3] = {a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]};
            const T uo = u[0] * o[0] + u[1] * o[1] + u[2] * o[2];
            const T sc = uo / den;
            const T uxo[3] = {u[1] * o[2] - u[2] * o[1], u[2] * o[0] - u[0] * o[2], u[0] * o[1] - u[1] * o[0]};
            for (int c = 0; c < 3; c++) r[c] = cs * o[c] + uxo[c] + sc * u[c];
        }
    }
    for (int c = 0; c < 3; c++) y[c] = x(g, k, c) + r[c];
}

/* The head collision of follower point q at distance ell from its predecessor a (fl_collide):
 * inside the collider, the nearest point of the circle where the sphere of radius ell about a meets
 * it, else (no such circle) §3.5's radial projection. */
template <typename T> HB_DHD void follower_collide(const T *a, T ell, T rc, T *q)
{
    const T len = m_sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2]);
    if (!(len < rc)) return;
    const T d = m_sqrt(a[0] * a[0] + a[1] * a[1] + a[2] * a[2]);
    if (d > (T)0) {
        const T tau = ((d - rc) * (d + rc) + ell * ell) / (d + d);
        const T cp = d - tau;
        const T h2 = ((rc - d) + tau) * (rc + cp);
        if (h2 > (T)0) {
            const T n[3] = {a[0] / d, a[1] / d, a[2] / d};
            const T m[3] = {cp * n[0], cp * n[1], cp * n[2]};
            const T v[3] = {q[0] - m[0], q[1] - m[1], q[2] - m[2]};
            const T s = v[0] * n[0] + v[1] * n[1] + v[2] * n[2];
            const T u[3] = {v[0] - s * n[0], v[1] - s * n[1], v[2] - s * n[2]};
            const T lam = m_sqrt(u[0] * u[0] + u[1] * u[1] + u[2] * u[2]);
            if (lam > (T)0) {
                const T r = m_sqrt(h2);
                for (int c = 0; c < 3; c++) q[c] = m[c] + r * (u[c] / lam);
                return;
            }
        }
    }
    collide_sphere(q[0], q[1], q[2], rc);
}

/* Follower f placed from its W guides g[] with weights w[] (hb_follower_place): each point the
 * blend of its guides' carried offsets, then pulled onto the segment of rest length ℓ_k from the
 * follower's placed predecessor (ℓ_k from m.seg_rest in its layout, else m.seg_len). */
template <typename T>
HB_DHD void place_follower(const DModel<T> &m, const T *q, const At<T> &x, const At<T> &v, const At<const T> &rest,
                           int64_t f, const int64_t *g, const T *w, int W)
{
    const int64_t P = m.points;
    T root[3];
    if (q) rotate(q, rest(f, 0, 0), rest(f, 0, 1), rest(f, 0, 2), root);
    else
        for (int c = 0; c < 3; c++) root[c] = rest(f, 0, c);
    for (int c = 0; c < 3; c++) x(f, 0, c) = root[c];
    for (int64_t k = 0; k < P; k++)
        for (int c = 0; c < 3; c++) {
            T acc = w[0] * v(g[0], k, c);
            for (int i = 1; i < W; i++) acc = acc + w[i] * v(g[i], k, c);
            v(f, k, c) = acc;
        }
    for (int64_t k = 1; k < P; k++) {
        T acc[3] = {0, 0, 0};
        for (int i = 0; i < W; i++) {
            T y[3];
            carry(x, rest, g[i], f, k, q, y);
            for (int c = 0; c < 3; c++) acc[c] = i == 0 ? w[0] * y[c] : acc[c] + w[i] * y[c];
        }
        /* the segment toward the blended point, at the follower's own rest length ℓ_k */
        const T ell = m.seg_rest ? m.seg_rest[f * m.seg_is + (k - 1) * m.seg_s] : m.seg_len;
        const T px = x(f, k - 1, 0), py = x(f, k - 1, 1), pz = x(f, k - 1, 2);
        const T ex = acc[0] - px, ey = acc[1] - py, ez = acc[2] - pz;
        const T rho = m_sqrt(ex * ex + ey * ey + ez * ez);
        T p[3];
        if (rho > (T)0) {
            p[0] = px + ell * (ex / rho);
            p[1] = py + ell * (ey / rho);
            p[2] = pz + ell * (ez / rho);
        } else {
            p[0] = px;
            p[1] = py - ell;
            p[2] = pz;
        }
        if (m.features & HB_F_COLLIDE) {
            const T prev[3] = {px, py, pz};
            follower_collide(prev, ell, m.collide_r, p);
        }
        for (int c = 0; c < 3; c++) x(f, k, c) = p[c];
    }
}

/* One thread per follower j: strand follower[j] placed from the strands src[width·j + i]
 * with weights w[width·j + i] (c_ref/dynamic/dyn_followers.c's plan, on the device); q the head
 * rotation at the frame's end ([9] on the device; nullptr: still head); x, v, rest in the
 * variant's layout `lay`. The same operations in the same order as
 * c_ref/dynamic/dyn_followers_impl.h. */
template <typename T>
cudaError_t launch_place_followers(const DModel<T> &m, const T *q, T *x, T *v, const T *rest, Layout lay,
                                   const int64_t *follower, const int64_t *src, const T *w, int width,
                                   int64_t n_followers, cudaStream_t stream);

} /* namespace dyn */
} /* namespace hb */
#endif
