/* cuda/dynamic/contact_free.cuh — the colliders with friction of docs/model.md §3.17 in the normal
 * and fast-math builds' free arithmetic (docs/cuda.md "Builds and arithmetic"): the operations of
 * c_ref/dynamic/contact_impl.h with each square root and division replaced by a reciprocal
 * square root (rsq) or a product, and a length below floor_of<T>() taken as zero. Judged by the
 * one-frame rule; the strict build calls contact_impl.h itself. Included by lanes.cu after its
 * rsq, floor_of and fdiv, inside its namespace. */
#ifndef HB_DYN_CONTACT_FREE_CUH
#define HB_DYN_CONTACT_FREE_CUH

/* A sphere of radius rc about c (hb_push_sphere): moves p out, returns the depth removed (0: p
 * was outside) and the normal in n. */
template <typename T>
__device__ __forceinline__ T push_sphere_free(T (&p)[3], const T *c, T rc, const T *nperp, bool bounded, T depen,
                                              T (&n)[3])
{
    const T e[3] = {p[0] - c[0], p[1] - c[1], p[2] - c[2]};
    const T q = (e[0] * e[0] + e[1] * e[1]) + e[2] * e[2];
    if (!(q < rc * rc)) return (T)0;
    const bool zero = !(q > floor_of<T>());
    const T inv = zero ? (T)0 : rsq(q), rho = q * inv;
    for (int k = 0; k < 3; k++) n[k] = zero ? (nperp ? nperp[k] : (k == 1 ? (T)1 : (T)0)) : e[k] * inv;
    const T d = rc - rho;
    if (!bounded) {
        for (int k = 0; k < 3; k++) p[k] = zero ? c[k] + rc * n[k] : c[k] + e[k] * (rc * inv);
        return d;
    }
    const T m = d < depen ? d : depen;
    for (int k = 0; k < 3; k++) p[k] = p[k] + m * n[k];
    return m;
}

/* Coulomb friction after a projection of depth m along n (hb_friction). */
template <typename T>
__device__ __forceinline__ void friction_free(T (&p)[3], const T *x, const T (&n)[3], T m, T mu_s, T mu_k, bool turn,
                                              bool sway, const T *back)
{
    T r[3], t[3];
    for (int c = 0; c < 3; c++) {
        const T bp = turn   ? (back[3 * c] * p[0] + back[3 * c + 1] * p[1]) + back[3 * c + 2] * p[2]
                     : sway ? p[c] + back[9 + c]
                            : p[c];
        r[c] = bp - x[c];
    }
    const T rn = (r[0] * n[0] + r[1] * n[1]) + r[2] * n[2];
    for (int c = 0; c < 3; c++) t[c] = r[c] - rn * n[c];
    const T tt = (t[0] * t[0] + t[1] * t[1]) + t[2] * t[2], sm = mu_s * m;
    if (tt < sm * sm) {
        for (int c = 0; c < 3; c++) p[c] = p[c] - t[c];
    } else if (tt > floor_of<T>()) {
        T k = (mu_k * m) * rsq(tt);
        if (k > (T)1) k = (T)1;
        for (int c = 0; c < 3; c++) p[c] = p[c] - k * t[c];
    }
}

/* Collider i of the world w on p (hb_collide_one); x: p at the start of the substep. */
template <typename T, class Wd>
__device__ __forceinline__ void collide_one_free(const Wd &w, int i, const T *pose, const T *back, T (&p)[3],
                                                 const T *x)
{
    {
        const T bx = p[0] - pose[16], by = p[1] - pose[17], bz = p[2] - pose[18];
        if (!((bx * bx + by * by) + bz * bz < pose[19])) return;
    }
    const int kind = w.col_kind[i], frame = w.col_frame[i];
    const bool turn = frame == HB_FRAME_HEAD && w.motion, sway = frame == HB_FRAME_BODY && w.sway;
    T n[3], m = (T)0;
    if (kind == HB_COL_SPHERE) {
        m = push_sphere_free(p, pose, pose[3], (const T *)nullptr, w.bounded != 0, w.depen, n);
    } else if (kind == HB_COL_CAPSULE) {
        const T ab[3] = {pose[3] - pose[0], pose[4] - pose[1], pose[5] - pose[2]};
        const T ap[3] = {p[0] - pose[0], p[1] - pose[1], p[2] - pose[2]};
        T t = fdiv((ap[0] * ab[0] + ap[1] * ab[1]) + ap[2] * ab[2], pose[10]);
        t = t < (T)0 ? (T)0 : t > (T)1 ? (T)1 : t;
        const T c[3] = {pose[0] + t * ab[0], pose[1] + t * ab[1], pose[2] + t * ab[2]};
        m = push_sphere_free(p, c, pose[6], pose + 7, w.bounded != 0, w.depen, n);
    } else if (kind == HB_COL_PLANE) {
        const T rho = ((p[0] - pose[0]) * pose[3] + (p[1] - pose[1]) * pose[4]) + (p[2] - pose[2]) * pose[5];
        if (!(rho < pose[6])) return;
        const T d = pose[6] - rho;
        m = w.bounded && w.depen < d ? w.depen : d;
        for (int c = 0; c < 3; c++) {
            n[c] = pose[3 + c];
            p[c] = p[c] + m * n[c];
        }
    } else { /* mesh */
        T u[3], phi, g[3];
        for (int c = 0; c < 3; c++)
            u[c] = turn ? (pose[c] * p[0] + pose[3 + c] * p[1]) + pose[6 + c] * p[2] : sway ? p[c] - pose[9 + c] : p[c];
        if (!sdf_sample(w.sdf[i], w.sdf_n[i], w.sdf_geo + 4 * i, u, &phi, g)) return;
        const T gq = (g[0] * g[0] + g[1] * g[1]) + g[2] * g[2];
        if (!(phi < pose[12] && gq > floor_of<T>())) return;
        const T d = pose[12] - phi, inv = rsq(gq);
        const T nl[3] = {g[0] * inv, g[1] * inv, g[2] * inv};
        for (int r = 0; r < 3; r++)
            n[r] = turn ? (pose[3 * r] * nl[0] + pose[3 * r + 1] * nl[1]) + pose[3 * r + 2] * nl[2] : nl[r];
        m = w.bounded && w.depen < d ? w.depen : d;
        for (int c = 0; c < 3; c++) p[c] = p[c] + m * n[c];
    }
    const T mu_s = w.col_mu[2 * i];
    if (m > (T)0 && mu_s > (T)0) friction_free(p, x, n, m, mu_s, w.col_mu[2 * i + 1], turn, sway, back);
}

/* The head sphere of §3.5 with friction or a bounded depenetration (hb_collide_head). */
template <typename T, class Wd>
__device__ __forceinline__ void collide_head_free(const Wd &w, T rc, const T *back, T (&p)[3], const T *x)
{
    const T origin[3] = {(T)0, (T)0, (T)0};
    T n[3];
    const T m = push_sphere_free(p, origin, rc, (const T *)nullptr, w.bounded != 0, w.depen, n);
    if (m > (T)0 && w.head_friction && w.head_mu_s > (T)0)
        friction_free(p, x, n, m, w.head_mu_s, w.head_mu_k, w.motion != 0, false, back);
}

#endif
