/* dyn_hostcheck.cu — runs the CUDA port's dynamic model (cuda/dynamic/model.cuh,
 * __host__ __device__) on the HOST and compares it bit for bit with the C reference
 * (c_ref/dynamic/dynamics_impl.h via dynamics_f32.c / dynamics_f64.c).
 *
 * No kernel is launched, so it runs on a machine without a GPU. On the host the templates
 * call glibc's sqrtf/sinf (sqrt/sin), as the C reference does, so any difference is a
 * porting, layout, indexing or ordering bug. On the device, sinf/sin may differ from glibc
 * (gust frames only) and the normal build contracts FMAs: the GPU tests
 * (tests/gpu/test_gpu_dynamic.py) cover that.
 *
 * Every valid feature set (96) x both solvers x fp32 and fp64 x P in {2, 3, 5, 8, 33, 70},
 * two frames each (the second from the port's own first frame), in the three ways the
 * kernels run the math:
 *   seq-canonical   Exec Seq, canonical layout, scratch contiguous (the C reference's own);
 *   strand          Exec Seq, point-major X|Y|Z [P][N] with the thread-interleaved scratch of
 *                   the strand kernel (cuda/dynamic/kernels.cu k_strand);
 *   warp            a host emulation of the warp kernel's Lanes: the component planes [3][P]
 *                   of its shared memory, every `each` loop run lane by lane in reverse lane
 *                   order (lane 31 first), so a group whose members were not independent
 *                   would show it.
 * Each with the feature set as a compile-time constant where the device build specialises
 * it (cuda/dynamic/kernels.cuh specialised_mask) and always as the run-time mask (DynF, the generic
 * kernel). Also the bend rest lengths and the per-strand observables (hb_dyn_observe_strand).
 *
 * Built by `make hostcheck` (build/hostcheck/dyn_hostcheck, against the reference's objects),
 * run by tests/native/test_cuda_dyn_host.py.
 * Exit status 0 = all identical; the last line counts the cases and mismatches.
 */
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <utility>
#include <vector>

#include "dynamic/kernels.cuh"
#include "dynamic/model.cuh"
#include "dynamic/dynamics.h"
#include "hostcheck/hostcheck_scene.h"
#include "runtime/params.h"

using namespace hb::dyn;

