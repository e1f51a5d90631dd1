/* post_hostcheck.cu — runs the CUDA port's follower placement (cuda/dynamic/post.cuh
 * place_follower, __host__ __device__) on the HOST and compares it bit for bit with the C
 * reference (c_ref/dynamic/dyn_followers_impl.h via hb_follower_place_f32/_f64), as dyn_hostcheck.cu
 * does for the frame. No kernel is launched.
 *
 * Scenes: N strands of P points with random rest shapes (roots on the head sphere) and
 * states (points near the rest, some inside the collider, one guide with two coincident
 * points), the plan from c_ref/dynamic/dyn_followers.c for guide fractions 1/2, 1/5 and a count of 2,
 * both schemes, fp32 and fp64, a still head and a nodding one, collider on and off, the rest
 * length ℓ or a groom's per-segment ℓ_k (§3.15); the port in the canonical layout (warp
 * variants) and point-major X|Y|Z [P][N] (strand).
 *
 * Built by tests/native/test_cuda_post_host.py (gcc for the C files, nvcc for this one);
 * exit status 0 = all identical; the last line counts the cases and mismatches.
 */
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <string.h>

#include <vector>

#include "dynamic/dyn_followers.h"
#include "dynamic/post.cuh"
#include "hostcheck/hostcheck_rng.h"
#include "hostcheck/hostcheck_scene.h"

using namespace hb::dyn;

