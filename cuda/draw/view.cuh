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
 * depths in [0, 1] order as their bits do, so a 64-bit atomicMin keeps the nearest colour.
 *
 * Shadows (the compute path): a shadow map of S×S depths seen from the light, orthographic
 * along it over the same sphere of radius E (light-space axes lu, lw ⟂ light; a point lands at
 * ((p·lu/E + 1)/2·S, (p·lw/E + 1)/2·S) at depth (E − p·light)/(2E)), holding the head and every
 * segment; a hair pixel farther from the light than the nearest depth of its 3×3 texels plus
 * kShadowBias is in shadow: diffuse times kShadowed, no specular. */
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
    float lu[3], lw[3];             /* the shadow map's axes (unit, ⟂ light and each other) */
    int S;                          /* the shadow map's side, texels */
};

constexpr float kAmbient = 0.2f, kDiffuse = 0.8f, kSpecular = 0.25f, kShininess = 48.0f;
constexpr int kMaxSteps = 8192;               /* the most pixels a segment walks */
constexpr int kShadowMap = 1024;              /* S */
constexpr float kShadowBias = 2.0f;           /* texels of depth (2E/S each) before a fragment counts as shadowed */
constexpr float kShadowed = 0.35f;            /* the diffuse term's share left in shadow */
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
    /* the shadow map's axes: lu = light × ŷ normalised (x̂ if the light is vertical), lw = light × lu */
    double u[3] = {-v.light[2], 0.0, v.light[0]};
    double un = sqrt(u[0] * u[0] + u[2] * u[2]);
    if (un < 1e-6) u[0] = 1.0, u[2] = 0.0, un = 1.0;
    for (int i = 0; i < 3; i++) v.lu[i] = (float)(u[i] / un);
    v.lw[0] = v.light[1] * v.lu[2] - v.light[2] * v.lu[1];
    v.lw[1] = v.light[2] * v.lu[0] - v.light[0] * v.lu[2];
    v.lw[2] = v.light[0] * v.lu[1] - v.light[1] * v.lu[0];
    v.S = kShadowMap;
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

/* Kajiya–Kay colour of a fibre of unit tangent t at fraction s from root (0) to tip (1); lit = 0:
 * in shadow (diffuse times kShadowed, no specular) */
HB_DV uint32_t shade_hair(const View &v, float tx, float ty, float tz, float s, bool lit = true)
{
    const float tl = tx * v.light[0] + ty * v.light[1] + tz * v.light[2];
    const float th = tx * v.half[0] + ty * v.half[1] + tz * v.half[2];
    const float diffuse = sqrtf(fmaxf(1.0f - tl * tl, 0.0f)) * (lit ? 1.0f : kShadowed);
    const float specular = lit ? powf(sqrtf(fmaxf(1.0f - th * th, 0.0f)), kShininess) : 0.0f;
    float c[3];
    for (int i = 0; i < 3; i++)
        c[i] = (v.root[i] + (v.tip[i] - v.root[i]) * s) * (kAmbient + kDiffuse * diffuse) + kSpecular * specular;
    return rgba8(c[0], c[1], c[2]);
}

/* a point's place in the shadow map: texel coordinates (su, sv) and depth from the light in [0, 1] */
HB_DV void light_space(const View &v, const float p[3], float &su, float &sv, float &d)
{
    su = ((p[0] * v.lu[0] + p[1] * v.lu[1] + p[2] * v.lu[2]) / v.E + 1.0f) * 0.5f * v.S;
    sv = ((p[0] * v.lw[0] + p[1] * v.lw[1] + p[2] * v.lw[2]) / v.E + 1.0f) * 0.5f * v.S;
    d = (v.E - (p[0] * v.light[0] + p[1] * v.light[1] + p[2] * v.light[2])) / (2.0f * v.E);
}

/* The shadow map's texel (col, row) before any strand: the depth of the head sphere's surface
 * nearest the light where it covers the texel's centre, else 1 (as float bits: they order as
 * the depths do). */
