/* paper_hostcheck.cu — runs the CUDA port's model (cuda/paper/model.cuh, __host__ __device__) on
 * the HOST against the C reference (c_ref/paper/model.c).
 *
 * Built twice (tests/test_cuda_port_host.py):
 *   - with -DHB_REFERENCE_ARITHMETIC=1 (the strict build's arithmetic): bit for bit. On the
 *     host the templates call glibc's sinf/cosf/asinf/atan2f (sin/… for double), exactly as
 *     model.c does, so any difference is a porting, layout or indexing bug;
 *   - without it (the normal build's free arithmetic): every point within the paper
 *     model's tolerance of the reference (the fp32↔fp32 and fp64↔fp64 pairs of
 *     harness/tolerances.py, passed on the command line; roots are bit-identical here, so
 *     u = ε·P·(R + h + L)), collide's moved counts within MOVED_COUNT_FRACTION, and the
 *     port's layouts, prefetch depths and fused/unfused walks bit-identical to each other.
 *     The worst error (in u) of each precision is printed.
 *
 * No kernel is launched, so it runs on a machine without a GPU. Both layouts (StrandMajor =
 * canonical [N][P][3], PointMajor = X, Y, Z [P][N]), fp32 and fp64, several P and scenes,
 * every stage, the fused wind+collide with and without the kept intermediate, the prefetch
 * depths D = 0 … 4 of the walks (paper/model.cuh walk_points; 0 and 1 are built into the kernels,
 * 2 to 4 catch queue-boundary bugs); each stage starts from the reference's previous frame
 * (per stage) and the port's own chain is compared too. Point-major wind/collide/fused
 * (without the intermediate) must not write x: X is poisoned with a NaN pattern first and
 * must come back untouched.
 *
 * Built by `make hostcheck` twice (build/hostcheck/paper_hostcheck_{reference,free}, with and
 * without -DHB_REFERENCE_ARITHMETIC=1), run by tests/native/test_cuda_port_host.py.
 * Usage: paper_hostcheck [N [k32 over32 k64 over64 moved]]   (default 2000 strands; the
 * tolerances only for the free arithmetic). Exit status 0 = all checks pass.
 */
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <map>
#include <string>
#include <vector>

#include "paper/model.cuh"
#include "paper/model.h"
#include "runtime/params.h"

using hb::Model;
using hb::PointMajor;
using hb::StrandMajor;

