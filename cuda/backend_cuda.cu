/* backend_cuda.cu — the CUDA backend (docs/model.md §5.1): the hb_backend the shared driver
 * (c_ref/app/driver.c) runs, and main().
 *
 * Variants (docs/cuda.md):
 *   paper  the paper's scheme, kept as the baseline and not tuned: the canonical
 *          strand-major array [N][P][3] on the device, one thread per strand, init, wind
 *          and collide as separate kernels.
 *   soa    point-major structure of arrays X, Y, Z [P][N] (a warp's strands coalesce),
 *          separate kernels; wind and collide never touch X.
 *   fused  (default) point-major; a wind immediately followed by collide in the stage list
 *          runs as one kernel (run_stage returns consumed = 2).
 *   strand, warp, warpreg  the variants that also run simulate (the dynamic model;
 *          backend_dyn.cu): strand point-major as soa, warp and warpreg strand-major as
 *          paper for the other stages.
 *
 * Memory on the device: the state (one state's bytes; point-major: X|Y|Z in one
 * allocation), for soa and fused a canonical staging buffer of the same size (load/fetch
 * go through it and a transpose kernel; the fused kernel writes the intermediate wind frame
 * there when asked, see keep_intermediate), and a saved copy when the driver repeats
 * stages. Checked against cudaMemGetInfo before anything is allocated.
 *
 * Timing (docs/model.md §5.3): run_stage records CUDA events immediately around its kernel
 * launch(es) and nothing else; r->ms is their elapsed time. The collide count is read back
 * after the stop event. load/fetch report the host wall time of the whole transfer,
 * conversion included, after synchronisation.
 */
#include <cuda_runtime.h>

#include <algorithm>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <vector>

#include "app/backend.h"
#include "runtime/checked.h"
#include "backend_cuda.cuh"
#include "check.cuh"
#include "dynamic/kernels.cuh"
#include "runtime/host.h"
#include "paper/kernels.cuh"
#include "paper/model.h"

using hb::Model;
using hb::PointMajor;
using hb::StrandMajor;
using namespace hb_cuda;

namespace {

/* The scene's numbers rounded once to the working precision (paper/model_host.c, shared with the CPU). */
void round_scene(cuda_impl *c, const hb_scene *s)
{
    hb_model_f64 d;
    hb_model_f32 f;
    hb_model_round(s, &f, &d);
    c->m64 = hb::model_from<hb_model_f64, double>(d);
    c->m32 = hb::model_from<hb_model_f32, float>(f);
}

/* Device 0, refused cleanly when there is none. */
int pick_device(char *name, size_t n, char *err, size_t errlen)
{
    int count = 0;
    cudaError_t e = cudaGetDeviceCount(&count);
    if (e != cudaSuccess) {
        snprintf(err, errlen, "no CUDA device: %s", cudaGetErrorString(e));
        return -1;
    }
    if (count < 1) {
        snprintf(err, errlen, "no CUDA device: cudaGetDeviceCount found none");
        return -1;
    }
    HB_CUDA(cudaSetDevice(0));
    cudaDeviceProp p;
    HB_CUDA(cudaGetDeviceProperties(&p, 0));
    snprintf(name, n, "%s", p.name);
#ifdef HB_DEVICE_OPT_CHECK
    snprintf(err, errlen,
             "this binary's device code is not optimised (built with make CUDA_DEVICE_OPT=check, to compile "
             "without a GPU): rebuild with make to run on %s",
             p.name);
    return -1;
#else
    return 0;
#endif
}

} /* namespace */

int hb_cuda::device_alloc(void **p, uint64_t bytes, const cuda_impl *c, const char *what, char *err, size_t errlen)
{
    cudaError_t e = cudaMalloc(p, (size_t)bytes);
    if (e != cudaSuccess) {
        *p = NULL;
        (void)cudaGetLastError(); /* an allocation failure is not sticky: clear it */
        snprintf(err, errlen, "cannot allocate %.2f GB of GPU memory for the %s on %s: %s", 1e-9 * (double)bytes, what,
                 c->device, cudaGetErrorString(e));
        return HB_EXIT_MEMORY;
    }
    return 0;
}

