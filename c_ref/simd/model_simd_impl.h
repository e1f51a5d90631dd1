/* model_simd_impl.h — the stages of model_impl.h on a block of strands in the point-major
 * layout, one strand per SIMD lane (model_simd.h says the layout and the contract).
 *
 * Included twice by model_simd.c, after paper/points_impl.h, with REAL (float, double),
 * ITYPE (an integer as wide as REAL, for per-lane flags and counts), BLOCK (lanes per
 * block), SFX, MODEL, SQRT, SIN, COS, ASIN, ATAN2 and EPS. Every `#pragma omp simd` loop below runs over the BLOCK lanes
 * of one point k (collide: over a chunk of HB_SIMD_CHUNK of them): its body is the body of
 * the matching loop of model_impl.h for one strand, with each `if` turned into values
 * computed on every lane and a select. Nothing in a lane depends on another lane, and
 * BLOCK and HB_SIMD_CHUNK are multiples of every vector width, so no lane is ever computed
 * by a scalar remainder loop: every strand goes through the same vector code whatever its
 * position, its block and the thread that runs it.
 *
 * Where model_impl.h evaluates X in a branch, the lanes here evaluate X everywhere and
 * discard it where the branch was not taken; such values may be Inf or NaN (e.g. s² with
 * ρ = 0) and are never selected.
 *
 * The free arithmetic (docs/cpu_simd.md): the same decisions as model_impl.h, computed more
 * cheaply and judged by tolerance, like the CUDA normal build (cuda/paper/model.cuh). In every
 * precision: t = k·(w/(P−1)), and collide's pull multiplies by one quotient ℓ/len instead
 * of dividing twice (its projection keeps model_impl.h's operations: where the circle of
 * radius ℓ about the root only touches the shell, ℓ = h, √h² turns an ulp into √ε). With FAST_TRIG (fp32) the drape's step angles are computed once per
 * strand (every step after the first goes from the shell to the shell), θ advances by
 * additions as in model_impl.h, and a point's sin and cos are fast_trig.h's inline
 * polynomials (one loop per point); the wind takes its atan2 and the turned direction's
 * sin and cos from fast_trig.h in one loop (docs/cpu_simd.md). A wind followed
 * by collide runs as one pass (hb_simd_wind_collide_block).
 */

#define PI_R ((REAL)3.14159265358979323846)
#define HALF_PI_R ((REAL)1.57079632679489661923)
#define TWO_PI_R ((REAL)6.28318530717958647692)

#define ROW(A, k) ((A) + (size_t)(k) * (size_t)stride)

