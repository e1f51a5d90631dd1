/* draw.cu — --draw WxH (docs/interfaces.md "Drawing on the GPU"): after the run, F more frames,
 * each simulated and drawn on the device with nothing copied through the host, by two paths:
 *
 *   compute  a CUDA strand rasteriser: the head and the background written into a W×H buffer of
 *            64-bit words (depth bits << 32 | RGBA8), one thread a segment walking its pixels with
 *            a 64-bit atomicMin each (the nearest colour wins), then the colours resolved into an
 *            RGBA8 image (cuda/draw/view.cuh);
 *   gl       OpenGL through EGL (cuda/draw/egl_gl.cuh): a GL vertex buffer registered with CUDA
 *            (cudaGraphicsGLRegisterBuffer), written each frame by a kernel straight from the
 *            simulation's positions (position and unit tangent a point), then drawn as line
 *            strips with Kajiya–Kay shading into a W×H framebuffer.
 *
 * The frames are split: the first half (all of them where the GL path cannot run) drawn by the
 * compute path, the second by the GL path, each half's first frame a warm-up. Times (per frame,
 * the mean over the timed frames): the simulation kernel and the compute drawing by CUDA events,
 * and the two back to back from the first event to the last; the vertex buffer's write by CUDA
 * events, the GL draw by GL_TIME_ELAPSED, and the GL half's frames by the host clock after one
 * synchronisation at the end. Where EGL, GL or the interop is missing, one line says so and the
 * compute path runs alone. --draw-image PREFIX writes each path's last frame as PREFIX-PATH.ppm. */

#include <cuda_runtime.h>

#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <string.h>

#include <vector>

#include "backend_cuda.cuh"
#include "check.cuh"
#include "draw/view.cuh"
#include "draw/egl_gl.cuh"
#include "runtime/host.h"

/* declared by cuda_gl_interop.h, which needs GL's headers: GLuint is an unsigned int */
extern "C" cudaError_t cudaGraphicsGLRegisterBuffer(struct cudaGraphicsResource **resource, unsigned int buffer,
                                                    unsigned int flags);