namespace {

long g_cases = 0, g_mismatch = 0;

template <typename T> const T *weights(const hb_followers &fl);
template <> const float *weights<float>(const hb_followers &fl)
{
    return fl.w32;
}
template <> const double *weights<double>(const hb_followers &fl)
{
    return fl.w64;
}
void place_c(const hb_dyn_model_f32 *m, const hb_followers *fl, int64_t j, const float *q, float *x, float *v,
             const float *r, const float *seg)
{
    hb_follower_place_f32(m, fl, j, q, x, v, r, seg);
}
void place_c(const hb_dyn_model_f64 *m, const hb_followers *fl, int64_t j, const double *q, double *x, double *v,
             const double *r, const double *seg)
{
    hb_follower_place_f64(m, fl, j, q, x, v, r, seg);
}

template <typename T, typename CM>
void check(double guides, hb_follow follow, int motion, int collider, int per_segment, uint64_t seed)
{
    const int64_t N = 23, P = 9;
    hb_scene s = hostcheck_scene(N, P, 8.0, sizeof(T) == 4 ? HB_FP32 : HB_FP64);
    s.dyn.guided = 1;
    s.dyn.guides = guides;
    s.dyn.follow = follow;
    s.dyn.collider = collider;
    s.dyn.collision_margin = 0.05;
    s.dyn.motion = motion ? HB_MOTION_NOD : HB_MOTION_STILL;
    hb_dyn_model_f32 m32;
    hb_dyn_model_f64 m64;
    hb_dyn_round(&s, &m32, &m64);
    CM cm;
    if constexpr (sizeof(T) == 4) cm = m32;
    else cm = m64;
    DModel<T> dm = dmodel_from<T>(cm);
    Rng g{seed * 0x9e3779b97f4a7c15ull + 7};
    const size_t n = (size_t)(N * P * 3);
    std::vector<T> rest(n), x(n), v(n);
    const double ell = 1.0;
    for (int64_t i = 0; i < N; i++) {
        double d[3] = {g.sym(), 0.2 + g.u(), g.sym()};
        const double nd = sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
        double p[3];
        for (int c = 0; c < 3; c++) p[c] = s.head_radius * d[c] / nd;
        for (int64_t k = 0; k < P; k++) {
            if (k > 0)
                for (int c = 0; c < 3; c++) p[c] += ell * (d[c] / nd + 0.5 * g.sym());
            for (int c = 0; c < 3; c++) {
                rest[(size_t)(3 * (i * P + k) + c)] = (T)p[c];
                x[(size_t)(3 * (i * P + k) + c)] = (T)(p[c] + (k ? 0.8 * g.sym() : 0.0));
                v[(size_t)(3 * (i * P + k) + c)] = (T)(20.0 * g.sym());
            }
        }
    }
    for (int c = 0; c < 3; c++) x[(size_t)(3 * 3 + c)] = x[(size_t)(3 * 2 + c)]; /* strand 0: points 2, 3 coincide */
    for (int c = 0; c < 3; c++) x[(size_t)(3 * (5 * P + 4) + c)] = (T)0;         /* strand 5, point 4: the centre */
    /* a groom's ℓ_k (§3.15): canonical [N][P−1] for the C reference and the warp layout, [P−1][N]
     * for the strand layout */
    std::vector<double> seg64((size_t)(N * (P - 1)));
    std::vector<T> seg((size_t)(N * (P - 1))), segpm((size_t)(N * (P - 1)));
    hb_dyn_seg_rest(&s, rest.data(), seg64.data(), seg.data());
    for (int64_t i = 0; i < N; i++)
        for (int64_t k = 0; k < P - 1; k++) segpm[(size_t)(k * N + i)] = seg[(size_t)(i * (P - 1) + k)];
    const T *segc = per_segment ? seg.data() : nullptr;
    hb_followers fl;
    char err[256];
    if (hb_followers_plan(&s, rest.data(), &fl, err, sizeof err)) {
        printf("MISMATCH plan failed: %s\n", err);
        g_mismatch++;
        return;
    }
    double qd[9];
    hb_head_rotation(&s.dyn, 0.37, qd);
    T q[9];
    for (int e = 0; e < 9; e++) q[e] = (T)qd[e];
    const T *qp = motion ? q : nullptr;
    /* the C reference on canonical copies */
    std::vector<T> xc = x, vc = v;
    for (int64_t j = 0; j < fl.n_followers; j++) place_c(&cm, &fl, j, qp, xc.data(), vc.data(), rest.data(), segc);
    /* the port: canonical */
    std::vector<T> xa = x, va = v;
    const Layout can{3 * P, 3, 1};
    dm.seg_rest = segc;
    dm.seg_is = P - 1;
    dm.seg_s = 1;
    for (int64_t j = 0; j < fl.n_followers; j++)
        place_follower(dm, qp, At<T>{xa.data(), can}, At<T>{va.data(), can}, At<const T>{rest.data(), can},
                       fl.follower[j], fl.src + fl.width * j, weights<T>(fl) + fl.width * j, fl.width);
    /* the port: point-major */
    const Layout pm{1, N, N * P};
    dm.seg_rest = per_segment ? segpm.data() : nullptr;
    dm.seg_is = 1;
    dm.seg_s = N;
    std::vector<T> xp(n), vp(n), rp(n);
    for (int64_t i = 0; i < N; i++)
        for (int64_t k = 0; k < P; k++)
            for (int c = 0; c < 3; c++) {
                const size_t a = (size_t)(3 * (i * P + k) + c), b = (size_t)(i + k * N + c * N * P);
                xp[b] = x[a];
                vp[b] = v[a];
                rp[b] = rest[a];
            }
    for (int64_t j = 0; j < fl.n_followers; j++)
        place_follower(dm, qp, At<T>{xp.data(), pm}, At<T>{vp.data(), pm}, At<const T>{rp.data(), pm}, fl.follower[j],
                       fl.src + fl.width * j, weights<T>(fl) + fl.width * j, fl.width);
    long bad = 0;
    for (int64_t i = 0; i < N; i++)
        for (int64_t k = 0; k < P; k++)
            for (int c = 0; c < 3; c++) {
                const size_t a = (size_t)(3 * (i * P + k) + c), b = (size_t)(i + k * N + c * N * P);
                bad += memcmp(&xc[a], &xa[a], sizeof(T)) != 0 || memcmp(&vc[a], &va[a], sizeof(T)) != 0;
                bad += memcmp(&xc[a], &xp[b], sizeof(T)) != 0 || memcmp(&vc[a], &vp[b], sizeof(T)) != 0;
            }
    g_cases++;
    if (bad) {
        g_mismatch++;
        printf("MISMATCH %s guides %g %s motion %d collider %d per-segment %d: %ld values differ\n",
               sizeof(T) == 4 ? "fp32" : "fp64", guides, hb_follow_name(follow), motion, collider, per_segment, bad);
    }
    hb_followers_free(&fl);
}

} /* namespace */

int main()
{
    uint64_t seed = 1;
    for (double guides : {0.5, 0.2, 2.0})
        for (hb_follow follow : {HB_FOLLOW_ONE, HB_FOLLOW_BLEND3})
            for (int motion = 0; motion < 2; motion++)
                for (int collider = 0; collider < 2; collider++)
                    for (int per_segment = 0; per_segment < 2; per_segment++) {
                        check<float, hb_dyn_model_f32>(guides, follow, motion, collider, per_segment, seed);
                        check<double, hb_dyn_model_f64>(guides, follow, motion, collider, per_segment, seed++);
                    }
    printf("post host check: %ld cases, %ld mismatches%s\n", g_cases, g_mismatch, g_mismatch ? "" : " (all identical)");
    return g_mismatch ? 1 : 0;
}