HB_DV uint32_t head_shadow(const View &v, int col, int row)
{
    const float a = ((col + 0.5f) / v.S * 2.0f - 1.0f) * v.E, b = ((row + 0.5f) / v.S * 2.0f - 1.0f) * v.E;
    const float r2 = a * a + b * b, R2 = v.R * v.R;
    const float d = r2 >= R2 ? 1.0f : (v.E - sqrtf(R2 - r2)) / (2.0f * v.E);
    union {
        float f;
        uint32_t u;
    } x;
    x.f = d;
    return x.u;
}

/* Segment a → b walked in the shadow map, `plot(index, depth bits)` for each texel it covers. */
template <typename Plot> HB_DV void shadow_segment(const View &v, const float a[3], const float b[3], Plot plot)
{
    float ua, va, da, ub, vb, db;
    light_space(v, a, ua, va, da);
    light_space(v, b, ub, vb, db);
    const float du = ub - ua, dv = vb - va;
    if (!(isfinite(du) && isfinite(dv))) return;
    int n = (int)ceilf(fmaxf(fabsf(du), fabsf(dv)));
    n = n < 1 ? 1 : n > kMaxSteps ? kMaxSteps : n;
    for (int j = 0; j <= n; j++) {
        const float f = (float)j / (float)n;
        const int col = (int)floorf(ua + du * f), row = (int)floorf(va + dv * f);
        const float d = da + (db - da) * f;
        if (col < 0 || row < 0 || col >= v.S || row >= v.S || !(d >= 0.0f && d <= 1.0f)) continue;
        union {
            float f;
            uint32_t u;
        } x;
        x.f = d;
        plot((int64_t)row * v.S + col, x.u);
    }
}

/* no shadow map: every fragment lit */
struct NoShadow {
    HB_DV bool operator()(const View &, const float *) const { return false; }
};
/* a shadow map of v.S² depth bits (head_shadow, then shadow_segment's atomicMin), read as the
 * nearest depth of the 3×3 texels about the point's (a one-texel line drawn from one strand's
 * end points and looked up from another's pixels lands a texel off about half the time) */
struct ShadowMap {
    const uint32_t *map;
    HB_DV bool operator()(const View &v, const float p[3]) const
    {
        float su, sv, d;
        light_space(v, p, su, sv, d);
        const int col = (int)floorf(su), row = (int)floorf(sv);
        if (!(col >= 1 && row >= 1 && col < v.S - 1 && row < v.S - 1)) return false;
        uint32_t m = 0xffffffffu;
        for (int r = row - 1; r <= row + 1; r++)
            for (int c = col - 1; c <= col + 1; c++) {
                const uint32_t x = map[(int64_t)r * v.S + c];
                m = x < m ? x : m;
            }
        union {
            float f;
            uint32_t u;
        } x;
        x.u = m;
        return x.f + kShadowBias / (float)v.S < d;
    }
};

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

/* Segment a → b (world, cm) of point k of a strand: shaded once (lit and in shadow), then walked
 * one pixel a step along its longer screen axis, each pixel's centre-free position floor()ed,
 * `plot(index, value)` called for every pixel inside the image and the depth range (at most
 * kMaxSteps + 1), with the shadowed colour where `shadowed(v, point)` says so. The end point is
 * left to the next segment (the strand's last segment plots it). */
template <typename Plot, typename Shadow = NoShadow>
HB_DV void raster_segment(const View &v, const float a[3], const float b[3], int k, Plot plot, Shadow shadowed = {})
{
    float t[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]};
    const float len = sqrtf(t[0] * t[0] + t[1] * t[1] + t[2] * t[2]);
    if (!(len > 0.0f) || !isfinite(len)) return;
    const float sk = (k + 0.5f) / (float)(v.P - 1);
    const uint32_t rgba = shade_hair(v, t[0] / len, t[1] / len, t[2] / len, sk);
    const uint32_t dark = shade_hair(v, t[0] / len, t[1] / len, t[2] / len, sk, false);
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
        const float q[3] = {a[0] + t[0] * f, a[1] + t[1] * f, a[2] + t[2] * f};
        plot((int64_t)row * v.W + col, pack(d, shadowed(v, q) ? dark : rgba));
    }
}

} // namespace hb_draw

#endif
