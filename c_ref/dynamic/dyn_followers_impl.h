/* dyn_followers_impl.h — the placement of one follower (docs/model.md §3.14), written once for
 * a floating type REAL; dyn_followers.c includes it for float and for double (SFX, DMODEL,
 * SQRT, WEIGHTS). Every expression is evaluated in the order written; §3.14 states it. */

/* r = Q·a, row-major Q, each row summed left to right (as the root step). */
static inline void SFX(fl_rotate)(const REAL *q, const REAL *a, REAL *r)
{
    r[0] = q[0] * a[0] + q[1] * a[1] + q[2] * a[2];
    r[1] = q[3] * a[0] + q[4] * a[1] + q[5] * a[2];
    r[2] = q[6] * a[0] + q[7] * a[1] + q[8] * a[2];
}

/* Point k ≥ 1 of the follower with rest fk as carried by the guide g (x xg, rest rg):
 * y = xg_k + M(a → b)·o, o = Q·(fk − rg_k), a = Q·t̄, b the guide's current tangent. */
static inline void SFX(fl_carry)(const REAL *xg, const REAL *rg, const REAL *fk, int64_t k, const REAL *q, REAL *y)
{
    const REAL *r1 = rg + 3 * k, *r0 = rg + 3 * (k - 1), *x1 = xg + 3 * k, *x0 = xg + 3 * (k - 1);
    REAL e[3], a[3], o[3], b[3];
    for (int c = 0; c < 3; c++) e[c] = r1[c] - r0[c];
    const REAL len = SQRT(e[0] * e[0] + e[1] * e[1] + e[2] * e[2]);
    REAL t[3], d[3];
    for (int c = 0; c < 3; c++) d[c] = fk[c] - r1[c];
    if (len > (REAL)0)
        for (int c = 0; c < 3; c++) t[c] = e[c] / len;
    else
        for (int c = 0; c < 3; c++) t[c] = (REAL)0;
    if (q) {
        SFX(fl_rotate)(q, t, a);
        SFX(fl_rotate)(q, d, o);
    } else {
        for (int c = 0; c < 3; c++) {
            a[c] = t[c];
            o[c] = d[c];
        }
    }
    for (int c = 0; c < 3; c++) e[c] = x1[c] - x0[c];
    const REAL rho = SQRT(e[0] * e[0] + e[1] * e[1] + e[2] * e[2]);
    REAL r[3] = {o[0], o[1], o[2]};
    if (len > (REAL)0 && rho > (REAL)0) {
        for (int c = 0; c < 3; c++) b[c] = e[c] / rho;
        const REAL cs = a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
        const REAL den = (REAL)1 + cs;
        if (den > (REAL)0) {
            const REAL u[3] = {a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]};
            const REAL uo = u[0] * o[0] + u[1] * o[1] + u[2] * o[2];
            const REAL sc = uo / den;
            const REAL uxo[3] = {u[1] * o[2] - u[2] * o[1], u[2] * o[0] - u[0] * o[2], u[0] * o[1] - u[1] * o[0]};
            for (int c = 0; c < 3; c++) r[c] = cs * o[c] + uxo[c] + sc * u[c];
        }
    }
    for (int c = 0; c < 3; c++) y[c] = x1[c] + r[c];
}

/* The head collision of a follower point q placed at distance ell from its predecessor a:
 * inside the sphere rc it goes to the nearest point of the circle where the sphere of radius ell
 * about a meets the collider sphere (so the segment keeps its length), or, where they do not
 * meet, radially onto the collider as §3.5. The factored forms are §2.5's. */