/* ---- timing without the launch gap --------------------------------------------------------
 * A timed region is ev0, the work, ev1 on stream 0. Recorded on an idle GPU, ev0 would fire at
 * once and the work start only when the host's launch reaches the GPU, a few microseconds later:
 * the gap would be timed as the kernel's. hold_stream enqueues a kernel that keeps the stream
 * busy for kHoldNs first, so the host has enqueued ev0, the work and ev1 before ev0 fires and
 * they run back to back (a host slower than kHoldNs leaves a gap: the time is then too long,
 * never too short). The frame loop (--frame-loop) times launches and all, as an application. */
constexpr unsigned long long kHoldNs = 50000;

static __global__ void k_hold(unsigned long long ns)
{
    unsigned long long t0, t;
    asm volatile("mov.u64 %0, %%globaltimer;" : "=l"(t0));
    do {
        __nanosleep(1000);
        asm volatile("mov.u64 %0, %%globaltimer;" : "=l"(t));
    } while (t - t0 < ns);
}

cudaError_t hb_cuda::hold_stream(cudaStream_t stream)
{
    k_hold<<<1, 1, 0, stream>>>(kHoldNs);
    return cudaGetLastError();
}

namespace {


int setup_inner(hb_backend *b, cuda_impl *c, const hb_options *o, int need_save, uint64_t driver_bytes, char *err,
                size_t errlen)
{
    c->scene = o->scene;
    c->N = o->scene.n_strands;
    c->P = o->scene.points;
    c->bytes = hb_state_bytes(&o->scene);
    const char *v = o->variant ? o->variant : "fused";
    c->variant = strcmp(v, "paper") == 0     ? V_PAPER
                 : strcmp(v, "soa") == 0     ? V_SOA
                 : strcmp(v, "strand") == 0  ? V_STRAND
                 : strcmp(v, "warp") == 0    ? V_WARP
                 : strcmp(v, "warpreg") == 0 ? V_WARPREG
                 : strcmp(v, "lanes") == 0   ? V_LANES
                                             : V_FUSED;
    c->block = o->block_size;
    b->block_size = c->block;
    b->threads = 0;
    round_scene(c, &o->scene);

    if (pick_device(c->device, sizeof c->device, err, errlen)) return -1;

    /* ---- memory: refuse before allocating anything ---- */
    int rc;
    const int point_major = !dyn_is_strand_major(c);
    uint64_t need = c->bytes;
    if (point_major) need = sat_add(need, c->bytes); /* staging / intermediate */
    if (need_save) need = sat_add(need, c->bytes);
    uint64_t dyn_bytes = 0;
    if ((rc = dyn_plan(c, o, need_save, &dyn_bytes, err, errlen))) return rc;
    need = sat_add(need, dyn_bytes);
    size_t free_b = 0, total_b = 0;
    HB_CUDA(cudaMemGetInfo(&free_b, &total_b));
    if (need > (uint64_t)free_b) {
        char detail[160];
        snprintf(detail, sizeof detail, ": state%s%s%s", point_major ? " + staging" : "",
                 need_save ? " + saved copy" : "", dyn_bytes ? " + simulate (velocities, rest shape, scratch)" : "");
        hb_memory_message(err, errlen, &o->scene, "GPU", need, (uint64_t)free_b, detail, c->device);
        return HB_EXIT_MEMORY;
    }
    const uint64_t avail = hb_host_memory_available();
    if (avail && driver_bytes > avail) {
        hb_memory_message(err, errlen, &o->scene, "host", driver_bytes, avail, NULL, NULL);
        return HB_EXIT_MEMORY;
    }

    if ((rc = device_alloc(&c->state, c->bytes, c, "state", err, errlen))) return rc;
    if (point_major && (rc = device_alloc(&c->staging, c->bytes, c, "staging buffer", err, errlen))) return rc;
    if (need_save && (rc = device_alloc(&c->saved, c->bytes, c, "saved copy", err, errlen))) return rc;
    if ((rc = device_alloc((void **)&c->d_count, sizeof *c->d_count, c, "collide counter", err, errlen))) return rc;
    if ((rc = dyn_alloc(c, need_save, err, errlen))) return rc;
    HB_CUDA(cudaEventCreate(&c->ev0));
    HB_CUDA(cudaEventCreate(&c->ev1));
    c->have_events = 1;
    return 0;
}

int cuda_setup(hb_backend *b, const hb_options *o, int need_save, uint64_t driver_bytes, char *err, size_t errlen)
{
    cuda_impl *c = (cuda_impl *)calloc(1, sizeof *c);
    if (!c) {
        snprintf(err, errlen, "out of host memory");
        return HB_EXIT_MEMORY;
    }
    b->impl = c;
    const int rc = setup_inner(b, c, o, need_save, driver_bytes, err, errlen);
    return rc < 0 ? HB_EXIT_RUNTIME : rc;
}

int cuda_load(hb_backend *b, const void *canonical, double *ms, char *err, size_t errlen)
{
    cuda_impl *c = (cuda_impl *)b->impl;
    const double t0 = hb_now_ms();
    if (dyn_is_strand_major(c)) {
        HB_CUDA(cudaMemcpy(c->state, canonical, (size_t)c->bytes, cudaMemcpyHostToDevice));
    } else {
        c->inter_valid = 0;
        HB_CUDA(cudaMemcpy(c->staging, canonical, (size_t)c->bytes, cudaMemcpyHostToDevice));
        if (c->scene.precision == HB_FP32)
            HB_CUDA_AS(hb::launch_to_point_major<float>((const float *)c->staging, point_major<float>(c, c->state),
                                                        c->N, c->P, 0),
                       "the canonical-to-point-major kernel launch");
        else
            HB_CUDA_AS(hb::launch_to_point_major<double>((const double *)c->staging, point_major<double>(c, c->state),
                                                         c->N, c->P, 0),
                       "the canonical-to-point-major kernel launch");
    }
    HB_CUDA_AS(cudaDeviceSynchronize(), "load (cudaDeviceSynchronize)");
    *ms = hb_now_ms() - t0;
    return 0;
}

int cuda_fetch(hb_backend *b, void *canonical, double *ms, char *err, size_t errlen)
{
    cuda_impl *c = (cuda_impl *)b->impl;
    const double t0 = hb_now_ms();
    if (dyn_is_strand_major(c)) {
        HB_CUDA(cudaMemcpy(canonical, c->state, (size_t)c->bytes, cudaMemcpyDeviceToHost));
    } else {
        c->inter_valid = 0; /* the staging buffer is about to be overwritten */
        if (c->scene.precision == HB_FP32)
            HB_CUDA_AS(
                hb::launch_to_canonical<float>(point_major<float>(c, c->state), (float *)c->staging, c->N, c->P, 0),
                "the point-major-to-canonical kernel launch");
        else
            HB_CUDA_AS(
                hb::launch_to_canonical<double>(point_major<double>(c, c->state), (double *)c->staging, c->N, c->P, 0),
                "the point-major-to-canonical kernel launch");
        HB_CUDA(cudaMemcpy(canonical, c->staging, (size_t)c->bytes, cudaMemcpyDeviceToHost));
    }
    HB_CUDA_AS(cudaDeviceSynchronize(), "fetch (cudaDeviceSynchronize)");
    *ms = hb_now_ms() - t0;
    return 0;
}

int cuda_fetch_intermediate(hb_backend *b, void *canonical, char *err, size_t errlen)
{
    cuda_impl *c = (cuda_impl *)b->impl;
    if (!c->inter_valid) {
        snprintf(err, errlen,
                 "internal error: no intermediate state to fetch (the last stage call was not a fused "
                 "wind+collide that kept it)");
        return -1;
    }
    HB_CUDA(cudaMemcpy(canonical, c->staging, (size_t)c->bytes, cudaMemcpyDeviceToHost));
    return 0;
}

void cuda_keep_intermediate(hb_backend *b, int keep)
{
    cuda_impl *c = (cuda_impl *)b->impl;
    if (c) c->keep = keep;
}

int cuda_save(hb_backend *b, char *err, size_t errlen)
{
    cuda_impl *c = (cuda_impl *)b->impl;
    if (!c->saved) {
        snprintf(err, errlen, "internal error: save without a saved-copy buffer");
        return -1;
    }
    HB_CUDA(cudaMemcpy(c->saved, c->state, (size_t)c->bytes, cudaMemcpyDeviceToDevice));
    return dyn_save(c, err, errlen);
}

int cuda_restore(hb_backend *b, char *err, size_t errlen)
{
    cuda_impl *c = (cuda_impl *)b->impl;
    if (!c->saved) {
        snprintf(err, errlen, "internal error: restore without a saved copy");
        return -1;
    }
    HB_CUDA(cudaMemcpy(c->state, c->saved, (size_t)c->bytes, cudaMemcpyDeviceToDevice));
    return dyn_restore(c, err, errlen);
}

/* Enqueues the kernel(s) of one stage call; *what names the launch for an error. */
template <typename T>
cudaError_t launch_stage(cuda_impl *c, const Model<T> &m, hb_stage st, int fuse, const char **what)
{
    /* what each launch is called in an error: [strand-major, point-major][stage] */
    static const char *const kLaunch[2][3] = {
        {"the init kernel launch (paper)", "the wind kernel launch (paper)", "the collide kernel launch (paper)"},
        {"the init kernel launch (point-major)", "the wind kernel launch (point-major)",
         "the collide kernel launch (point-major)"}};
    static_assert(HB_STAGE_INIT == 0 && HB_STAGE_WIND == 1 && HB_STAGE_COLLIDE == 2, "kLaunch is indexed by hb_stage");
    const int64_t N = c->N;
    const int B = c->block;
    const int paper = dyn_is_strand_major(c); /* paper and warp: the canonical layout */
    if (!paper && fuse) {
        *what = "the fused wind+collide kernel launch";
        return hb::launch_wind_collide<T>(m, point_major<T>(c, c->state), N, c->keep ? (T *)c->staging : (T *)NULL,
                                          c->d_count, B, 0);
    }
    if ((unsigned)st > HB_STAGE_COLLIDE) {
        *what = "an unknown stage";
        return cudaErrorInvalidValue;
    }
    *what = kLaunch[paper ? 0 : 1][st];
    return paper ? hb::launch_stage<T>(st, m, strand_major<T>(c, c->state), N, c->d_count, B, 0)
                 : hb::launch_stage<T>(st, m, point_major<T>(c, c->state), N, c->d_count, B, 0);
}

int cuda_run_stage(hb_backend *b, const hb_stage *stages, int i, int n, hb_stage_result *r, char *err, size_t errlen)
{
    cuda_impl *c = (cuda_impl *)b->impl;
    const hb_stage st = stages[i];
    const int fuse = c->variant == V_FUSED && st == HB_STAGE_WIND && i + 1 < n && stages[i + 1] == HB_STAGE_COLLIDE;
    const int counts = fuse || st == HB_STAGE_COLLIDE;
    if (fuse) c->inter_valid = 0;
    if (counts) HB_CUDA(cudaMemsetAsync(c->d_count, 0, sizeof *c->d_count, 0));

    /* the timed region: the stage's kernel launch(es) only */
    const char *what = "a stage kernel launch";
    HB_CUDA_AS(hold_stream(0), "the hold kernel launch");
    HB_CUDA(cudaEventRecord(c->ev0, 0));
    const cudaError_t e = c->scene.precision == HB_FP32 ? launch_stage<float>(c, c->m32, st, fuse, &what)
                                                        : launch_stage<double>(c, c->m64, st, fuse, &what);
    HB_CUDA_AS(e, what);
    HB_CUDA(cudaEventRecord(c->ev1, 0));
    HB_CUDA_AS(cudaEventSynchronize(c->ev1), fuse ? "the fused wind+collide kernel (cudaEventSynchronize)"
                                                  : "the stage's kernel (cudaEventSynchronize)");
    float ms = 0.0f;
    HB_CUDA(cudaEventElapsedTime(&ms, c->ev0, c->ev1));

    unsigned long long moved = 0;
    if (counts) HB_CUDA(cudaMemcpy(&moved, c->d_count, sizeof moved, cudaMemcpyDeviceToHost));
    r->ms = (double)ms;
    r->moved_points = counts ? (int64_t)moved : -1;
    r->consumed = fuse ? 2 : 1;
    if (fuse && c->keep) c->inter_valid = 1;
    return 0;
}

/* ---- copy bandwidth: a large device-to-device cudaMemcpy ---------------------------------- */
struct bw_res {
    void *src = nullptr, *dst = nullptr;
    cudaEvent_t e0 = nullptr, e1 = nullptr;
    ~bw_res()
    {
        if (src) cudaFree(src);
        if (dst) cudaFree(dst);
        if (e0) cudaEventDestroy(e0);
        if (e1) cudaEventDestroy(e1);
    }
};

int cuda_measure_bandwidth(hb_backend *b, const hb_options *o, double *gbps, double *bytes, char *err, size_t errlen)
{
    (void)b;
    (void)o;
    char name[256];
    if (pick_device(name, sizeof name, err, errlen)) return -1;
    size_t free_b = 0, total_b = 0;
    HB_CUDA(cudaMemGetInfo(&free_b, &total_b));
    const size_t MiB = (size_t)1 << 20, reserve = 256 * MiB;
    size_t size = (size_t)2 << 30; /* 2 GiB a buffer: far beyond the L2 */
    if (free_b < reserve + 2 * size) size = free_b > reserve ? (free_b - reserve) / 2 : 0;
    size &= ~(MiB - 1);
    if (size < 64 * MiB) {
        snprintf(err, errlen, "only %.2f GB of GPU memory is free on %s: too little to measure the copy bandwidth",
                 1e-9 * (double)free_b, name);
        return -1;
    }
    bw_res r;
    HB_CUDA(cudaMalloc(&r.src, size));
    HB_CUDA(cudaMalloc(&r.dst, size));
    HB_CUDA(cudaMemset(r.src, 0x5a, size));
    HB_CUDA(cudaMemset(r.dst, 0, size));
    HB_CUDA(cudaEventCreate(&r.e0));
    HB_CUDA(cudaEventCreate(&r.e1));
    for (int w = 0; w < 3; w++) HB_CUDA(cudaMemcpy(r.dst, r.src, size, cudaMemcpyDeviceToDevice));
    HB_CUDA(cudaDeviceSynchronize());
    std::vector<double> t;
    for (int rep = 0; rep < 20; rep++) {
        HB_CUDA_AS(hold_stream(0), "the hold kernel launch");
        HB_CUDA(cudaEventRecord(r.e0, 0));
        HB_CUDA(cudaMemcpyAsync(r.dst, r.src, size, cudaMemcpyDeviceToDevice, 0));
        HB_CUDA(cudaEventRecord(r.e1, 0));
        HB_CUDA(cudaEventSynchronize(r.e1));
        float ms = 0.0f;
        HB_CUDA(cudaEventElapsedTime(&ms, r.e0, r.e1));
        t.push_back((double)ms);
    }
    std::sort(t.begin(), t.end());
    const double median = 0.5 * (t[t.size() / 2 - 1] + t[t.size() / 2]);
    *bytes = 2.0 * (double)size; /* bytes read + bytes written */
    *gbps = *bytes / (median * 1e-3) * 1e-9;
    return 0;
}

/* The driver version: the "NVRM version" line of /proc/driver/nvidia/version (its first
 * token that is a dotted number), else the CUDA driver API version. */
void driver_version(char *out, size_t n)
{
    if (!n) return;
    out[0] = '\0';
    FILE *f = fopen("/proc/driver/nvidia/version", "r");
    if (f) {
        char line[512];
        while (fgets(line, sizeof line, f)) {
            if (strncmp(line, "NVRM version", 12) != 0) continue;
            char *save = NULL;
            for (char *tok = strtok_r(line, " \t\n", &save); tok; tok = strtok_r(NULL, " \t\n", &save)) {
                const size_t len = strlen(tok);
                if (len == 0 || tok[0] < '0' || tok[0] > '9' || strspn(tok, "0123456789.") != len || !strchr(tok, '.'))
                    continue;
                snprintf(out, n, "%s", tok);
                break;
            }
            break;
        }
        fclose(f);
    }
    if (out[0]) return;
    int v = 0;
    if (cudaDriverGetVersion(&v) == cudaSuccess && v > 0)
        snprintf(out, n, "CUDA driver API %d.%d", v / 1000, (v % 1000) / 10);
}

void cuda_describe(hb_backend *b, char *device, size_t dlen, char *driver, size_t vlen)
{
    const cuda_impl *c = (const cuda_impl *)b->impl;
    if (dlen) {
        int count = 0;
        cudaDeviceProp p;
        if (c && c->device[0]) snprintf(device, dlen, "%s", c->device);
        else if (cudaGetDeviceCount(&count) == cudaSuccess && count > 0 &&
                 cudaGetDeviceProperties(&p, 0) == cudaSuccess)
            snprintf(device, dlen, "%s", p.name);
        else snprintf(device, dlen, "unknown CUDA device");
    }
    driver_version(driver, vlen);
    /* the compute capability the binary runs on (docs/cuda.md, "Building for your GPU") */
    int dev = 0, major = 0, minor = 0;
    if (vlen && cudaGetDevice(&dev) == cudaSuccess &&
        cudaDeviceGetAttribute(&major, cudaDevAttrComputeCapabilityMajor, dev) == cudaSuccess &&
        cudaDeviceGetAttribute(&minor, cudaDevAttrComputeCapabilityMinor, dev) == cudaSuccess && major > 0)
        snprintf(driver + strlen(driver), vlen - strlen(driver), "%scompute capability %d.%d", driver[0] ? "; " : "",
                 major, minor);
}

void cuda_teardown(hb_backend *b)
{
    cuda_impl *c = (cuda_impl *)b->impl;
    if (!c) return;
    /* errors are ignored here: after a fault the context may be unusable */
    if (c->state) cudaFree(c->state);
    if (c->staging) cudaFree(c->staging);
    if (c->saved) cudaFree(c->saved);
    if (c->d_count) cudaFree(c->d_count);
    dyn_free(c);
    if (c->have_events) {
        cudaEventDestroy(c->ev0);
        cudaEventDestroy(c->ev1);
    }
    free(c);
    b->impl = NULL;
}

#define CUDA_PAPER_STAGES ((1u << HB_STAGE_INIT) | (1u << HB_STAGE_COLLIDE) | (1u << HB_STAGE_WIND))
const hb_variant cuda_variants[] = {
    {"paper", CUDA_PAPER_STAGES, "the paper's scheme: strand-major, one thread per strand, one kernel per stage", 0, 0},
    {"soa", CUDA_PAPER_STAGES, "point-major structure of arrays, one thread per strand, one kernel per stage", 0, 0},
    {"fused", CUDA_PAPER_STAGES, "point-major, wind and the collide after it in one kernel", 0, 0},
    {"strand", CUDA_PAPER_STAGES | (1u << HB_STAGE_SIMULATE),
     "point-major like soa; simulate: one thread per strand, a frame's substeps in one launch", 0, 0, 0, 1,
     HB_X_GRID | HB_X_COLLIDERS | HB_X_FRICTION | HB_X_PLANES | HB_X_ONCE},
    {"warp", CUDA_PAPER_STAGES | (1u << HB_STAGE_SIMULATE),
     "strand-major like paper; simulate: one warp per strand, a lane per point, the frame in shared memory", 0, 0, 0, 1,
     HB_X_GRID | HB_X_COLLIDERS | HB_X_FRICTION | HB_X_PLANES | HB_X_ONCE},
    {"warpreg", CUDA_PAPER_STAGES | (1u << HB_STAGE_SIMULATE),
     "strand-major like paper; simulate: one warp per strand, lane k holds point k in registers (at most 32 points), "
     "neighbours through warp shuffles",
     hb::dyn::kWarpregMaxPoints, 0, 0, 1, HB_X_GRID | HB_X_COLLIDERS | HB_X_FRICTION | HB_X_PLANES | HB_X_ONCE},
    {"lanes", CUDA_PAPER_STAGES | (1u << HB_STAGE_SIMULATE),
     "strand-major like paper; simulate: L lanes a strand (16 for xpbd, 8 for ftl), 2 to 8 points a lane in "
     "registers (at most 128 points), nearly every lane busy in every constraint group; free arithmetic outside "
     "the strict build",
     hb::dyn::kLanesMaxPoints, hb::dyn::kLanesMaxBlock, 0, 1, HB_X_GUIDES | HB_X_LRA},
    {NULL, 0, NULL, 0, 0},
};

} /* namespace */