/* ---- init: roots (points_impl.h hb_root_place) and drape (model_impl.h drape) -------- */
void SFX(hb_simd_init_block)(const MODEL *m, uint64_t first, REAL *X, REAL *Y, REAL *Z, int64_t stride)
{
    const int64_t P = m->points;
    const REAL R = m->head_radius, h = m->hair_offset, ell = m->seg_len;
    /* the lane state: the strand's x, its predecessor (py, pz), shell radius, angle θ,
     * slice radius ρ of the predecessor, and whether it hangs */
    REAL x0[BLOCK] HB_ALIGNED, py[BLOCK] HB_ALIGNED, pz[BLOCK] HB_ALIGNED, rc[BLOCK] HB_ALIGNED;
    REAL theta[BLOCK] HB_ALIGNED, rho[BLOCK] HB_ALIGNED;
    ITYPE hang[BLOCK] HB_ALIGNED;
    /* within one point: whether the lane stepped onto the shell, and its y if it did not */
    ITYPE stepped[BLOCK] HB_ALIGNED;
    REAL ynot[BLOCK] HB_ALIGNED;
#if FAST_TRIG
    /* the step angles, once per strand: from the root (ρ = r0) and from the shell (ρ = rc) */
    REAL alpha0[BLOCK] HB_ALIGNED, alpha1[BLOCK] HB_ALIGNED;
    ITYPE fits0[BLOCK] HB_ALIGNED, fits1[BLOCK] HB_ALIGNED;
#endif

    /* Roots: the reference's own function (points_impl.h), integer Philox draws and IEEE
     * arithmetic only, so they are its bits whether this loop is vectorised or not. */
    for (int j = 0; j < BLOCK; j++) {
        REAL p[3];
        SFX(hb_root_place)(m->seed, first + (uint64_t)j, R, m->face_margin, p);
        x0[j] = p[0];
        py[j] = p[1];
        pz[j] = p[2];
    }

    {
        REAL *restrict X0 = HB_ASSUME_ALIGNED(X), *restrict Y0 = HB_ASSUME_ALIGNED(Y),
                       *restrict Z0 = HB_ASSUME_ALIGNED(Z);
#pragma omp simd
        for (int j = 0; j < BLOCK; j++) {
            const REAL y = py[j], z = pz[j];
            const REAL r0 = SQRT(y * y + z * z);
            rc[j] = r0 + h;
            REAL th = ATAN2(y, z);                      /* (−π, π] … */
            th = th <= -HALF_PI_R ? th + TWO_PI_R : th; /* … taken in (−π/2, 3π/2] */
            theta[j] = th;
            hang[j] = th > PI_R; /* a root on the lower back hangs from the root */
            rho[j] = r0;
            X0[j] = x0[j];
            Y0[j] = y;
            Z0[j] = z;
#if FAST_TRIG
            /* model_impl.h's s² and 2·asin(√s²) for ρ = r0 and for ρ = rc (g = 0) */
            const REAL c = rc[j], g = c - r0;
            const REAL s20 = ((ell - g) * (ell + g)) / ((REAL)4 * r0 * c);
            const REAL s21 = ((ell - (REAL)0) * (ell + (REAL)0)) / ((REAL)4 * c * c);
            const ITYPE f0 = (r0 > (REAL)0) & (s20 <= (REAL)1), f1 = (c > (REAL)0) & (s21 <= (REAL)1);
            const REAL s20c = f0 & (s20 >= (REAL)0) ? s20 : (REAL)0, s21c = f1 & (s21 >= (REAL)0) ? s21 : (REAL)0;
            alpha0[j] = (REAL)2 * ASIN(SQRT(s20c));
            alpha1[j] = (REAL)2 * ASIN(SQRT(s21c));
            fits0[j] = f0;
            fits1[j] = f1;
#endif
        }
    }

#if FAST_TRIG
    for (int64_t k = 1; k < P; k++) {
        REAL *restrict Xk = HB_ASSUME_ALIGNED(ROW(X, k)), *restrict Yk = HB_ASSUME_ALIGNED(ROW(Y, k)),
                       *restrict Zk = HB_ASSUME_ALIGNED(ROW(Z, k));
        const REAL *alpha = k == 1 ? alpha0 : alpha1;
        const ITYPE *fits = k == 1 ? fits0 : fits1;
#pragma omp simd
        for (int j = 0; j < BLOCK; j++) {
            const REAL th = theta[j], y = py[j], z = pz[j], c = rc[j];
            const ITYPE hg = hang[j];
            const REAL next = th + alpha[j];
            const ITYPE step = (hg == 0) & fits[j] & (next <= PI_R);
            REAL sn, cs;
            hb_sincos_fast(next, &sn, &cs);
            const REAL dz = z + c;
            const REAL dy2 = ell * ell - dz * dz;
            const REAL tangent = y - SQRT(dy2 > (REAL)0 ? dy2 : (REAL)0), down = y - ell, mc = -c;
            const REAL nz = step ? c * cs : (hg ? z : mc);
            const REAL ny = step ? c * sn : (hg ? down : tangent);
            theta[j] = step ? next : th;
            hang[j] = step ? 0 : 1;
            py[j] = ny;
            pz[j] = nz;
            Xk[j] = x0[j];
            Yk[j] = ny;
            Zk[j] = nz;
        }
    }
    (void)rho;
    (void)stepped;
    (void)ynot;
#else
    for (int64_t k = 1; k < P; k++) {
        REAL *restrict Xk = HB_ASSUME_ALIGNED(ROW(X, k)), *restrict Yk = HB_ASSUME_ALIGNED(ROW(Y, k)),
                       *restrict Zk = HB_ASSUME_ALIGNED(ROW(Z, k));
        /* Two loops per point: the cos and the sin of the same angle in one loop would be
         * merged by GCC into one sincos call, which it cannot vectorise (model_simd.c). The
         * first loop does everything but the sin, the second the sin and y. */
#pragma omp simd
        for (int j = 0; j < BLOCK; j++) {
            const REAL th = theta[j], rh = rho[j], y = py[j], z = pz[j], c = rc[j];
            const ITYPE hg = hang[j];
            /* the step onto the shell, in the half-angle form of model_impl.h:
             * s² = sin²(α/2) = (ℓ − g)(ℓ + g) / (4ρ rc), g = rc − ρ; it fits when ρ > 0 and
             * s² ≤ 1, and s² < 0 (out of reach only by rounding) is clamped to 0 */
            const REAL g = c - rh;
            const REAL s2 = ((ell - g) * (ell + g)) / ((REAL)4 * rh * c);
            const ITYPE fits = (rh > (REAL)0) & (s2 <= (REAL)1);
            const ITYPE neg = s2 < (REAL)0;
            const REAL s2c = fits & (neg == 0) ? s2 : (REAL)0;
            const REAL next = th + (REAL)2 * ASIN(SQRT(s2c));
            const ITYPE step = (hg == 0) & fits & (next <= PI_R);
            const REAL sz = c * COS(next);
            /* not stepping: the first hanging point goes onto the tangent line z = −rc at
             * distance ℓ below the predecessor; a hanging one goes straight down */
            const REAL dz = z + c;
            const REAL dy2 = ell * ell - dz * dz;
            const REAL tangent = y - SQRT(dy2 > (REAL)0 ? dy2 : (REAL)0), down = y - ell, mc = -c;
            const REAL hz = hg ? z : mc;
            const REAL nz = step ? sz : hz;
            theta[j] = step ? next : th;
            rho[j] = step ? c : rh;
            hang[j] = step ? 0 : 1;
            stepped[j] = step;
            ynot[j] = hg ? down : tangent;
            pz[j] = nz;
            Xk[j] = x0[j];
            Zk[j] = nz;
        }
#pragma omp simd
        for (int j = 0; j < BLOCK; j++) {
            const REAL sy = rc[j] * SIN(theta[j]); /* θ is `next` where the lane stepped */
            const REAL ny = stepped[j] ? sy : ynot[j];
            py[j] = ny;
            Yk[j] = ny;
        }
    }
#endif
}

