/* cuda/dynamic/contact_free.cuh — the colliders with friction of docs/model.md §3.17 in the normal
 * and fast-math builds' free arithmetic (docs/cuda.md "Builds and arithmetic"): the operations of
 * c_ref/dynamic/contact_impl.h with each square root and division replaced by a reciprocal
 * square root (rsq) or a product, and a length below floor_of<T>() taken as zero. Judged by the
 * one-frame rule; the strict build calls contact_impl.h itself. Included by lanes_kernel.cuh after its
 * rsq, floor_of and fdiv, inside its namespace. */
#ifndef HB_DYN_CONTACT_FREE_CUH
#define HB_DYN_CONTACT_FREE_CUH

/* The depth of p in the sphere (c, rc), rc − ρ > 0 with the outward normal in n, or 0 outside
 * (hb_sphere_depth); rinv: 1/ρ (0 at ρ = 0). */
template <typename T>
__device__ __forceinline__ T sphere_depth_free(const T *p, const T *c, T rc, const T *nperp, T (&n)[3], T &rinv)
{
    const T e[3] = {p[0] - c[0], p[1] - c[1], p[2] - c[2]};
    const T q = (e[0] * e[0] + e[1] * e[1]) + e[2] * e[2];
    if (!(q < rc * rc)) return (T)0;
    const bool zero = !(q > floor_of<T>());
    rinv = zero ? (T)0 : rsq(q);
    for (int k = 0; k < 3; k++) n[k] = zero ? (nperp ? nperp[k] : (k == 1 ? (T)1 : (T)0)) : e[k] * rinv;
    return rc - q * rinv;
}

/* p moved out of the sphere (c, rc) along n by m, or (exact) onto its surface (hb_sphere_move). */
template <typename T>
__device__ __forceinline__ void sphere_move_free(T (&p)[3], const T *c, T rc, const T (&n)[3], T rinv, T m, bool exact)
{
    for (int k = 0; k < 3; k++)
        p[k] = !exact ? p[k] + m * n[k] : rinv == (T)0 ? c[k] + rc * n[k] : c[k] + (p[k] - c[k]) * (rc * rinv);
}

/* The bounded depenetration (hb_bounded_move): d − min(d, max(d0 − V·h, 0)). */
template <typename T> __device__ __forceinline__ T bounded_move_free(T d, T d0, T depen)
{
    T keep = d0 - depen;
    keep = keep > (T)0 ? keep : (T)0;
    return d - (keep < d ? keep : d);
}

/* y = β⁻¹(x) (hb_carry). */
template <typename T>
__device__ __forceinline__ void carry_free(const T *back, bool turn, bool sway, const T *x, T (&y)[3])
{
    for (int c = 0; c < 3; c++)
        y[c] = turn ? (back[c] * x[0] + back[3 + c] * x[1]) + back[6 + c] * x[2] : sway ? x[c] - back[9 + c] : x[c];
}

