/* view.cuh — what both drawing paths of --draw share (docs/interfaces.md, "Drawing on the
 * GPU"), host and device: the view, the shading, and the compute path's rasterisation of one
 * segment. Plain arithmetic, no CUDA API: the host check (cuda/hostcheck/draw_hostcheck.cu)
 * runs the same functions on the host.
 *
 * The view is orthographic from the front (the viewer on +z, y up, x to the right), holding
 * the sphere of radius E = R + h + L about the head's centre: a point (x, y, z) lands at
 * column (x/hw + 1)/2·W and row (1 − y/hh)/2·H (row 0 at the top), hh = E, hw = E·W/H, at
 * depth (E − z)/(2E) (0 nearest). Hair: Kajiya–Kay (diffuse sin(T, L), specular sin(T, H)^p,
 * V = +z); the head: Lambert. A pixel of the compute path holds (depth bits << 32) | RGBA8:
 * depths in [0, 1] order as their bits do, so a 64-bit atomicMin keeps the nearest colour. */
#ifndef HB_DRAW_VIEW_CUH
#define HB_DRAW_VIEW_CUH

#include <math.h>
#include <stdint.h>

#if defined(__CUDACC__)
#define HB_DV __host__ __device__ __forceinline__
#else
#define HB_DV inline
#endif