namespace {

/* ---- the C reference, overloaded on the model type ---------------------------------------- */
void ref_init(const hb_model_f32 *m, uint64_t i, float *s)
{
    hb_init_strand_f32(m, i, s);
}
void ref_init(const hb_model_f64 *m, uint64_t i, double *s)
{
    hb_init_strand_f64(m, i, s);
}
void ref_drape(const hb_model_f32 *m, float *s)
{
    hb_drape_strand_f32(m, s);
}
void ref_drape(const hb_model_f64 *m, double *s)
{
    hb_drape_strand_f64(m, s);
}
void ref_wind(const hb_model_f32 *m, float *s)
{
    hb_wind_strand_f32(m, s);
}
void ref_wind(const hb_model_f64 *m, double *s)
{
    hb_wind_strand_f64(m, s);
}
int64_t ref_collide(const hb_model_f32 *m, float *s)
{
    return hb_collide_strand_f32(m, s);
}
int64_t ref_collide(const hb_model_f64 *m, double *s)
{
    return hb_collide_strand_f64(m, s);
}

template <typename T> struct CModel;
template <> struct CModel<float> {
    typedef hb_model_f32 type;
};
template <> struct CModel<double> {
    typedef hb_model_f64 type;
};

/* backend_cpu.c's round_scene */
void round_scene(const hb_scene *s, hb_model_f32 *m32, hb_model_f64 *m64)
{
    const hb_model_f64 d = {s->seed,          s->points,
                            s->head_radius,   s->hair_offset,
                            s->face_margin,   hb_segment_length(s),
                            s->wind_strength, hb_wind_angle_reduced(s)};
    const hb_model_f32 f = {s->seed,
                            s->points,
                            (float)d.head_radius,
                            (float)d.hair_offset,
                            (float)d.face_margin,
                            (float)d.seg_len,
                            (float)d.wind_strength,
                            (float)d.wind_angle};
    *m64 = d;
    *m32 = f;
}
void pick(const hb_model_f32 &a, const hb_model_f64 &, hb_model_f32 *out)
{
    *out = a;
}
void pick(const hb_model_f32 &, const hb_model_f64 &b, hb_model_f64 *out)
{
    *out = b;
}

/* ---- the port's layouts in host memory ----------------------------------------------------- */
template <typename T> struct StrandBuf {
    static const char *name() { return "strand-major"; }
    int64_t N, P;
    std::vector<T> s;
    StrandBuf(int64_t n, int64_t p) : N(n), P(p), s((size_t)(n * p * 3)) {}
    StrandMajor<T> lay() { return StrandMajor<T>{s.data(), P}; }
    void load(const std::vector<T> &c) { s = c; }
    std::vector<T> canonical() const { return s; }
    void poison_x() {}
    bool x_untouched() const { return true; }
};

/* a NaN whose payload the model never produces */
template <typename T> T poison();
template <> float poison<float>()
{
    uint32_t u = 0x7fc0beefu;
    float f;
    memcpy(&f, &u, sizeof f);
    return f;
}
template <> double poison<double>()
{
    uint64_t u = 0x7ff80000deadbeefull;
    double d;
    memcpy(&d, &u, sizeof d);
    return d;
}

template <typename T> struct PointBuf {
    static const char *name() { return "point-major"; }
    int64_t N, P;
    std::vector<T> a; /* X | Y | Z, each [P][N] */
    PointBuf(int64_t n, int64_t p) : N(n), P(p), a((size_t)(3 * n * p)) {}
    T *X() { return a.data(); }
    T *Y() { return a.data() + N * P; }
    T *Z() { return a.data() + 2 * N * P; }
    PointMajor<T> lay() { return PointMajor<T>{X(), Y(), Z(), N}; }
    void load(const std::vector<T> &c)
    {
        for (int64_t i = 0; i < N; i++)
            for (int64_t k = 0; k < P; k++) {
                X()[k * N + i] = c[(size_t)((i * P + k) * 3 + 0)];
                Y()[k * N + i] = c[(size_t)((i * P + k) * 3 + 1)];
                Z()[k * N + i] = c[(size_t)((i * P + k) * 3 + 2)];
            }
    }
    std::vector<T> canonical() const
    {
        std::vector<T> c((size_t)(N * P * 3));
        const T *x = a.data(), *y = a.data() + N * P, *z = a.data() + 2 * N * P;
        for (int64_t i = 0; i < N; i++)
            for (int64_t k = 0; k < P; k++) {
                c[(size_t)((i * P + k) * 3 + 0)] = x[k * N + i];
                c[(size_t)((i * P + k) * 3 + 1)] = y[k * N + i];
                c[(size_t)((i * P + k) * 3 + 2)] = z[k * N + i];
            }
        return c;
    }
    void poison_x()
    {
        const T p = poison<T>();
        for (int64_t e = 0; e < N * P; e++) X()[e] = p;
    }
    bool x_untouched() const
    {
        const T p = poison<T>();
        return memcmp(a.data(), std::vector<T>((size_t)(N * P), p).data(), sizeof(T) * (size_t)(N * P)) == 0;
    }
};

/* ---- bookkeeping ------------------------------------------------------------------------------ */
struct Tally {
    long checks = 0, failures = 0;
    long long moved = 0; /* points the reference's collide passes changed (coverage) */
};

/* The free arithmetic's tolerances (harness/tolerances.py, from the command line) and the
 * scale of the case being checked. */
struct FreeRule {
    double k[2] = {6.0, 4.0};          /* point_k: fp32, fp64 */
    double over[2] = {1e-5, 0.0};      /* max_over_fraction: fp32, fp64 */
    double moved = 1e-3;               /* MOVED_COUNT_FRACTION */
    double extent = 0.0;               /* R + h + L of the case */
    double worst[2] = {0.0, 0.0};      /* the worst error seen, in u */
    double case_worst = 0.0;           /* the worst error of the current case, in u */
    long long over_points[2] = {0, 0}; /* points over point_k·u, all cases */
    /* the port's own output of each check, keyed without the layout and depth: all
     * layouts, depths and walks must agree with each other bit for bit */
    std::map<std::string, std::vector<char>> first;
};
FreeRule g_free;

template <typename T> long mismatches(const std::vector<T> &a, const std::vector<T> &b, long *first)
{
    long n = 0;
    *first = -1;
    for (size_t e = 0; e < a.size(); e++)
        if (memcmp(&a[e], &b[e], sizeof(T)) != 0) {
            if (n == 0) *first = (long)e;
            n++;
        }
    return n;
}

/* canonical arrays of P points a strand; `same` = the check's name without the layout and
 * depth (free arithmetic: the port's outputs of one check must be bit-identical) */
template <typename T>
void expect(Tally &t, const std::string &what, const std::vector<T> &got, const std::vector<T> &want, int64_t P,
            const std::string &same = "")
{
    t.checks++;
    if (hb::kFree && !same.empty()) {
        std::vector<char> bytes((const char *)got.data(), (const char *)(got.data() + got.size()));
        auto it = g_free.first.find(same);
        if (it == g_free.first.end()) g_free.first.emplace(same, std::move(bytes));
        else if (it->second != bytes) {
            t.failures++;
            printf("MISMATCH %s: differs from the port's other layouts/depths (free arithmetic)\n", what.c_str());
        }
    }
    if (hb::kFree) {
        const int p = sizeof(T) == 4 ? 0 : 1;
        const double eps = sizeof(T) == 4 ? 0x1p-23 : 0x1p-52;
        const double u = eps * (double)P * g_free.extent;
        const size_t points = got.size() / 3;
        long over = 0, first = -1;
        double worst = 0.0;
        for (size_t q = 0; q < points; q++) {
            double d2 = 0.0;
            bool finite = true;
            for (int c = 0; c < 3; c++) {
                const double a = (double)got[3 * q + c], b = (double)want[3 * q + c];
                finite = finite && std::isfinite(a) && std::isfinite(b);
                d2 += (a - b) * (a - b);
            }
            const double k = sqrt(d2) / u;
            if (!finite || !(k <= g_free.k[p])) {
                if (over == 0) first = (long)q;
                over++;
            }
            if (finite && k > worst) worst = k;
        }
        if (worst > g_free.worst[p]) g_free.worst[p] = worst;
        if (worst > g_free.case_worst) g_free.case_worst = worst;
        g_free.over_points[p] += over;
        if ((double)over > g_free.over[p] * (double)points) {
            t.failures++;
            printf("MISMATCH %s: %ld of %zu points farther than %.1f u from the reference (worst %.2f u); "
                   "first: strand %lld, point %lld\n",
                   what.c_str(), over, points, g_free.k[p], worst, (long long)(first / P), (long long)(first % P));
        }
        return;
    }
    long first;
    const long n = mismatches(got, want, &first);
    if (n) {
        t.failures++;
        printf("MISMATCH %s: %ld of %zu values differ; first: strand %lld, point %lld, coordinate %ld: "
               "got %.17g, reference %.17g\n",
               what.c_str(), n, want.size(), (long long)(first / (3 * P)), (long long)((first / 3) % P), first % 3,
               (double)got[(size_t)first], (double)want[(size_t)first]);
    }
}

/* moved-point counts; the free arithmetic may differ by MOVED_COUNT_FRACTION of the points */
void expect_count(Tally &t, const std::string &what, int64_t got, int64_t want, int64_t points)
{
    t.checks++;
    const double allowed = hb::kFree ? g_free.moved * (double)points : 0.0;
    if ((double)llabs(got - want) > allowed) {
        t.failures++;
        printf("MISMATCH %s: moved-point count %lld, reference %lld\n", what.c_str(), (long long)got, (long long)want);
    }
}

void expect_true(Tally &t, const std::string &what, bool ok)
{
    t.checks++;
    if (!ok) {
        t.failures++;
        printf("MISMATCH %s\n", what.c_str());
    }
}

/* ---- the port's stages over all strands ------------------------------------------------------ */
template <typename T, class Buf> void port_init(const Model<T> &m, Buf &b)
{
    const auto lay = b.lay();
    for (int64_t i = 0; i < b.N; i++) hb::init_strand(m, lay, i);
}
template <typename T, class Buf> void port_drape(const Model<T> &m, Buf &b)
{
    const auto lay = b.lay();
    for (int64_t i = 0; i < b.N; i++) hb::drape_strand(m, lay, i);
}
template <int D, typename T, class Buf> void port_wind(const Model<T> &m, Buf &b)
{
    const auto lay = b.lay();
    for (int64_t i = 0; i < b.N; i++) hb::wind_strand<D>(m, lay, i);
}
template <int D, typename T, class Buf> int64_t port_collide(const Model<T> &m, Buf &b)
{
    const auto lay = b.lay();
    int64_t n = 0;
    for (int64_t i = 0; i < b.N; i++) n += hb::collide_strand<D>(m, lay, i);
    return n;
}
template <bool Keep, int D, typename T, class Buf> int64_t port_fused(const Model<T> &m, Buf &b, std::vector<T> *inter)
{
    const auto lay = b.lay();
    const StrandMajor<T> keep = {inter ? inter->data() : nullptr, b.P};
    int64_t n = 0;
    for (int64_t i = 0; i < b.N; i++) n += hb::wind_collide_strand<Keep, D>(m, lay, i, keep);
    return n;
}

/* ---- one (precision, P, scene) case ----------------------------------------------------------- */
/* D: the prefetch depth of the walks (paper/model.cuh walk_points; kernels use 0, 2 and 4) */
template <typename T, class Buf, int D>
void check_layout(Tally &t, const std::string &tag, const Model<T> &m, int64_t N, int64_t P,
                  const std::vector<std::vector<T>> &f, const int64_t *moved)
{
    /* f[0] init, f[1] collide, f[2] wind, f[3] collide, f[4] wind, f[5] collide;
     * moved[j] = the reference's count for the collide frame j */
    const std::string at = tag + " " + Buf::name() + " D=" + std::to_string(D);
    const int64_t NP = N * P;
    /* the name of a check without the layout and depth (free arithmetic: same bits) */
    auto same = [&](const std::string &what) { return tag + " " + what.substr(at.size()); };
    Buf b(N, P);

    port_init(m, b);
    expect(t, at + " init", b.canonical(), f[0], P, same(at + " init"));

    /* drape alone, from the roots of f[0] (every other point poisoned first) */
    std::vector<T> roots = f[0];
    for (int64_t i = 0; i < N; i++)
        for (int64_t e = 3; e < 3 * P; e++) roots[(size_t)(i * 3 * P + e)] = poison<T>();
    b.load(roots);
    port_drape(m, b);
    expect(t, at + " drape", b.canonical(), f[0], P, same(at + " init"));

    for (int j = 1; j <= 5; j++) {
        b.load(f[j - 1]);
        b.poison_x();
        std::string what = at + (j % 2 ? " collide" : " wind") + " (frame " + std::to_string(j) + ")";
        if (j % 2) expect_count(t, what, port_collide<D>(m, b), moved[j], NP);
        else port_wind<D>(m, b);
        expect_true(t, what + ": x left untouched", b.x_untouched());
        b.load(f[j - 1]); /* x back for the comparison: the stage must not have written it */
        if (j % 2) port_collide<D>(m, b);
        else port_wind<D>(m, b);
        expect(t, what, b.canonical(), f[j], P, same(what));
    }

    for (int j = 2; j <= 4; j += 2) {
        const std::string what =
            at + " fused wind+collide (frames " + std::to_string(j) + "," + std::to_string(j + 1) + ")";
        /* with the intermediate: x is read (and copied), not written */
        std::vector<T> inter((size_t)(N * P * 3), poison<T>());
        b.load(f[j - 1]);
        expect_count(t, what + " kept", port_fused<true, D>(m, b, &inter), moved[j + 1], NP);
        /* the fused walk is the wind then the collide walk: the separate stages' bits */
        expect(t, what + " kept: intermediate", inter, f[j], P, same(at + " wind (frame " + std::to_string(j) + ")"));
        const std::string fused_result = same(what + ": result");
        expect(t, what + " kept: result", b.canonical(), f[j + 1], P, fused_result);
        /* without it: x is neither read nor written */
        b.load(f[j - 1]);
        b.poison_x();
        expect_count(t, what, port_fused<false, D>(m, b, (std::vector<T> *)nullptr), moved[j + 1], NP);
        expect_true(t, what + ": x left untouched", b.x_untouched());
        b.load(f[j - 1]);
        port_fused<false, D>(m, b, (std::vector<T> *)nullptr);
        expect(t, what + ": result", b.canonical(), f[j + 1], P, fused_result);
    }

    /* the port's own chain, init through the last collide, fused and unfused */
    Buf c(N, P);
    port_init(m, c);
    int64_t n1 = port_collide<D>(m, c);
    port_wind<D>(m, c);
    int64_t n3 = port_collide<D>(m, c);
    const std::string chain = at + " chain init,collide,wind,collide";
    expect(t, chain, c.canonical(), f[3], P, same(chain));
    expect_count(t, at + " chain collide 1", n1, moved[1], NP);
    expect_count(t, at + " chain collide 3", n3, moved[3], NP);
    int64_t n5 = port_fused<false, D>(m, c, (std::vector<T> *)nullptr);
    const std::string chain5 = at + " chain +fused wind,collide";
    expect(t, chain5, c.canonical(), f[5], P, same(chain5));
    expect_count(t, at + " chain fused 5", n5, moved[5], NP);
}

template <typename T> void check_case(Tally &t, const hb_scene &scene, const char *scene_name)
{
    hb_model_f32 m32;
    hb_model_f64 m64;
    round_scene(&scene, &m32, &m64);
    typename CModel<T>::type cm;
    pick(m32, m64, &cm);
    const Model<T> m = hb::model_from<typename CModel<T>::type, T>(cm);
    const int64_t N = scene.n_strands, P = scene.points;
    const size_t stride = (size_t)P * 3;
    g_free.extent = scene.head_radius + scene.hair_offset + scene.hair_length;

    /* the reference frames */
    std::vector<std::vector<T>> f(6, std::vector<T>((size_t)(N * P * 3)));
    int64_t moved[6] = {-1, 0, -1, 0, -1, 0};
    for (int64_t i = 0; i < N; i++) ref_init(&cm, (uint64_t)i, f[0].data() + (size_t)i * stride);
    {
        /* the reference's own drape reproduces its init from the roots */
        std::vector<T> d = f[0];
        for (int64_t i = 0; i < N; i++) ref_drape(&cm, d.data() + (size_t)i * stride);
        long first;
        expect_true(t, "reference drape vs init", mismatches(d, f[0], &first) == 0);
    }
    for (int j = 1; j <= 5; j++) {
        f[j] = f[j - 1];
        for (int64_t i = 0; i < N; i++) {
            T *s = f[j].data() + (size_t)i * stride;
            if (j % 2) moved[j] += ref_collide(&cm, s);
            else ref_wind(&cm, s);
        }
    }
    for (int j = 1; j <= 5; j += 2) t.moved += moved[j];

    char tag[160];
    snprintf(tag, sizeof tag, "%s P=%lld scene=%s", sizeof(T) == 4 ? "fp32" : "fp64", (long long)P, scene_name);
    const long before = t.failures;
    g_free.case_worst = 0.0;
    check_layout<T, StrandBuf<T>, 0>(t, tag, m, N, P, f, moved);
    check_layout<T, PointBuf<T>, 0>(t, tag, m, N, P, f, moved);
    check_layout<T, StrandBuf<T>, 1>(t, tag, m, N, P, f, moved);
    check_layout<T, PointBuf<T>, 1>(t, tag, m, N, P, f, moved);
    check_layout<T, PointBuf<T>, 2>(t, tag, m, N, P, f, moved);
    check_layout<T, PointBuf<T>, 3>(t, tag, m, N, P, f, moved);
    check_layout<T, PointBuf<T>, 4>(t, tag, m, N, P, f, moved);
    char worst[64] = "";
    if (hb::kFree) snprintf(worst, sizeof worst, ", worst %.3f u", g_free.case_worst);
    printf("%-48s %s  (reference collide moved %lld, %lld, %lld points%s)\n", tag,
           t.failures == before ? (hb::kFree ? "within tolerance" : "identical") : "MISMATCH", (long long)moved[1],
           (long long)moved[3], (long long)moved[5], worst);
}

struct SceneDef {
    const char *name;
    double R, h, L, m, w, psi;
};

} /* namespace */