#ifndef HB_FLAGS
#define HB_FLAGS "unknown"
#endif
#ifndef HB_MATH_MODE
#define HB_MATH_MODE "normal"
#endif
#define HB_STR_(x) #x
#define HB_STR(x) HB_STR_(x)

/* The build, recorded in every output: the math mode (normal | strict | fastmath), the
 * nvcc version and the flags the Makefile passed. */
static const char hb_cuda_compiler[] = "nvcc " HB_STR(__CUDACC_VER_MAJOR__) "." HB_STR(__CUDACC_VER_MINOR__) "." HB_STR(
    __CUDACC_VER_BUILD__) " (host gcc " HB_STR(__GNUC__) "." HB_STR(__GNUC_MINOR__) ")";
static const char hb_cuda_flags[] = "math-mode=" HB_MATH_MODE "; nvcc " HB_STR(__CUDACC_VER_MAJOR__) "." HB_STR(
    __CUDACC_VER_MINOR__) "." HB_STR(__CUDACC_VER_BUILD__) "; " HB_FLAGS;

int main(int argc, char **argv)
{
    hb_backend b;
    memset(&b, 0, sizeof b);
    b.name = "cuda";
    b.default_variant = "fused";
    b.variants = cuda_variants;
    b.build = strcmp(HB_MATH_MODE, "normal") == 0 ? "default" : HB_MATH_MODE;
    b.flags = hb_cuda_flags;
    b.compiler = hb_cuda_compiler;
    b.setup = cuda_setup;
    b.load = cuda_load;
    b.run_stage = cuda_run_stage;
    b.save = cuda_save;
    b.restore = cuda_restore;
    b.fetch = cuda_fetch;
    b.fetch_intermediate = cuda_fetch_intermediate;
    b.keep_intermediate = cuda_keep_intermediate;
    b.measure_bandwidth = cuda_measure_bandwidth;
    b.describe = cuda_describe;
    b.teardown = cuda_teardown;
    b.dyn_load = cuda_dyn_load;
    b.dyn_frame = cuda_dyn_frame;
    b.dyn_observe = cuda_dyn_observe;
    b.dyn_fetch_velocity = cuda_dyn_fetch_velocity;
    b.dyn_loop = cuda_dyn_loop;
    b.dyn_draw = cuda_dyn_draw;
    b.dyn_render = cuda_dyn_render;
    return hb_main(argc, argv, &b);
}