namespace hb_cuda {

namespace {

/* where the run's positions are: point k of strand i, component c at base[i·is + k·ks + c·cs] */
struct Positions {
    const void *base;
    int64_t N, P, is, ks, cs;
};

template <typename T> __device__ void load_point(const Positions &p, int64_t i, int64_t k, float out[3])
{
    const T *b = (const T *)p.base;
    const int64_t o = i * p.is + k * p.ks;
    out[0] = (float)b[o];
    out[1] = (float)b[o + p.cs];
    out[2] = (float)b[o + 2 * p.cs];
}

__global__ void k_head(unsigned long long *fb, hb_draw::View v)
{
    const int c = blockIdx.x * blockDim.x + threadIdx.x, r = blockIdx.y;
    if (c < v.W) fb[(int64_t)r * v.W + c] = hb_draw::head_pixel(v, c, r);
}

/* the nearest fragment wins; a plain read first skips the atomic for a fragment already
 * behind what the pixel holds (most of them, where hair lies over hair or behind the head) */
struct DeviceMin {
    unsigned long long *fb;
    __device__ void operator()(int64_t i, uint64_t value) const
    {
        if ((unsigned long long)value < *(volatile unsigned long long *)(fb + i))
            atomicMin(fb + i, (unsigned long long)value);
    }
};

/* this thread's segment (one a thread): its end points a, b and its first point's index k;
 * false past the last segment */
template <typename T> __device__ bool load_segment(const Positions &p, float a[3], float b[3], int &k)
{
    const int64_t s = (int64_t)blockIdx.x * blockDim.x + threadIdx.x, per = p.P - 1;
    if (s >= p.N * per) return false;
    const int64_t i = s / per;
    k = (int)(s % per);
    load_point<T>(p, i, k, a);
    load_point<T>(p, i, k + 1, b);
    return true;
}

template <typename T>
__global__ void k_segments(unsigned long long *fb, hb_draw::View v, Positions p, const uint32_t *smap)
{
    float a[3], b[3];
    int k;
    if (load_segment<T>(p, a, b, k)) hb_draw::raster_segment(v, a, b, k, DeviceMin{fb}, hb_draw::ShadowMap{smap});
}

/* the shadow map (view.cuh): the head first, then every segment's nearest depth */
__global__ void k_shadow_head(uint32_t *smap, hb_draw::View v)
{
    const int c = blockIdx.x * blockDim.x + threadIdx.x, r = blockIdx.y;
    if (c < v.S) smap[(int64_t)r * v.S + c] = hb_draw::head_shadow(v, c, r);
}
struct DeviceMin32 {
    uint32_t *map;
    __device__ void operator()(int64_t i, uint32_t value) const
    {
        if (value < *(volatile uint32_t *)(map + i)) atomicMin(map + i, value);
    }
};
template <typename T> __global__ void k_shadow_segments(uint32_t *smap, hb_draw::View v, Positions p)
{
    float a[3], b[3];
    int k;
    if (load_segment<T>(p, a, b, k)) hb_draw::shadow_segment(v, a, b, DeviceMin32{smap});
}

__global__ void k_resolve(const unsigned long long *fb, uint32_t *rgba, int64_t n)
{
    const int64_t i = (int64_t)blockIdx.x * blockDim.x + threadIdx.x;
    if (i < n) rgba[i] = (uint32_t)fb[i];
}

/* the GL vertex buffer: position and unit tangent (central differences) of every point */
template <typename T> __global__ void k_vertices(float *out, Positions p)
{
    const int64_t j = (int64_t)blockIdx.x * blockDim.x + threadIdx.x;
    if (j >= p.N * p.P) return;
    const int64_t i = j / p.P, k = j % p.P;
    float x[3], a[3], b[3];
    load_point<T>(p, i, k, x);
    load_point<T>(p, i, k > 0 ? k - 1 : 0, a);
    load_point<T>(p, i, k + 1 < p.P ? k + 1 : p.P - 1, b);
    float t[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]};
    const float n = sqrtf(t[0] * t[0] + t[1] * t[1] + t[2] * t[2]);
    const float s = n > 0.0f ? 1.0f / n : 0.0f;
    float *o = out + 6 * j;
    o[0] = x[0], o[1] = x[1], o[2] = x[2], o[3] = t[0] * s, o[4] = t[1] * s, o[5] = t[2] * s;
}

unsigned blocks(int64_t n, int block)
{
    return (unsigned)((n + block - 1) / block);
}

/* what one --draw holds; freed on every path out */
struct DrawRes {
    void *dq = nullptr, *dp = nullptr;
    unsigned long long *fb = nullptr;
    uint32_t *rgba = nullptr, *smap = nullptr;
    cudaStream_t st = nullptr;
    std::vector<cudaEvent_t> ev;
    cudaGraphicsResource *res = nullptr;
    hb_gl::GlDraw gl;
    bool gl_open = false;
    ~DrawRes()
    { /* errors ignored: after a fault the context may be unusable */
        if (res) cudaGraphicsUnregisterResource(res);
        if (gl_open) gl.close();
        for (cudaEvent_t e : ev) cudaEventDestroy(e);
        if (st) cudaStreamDestroy(st);
        cudaFree(dq);
        cudaFree(dp);
        cudaFree(fb);
        cudaFree(rgba);
        cudaFree(smap);
    }
};

int write_ppm(const char *prefix, const char *path, const uint32_t *rgba, int W, int H, char *err, size_t errlen)
{
    char name[4096], tmp[4200];
    snprintf(name, sizeof name, "%s-%s.ppm", prefix, path);
    snprintf(tmp, sizeof tmp, "%s.tmp", name);
    FILE *f = fopen(tmp, "wb");
    if (!f) return snprintf(err, errlen, "--draw-image: cannot write %s", tmp), -1;
    fprintf(f, "P6\n%d %d\n255\n", W, H);
    for (int64_t i = 0; i < (int64_t)W * H; i++) {
        const unsigned char px[3] = {(unsigned char)rgba[i], (unsigned char)(rgba[i] >> 8),
                                     (unsigned char)(rgba[i] >> 16)};
        fwrite(px, 1, 3, f);
    }
    if (fclose(f) != 0 || rename(tmp, name) != 0) {
        remove(tmp);
        return snprintf(err, errlen, "--draw-image: cannot write %s", name), -1;
    }
    return 0;
}

template <typename T>
cudaError_t enqueue_compute(const DrawRes &r, const hb_draw::View &v, const Positions &p, int block)
{
    const int64_t segs = p.N * (p.P - 1), px = (int64_t)v.W * v.H;
    k_shadow_head<<<dim3(blocks(v.S, 256), (unsigned)v.S), 256, 0, r.st>>>(r.smap, v);
    if (segs > 0) k_shadow_segments<T><<<blocks(segs, block), block, 0, r.st>>>(r.smap, v, p);
    k_head<<<dim3(blocks(v.W, 256), (unsigned)v.H), 256, 0, r.st>>>(r.fb, v);
    if (segs > 0) k_segments<T><<<blocks(segs, block), block, 0, r.st>>>(r.fb, v, p, r.smap);
    k_resolve<<<blocks(px, 256), 256, 0, r.st>>>(r.fb, r.rgba, px);
    return cudaGetLastError();
}

float elapsed(cudaEvent_t a, cudaEvent_t b)
{
    float ms = NAN;
    return cudaEventElapsedTime(&ms, a, b) == cudaSuccess ? ms : NAN;
}

} // namespace