int main(int argc, char **argv)
{
    const int64_t N = argc > 1 ? atoll(argv[1]) : 2000;
    if (N < 1 || (argc != 1 && argc != 2 && argc != 7)) {
        fprintf(stderr, "usage: %s [strands [k_fp32 over_fp32 k_fp64 over_fp64 moved_fraction]]\n", argv[0]);
        return 2;
    }
    if (argc == 7) {
        g_free.k[0] = atof(argv[2]);
        g_free.over[0] = atof(argv[3]);
        g_free.k[1] = atof(argv[4]);
        g_free.over[1] = atof(argv[5]);
        g_free.moved = atof(argv[6]);
    }
    const double pi = 3.14159265358979323846;
    const SceneDef scenes[] = {
        /* the CLI defaults: wind from the face toward the back */
        {"default", 10.0, 0.1, 30.0, 1.0, 0.5, pi},
        /* a small head, long hair, a full-strength downward wind: many collisions */
        {"down-wind", 2.0, 0.3, 40.0, 3.0, 1.0, -pi / 2},
        /* an upward wind: hanging segments (pointing straight down) are exactly opposite */
        {"up-wind", 10.0, 0.1, 30.0, 1.0, 0.8, pi / 2},
        /* a wind toward the face and a large margin */
        {"face-wind", 10.0, 0.2, 25.0, 6.0, 0.3, 0.3 - 8 * pi},
    };
    const int64_t Ps[] = {2, 3, 16, 64};
    Tally t;
    for (const SceneDef &sd : scenes)
        for (int64_t P : Ps) {
            hb_scene s;
            memset(&s, 0, sizeof s);
            s.n_strands = N;
            s.points = P;
            s.seed = 0x5eed0000u + (uint64_t)P;
            s.head_radius = sd.R;
            s.hair_offset = sd.h;
            s.hair_length = sd.L;
            s.face_margin = sd.m;
            s.wind_strength = sd.w;
            s.wind_angle = sd.psi;
            char err[256];
            s.precision = HB_FP32;
            if (hb_scene_validate(&s, err, sizeof err) != 0) {
                printf("bad scene %s P=%lld: %s\n", sd.name, (long long)P, err);
                return 2;
            }
            check_case<float>(t, s, sd.name);
            s.precision = HB_FP64;
            check_case<double>(t, s, sd.name);
        }
    if (hb::kFree)
        printf("free arithmetic against the reference: worst %.3f u fp32 (tolerance %.1f u), %.3f u fp64 (tolerance "
               "%.1f u); %lld and %lld points over\n",
               g_free.worst[0], g_free.k[0], g_free.worst[1], g_free.k[1], g_free.over_points[0],
               g_free.over_points[1]);
    printf("host check (%s arithmetic): %ld comparisons, %ld mismatches (%lld strands a case, reference collide moved "
           "%lld points "
           "in all)\n",
           hb::kFree ? "free" : "reference", t.checks, t.failures, (long long)N, t.moved);
    if (t.moved == 0) {
        printf("host check: the collide paths were never exercised\n");
        return 1;
    }
    return t.failures ? 1 : 0;
}
