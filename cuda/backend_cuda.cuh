/* backend_cuda.cuh — what the CUDA backend's two files share: its state (cuda_impl), its
 * variants, the views of its device arrays, and the simulate hooks backend_dyn.cu gives
 * backend_cuda.cu. Host code. */
#ifndef HB_BACKEND_CUDA_CUH
#define HB_BACKEND_CUDA_CUH

#include <cuda_runtime.h>
#include <stddef.h>
#include <stdint.h>

#include "paper/kernels.cuh"
#include "app/backend.h"

namespace hb_cuda {

using hb::Model;
using hb::PointMajor;
using hb::StrandMajor;

enum Variant {
    V_PAPER = 0,
    V_SOA = 1,
    V_FUSED = 2,
    V_STRAND = 3,
    V_WARP = 4,
    V_WARPREG = 5,
    V_LANES = 6
}; /* strand, warp, warpreg, lanes: simulate (backend_dyn.cu) */
struct DynState;

struct cuda_impl {
    hb_scene scene;
    Model<float> m32;
    Model<double> m64;
    Variant variant;
    int block;
    int layout[4]; /* lanes: the simulate kernel's layout (hb_backend's layout; zeros: none) */
    int64_t N, P;
    uint64_t bytes;              /* one state [N·P][3] in the run's precision */
    void *state;                 /* paper: canonical; soa, fused: X | Y | Z, each [P][N] */
    void *saved;                 /* a copy of state for repeats (need_save) */
    void *staging;               /* soa, fused: canonical; load/fetch and the fused intermediate */
    unsigned long long *d_count; /* collide: points changed */
    cudaEvent_t ev0, ev1;
    int have_events;
    int keep;        /* keep_intermediate(1): fused calls write the wind frame to staging */
    int inter_valid; /* staging holds the last fused call's wind frame */
    char device[256];
    DynState *dyn; /* simulate (backend_dyn.cu); NULL when the run does not simulate */
};

inline uint64_t sat_add(uint64_t a, uint64_t b)
{
    return a > UINT64_MAX - b ? UINT64_MAX : a + b;
}

template <typename T> PointMajor<T> point_major(const cuda_impl *c, void *base)
{
    T *p = (T *)base;
    const int64_t np = c->N * c->P;
    return PointMajor<T>{p, p + np, p + 2 * np, c->N};
}

template <typename T> StrandMajor<T> strand_major(const cuda_impl *c, void *base)
{
    return StrandMajor<T>{(T *)base, c->P};
}

/* cudaMalloc, or HB_EXIT_MEMORY with a one-line message naming what did not fit. */
int device_alloc(void **p, uint64_t bytes, const cuda_impl *c, const char *what, char *err, size_t errlen);
/* keeps `stream` busy before a timed region starts (backend_cuda.cu: timing without the launch gap) */
cudaError_t hold_stream(cudaStream_t stream);

/* simulate (backend_dyn.cu): its device memory, planned, allocated, saved and freed with the
 * rest of the backend's, and the hb_backend hooks of the dynamic model. */
int dyn_is_strand_major(const cuda_impl *c);
int dyn_plan(cuda_impl *c, const hb_options *o, int need_save, uint64_t *bytes, char *err, size_t errlen);
int dyn_alloc(cuda_impl *c, int need_save, char *err, size_t errlen);
void dyn_free(cuda_impl *c);
int dyn_save(cuda_impl *c, char *err, size_t errlen);
int dyn_restore(cuda_impl *c, char *err, size_t errlen);
int cuda_dyn_load(hb_backend *b, const void *velocity, const void *rest, char *err, size_t errlen);
int cuda_dyn_frame(hb_backend *b, const hb_dyn_frame *f, hb_stage_result *r, char *err, size_t errlen);
int cuda_dyn_observe(hb_backend *b, hb_observables *obs, char *err, size_t errlen);
int cuda_dyn_fetch_velocity(hb_backend *b, void *canonical, char *err, size_t errlen);
int cuda_dyn_render(hb_backend *b, void *position, void *velocity, double *ms, char *err, size_t errlen);
int cuda_dyn_loop(hb_backend *b, const hb_dyn_frame *plans, int n, double *ms, double *graph_ms, char *err,
                  size_t errlen);
/* --draw (draw.cu): one frame's simulation from the device tables q, ph on `stream`; the strides
 * of the positions in c->state (strand i, point k, component: base[i·s[0] + k·s[1] + c·s[2]]) */
cudaError_t dyn_launch_tables(cuda_impl *c, const void *q, const void *ph, cudaStream_t stream);
void dyn_position_strides(const cuda_impl *c, int64_t s[3]);
int cuda_dyn_draw(hb_backend *b, const hb_dyn_frame *plans, int n, int width, int height, const char *image,
                  hb_draw_result *out, char *err, size_t errlen);

} // namespace hb_cuda

#endif