/* ---- wind (model_impl.h hb_wind_strand) ----------------------------------------------- */
/* a block's running wind state: the predecessor before (oy, oz) and after (ny, nz) the
 * wind (the root never moves), and within one point the turned direction */
typedef struct {
    REAL oy[BLOCK] HB_ALIGNED, oz[BLOCK] HB_ALIGNED, ny[BLOCK] HB_ALIGNED, nz[BLOCK] HB_ALIGNED;
    REAL angle[BLOCK] HB_ALIGNED;
} SFX(hb_wind_lanes);

static inline void SFX(hb_wind_start)(SFX(hb_wind_lanes) * ws, const REAL *Y, const REAL *Z)
{
    const REAL *restrict Y0 = HB_ASSUME_ALIGNED(Y), *restrict Z0 = HB_ASSUME_ALIGNED(Z);
#pragma omp simd
    for (int j = 0; j < BLOCK; j++) {
        ws->oy[j] = ws->ny[j] = Y0[j];
        ws->oz[j] = ws->nz[j] = Z0[j];
    }
}

/* Point k read from (inY, inZ), its wound value left in ws->ny, ws->nz and stored to
 * (outY, outZ) (which may be the input row, or ws->ny, ws->nz themselves). */
static inline __attribute__((always_inline)) void SFX(hb_wind_point)(SFX(hb_wind_lanes) * ws, const MODEL *m, REAL t,
                                                                     const REAL *inY, const REAL *inZ, REAL *outY,
                                                                     REAL *outZ)
{
    const REAL ell = m->seg_len;
    const REAL psi = m->wind_angle; /* already reduced to (−π, π] */
    inY = HB_ASSUME_ALIGNED(inY);
    inZ = HB_ASSUME_ALIGNED(inZ);
    outY = HB_ASSUME_ALIGNED(outY);
    outZ = HB_ASSUME_ALIGNED(outZ);
#if FAST_TRIG
    /* one loop: fast_trig.h's inline atan2 and sincos (the fused walk's, model_simd.c) */
#pragma omp simd
    for (int j = 0; j < BLOCK; j++) {
        const REAL cy = inY[j], cz = inZ[j];
        const REAL dy = cy - ws->oy[j], dz = cz - ws->oz[j];
        const REAL phi = hb_atan2_fast(dy, dz);
        REAL delta = psi - phi;
        const REAL dm = delta - TWO_PI_R, dp = delta + TWO_PI_R;
        const ITYPE above = delta > PI_R, below = delta <= -PI_R;
        delta = above ? dm : (below ? dp : delta);
        const ITYPE opposite = delta == PI_R, up = dz >= (REAL)0;
        delta = opposite ? (up ? PI_R : -PI_R) : delta;
        REAL sn, cs;
        hb_sincos_fast(phi + t * delta, &sn, &cs);
        const REAL z = ws->nz[j] + ell * cs, y = ws->ny[j] + ell * sn;
        ws->nz[j] = z;
        ws->ny[j] = y;
        outZ[j] = z;
        outY[j] = y;
        ws->oy[j] = cy;
        ws->oz[j] = cz;
    }
#else
    /* Two loops per point, the cos in the first and the sin in the second (see init). */
#pragma omp simd
    for (int j = 0; j < BLOCK; j++) {
        const REAL cy = inY[j], cz = inZ[j];
        const REAL dy = cy - ws->oy[j], dz = cz - ws->oz[j];
        const REAL phi = ATAN2(dy, dz);
        REAL delta = psi - phi; /* in [−2π, 2π]: wrap to (−π, π] */
        const REAL dm = delta - TWO_PI_R, dp = delta + TWO_PI_R;
        const ITYPE above = delta > PI_R, below = delta <= -PI_R;
        delta = above ? dm : (below ? dp : delta);
        /* exactly opposite: the arc through +y (the sign of dz, model_impl.h) */
        const ITYPE opposite = delta == PI_R, up = dz >= (REAL)0;
        delta = opposite ? (up ? PI_R : -PI_R) : delta;
        const REAL turned = phi + t * delta;
        const REAL z = ws->nz[j] + ell * COS(turned);
        ws->angle[j] = turned;
        ws->nz[j] = z;
        outZ[j] = z;
        ws->oy[j] = cy;
        ws->oz[j] = cz;
    }
#pragma omp simd
    for (int j = 0; j < BLOCK; j++) {
        const REAL y = ws->ny[j] + ell * SIN(ws->angle[j]);
        ws->ny[j] = y;
        outY[j] = y;
    }
#endif
}

