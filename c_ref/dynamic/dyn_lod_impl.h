/* dyn_lod_impl.h — the rendered points of one strand (docs/model.md §3.14), written once for
 * a floating type REAL; dyn_lod.c includes it for float and for double (SFX, SQRT). Every
 * expression is evaluated in the order written; §3.14 states it. */

/* Simulated point j of a strand, j = −1 … ps, coordinate c: the phantom ends are the
 * reflections x_{−1} = x_0 + (x_0 − x_1) and x_ps = x_{ps−1} + (x_{ps−1} − x_{ps−2}). */
static inline REAL SFX(lod_at)(const REAL *x, int64_t ps, int64_t j, int c)
{
#if HB_PLANT == 14 /* judge test: the root's phantom end copied, not reflected */
    if (j < 0) return x[c];
#else
    if (j < 0) return x[c] + (x[c] - x[3 + c]);
#endif
    if (j >= ps) return x[3 * (ps - 1) + c] + (x[3 * (ps - 1) + c] - x[3 * (ps - 2) + c]);
    return x[3 * j + c];
}

/* The centripetal knot interval between simulated points a and b: sqrt(|x_b − x_a|). */
static inline REAL SFX(lod_knot)(const REAL *x, int64_t ps, int64_t a, int64_t b)
{
    REAL e[3];
    for (int c = 0; c < 3; c++) e[c] = SFX(lod_at)(x, ps, b, c) - SFX(lod_at)(x, ps, a, c);
    return SQRT(SQRT(e[0] * e[0] + e[1] * e[1] + e[2] * e[2]));
}

/* Rendered point k·m + i (0 < i < m) of segment k: out = C of the Barry–Goldman pyramid over
 * the control values y_{k−1} … y_{k+2} (positions, or velocities with the positions' knots). */
static inline void SFX(lod_point)(const REAL *x, const REAL *y, int64_t ps, int64_t k, int64_t i, int64_t m, REAL *out)
{
    const REAL s = (REAL)i / (REAL)m;
    const REAL da = SFX(lod_knot)(x, ps, k - 1, k), db = SFX(lod_knot)(x, ps, k, k + 1),
               dc = SFX(lod_knot)(x, ps, k + 1, k + 2);
    for (int c = 0; c < 3; c++) {
        const REAL p0 = SFX(lod_at)(y, ps, k - 1, c), p1 = SFX(lod_at)(y, ps, k, c), p2 = SFX(lod_at)(y, ps, k + 1, c),
                   p3 = SFX(lod_at)(y, ps, k + 2, c);
        if (da > (REAL)0 && db > (REAL)0 && dc > (REAL)0) {
            const REAL t = s * db;
            const REAL ua = (t + da) / da, ub = t / db, uc = (t - db) / dc, ud = (t + da) / (da + db),
                       ue = t / (db + dc);
            const REAL a1 = p0 + ua * (p1 - p0), a2 = p1 + ub * (p2 - p1), a3 = p2 + uc * (p3 - p2);
            const REAL b1 = a1 + ud * (a2 - a1), b2 = a2 + ue * (a3 - a2);
            out[c] = b1 + ub * (b2 - b1);
        } else {
            out[c] = p1 + s * (p2 - p1);
        }
    }
}

void SFX(hb_lod_strand)(const REAL *x, const REAL *y, int64_t ps, int64_t pr, REAL *out)
{
    const int64_t m = (pr - 1) / (ps - 1);
    for (int64_t k = 0; k < ps - 1; k++) {
        for (int c = 0; c < 3; c++) out[3 * (k * m) + c] = y[3 * k + c];
        for (int64_t i = 1; i < m; i++) SFX(lod_point)(x, y, ps, k, i, m, out + 3 * (k * m + i));
    }
    for (int c = 0; c < 3; c++) out[3 * (pr - 1) + c] = y[3 * (ps - 1) + c];
}

void SFX(hb_lod_render)(const REAL *x, const REAL *v, int64_t n, int64_t ps, int64_t pr, REAL *xr, REAL *vr)
{
    const size_t ss = (size_t)ps * 3u, sr = (size_t)pr * 3u;
    for (int64_t i = 0; i < n; i++) {
        const REAL *xi = x + (size_t)i * ss;
        SFX(hb_lod_strand)(xi, xi, ps, pr, xr + (size_t)i * sr);
        if (v) SFX(hb_lod_strand)(xi, v + (size_t)i * ss, ps, pr, vr + (size_t)i * sr);
    }
}