/* The point of capsule a–b (pose) nearest to p (hb_capsule_centre). */
template <typename T> __device__ __forceinline__ void capsule_centre_free(const T *pose, const T *p, T (&c)[3])
{
    const T ab[3] = {pose[3] - pose[0], pose[4] - pose[1], pose[5] - pose[2]};
    const T ap[3] = {p[0] - pose[0], p[1] - pose[1], p[2] - pose[2]};
    T t = fdiv((ap[0] * ab[0] + ap[1] * ab[1]) + ap[2] * ab[2], pose[10]);
    t = t < (T)0 ? (T)0 : t > (T)1 ? (T)1 : t;
    for (int k = 0; k < 3; k++) c[k] = pose[k] + t * ab[k];
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

/* The mesh-frame point of p (hb_mesh_local). */
template <typename T>
__device__ __forceinline__ void mesh_local_free(const T *pose, bool turn, bool sway, const T *p, T (&u)[3])
{
    for (int c = 0; c < 3; c++)
        u[c] = turn ? (pose[c] * p[0] + pose[3 + c] * p[1]) + pose[6 + c] * p[2] : sway ? p[c] - pose[9 + c] : p[c];
}

/* A mesh's SDF value alone at the mesh-frame point u (hb_sdf_sample's φ, as lerps in 32-bit
 * indices: n_s ≤ 512); false outside the cube. */
template <typename T>
__device__ __forceinline__ bool sdf_value_free(const T *sdf, int64_t n64, const T *geo, const T (&u)[3], T &phi)
{
    const int n = (int)n64;
    T f[3];
    int i[3];
    for (int c = 0; c < 3; c++) {
        const T gc = (u[c] - geo[c]) * geo[3];
        if (!(gc >= (T)0 && gc < (T)(n - 1))) return false;
        i[c] = (int)gc;
        f[c] = gc - (T)i[c];
    }
    const T *b = sdf + (i[0] + n * (i[1] + n * i[2]));
    const int nn = n * n;
    const T x00 = b[0] + f[0] * (b[1] - b[0]), x10 = b[n] + f[0] * (b[n + 1] - b[n]);
    const T x01 = b[nn] + f[0] * (b[nn + 1] - b[nn]), x11 = b[nn + n] + f[0] * (b[nn + n + 1] - b[nn + n]);
    const T y0 = x00 + f[1] * (x10 - x00), y1 = x01 + f[1] * (x11 - x01);
    phi = y0 + f[2] * (y1 - y0);
    return true;
}

/* The depth at t + h of the carried start y in collider i (hb_start_depth). */
template <typename T, class Wd>
__device__ __forceinline__ T start_depth_free(const Wd &w, int i, int kind, bool turn, bool sway, const T *pose,
                                              const T (&y)[3])
{
    T n[3], rinv;
    if (kind == HB_COL_SPHERE) return sphere_depth_free(y, pose, pose[3], (const T *)nullptr, n, rinv);
    if (kind == HB_COL_CAPSULE) {
        T c[3];
        capsule_centre_free(pose, y, c);
        return sphere_depth_free(y, c, pose[6], pose + 7, n, rinv);
    }
    if (kind == HB_COL_PLANE)
        return pose[6] - (((y[0] - pose[0]) * pose[3] + (y[1] - pose[1]) * pose[4]) + (y[2] - pose[2]) * pose[5]);
    T u[3], phi;
    mesh_local_free(pose, turn, sway, y, u);
    if (!sdf_value_free(w.sdf[i], w.sdf_n[i], w.sdf_geo + 4 * i, u, phi)) return (T)0;
    return pose[12] - phi;
}

/* Collider i of the world w on p (hb_collide_one) inside its bounding sphere (the caller tests
 * it: lanes_kernel.cuh col_in_bound); x: p at the start of the substep. */
template <typename T, class Wd>
__device__ __forceinline__ void collide_one_free(const Wd &w, int i, const T *pose, const T *back, T (&p)[3],
                                                 const T *x)
{
    const int kind = w.col_kind[i], frame = w.col_frame[i];
    const bool turn = frame == HB_FRAME_HEAD && w.motion, sway = frame == HB_FRAME_BODY && w.sway;
    const bool ball = kind == HB_COL_SPHERE || kind == HB_COL_CAPSULE;
    T n[3], c[3], d, rinv = (T)0;
    if (ball) {
        if (kind == HB_COL_SPHERE) {
            for (int k = 0; k < 3; k++) c[k] = pose[k];
            d = sphere_depth_free(p, c, pose[3], (const T *)nullptr, n, rinv);
        } else {
            capsule_centre_free(pose, p, c);
            d = sphere_depth_free(p, c, pose[6], pose + 7, n, rinv);
        }
        if (!(d > (T)0)) return;
    } else if (kind == HB_COL_PLANE) {
        const T rho = ((p[0] - pose[0]) * pose[3] + (p[1] - pose[1]) * pose[4]) + (p[2] - pose[2]) * pose[5];
        if (!(rho < pose[6])) return;
        d = pose[6] - rho;
        for (int k = 0; k < 3; k++) n[k] = pose[3 + k];
    } else { /* mesh */
        T u[3], phi, g[3];
        mesh_local_free(pose, turn, sway, p, u);
        if (!sdf_sample(w.sdf[i], w.sdf_n[i], w.sdf_geo + 4 * i, u, &phi, g)) return;
        const T gq = (g[0] * g[0] + g[1] * g[1]) + g[2] * g[2];
        if (!(phi < pose[12] && gq > floor_of<T>())) return;
        d = pose[12] - phi;
        const T inv = rsq(gq);
        const T nl[3] = {g[0] * inv, g[1] * inv, g[2] * inv};
        for (int r = 0; r < 3; r++)
            n[r] = turn ? (pose[3 * r] * nl[0] + pose[3 * r + 1] * nl[1]) + pose[3 * r + 2] * nl[2] : nl[r];
    }
    T m = d;
    if (!w.bounded) { /* unbounded: onto the surface now (c and rinv die here) */
        if (ball) sphere_move_free(p, c, kind == HB_COL_SPHERE ? pose[3] : pose[6], n, rinv, m, true);
        else
            for (int k = 0; k < 3; k++) p[k] = p[k] + m * n[k];
    } else {
        T y[3];
        carry_free(back, turn, sway, x, y);
        m = bounded_move_free(d, start_depth_free(w, i, kind, turn, sway, pose, y), w.depen);
        for (int k = 0; k < 3; k++) p[k] = p[k] + m * n[k];
    }
    const T mu_s = w.col_mu[2 * i];
    if (m > (T)0 && mu_s > (T)0) friction_free(p, x, n, m, mu_s, w.col_mu[2 * i + 1], turn, sway, back);
}

/* The head sphere of §3.5 with friction or a bounded depenetration (hb_collide_head). */
template <typename T, class Wd>
__device__ __forceinline__ void collide_head_free(const Wd &w, T rc, const T *back, T (&p)[3], const T *x)
{
    const T origin[3] = {(T)0, (T)0, (T)0};
    T n[3], n0[3], rinv = (T)0, r0;
    const T d = sphere_depth_free(p, origin, rc, (const T *)nullptr, n, rinv);
    if (!(d > (T)0)) return;
    const T m =
        w.bounded ? bounded_move_free(d, sphere_depth_free(x, origin, rc, (const T *)nullptr, n0, r0), w.depen) : d;
    sphere_move_free(p, origin, rc, n, rinv, m, !w.bounded);
    if (m > (T)0 && w.head_friction && w.head_mu_s > (T)0)
        friction_free(p, x, n, m, w.head_mu_s, w.head_mu_k, w.motion != 0, false, back);
}

#endif