namespace {

/* ---- the C reference, overloaded on T ---- */
void ref_frame(const hb_dyn_model_f32 *m, const hb_dyn_frame *f, float *x, float *v, const float *r, const float *b,
               float *s)
{
    hb_dyn_frame_strand_f32(m, NULL, f, 0, f->substeps, x, v, r, b, NULL, s, NULL);
}
void ref_frame(const hb_dyn_model_f64 *m, const hb_dyn_frame *f, double *x, double *v, const double *r, const double *b,
               double *s)
{
    hb_dyn_frame_strand_f64(m, NULL, f, 0, f->substeps, x, v, r, b, NULL, s, NULL);
}
void ref_bend(const hb_dyn_model_f32 *m, const float *r, float *b)
{
    hb_dyn_bend_rest_f32(m, r, b);
}
void ref_bend(const hb_dyn_model_f64 *m, const double *r, double *b)
{
    hb_dyn_bend_rest_f64(m, r, b);
}
void ref_obs(const hb_scene *s, const float *x, const float *v, hb_obs_partial *o)
{
    hb_dyn_observe_strand_f32(s, NULL, NULL, x, v, NULL, o);
}
void ref_obs(const hb_scene *s, const double *x, const double *v, hb_obs_partial *o)
{
    hb_dyn_observe_strand_f64(s, NULL, NULL, x, v, NULL, o);
}
template <typename T> struct CM;
template <> struct CM<float> {
    typedef hb_dyn_model_f32 type;
    static const type &pick(const hb_dyn_model_f32 &a, const hb_dyn_model_f64 &) { return a; }
    static const float *q(const hb_dyn_frame &f) { return f.q32; }
    static const float *ph(const hb_dyn_frame &f) { return f.phase32; }
};
template <> struct CM<double> {
    typedef hb_dyn_model_f64 type;
    static const type &pick(const hb_dyn_model_f32 &, const hb_dyn_model_f64 &b) { return b; }
    static const double *q(const hb_dyn_frame &f) { return f.q64; }
    static const double *ph(const hb_dyn_frame &f) { return f.phase64; }
};

/* The warp kernel's Lanes on one host thread: lane 31 first, each lane its strided share. */
struct HostLanes {
    template <class Fn> HB_DHD void each(int64_t b, int64_t e, int64_t step, Fn f) const
    {
        for (int lane = 31; lane >= 0; lane--)
            for (int64_t k = b + (int64_t)lane * step; k < e; k += 32 * step) f(k);
    }
    template <class Fn> HB_DHD void one(Fn f) const { f(); }
};

/* a small deterministic generator (no libc rand: the same numbers everywhere) */
struct Rng {
    uint64_t s;
    double u()
    {
        s = s * 6364136223846793005ull + 1442695040888963407ull;
        return (double)(s >> 11) * 0x1p-53;
    }
    double sym() { return 2.0 * u() - 1.0; }
};

hb_scene make_scene(unsigned F, int solver, int64_t N, int64_t P, int precision, int variant)
{
    hb_scene s = hostcheck_scene(N, P, 3.0 * (double)(P - 1) / 4.0 + 1.0, precision ? HB_FP64 : HB_FP32);
    s.seed = 7;
    s.hair_offset = 0.1;
    s.face_margin = 1.0;
    s.wind_strength = 0.0;
    s.wind_angle = 0.7 + 0.3 * variant;
    hb_dynamics *d = &s.dyn;
    d->frame_dt = 1.0 / 60.0;
    d->substeps = 4;
    d->iterations = 3;
    d->solver = solver ? HB_SOLVER_FTL : HB_SOLVER_XPBD;
    d->gravity = 981.0;
    d->stretch_compliance = variant % 2 ? 1e-7 : 0.0;
    d->bend = (F & HB_F_BEND) != 0;
    d->bend_compliance = 1e-6;
    d->shape = (F & HB_F_SHAPE) != 0;
    d->shape_compliance = 1e-5;
    d->shape_range = 0.6;
    d->ftl_damping = 0.9;
    d->collider = (F & HB_F_COLLIDE) != 0;
    d->collision_margin = 0.05;
    d->drag_declared = (F & HB_F_DRAG) != 0;
    d->drag = (F & HB_F_WIND) ? 2.5 : 0.0;
    d->damping = (F & HB_F_DRAG) ? 0.7 : 0.0;
    d->wind_speed = (F & HB_F_WIND) ? 300.0 : 0.0;
    d->gust_amplitude = (F & HB_F_GUST) ? 0.6 : 0.0;
    d->gust_frequency = 1.7;
    d->gust_wavelength = 23.0;
    d->motion = (F & HB_F_MOTION) ? (hb_motion)(1 + variant % 3) : HB_MOTION_STILL;
    d->motion_amplitude = 0.4;
    d->motion_frequency = 1.3;
    d->lra = variant % 3 == 1; /* docs/model.md §3.14, a run-time switch: on in a third of the cases */
    d->lra_scale = 1.0 + 0.01 * (double)(variant % 2);
    return s;
}

/* Rest shapes and states: roots on the head, strands wandering outward, points within a
 * segment of the rest shape (some inside the collider), random velocities; strand 1 has two
 * coincident points with equal velocities (the zero-length branches). */
template <typename T>
void make_state(const hb_scene &s, uint64_t seed, std::vector<T> &rest, std::vector<T> &x, std::vector<T> &v)
{
    const int64_t N = s.n_strands, P = s.points;
    const double ell = hb_segment_length(&s), R = s.head_radius;
    Rng g{seed * 0x9e3779b97f4a7c15ull + 1};
    rest.assign((size_t)(N * P * 3), 0);
    x = rest;
    v = rest;
    for (int64_t i = 0; i < N; i++) {
        double dir[3] = {g.sym(), 0.3 + g.u(), g.sym()};
        double n = sqrt(dir[0] * dir[0] + dir[1] * dir[1] + dir[2] * dir[2]);
        double p[3];
        for (int c = 0; c < 3; c++) p[c] = R * dir[c] / n;
        for (int64_t k = 0; k < P; k++) {
            if (k > 0) {
                double t[3] = {dir[0] / n + 0.6 * g.sym(), dir[1] / n - 0.5 + 0.6 * g.sym(),
                               dir[2] / n + 0.6 * g.sym()};
                double tn = sqrt(t[0] * t[0] + t[1] * t[1] + t[2] * t[2]);
                for (int c = 0; c < 3; c++) p[c] += ell * t[c] / tn;
            }
            for (int c = 0; c < 3; c++) {
                const size_t e = (size_t)((i * P + k) * 3 + c);
                rest[e] = (T)p[c];
                x[e] = k == 0 ? rest[e] : (T)(p[c] + 0.4 * ell * g.sym());
                v[e] = k == 0 ? (T)0 : (T)(60.0 * g.sym());
            }
        }
        if (i == 1 && P >= 3)
            for (int c = 0; c < 3; c++) {
                x[(size_t)((i * P + 2) * 3 + c)] = x[(size_t)((i * P + 1) * 3 + c)];
                v[(size_t)((i * P + 2) * 3 + c)] = v[(size_t)((i * P + 1) * 3 + c)];
            }
    }
}

long g_cases = 0, g_mismatch = 0;

template <typename T> bool same_bits(const std::vector<T> &a, const std::vector<T> &b)
{
    return a.size() == b.size() && memcmp(a.data(), b.data(), a.size() * sizeof(T)) == 0;
}

void report(bool ok, const char *what, unsigned F, int solver, int64_t P, const char *prec, const char *feat)
{
    g_cases++;
    if (!ok) {
        g_mismatch++;
        printf("MISMATCH %s: features %u (%s), solver %s, P %lld, %s\n", what, F, feat, solver ? "ftl" : "xpbd",
               (long long)P, prec);
    }
}

/* One way of running the port over all strands of a canonical state, in place. */
enum Mode { SEQ_CANONICAL = 0, STRAND = 1, WARP = 2 };

template <typename T, class Feat>
void port_frames(Mode mode, Feat has, const DModel<T> &m, const T *q, const T *ph, int64_t N, int64_t P,
                 std::vector<T> &x, std::vector<T> &v, const std::vector<T> &rest, const std::vector<T> &br)
{
    const int64_t NP = N * P, P3 = 3 * P, B = P - 2 > 0 ? P - 2 : 0;
    if (mode == SEQ_CANONICAL) {
        std::vector<T> scratch((size_t)(9 * P));
        for (int64_t i = 0; i < N; i++) {
            Strand<T> s;
            s.x = Arr<T>{x.data() + i * P3, 3, 1};
            s.v = Arr<T>{v.data() + i * P3, 3, 1};
            s.rest = Arr<const T>{rest.data() + i * P3, 3, 1};
            s.bend_rest = Arr1<const T>{br.data() + i * B, 1};
            s.p = Arr<T>{scratch.data(), 3, 1};
            s.lam = Arr1<T>{scratch.data() + 3 * P, 1};
            s.d = Arr<T>{scratch.data() + 6 * P, 3, 1};
            frame_body(m, q, ph, s, Seq(), has);
        }
    } else if (mode == STRAND) {
        /* point-major state, bend [P−2][N], scratch interleaved over nt = 3 "threads" */
        auto pm = [&](const std::vector<T> &c) {
            std::vector<T> o((size_t)(3 * NP));
            for (int64_t i = 0; i < N; i++)
                for (int64_t k = 0; k < P; k++)
                    for (int c2 = 0; c2 < 3; c2++) o[(size_t)(c2 * NP + k * N + i)] = c[(size_t)(i * P3 + 3 * k + c2)];
            return o;
        };
        std::vector<T> X = pm(x), V = pm(v), Rr = pm(rest), Br((size_t)(B * N + 1));
        for (int64_t i = 0; i < N; i++)
            for (int64_t j = 0; j < B; j++) Br[(size_t)(j * N + i)] = br[(size_t)(i * B + j)];
        const int64_t nt = 3;
        std::vector<T> scratch((size_t)(9 * P * nt), (T)12345);
        for (int64_t t = 0; t < nt; t++)
            for (int64_t i = t; i < N; i += nt) {
                Strand<T> s;
                s.p = Arr<T>{scratch.data() + t, nt, P * nt};
                s.lam = Arr1<T>{scratch.data() + 3 * P * nt + t, nt};
                s.d = Arr<T>{scratch.data() + 6 * P * nt + t, nt, P * nt};
                s.x = Arr<T>{X.data() + i, N, NP};
                s.v = Arr<T>{V.data() + i, N, NP};
                s.rest = Arr<const T>{Rr.data() + i, N, NP};
                s.bend_rest = Arr1<const T>{Br.data() + i, N};
                frame_body(m, q, ph, s, Seq(), has);
            }
        for (int64_t i = 0; i < N; i++)
            for (int64_t k = 0; k < P; k++)
                for (int c2 = 0; c2 < 3; c2++) {
                    x[(size_t)(i * P3 + 3 * k + c2)] = X[(size_t)(c2 * NP + k * N + i)];
                    v[(size_t)(i * P3 + 3 * k + c2)] = V[(size_t)(c2 * NP + k * N + i)];
                }
    } else {
        std::vector<T> sm((size_t)warp_reals<T>(P), (T)-777);
        for (int64_t i = 0; i < N; i++) {
            T *base = sm.data();
            for (int64_t e = 0; e < P3; e++) {
                base[(e % 3) * P + e / 3] = x[(size_t)(i * P3 + e)];
                base[3 * P + (e % 3) * P + e / 3] = v[(size_t)(i * P3 + e)];
            }
            Strand<T> s = warp_strand(base, P);
            s.rest = Arr<const T>{rest.data() + i * P3, 3, 1};
            s.bend_rest = Arr1<const T>{br.data() + i * B, 1};
            frame_body(m, q, ph, s, HostLanes(), has);
            for (int64_t e = 0; e < P3; e++) {
                x[(size_t)(i * P3 + e)] = base[(e % 3) * P + e / 3];
                v[(size_t)(i * P3 + e)] = base[3 * P + (e % 3) * P + e / 3];
            }
        }
    }
}

template <typename T, unsigned F> void check_one(int solver, int64_t P, int variant)
{
    const int64_t N = 7;
    const int fp64 = sizeof(T) == 8;
    const char *prec = fp64 ? "fp64" : "fp32";
    hb_scene s = make_scene(F, solver, N, P, fp64, variant);
    char feat[96];
    hb_dyn_feature_names(hb_dyn_features(&s), feat, sizeof feat);
    if (hb_dyn_features(&s) != F) {
        printf("MISMATCH scene: asked for features %u, the scene has %u (%s)\n", F, hb_dyn_features(&s), feat);
        g_mismatch++;
        return;
    }
    hb_dyn_model_f32 m32;
    hb_dyn_model_f64 m64;
    hb_dyn_round(&s, &m32, &m64);
    const typename CM<T>::type &cm = CM<T>::pick(m32, m64);
    const DModel<T> m = dmodel_from<T>(cm);

    std::vector<T> rest, x0, v0;
    make_state<T>(s, (uint64_t)(F * 131 + solver * 7 + P * 3 + variant), rest, x0, v0);
    const int64_t P3 = 3 * P, B = P - 2 > 0 ? P - 2 : 0;

    /* bend rest lengths */
    std::vector<T> br_ref((size_t)(N * B + 1), 0), br_port((size_t)(N * B + 1), 0);
    for (int64_t i = 0; i < N; i++) {
        ref_bend(&cm, rest.data() + i * P3, br_ref.data() + i * B);
        bend_rest<T>(P, Arr<const T>{rest.data() + i * P3, 3, 1}, Arr1<T>{br_port.data() + i * B, 1});
    }
    report(same_bits(br_ref, br_port), "bend rest lengths", F, solver, P, prec, feat);

    /* reference: two frames */
    hb_dyn_frame fr[2];
    std::vector<T> xr[2], vr[2];
    {
        std::vector<T> x = x0, v = v0, scratch((size_t)(9 * P));
        for (int f = 0; f < 2; f++) {
            if (hb_dyn_frame_alloc(&fr[f], s.dyn.substeps) != 0) {
                printf("MISMATCH out of memory\n");
                exit(2);
            }
            hb_dyn_frame_plan(&s, (int64_t)(5 + f) * s.dyn.substeps, &fr[f]);
            for (int64_t i = 0; i < N; i++)
                ref_frame(&cm, &fr[f], x.data() + i * P3, v.data() + i * P3, rest.data() + i * P3,
                          br_ref.data() + i * B, scratch.data());
            xr[f] = x;
            vr[f] = v;
        }
    }
    /* observables of the reference's last frame */
    {
        const ObsScene os = obs_scene(&s);
        bool ok = true;
        for (int64_t i = 0; i < N; i++) {
            hb_obs_partial a;
            ObsPartial b;
            ref_obs(&s, xr[1].data() + i * P3, vr[1].data() + i * P3, &a);
            observe_strand<T>(os, Arr<const T>{xr[1].data() + i * P3, 3, 1}, Arr<const T>{vr[1].data() + i * P3, 3, 1},
                              &b);
            ok &= memcmp(&a.stretch_max, &b.stretch_max, 8) == 0 &&
                  memcmp(&a.penetration_max, &b.penetration_max, 8) == 0 && memcmp(&a.v2_sum, &b.v2_sum, 8) == 0 &&
                  a.blown == (int64_t)b.blown;
        }
        report(ok, "observables", F, solver, P, prec, feat);
    }

    static const char *const names[] = {"seq-canonical", "strand", "warp"};
    for (int mode = 0; mode < 3; mode++)
        for (int gen = 0; gen < 2; gen++) {
            if (gen == 0 && !specialised_mask(F)) continue;
            std::vector<T> x = x0, v = v0;
            bool ok = true;
            for (int f = 0; f < 2; f++) {
                const T *q = CM<T>::q(fr[f]), *ph = CM<T>::ph(fr[f]);
                if (gen == 1) port_frames<T>((Mode)mode, DynF{F}, m, q, ph, N, P, x, v, rest, br_port);
                else if constexpr (specialised_mask(F)) /* only these are compiled with F constant */
                    port_frames<T>((Mode)mode, StaticF<F>(), m, q, ph, N, P, x, v, rest, br_port);
                ok &= same_bits(x, xr[f]) && same_bits(v, vr[f]);
            }
            char what[96];
            snprintf(what, sizeof what, "frames (%s, %s features)", names[mode], gen == 0 ? "compiled" : "run-time");
            report(ok, what, F, solver, P, prec, feat);
        }
    for (int f = 0; f < 2; f++) hb_dyn_frame_free(&fr[f]);
}

template <typename T, unsigned... Fs>
void check_all(std::integer_sequence<unsigned, Fs...>, int solver, int64_t P, int variant)
{
    ((valid_mask(Fs) ? check_one<T, Fs>(solver, P, variant) : (void)0), ...);
}

} /* namespace */

int main()
{
    static const int64_t Ps[] = {2, 3, 5, 8, 33, 70};
    int variant = 0;
    for (int64_t P : Ps)
        for (int solver = 0; solver < 2; solver++) {
            check_all<float>(std::make_integer_sequence<unsigned, HB_F_COUNT>(), solver, P, variant);
            check_all<double>(std::make_integer_sequence<unsigned, HB_F_COUNT>(), solver, P, variant);
            variant++;
        }
    printf("dyn host check: %ld cases, %ld mismatches%s\n", g_cases, g_mismatch, g_mismatch ? "" : " (all identical)");
    return g_mismatch ? 1 : 0;
}