void SFX(hb_simd_wind_block)(const MODEL *m, REAL *Y, REAL *Z, int64_t stride)
{
    const int64_t P = m->points;
    SFX(hb_wind_lanes) ws;
    SFX(hb_wind_start)(&ws, Y, Z);
    const REAL w_per_point = m->wind_strength / (REAL)(P - 1);
    for (int64_t k = 1; k < P; k++)
        SFX(hb_wind_point)(&ws, m, (REAL)k * w_per_point, ROW(Y, k), ROW(Z, k), ROW(Y, k), ROW(Z, k));
}

/* ---- collide (model_impl.h hb_collide_strand) ----------------------------------------- */
/* a block's running collide state: the predecessor (after this pass), the shell, whether
 * the strand has moved, the count of points changed; within one point the point after the
 * pull and the projection, and whether it is inside the shell (then: whether it was
 * projected) */
typedef struct {
    REAL py[BLOCK] HB_ALIGNED, pz[BLOCK] HB_ALIGNED, rc[BLOCK] HB_ALIGNED, inner2[BLOCK] HB_ALIGNED;
    ITYPE moved[BLOCK] HB_ALIGNED, changed[BLOCK] HB_ALIGNED;
    REAL ny[BLOCK] HB_ALIGNED, nz[BLOCK] HB_ALIGNED;
    ITYPE inside[BLOCK] HB_ALIGNED;
} SFX(hb_collide_lanes);

static inline void SFX(hb_collide_start)(SFX(hb_collide_lanes) * cs, const MODEL *m, const REAL *Y, const REAL *Z)
{
    const REAL h = m->hair_offset;
    const REAL *restrict Y0 = HB_ASSUME_ALIGNED(Y), *restrict Z0 = HB_ASSUME_ALIGNED(Z);
#pragma omp simd
    for (int j = 0; j < BLOCK; j++) {
        const REAL y = Y0[j], z = Z0[j];
        const REAL r0 = SQRT(y * y + z * z);
        const REAL c = r0 + h;
        const REAL inner = c - c * ((REAL)HB_SHELL_ULPS * EPS); /* rounding allowance */
        cs->rc[j] = c;
        cs->inner2[j] = inner * inner;
        cs->py[j] = y;
        cs->pz[j] = z;
        cs->moved[j] = 0;
        cs->changed[j] = 0;
    }
}