static inline void SFX(fl_collide)(const REAL *a, REAL ell, REAL rc, REAL *q)
{
    const REAL len = SQRT(q[0] * q[0] + q[1] * q[1] + q[2] * q[2]);
    if (!(len < rc)) return;
    const REAL d = SQRT(a[0] * a[0] + a[1] * a[1] + a[2] * a[2]);
    if (d > (REAL)0) {
        const REAL tau = ((d - rc) * (d + rc) + ell * ell) / (d + d);
        const REAL cp = d - tau;
        const REAL h2 = ((rc - d) + tau) * (rc + cp);
        if (h2 > (REAL)0) {
            const REAL n[3] = {a[0] / d, a[1] / d, a[2] / d};
            const REAL m[3] = {cp * n[0], cp * n[1], cp * n[2]};
            const REAL v[3] = {q[0] - m[0], q[1] - m[1], q[2] - m[2]};
            const REAL s = v[0] * n[0] + v[1] * n[1] + v[2] * n[2];
            const REAL u[3] = {v[0] - s * n[0], v[1] - s * n[1], v[2] - s * n[2]};
            const REAL lam = SQRT(u[0] * u[0] + u[1] * u[1] + u[2] * u[2]);
            if (lam > (REAL)0) {
                const REAL r = SQRT(h2);
                for (int c = 0; c < 3; c++) q[c] = m[c] + r * (u[c] / lam);
                return;
            }
        }
    }
    if (len == (REAL)0) {
        q[0] = (REAL)0;
        q[1] = rc;
        q[2] = (REAL)0;
    } else {
        const REAL sc = rc / len;
        for (int c = 0; c < 3; c++) q[c] = q[c] * sc;
    }
}

void SFX(hb_follower_place)(const DMODEL *m, const hb_followers *fl, int64_t j, const REAL *q, REAL *x, REAL *v,
                            const REAL *rest, const REAL *seg_rest)
{
    const int64_t P = m->points;
    const size_t st = (size_t)P * 3u;
    const int W = fl->width;
    const int64_t *src = fl->src + (size_t)W * (size_t)j;
    const REAL *w = WEIGHTS(fl) + (size_t)W * (size_t)j;
    const int64_t f = fl->follower[j];
    REAL *xf = x + (size_t)f * st, *vf = v + (size_t)f * st;
    const REAL *rf = rest + (size_t)f * st;
    const REAL *sf = seg_rest ? seg_rest + (size_t)f * (size_t)(P - 1) : NULL;
    /* the root on the head */
    if (q) SFX(fl_rotate)(q, rf, xf);
    else
        for (int c = 0; c < 3; c++) xf[c] = rf[c];
    /* velocities: the guides' blended with the weights, point by point */
    for (size_t e = 0; e < st; e++) {
        REAL acc = w[0] * v[(size_t)src[0] * st + e];
        for (int i = 1; i < W; i++) acc = acc + w[i] * v[(size_t)src[i] * st + e];
        vf[e] = acc;
    }
    for (int64_t k = 1; k < P; k++) {
        REAL acc[3];
        for (int i = 0; i < W; i++) {
            REAL y[3];
            SFX(fl_carry)(x + (size_t)src[i] * st, rest + (size_t)src[i] * st, rf + 3 * k, k, q, y);
            for (int c = 0; c < 3; c++) acc[c] = i == 0 ? w[0] * y[c] : acc[c] + w[i] * y[c];
        }
        /* the segment toward the blended point, at the follower's own rest length ℓ_k */
        const REAL *pp = xf + 3 * (k - 1);
        REAL *p = xf + 3 * k;
        const REAL ell = sf ? sf[k - 1] : m->seg_len;
        const REAL ex = acc[0] - pp[0], ey = acc[1] - pp[1], ez = acc[2] - pp[2];
        const REAL rho = SQRT(ex * ex + ey * ey + ez * ez);
        if (rho > (REAL)0) {
            p[0] = pp[0] + ell * (ex / rho);
            p[1] = pp[1] + ell * (ey / rho);
            p[2] = pp[2] + ell * (ez / rho);
        } else {
            p[0] = pp[0];
            p[1] = pp[1] - ell;
            p[2] = pp[2];
        }
        if (m->features & HB_F_COLLIDE) SFX(fl_collide)(pp, ell, m->collide_r, p);
    }
}