int cuda_dyn_draw(hb_backend *b, const hb_dyn_frame *plans, int n, int width, int height, const char *image,
                  hb_draw_result *out, char *err, size_t errlen)
{
    cuda_impl *c = (cuda_impl *)b->impl;
    const hb_scene *s = &c->scene;
    const int fp32 = s->precision == HB_FP32;
    *out = hb_draw_result{};
    out->width = width, out->height = height, out->frames = n;
    out->simulate_ms = out->compute_ms = out->compute_frame_ms = NAN;
    out->gl_write_ms = out->gl_ms = out->gl_frame_ms = NAN;
    const hb_draw::View v =
        hb_draw::make_view(width, height, s->head_radius, s->head_radius + s->hair_offset + s->hair_length, (int)c->P);
    int64_t st3[3];
    dyn_position_strides(c, st3);
    const Positions p{c->state, c->N, c->P, st3[0], st3[1], st3[2]};
    DrawRes r;
    /* the frames' tables, on the device before anything is timed */
    const size_t rs = fp32 ? sizeof(float) : sizeof(double), tq = (size_t)s->dyn.substeps * 9u * rs,
                 tp = (size_t)s->dyn.substeps * rs;
    HB_CUDA(cudaMalloc(&r.dq, tq * (size_t)n));
    HB_CUDA(cudaMalloc(&r.dp, tp * (size_t)n));
    for (int i = 0; i < n; i++) {
        HB_CUDA(cudaMemcpy((char *)r.dq + (size_t)i * tq,
                           fp32 ? (const void *)plans[i].q32 : (const void *)plans[i].q64, tq, cudaMemcpyHostToDevice));
        HB_CUDA(cudaMemcpy((char *)r.dp + (size_t)i * tp,
                           fp32 ? (const void *)plans[i].phase32 : (const void *)plans[i].phase64, tp,
                           cudaMemcpyHostToDevice));
    }
    const int64_t px = (int64_t)width * height;
    HB_CUDA_AS(cudaMalloc((void **)&r.fb, (size_t)px * 8u), "cudaMalloc (the compute path's depth and colour buffer)");
    HB_CUDA_AS(cudaMalloc((void **)&r.rgba, (size_t)px * 4u), "cudaMalloc (the compute path's image)");
    HB_CUDA_AS(cudaMalloc((void **)&r.smap, (size_t)v.S * (size_t)v.S * 4u),
               "cudaMalloc (the compute path's shadow map)");
    HB_CUDA(cudaStreamCreateWithFlags(&r.st, cudaStreamNonBlocking));
    r.ev.resize((size_t)n * 3);
    for (cudaEvent_t &e : r.ev) HB_CUDA(cudaEventCreate(&e));
    /* the GL path: a context on this CUDA device's EGL device, its vertex buffer registered */
    int dev = 0;
    HB_CUDA(cudaGetDevice(&dev));
    char why[256] = "";
    r.gl_open = n >= 4 && r.gl.open(v, c->N, c->P, dev, n, why, sizeof why);
    if (n < 4) snprintf(why, sizeof why, "--frames %d: the GL path needs at least 4 frames (2 each)", n);
    if (r.gl_open) {
        const cudaError_t e = cudaGraphicsGLRegisterBuffer(&r.res, r.gl.vbo, cudaGraphicsRegisterFlagsWriteDiscard);
        if (e != cudaSuccess) {
            snprintf(why, sizeof why, "CUDA cannot write GL's vertex buffer (cudaGraphicsGLRegisterBuffer: %s)",
                     cudaGetErrorString(e));
            r.res = nullptr;
            r.gl.close();
            r.gl_open = false;
        }
    }
    if (!r.gl_open) {
        snprintf(out->gl_missing, sizeof out->gl_missing, "%s", why);
        fprintf(stderr, "hairsim-cuda: note: --draw: no OpenGL path: %s; the compute path draws every frame\n", why);
    } else {
        snprintf(out->gl, sizeof out->gl, "%s", r.gl.renderer);
    }
    const int n_compute = r.gl_open ? n / 2 : n;
    const int block = c->block > 0 ? c->block : 256;
    HB_CUDA(cudaDeviceSynchronize());
    /* compute: frame j's events 3j (before the simulation), 3j+1 (before the drawing), 3j+2 (after) */
    for (int j = 0; j < n_compute; j++) {
        cudaEvent_t *e = &r.ev[(size_t)3 * j];
        HB_CUDA(cudaEventRecord(e[0], r.st));
        HB_CUDA_AS(dyn_launch_tables(c, (char *)r.dq + (size_t)j * tq, (char *)r.dp + (size_t)j * tp, r.st),
                   "the simulate kernel launch (--draw)");
        HB_CUDA(cudaEventRecord(e[1], r.st));
        HB_CUDA_AS(fp32 ? enqueue_compute<float>(r, v, p, block) : enqueue_compute<double>(r, v, p, block),
                   "the compute rasteriser's launch");
        HB_CUDA(cudaEventRecord(e[2], r.st));
    }
    HB_CUDA_AS(cudaStreamSynchronize(r.st), "the compute path's frames (cudaStreamSynchronize)");
    double sim = 0, draw = 0;
    for (int j = 1; j < n_compute; j++) {
        sim += elapsed(r.ev[3 * j], r.ev[3 * j + 1]);
        draw += elapsed(r.ev[3 * j + 1], r.ev[3 * j + 2]);
    }
    if (n_compute > 1) {
        out->simulate_ms = sim / (n_compute - 1);
        out->compute_ms = draw / (n_compute - 1);
        out->compute_frame_ms = elapsed(r.ev[3], r.ev[3 * (n_compute - 1) + 2]) / (n_compute - 1);
    }
    if (image) {
        std::vector<uint32_t> host((size_t)px);
        HB_CUDA(cudaMemcpy(host.data(), r.rgba, (size_t)px * 4u, cudaMemcpyDeviceToHost));
        if (write_ppm(image, "compute", host.data(), width, height, err, errlen)) return HB_EXIT_USAGE;
    }
    if (!r.gl_open) return 0;
    /* gl: frame j's events 3j (before the simulation), 3j+1 (before the write), 3j+2 (after it) */
    double t0 = 0;
    for (int j = n_compute; j < n; j++) {
        if (j == n_compute + 1) { /* the timed frames start after the warm-up frame is done */
            r.gl.gl.glFinish();
            HB_CUDA(cudaStreamSynchronize(r.st));
            t0 = hb_now_ms();
        }
        cudaEvent_t *e = &r.ev[(size_t)3 * j];
        HB_CUDA(cudaEventRecord(e[0], r.st));
        HB_CUDA_AS(dyn_launch_tables(c, (char *)r.dq + (size_t)j * tq, (char *)r.dp + (size_t)j * tp, r.st),
                   "the simulate kernel launch (--draw)");
        HB_CUDA(cudaEventRecord(e[1], r.st));
        HB_CUDA(cudaGraphicsMapResources(1, &r.res, r.st));
        float *vbo = nullptr;
        size_t bytes = 0;
        HB_CUDA(cudaGraphicsResourceGetMappedPointer((void **)&vbo, &bytes, r.res));
        const int64_t points = c->N * c->P;
        if (fp32) k_vertices<float><<<blocks(points, 256), 256, 0, r.st>>>(vbo, p);
        else k_vertices<double><<<blocks(points, 256), 256, 0, r.st>>>(vbo, p);
        HB_LAUNCHED("the GL vertex buffer's write");
        HB_CUDA(cudaEventRecord(e[2], r.st));
        HB_CUDA(cudaGraphicsUnmapResources(1, &r.res, r.st));
        r.gl.draw(j);
    }
    r.gl.gl.glFinish();
    HB_CUDA_AS(cudaStreamSynchronize(r.st), "the GL path's frames (cudaStreamSynchronize)");
    const int timed = n - n_compute - 1;
    out->gl_frame_ms = (hb_now_ms() - t0) / timed;
    double write = 0, gl = 0;
    for (int j = n_compute + 1; j < n; j++) {
        write += elapsed(r.ev[3 * j + 1], r.ev[3 * j + 2]);
        gl += r.gl.elapsed_ms(j);
    }
    out->gl_write_ms = write / timed;
    out->gl_ms = gl / timed;
    if (image) {
        std::vector<uint32_t> host;
        r.gl.read(host);
        if (write_ppm(image, "gl", host.data(), width, height, err, errlen)) return HB_EXIT_USAGE;
    }
    return 0;
}

} // namespace hb_cuda