/* Point k read from (inY, inZ) and stored to (outY, outZ): with store_all every lane is
 * stored (the fused pass, whose input is not the output row), otherwise only the points
 * collide changes (a masked store: untouched points are not written). */
static inline __attribute__((always_inline)) void SFX(hb_collide_point)(SFX(hb_collide_lanes) * cs, const MODEL *m,
                                                                        const REAL *inY, const REAL *inZ, REAL *outY,
                                                                        REAL *outZ, const int store_all)
{
    const REAL ell = m->seg_len;
    inY = HB_ASSUME_ALIGNED(inY);
    inZ = HB_ASSUME_ALIGNED(inZ);
    outY = HB_ASSUME_ALIGNED(outY);
    outZ = HB_ASSUME_ALIGNED(outZ);
    /* model_impl.h's two branches, the pull of a moved strand and the projection of a
     * point inside the shell, cost divisions and square roots that selects would compute
     * on every lane; most lanes take neither. So each chunk of HB_SIMD_CHUNK lanes runs a
     * branch's loop only when one of its lanes takes it; every lane of the chunk then
     * computes it and the select keeps it where model_impl.h would. */
    for (int j0 = 0; j0 < BLOCK; j0 += HB_SIMD_CHUNK) {
        const int j1 = j0 + HB_SIMD_CHUNK;
        ITYPE any_moved = 0, any_inside = 0;
#pragma omp simd reduction(| : any_moved)
        for (int j = j0; j < j1; j++) any_moved |= cs->moved[j];
        if (any_moved) {
            /* follow the leader once the strand has moved:
             * p_k ← p_{k−1} + ℓ·unit(p_k − p_{k−1}), or ℓ straight down when there is no
             * direction left */
#pragma omp simd reduction(| : any_inside)
            for (int j = j0; j < j1; j++) {
                const REAL y = cs->py[j], z = cs->pz[j], qy = inY[j], qz = inZ[j];
                const REAL dy = qy - y, dz = qz - z;
                const REAL len = SQRT(dy * dy + dz * dz);
                const ITYPE dir = len > (REAL)0;
                const REAL scale = ell / len; /* one division (model_impl.h: two) */
                const REAL fy = y + dy * scale, fz = z + dz * scale, down = y - ell;
                const REAL cy = cs->moved[j] ? (dir ? fy : down) : qy;
                const REAL cz = cs->moved[j] ? (dir ? fz : z) : qz;
                const ITYPE in = cy * cy + cz * cz < cs->inner2[j];
                cs->ny[j] = cy;
                cs->nz[j] = cz;
                cs->inside[j] = in;
                any_inside |= in;
            }
        } else {
#pragma omp simd reduction(| : any_inside)
            for (int j = j0; j < j1; j++) {
                const REAL cy = inY[j], cz = inZ[j];
                const ITYPE in = cy * cy + cz * cz < cs->inner2[j];
                cs->ny[j] = cy;
                cs->nz[j] = cz;
                cs->inside[j] = in;
                any_inside |= in;
            }
        }
        if (any_inside) {
            /* inside the shell: onto the shell's intersection with the circle of radius ℓ
             * around the predecessor, points_impl.h's hb_shell_chord lane by lane */
#pragma omp simd
            for (int j = j0; j < j1; j++) {
                const REAL y = cs->py[j], z = cs->pz[j], cy = cs->ny[j], cz = cs->nz[j];
                const REAL d2 = y * y + z * z;
                const REAL d = SQRT(d2);
                const ITYPE proj = cs->inside[j] & (d > (REAL)0);
                REAL sy = cy, sz = cz;
                SFX(hb_shell_chord)(y, z, d, cs->rc[j], ell, &sy, &sz);
                cs->ny[j] = proj ? sy : cy;
                cs->nz[j] = proj ? sz : cz;
                cs->inside[j] = proj;
            }
        }
        if (!any_moved && !any_inside) {
#pragma omp simd
            for (int j = j0; j < j1; j++) {
                const REAL cy = cs->ny[j], cz = cs->nz[j];
                if (store_all) {
                    outY[j] = cy;
                    outZ[j] = cz;
                }
                cs->py[j] = cy;
                cs->pz[j] = cz;
            }
            continue;
        }
#pragma omp simd
        for (int j = j0; j < j1; j++) {
            const REAL cy = cs->ny[j], cz = cs->nz[j];
            const ITYPE now = cs->moved[j] | cs->inside[j]; /* inside[] is now "projected" */
            if (store_all || now) {
                outY[j] = cy;
                outZ[j] = cz;
            }
            cs->moved[j] = now;
            cs->changed[j] += now;
            cs->py[j] = cy;
            cs->pz[j] = cz;
        }
    }
}