namespace hb_draw {

struct View {
    int W, H;
    float hw, hh, E;                /* half-width, half-height, depth half-range (cm) */
    float R;                        /* the head sphere's radius, about the origin */
    float light[3];                 /* unit, toward the light */
    float half[3];                  /* unit, (light + view)/|…| with the view +z */
    int P;                          /* points a strand (the colour runs root to tip) */
    float root[3], tip[3], skin[3]; /* linear RGB, written as 8 bits without gamma */
};

constexpr float kAmbient = 0.2f, kDiffuse = 0.8f, kSpecular = 0.25f, kShininess = 48.0f;
constexpr uint32_t kBackground = 0xffebeeeeu; /* RGBA8 (0xAABBGGRR): a light grey */

inline View make_view(int W, int H, double R, double extent, int P)
{
    View v;
    v.W = W;
    v.H = H;
    v.E = (float)extent;
    v.hh = (float)extent;
    v.hw = (float)(extent * W / H);
    v.R = (float)R;
    const double l[3] = {-0.45, 0.75, 0.5};
    const double ln = sqrt(l[0] * l[0] + l[1] * l[1] + l[2] * l[2]);
    double h[3] = {l[0] / ln, l[1] / ln, l[2] / ln + 1.0};
    const double hn = sqrt(h[0] * h[0] + h[1] * h[1] + h[2] * h[2]);
    for (int i = 0; i < 3; i++) {
        v.light[i] = (float)(l[i] / ln);
        v.half[i] = (float)(h[i] / hn);
    }
    v.P = P;
    const float root[3] = {0.16f, 0.10f, 0.06f}, tip[3] = {0.52f, 0.36f, 0.22f}, skin[3] = {0.80f, 0.62f, 0.50f};
    for (int i = 0; i < 3; i++) {
        v.root[i] = root[i];
        v.tip[i] = tip[i];
        v.skin[i] = skin[i];
    }
    return v;
}

HB_DV uint32_t rgba8(float r, float g, float b)
{
    const float c[3] = {r, g, b};
    uint32_t out = 0xff000000u;
    for (int i = 0; i < 3; i++) {
        const float x = c[i] < 0.0f ? 0.0f : c[i] > 1.0f ? 1.0f : c[i];
        out |= (uint32_t)(x * 255.0f + 0.5f) << (8 * i);
    }
    return out;
}

/* Kajiya–Kay colour of a fibre of unit tangent t at fraction s from root (0) to tip (1) */
HB_DV uint32_t shade_hair(const View &v, float tx, float ty, float tz, float s)
{
    const float tl = tx * v.light[0] + ty * v.light[1] + tz * v.light[2];
    const float th = tx * v.half[0] + ty * v.half[1] + tz * v.half[2];
    const float diffuse = sqrtf(fmaxf(1.0f - tl * tl, 0.0f));
    const float specular = powf(sqrtf(fmaxf(1.0f - th * th, 0.0f)), kShininess);
    float c[3];
    for (int i = 0; i < 3; i++)
        c[i] = (v.root[i] + (v.tip[i] - v.root[i]) * s) * (kAmbient + kDiffuse * diffuse) + kSpecular * specular;
    return rgba8(c[0], c[1], c[2]);
}

HB_DV uint64_t pack(float depth, uint32_t rgba)
{
    union {
        float f;
        uint32_t u;
    } d;
    d.f = depth;
    return ((uint64_t)d.u << 32) | rgba;
}

/* The value of pixel (col, row) before any strand: the head where the sphere covers the
 * pixel's centre, else the background at depth 1. */
HB_DV uint64_t head_pixel(const View &v, int col, int row)
{
    const float x = ((col + 0.5f) / v.W * 2.0f - 1.0f) * v.hw;
    const float y = (1.0f - (row + 0.5f) / v.H * 2.0f) * v.hh;
    const float r2 = x * x + y * y, R2 = v.R * v.R;
    if (r2 >= R2) return pack(1.0f, kBackground);
    const float z = sqrtf(R2 - r2);
    const float lambert = fmaxf((x * v.light[0] + y * v.light[1] + z * v.light[2]) / v.R, 0.0f);
    const float k = kAmbient + (1.0f - kAmbient) * lambert;
    return pack((v.E - z) / (2.0f * v.E), rgba8(v.skin[0] * k, v.skin[1] * k, v.skin[2] * k));
}

/* Segment a → b (world, cm) of point k of a strand: shaded once, then walked one pixel a step
 * along its longer screen axis, each pixel's centre-free position floor()ed, `plot(index, value)`
 * called for every pixel inside the image and the depth range (at most kMaxSteps + 1). The
 * end point is left to the next segment (the strand's last segment plots it). */
constexpr int kMaxSteps = 8192;
template <typename Plot> HB_DV void raster_segment(const View &v, const float a[3], const float b[3], int k, Plot plot)
{
    float t[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]};
    const float len = sqrtf(t[0] * t[0] + t[1] * t[1] + t[2] * t[2]);
    if (!(len > 0.0f) || !isfinite(len)) return;
    const uint32_t rgba = shade_hair(v, t[0] / len, t[1] / len, t[2] / len, (k + 0.5f) / (float)(v.P - 1));
    const float x0 = (a[0] / v.hw + 1.0f) * 0.5f * v.W, y0 = (1.0f - a[1] / v.hh) * 0.5f * v.H;
    const float x1 = (b[0] / v.hw + 1.0f) * 0.5f * v.W, y1 = (1.0f - b[1] / v.hh) * 0.5f * v.H;
    const float d0 = (v.E - a[2]) / (2.0f * v.E), d1 = (v.E - b[2]) / (2.0f * v.E);
    const float dx = x1 - x0, dy = y1 - y0;
    int n = (int)ceilf(fmaxf(fabsf(dx), fabsf(dy)));
    n = n < 1 ? 1 : n > kMaxSteps ? kMaxSteps : n;
    const int last = k + 2 == v.P ? n : n - 1;
    for (int j = 0; j <= last; j++) {
        const float f = (float)j / (float)n;
        const int col = (int)floorf(x0 + dx * f), row = (int)floorf(y0 + dy * f);
        const float d = d0 + (d1 - d0) * f;
        if (col < 0 || row < 0 || col >= v.W || row >= v.H || !(d >= 0.0f && d <= 1.0f)) continue;
        plot((int64_t)row * v.W + col, pack(d, rgba));
    }
}

} // namespace hb_draw

#endif
