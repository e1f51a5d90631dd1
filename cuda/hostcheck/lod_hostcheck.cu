/* lod_hostcheck.cu — runs the CUDA port's rendering of simulated-point LOD (cuda/dynamic/lod.cuh
 * lod_render_point, __host__ __device__) on the HOST and compares it bit for bit with the C
 * reference (c_ref/dynamic/dyn_lod_impl.h via hb_lod_strand_f32/_f64), positions and velocities,
 * as post_hostcheck.cu does for the followers. No kernel is launched.
 *
 * Cases: N strands of P_s simulated points (random walks from random roots, one strand with two
 * coincident points so the chord fallback runs), P_s = 2, 3, 8, 17 and m = 2, 3, 5 rendered
 * points a segment, fp32 and fp64, the port reading the canonical layout (warp variants) and
 * point-major X|Y|Z [P][N] (strand).
 *
 * Built by tests/native/test_cuda_lod_host.py (make build/hostcheck/lod_hostcheck); exit status
 * 0 = all identical; the last line counts the cases and mismatches.
 */
#include <stdint.h>
#include <stdio.h>
#include <string.h>

#include <vector>

#include "dynamic/lod.cuh"
#include "dynamic/dyn_lod.h"
#include "hostcheck/hostcheck_rng.h"

using namespace hb::dyn;

namespace {

long g_cases = 0, g_mismatch = 0;

void strand_c(const float *x, const float *y, int64_t ps, int64_t pr, float *out)
{
    hb_lod_strand_f32(x, y, ps, pr, out);
}
void strand_c(const double *x, const double *y, int64_t ps, int64_t pr, double *out)
{
    hb_lod_strand_f64(x, y, ps, pr, out);
}

template <typename T> void run_case(Rng &rng, int64_t n, int64_t ps, int64_t m, bool point_major)
{
    const int64_t pr = (ps - 1) * m + 1;
    std::vector<T> x((size_t)(n * ps * 3)), v(x.size());
    for (int64_t i = 0; i < n; i++) {
        double p[3] = {10.0 * rng.sym(), 10.0 * rng.sym(), 10.0 * rng.sym()};
        for (int64_t k = 0; k < ps; k++) {
            for (int c = 0; c < 3; c++) {
                if (k > 0 && !(i == 1 && k == ps / 2)) p[c] += rng.sym(); /* strand 1: a repeated point */
                x[(size_t)((i * ps + k) * 3 + c)] = (T)p[c];
                v[(size_t)((i * ps + k) * 3 + c)] = (T)(50.0 * rng.sym());
            }
        }
    }
    /* the port reads the layout its variant keeps */
    std::vector<T> xl(x.size()), vl(v.size());
    const Layout lay = point_major ? Layout{1, n, n * ps} : Layout{3 * ps, 3, 1};
    for (int64_t i = 0; i < n; i++)
        for (int64_t k = 0; k < ps; k++)
            for (int c = 0; c < 3; c++) {
                const int64_t at = i * lay.is + k * lay.ks + (int64_t)c * lay.cs;
                xl[(size_t)at] = x[(size_t)((i * ps + k) * 3 + c)];
                vl[(size_t)at] = v[(size_t)((i * ps + k) * 3 + c)];
            }
    std::vector<T> want((size_t)(pr * 3)), wantv(want.size());
    long bad = 0;
    for (int64_t i = 0; i < n; i++) {
        const T *xi = x.data() + i * ps * 3;
        strand_c(xi, xi, ps, pr, want.data());
        strand_c(xi, v.data() + i * ps * 3, ps, pr, wantv.data());
        for (int64_t j = 0; j < pr; j++) {
            T got[3], gotv[3];
            lod_render_point(xl.data(), xl.data(), lay, i, ps, pr, j, got);
            lod_render_point(xl.data(), vl.data(), lay, i, ps, pr, j, gotv);
            bad += memcmp(got, want.data() + 3 * j, sizeof got) != 0;
            bad += memcmp(gotv, wantv.data() + 3 * j, sizeof gotv) != 0;
        }
    }
    g_cases++;
    if (bad) {
        g_mismatch++;
        printf("MISMATCH %s P_s=%lld m=%lld %s: %ld points\n", sizeof(T) == 4 ? "fp32" : "fp64", (long long)ps,
               (long long)m, point_major ? "point-major" : "canonical", bad);
    }
}

} /* namespace */

int main()
{
    Rng rng{0x9e3779b97f4a7c15ull};
    const int64_t ps_list[] = {2, 3, 8, 17}, m_list[] = {2, 3, 5};
    for (int64_t ps : ps_list)
        for (int64_t m : m_list)
            for (int pm = 0; pm < 2; pm++) {
                run_case<float>(rng, 12, ps, m, pm != 0);
                run_case<double>(rng, 12, ps, m, pm != 0);
            }
    printf("lod host check: %ld cases, %ld mismatches (%s)\n", g_cases, g_mismatch,
           g_mismatch ? "DIFFERENT" : "all identical");
    return g_mismatch ? 1 : 0;
}