static inline int64_t SFX(hb_collide_total)(const SFX(hb_collide_lanes) * cs, int real)
{
    int64_t total = 0;
    for (int j = 0; j < real && j < BLOCK; j++) total += (int64_t)cs->changed[j];
    return total;
}

int64_t SFX(hb_simd_collide_block)(const MODEL *m, int real, REAL *Y, REAL *Z, int64_t stride)
{
    const int64_t P = m->points;
    SFX(hb_collide_lanes) cs;
    SFX(hb_collide_start)(&cs, m, Y, Z);
    for (int64_t k = 1; k < P; k++) SFX(hb_collide_point)(&cs, m, ROW(Y, k), ROW(Z, k), ROW(Y, k), ROW(Z, k), 0);
    return SFX(hb_collide_total)(&cs, real);
}

/* The block's row k of Y and Z requested into the cache, for writing: a block reads 2·P
 * rows `stride` reals apart, more separate streams than a hardware prefetcher tracks. */
static inline void SFX(hb_prefetch_row)(const REAL *Y, const REAL *Z, int64_t k, int64_t stride)
{
    const REAL *y = ROW(Y, k), *z = ROW(Z, k);
    for (int j = 0; j < BLOCK; j += 64 / (int)sizeof(REAL)) {
        __builtin_prefetch(y + j, 1, 3);
        __builtin_prefetch(z + j, 1, 3);
    }
}

/* ---- wind then collide in one pass (the CUDA fused variant's pair) -------------------- */
#if FAST_TRIG
/* fp32: a strand walk. A group of HB_WALK_NV vectors of lanes walks the points with its
 * wind state (the previous input, the wound predecessor) and collide state (predecessor,
 * shell, moved, count) in registers. Per tile of points, a first loop computes each
 * point's turned angle (atan2, the wrap: it reads only the input), a
 * second winds (sincos) and collides (the pull and the projection only where a lane of the
 * vector needs them). The per-lane operations are those of hb_wind_point and
 * hb_collide_point, so the result is the two passes' bit for bit. */
