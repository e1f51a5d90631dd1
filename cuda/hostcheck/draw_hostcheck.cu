/* draw_hostcheck.cu — --draw's two paths on the HOST with known answers (no GPU needed):
 *
 *   compute  cuda/draw/view.cuh's head_pixel and raster_segment, the functions the compute
 *            rasteriser's kernels call, with a host atomicMin;
 *   gl       cuda/draw/egl_gl.cuh's GlDraw through EGL (Mesa's llvmpipe on a CPU-only machine), the
 *            vertex buffer filled from the host instead of by CUDA.
 *
 * Each draws, at 200×100 (hw = 20, hh = 10 cm: 5 px a cm), a head of radius 5 and
 *   1. a strand along x at y = 4.1, z = 6 (in front of the head): exactly row 29 (the row of
 *      y = 4.1 is (1 − 4.1/10)/2·100 = 29.5), columns 50 to 149 (x from −10 to 10 cm);
 *   2. a strand along x at y = 0.1, z = −8 (behind the head): hidden where the head covers
 *      it (|x| < 5 cm), drawn outside; and the same strand at z = +8 drawn over the head.
 * Exit status 0 when every check holds; the last line counts them. Where EGL gives no
 * context the gl checks are skipped with one line saying why (tests/native skips with it). */
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <string.h>

#include <vector>

#include "draw/view.cuh"
#include "draw/egl_gl.cuh"

namespace {

using hb_draw::View;

const int W = 200, H = 100, P = 9;
const double R = 5.0, E = 10.0;
int checks = 0, failed = 0;

void check(bool ok, const char *path, const char *what)
{
    checks++;
    if (!ok) {
        failed++;
        printf("MISMATCH %s: %s\n", path, what);
    }
}

/* a straight strand of P points from (x0, y, z) to (x1, y, z) */
std::vector<float> strand(float x0, float x1, float y, float z)
{
    std::vector<float> s;
    for (int k = 0; k < P; k++) s.insert(s.end(), {x0 + (x1 - x0) * k / (P - 1), y, z});
    return s;
}

/* the kernel's atomicMin, on the host */
struct HostMin {
    uint64_t *fb;
    HB_DV void operator()(int64_t i, uint64_t value) const
    {
        if (value < fb[i]) fb[i] = value;
    }
};

std::vector<uint32_t> compute_image(const View &v, const std::vector<std::vector<float>> &strands)
{
    std::vector<uint64_t> fb((size_t)W * H);
    for (int r = 0; r < H; r++)
        for (int c = 0; c < W; c++) fb[(size_t)r * W + c] = hb_draw::head_pixel(v, c, r);
    for (const auto &s : strands)
        for (int k = 0; k + 1 < P; k++) hb_draw::raster_segment(v, &s[3 * k], &s[3 * k + 3], k, HostMin{fb.data()});
    std::vector<uint32_t> out(fb.size());
    for (size_t i = 0; i < fb.size(); i++) out[i] = (uint32_t)fb[i];
    return out;
}

/* the vertex buffer's layout: position, unit tangent (central differences) */
std::vector<float> vertices(const std::vector<std::vector<float>> &strands)
{
    std::vector<float> out;
    for (const auto &s : strands)
        for (int k = 0; k < P; k++) {
            const int a = k > 0 ? k - 1 : 0, b = k + 1 < P ? k + 1 : P - 1;
            float t[3], n = 0;
            for (int c = 0; c < 3; c++) t[c] = s[3 * b + c] - s[3 * a + c], n += t[c] * t[c];
            n = sqrtf(n);
            out.insert(out.end(), {s[3 * k], s[3 * k + 1], s[3 * k + 2], t[0] / n, t[1] / n, t[2] / n});
        }
    return out;
}

bool is_background(uint32_t px)
{
    return (px & 0xffffffu) == (hb_draw::kBackground & 0xffffffu);
}

/* the checks of both scenes on one path's images */
void scenes(const char *path, const std::vector<uint32_t> &one, const std::vector<uint32_t> &behind,
            const std::vector<uint32_t> &front, const std::vector<uint32_t> &bare, int end_slack)
{
    bool rows_ok = true, cols_ok = true;
    for (int r = 0; r < H; r++)
        for (int c = 0; c < W; c++) {
            const bool hit = one[(size_t)r * W + c] != bare[(size_t)r * W + c];
            const bool inside = r == 29 && c >= 50 + end_slack && c <= 149 - end_slack;
            const bool maybe = r == 29 && c >= 49 && c <= 150;
            if (inside && !hit) cols_ok = false;
            if (hit && !maybe) rows_ok = false;
        }
    check(cols_ok, path, "a strand along x at y = 4.1 covers row 29, columns 50-149");
    check(rows_ok, path, "... and no pixel off that row or past its ends");
    const int row = 49; /* y = 0.1 → row 49.5 */
    bool hidden = true, outside = true, over = true;
    for (int c = 0; c < W; c++) {
        const double x = ((c + 0.5) / W * 2 - 1) * 20.0;
        const size_t i = (size_t)row * W + c;
        if (fabs(x) < R - 0.5 && behind[i] != bare[i]) hidden = false;
        if (fabs(x) > R + 0.5 && fabs(x) < 9.5 && is_background(behind[i])) outside = false;
        if (fabs(x) < R - 0.5 && front[i] == bare[i]) over = false;
    }
    check(hidden, path, "a strand behind the head is hidden where the head covers it");
    check(outside, path, "... and drawn beside the head");
    check(over, path, "a strand in front of the head is drawn over it");
}

} // namespace

int main()
{
    const View v = hb_draw::make_view(W, H, R, E, P);
    const auto one = strand(-10, 10, 4.1f, 6), behind = strand(-10, 10, 0.1f, -8), front = strand(-10, 10, 0.1f, 8);
    scenes("compute", compute_image(v, {one}), compute_image(v, {behind}), compute_image(v, {front}),
           compute_image(v, {}), 0);
    const int n_compute = checks, f_compute = failed;
    hb_gl::GlDraw g;
    char why[256] = "";
    const char *gl_note = "";
    if (!g.open(v, 1, P, 0, 1, why, sizeof why)) {
        gl_note = why;
    } else {
        std::vector<std::vector<uint32_t>> images;
        for (const auto *s : {&one, &behind, &front, (const std::vector<float> *)nullptr}) {
            /* the bare image: the strand moved out of the view */
            const auto data = vertices({s ? *s : strand(-10, 10, 50, 0)});
            g.gl.glBindBuffer(hb_gl::GL_ARRAY_BUFFER, g.vbo);
            g.gl.glBufferSubData(hb_gl::GL_ARRAY_BUFFER, 0, (hb_gl::GLsizeiptr)(data.size() * sizeof(float)),
                                 data.data());
            g.draw(0);
            g.elapsed_ms(0);
            images.emplace_back();
            g.read(images.back());
        }
        scenes("gl", images[0], images[1], images[2], images[3], 1);
        printf("gl on %s\n", g.renderer);
        g.close();
    }
    if (*gl_note)
        printf("draw host check: compute %d checks, %d failed; gl skipped: %s; %d mismatches\n", n_compute, f_compute,
               gl_note, failed);
    else
        printf("draw host check: compute %d checks, %d failed; gl %d checks, %d failed; %d mismatches\n", n_compute,
               f_compute, checks - n_compute, failed - f_compute, failed);
    return failed ? 1 : 0;
}