#ifndef HB_WALK_TILE
#define HB_WALK_TILE 32
#endif
#define HB_WALK_G (HB_WALK_NV * HB_VW)
_Static_assert(BLOCK % HB_WALK_G == 0, "a block is a whole number of walk groups");
int64_t SFX(hb_simd_wind_collide_block)(const MODEL *m, int real, REAL *Y, REAL *Z, REAL *WY, REAL *WZ, int64_t stride)
{
    const int64_t P = m->points;
    const REAL w_per_point = m->wind_strength / (REAL)(P - 1);
    const hb_vf ell = VSET(m->seg_len), psi = VSET(m->wind_angle), h = VSET(m->hair_offset);
    const hb_vf pi = VSET(PI_R), mpi = VSET(-PI_R), twopi = VSET(TWO_PI_R), zero = VSET((REAL)0);
    const hb_vf allow = VSET((REAL)HB_SHELL_ULPS * EPS);
    int32_t changed_l[BLOCK] HB_ALIGNED;
    hb_vf turned[HB_WALK_TILE][HB_WALK_NV];
    if (WY) {
        for (int64_t j = 0; j < BLOCK; j++) {
            WY[j] = Y[j];
            WZ[j] = Z[j];
        }
    }
    for (int g = 0; g < BLOCK; g += HB_WALK_G) {
        hb_vf oy[HB_WALK_NV], oz[HB_WALK_NV], ny[HB_WALK_NV], nz[HB_WALK_NV], py[HB_WALK_NV], pz[HB_WALK_NV],
            rc[HB_WALK_NV], inner2[HB_WALK_NV];
        hb_vm moved[HB_WALK_NV];
        hb_vi changed[HB_WALK_NV];
        for (int v = 0; v < HB_WALK_NV; v++) { /* hb_wind_start, hb_collide_start */
            const hb_vf y = VLD(Y + g + v * HB_VW), z = VLD(Z + g + v * HB_VW);
            const hb_vf c = VADD(VSQRT(VADD(VMUL(y, y), VMUL(z, z))), h);
            const hb_vf inner = VSUB(c, VMUL(c, allow));
            oy[v] = ny[v] = py[v] = y;
            oz[v] = nz[v] = pz[v] = z;
            rc[v] = c;
            inner2[v] = VMUL(inner, inner);
            moved[v] = MNONE;
            changed[v] = VIZERO;
        }
        for (int64_t k0 = 1; k0 < P; k0 += HB_WALK_TILE) {
            const int64_t k1 = P - k0 < HB_WALK_TILE ? P : k0 + HB_WALK_TILE;
            /* the wind's turned angles: the input only */
            for (int64_t k = k0; k < k1; k++) {
                const hb_vf t = VSET((REAL)k * w_per_point);
                for (int v = 0; v < HB_WALK_NV; v++) {
                    const int64_t o = (k - 1) * stride + g + v * HB_VW;
#if HB_SIMD_WALK_PREFETCH
                    /* the lanes HB_SIMD_WALK_PREFETCH groups ahead (past the block: the next
                     * block's, or the next row's; a prefetch never faults) */
                    if ((v * HB_VW * (int)sizeof(REAL)) % 64 == 0) {
                        VPREFETCH(Y + o + stride + HB_SIMD_WALK_PREFETCH * HB_WALK_G);
                        VPREFETCH(Z + o + stride + HB_SIMD_WALK_PREFETCH * HB_WALK_G);
                    }
#endif
                    const hb_vf cy = VLD(Y + o + stride), cz = VLD(Z + o + stride);
                    const hb_vf dy = VSUB(cy, oy[v]), dz = VSUB(cz, oz[v]);
                    oy[v] = cy;
                    oz[v] = cz;
                    const hb_vf phi = hb_v_atan2(dy, dz);
                    hb_vf delta = VSUB(psi, phi);
                    const hb_vf dm = VSUB(delta, twopi), dp = VADD(delta, twopi);
                    const hb_vm above = VCMP(delta, pi, _CMP_GT_OQ), below = VCMP(delta, mpi, _CMP_LE_OQ);
                    delta = VSEL(above, dm, VSEL(below, dp, delta));
                    const hb_vm opposite = VCMP(delta, pi, _CMP_EQ_OQ), up = VCMP(dz, zero, _CMP_GE_OQ);
                    delta = VSEL(opposite, VSEL(up, pi, mpi), delta);
                    turned[k - k0][v] = VADD(phi, VMUL(t, delta));
                }
            }
            /* wind (the running sum) and collide, point by point */
            for (int64_t k = k0; k < k1; k++) {
                for (int v = 0; v < HB_WALK_NV; v++) {
                    const int64_t o = k * stride + g + v * HB_VW;
                    hb_vf sn, cs;
                    hb_v_sincos(turned[k - k0][v], &sn, &cs);
                    const hb_vf qz = VADD(nz[v], VMUL(ell, cs)), qy = VADD(ny[v], VMUL(ell, sn));
                    nz[v] = qz;
                    ny[v] = qy;
                    if (WY) {
                        VST(WY + o, qy);
                        VST(WZ + o, qz);
                    }
                    hb_vf cy = qy, cz = qz;
                    if (MANY(moved[v])) { /* the pull */
                        const hb_vf y = py[v], z = pz[v];
                        const hb_vf dy = VSUB(qy, y), dz = VSUB(qz, z);
                        const hb_vf len = VSQRT(VADD(VMUL(dy, dy), VMUL(dz, dz)));
                        const hb_vm dir = VCMP(len, zero, _CMP_GT_OQ);
                        const hb_vf scale = VDIV(ell, len);
                        const hb_vf fy = VADD(y, VMUL(dy, scale)), fz = VADD(z, VMUL(dz, scale));
                        const hb_vf down = VSUB(y, ell);
                        cy = VSEL(moved[v], VSEL(dir, fy, down), qy);
                        cz = VSEL(moved[v], VSEL(dir, fz, z), qz);
                    }
                    const hb_vm in = VCMP(VADD(VMUL(cy, cy), VMUL(cz, cz)), inner2[v], _CMP_LT_OQ);
                    if (MANY(in)) { /* the projection */
                        const hb_vf y = py[v], z = pz[v], c = rc[v];
                        const hb_vf d2 = VADD(VMUL(y, y), VMUL(z, z));
                        const hb_vf d = VSQRT(d2);
                        const hb_vm proj = MAND(in, VCMP(d, zero, _CMP_GT_OQ));
                        const hb_vf tt =
                            VDIV(VADD(VMUL(VSUB(d, c), VADD(d, c)), VMUL(ell, ell)), VMUL(VSET((REAL)2), d));
                        const hb_vf a = VSUB(d, tt);
                        const hb_vf h2 = VMUL(VADD(VSUB(c, d), tt), VADD(c, a));
                        const hb_vf hh = VSQRT(VSEL(VCMP(h2, zero, _CMP_GT_OQ), h2, zero));
                        const hb_vf uy = VDIV(y, d), uz = VDIV(z, d);
                        const hb_vf fy = VMUL(a, uy), fz = VMUL(a, uz);
                        const hb_vf y1 = VADD(fy, VMUL(hh, uz)), z1 = VSUB(fz, VMUL(hh, uy));
                        const hb_vf y2 = VSUB(fy, VMUL(hh, uz)), z2 = VADD(fz, VMUL(hh, uy));
                        const hb_vf ey1 = VSUB(y1, cy), ez1 = VSUB(z1, cz), ey2 = VSUB(y2, cy), ez2 = VSUB(z2, cz);
                        const hb_vf e1 = VADD(VMUL(ey1, ey1), VMUL(ez1, ez1));
                        const hb_vf e2 = VADD(VMUL(ey2, ey2), VMUL(ez2, ez2));
                        const hb_vm upper =
                            MOR(VCMP(e1, e2, _CMP_LT_OQ), MAND(VCMP(e1, e2, _CMP_EQ_OQ), VCMP(y1, y2, _CMP_GE_OQ)));
                        cy = VSEL(proj, VSEL(upper, y1, y2), cy);
                        cz = VSEL(proj, VSEL(upper, z1, z2), cz);
                        moved[v] = MOR(moved[v], proj);
                    }
                    changed[v] = VICOUNT(changed[v], moved[v]);
                    py[v] = cy;
                    pz[v] = cz;
                    VST(Y + o, cy);
                    VST(Z + o, cz);
                }
            }
        }
        for (int v = 0; v < HB_WALK_NV; v++) VIST(changed_l + g + v * HB_VW, changed[v]);
    }
    int64_t total = 0;
    for (int j = 0; j < real && j < BLOCK; j++) total += (int64_t)changed_l[j];
    return total;
}
#undef HB_WALK_TILE
#undef HB_WALK_G
#else

/* Each point is read once and written once: wound into the lanes' wind state, then
 * collided from there with exactly the operations of the two passes above, so the result
 * is theirs bit for bit. With WY, WZ (not NULL) the wound state is stored there too. */
int64_t SFX(hb_simd_wind_collide_block)(const MODEL *m, int real, REAL *Y, REAL *Z, REAL *WY, REAL *WZ, int64_t stride)
{
    const int64_t P = m->points;
    SFX(hb_wind_lanes) ws;
    SFX(hb_collide_lanes) cs;
    SFX(hb_wind_start)(&ws, Y, Z);
    SFX(hb_collide_start)(&cs, m, Y, Z);
    const REAL w_per_point = m->wind_strength / (REAL)(P - 1);
    if (WY) {
        for (int64_t j = 0; j < BLOCK; j++) {
            WY[j] = Y[j];
            WZ[j] = Z[j];
        }
    }
    for (int64_t k = 1; k < P && k <= HB_SIMD_PREFETCH_ROWS; k++) SFX(hb_prefetch_row)(Y, Z, k, stride);
    for (int64_t k = 1; k < P; k++) {
        const REAL t = (REAL)k * w_per_point;
        if (k + HB_SIMD_PREFETCH_ROWS < P) SFX(hb_prefetch_row)(Y, Z, k + HB_SIMD_PREFETCH_ROWS, stride);
        if (WY) SFX(hb_wind_point)(&ws, m, t, ROW(Y, k), ROW(Z, k), ROW(WY, k), ROW(WZ, k));
        else SFX(hb_wind_point)(&ws, m, t, ROW(Y, k), ROW(Z, k), ws.ny, ws.nz);
        SFX(hb_collide_point)(&cs, m, ws.ny, ws.nz, ROW(Y, k), ROW(Z, k), 1);
    }
    return SFX(hb_collide_total)(&cs, real);
}
#endif

#undef ROW
#undef PI_R
#undef HALF_PI_R
#undef TWO_PI_R
