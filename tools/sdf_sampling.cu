/* tools/sdf_sampling.cu — issue #43: a collider mesh's SDF (docs/model.md §3.17) sampled on the GPU
 * by plain loads against a 3-D texture with hardware trilinear filtering. The head mesh's field is
 * built by the reference (hb_mesh_sdf), rounded to fp32, and sampled at Q points inside the narrow
 * band, φ and its gradient a point, in two orders: the cells' Morton order (as the lanes kernel's
 * warps take strands) and random. Each sampler × order: the median kernel time of R repeats after a
 * warm-up (CUDA events, the samplers taken in turn each repeat) and its accuracy against `loads`.
 * One table on stdout; --json PATH writes every number. docs/cuda.md, "The hair–hair grid and the
 * colliders". Built by `make build/sdf-sampling` (part of `make cuda`).
 *
 *   build/sdf-sampling --obj configs/bodies/head.obj --n 64 --points 16777216 [--band 4]
 *                      [--seed 1] [--repeats 20] [--json out.json]
 *
 * Texture coordinates: unnormalized, and a linear fetch at x weighs the texels floor(x − 0.5) and
 * floor(x − 0.5) + 1 by frac(x − 0.5), so node i's value sits at i + 0.5: grid coordinate g is
 * fetched at g + 0.5 (the node check below confirms it on the device). The hardware's weights
 * carry 8 fractional bits.
 */
#include <cuda_runtime.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdarg>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>
#include <vector>

#include "dynamic/world.h"

#ifndef HB_GIT_REV
#define HB_GIT_REV "unknown"
#endif
#ifndef HB_FLAGS
#define HB_FLAGS "unknown"
#endif

enum { EXIT_RUNTIME = 1, EXIT_USAGE = 2 }; /* a CUDA call or the JSON write failed; bad input */

/* the JSON being written (PATH.partial), removed by fail so that no partial output is left */
static std::string g_partial;

__attribute__((format(printf, 2, 3))) [[noreturn]] static void fail(int code, const char *fmt, ...)
{
    if (!g_partial.empty()) remove(g_partial.c_str());
    va_list ap;
    va_start(ap, fmt);
    fputs("error: ", stderr);
    vfprintf(stderr, fmt, ap);
    fputc('\n', stderr);
    va_end(ap);
    exit(code);
}

#define CUDA_CHECK(call) cuda_check((call), #call)
static void cuda_check(cudaError_t e, const char *what)
{
    if (e != cudaSuccess) fail(EXIT_RUNTIME, "%s: %s", what, cudaGetErrorString(e));
}

/* ---- the samplers ---- */
enum Sampler { IO_ONLY, LOADS, TEX_FORWARD, TEX_CENTRAL, TEX_FACES, TEX_POINTS, SAMPLERS };
struct SamplerInfo {
    const char *name;
    int fetches; /* loads or texture fetches a point */
    const char *what;
};
static const SamplerInfo kSamplers[SAMPLERS] = {
    {"io-only", 0, "the point read and written back, no SDF: the streaming every row pays"},
    {"loads", 8, "8 corner loads through the read-only cache (__ldg), hb_sdf_sample's phi and analytic gradient"},
    {"texture", 4, "linear filtering: phi at g + 0.5, the gradient by forward differences one cell apart"},
    {"texture-central", 7, "linear filtering: phi at g + 0.5, the gradient by central differences over two cells"},
    {"texture-faces", 6,
     "linear filtering on the cell's faces: per axis the two bilinear values at the cell's nodes along it "
     "(their difference is the analytic gradient), phi by one axis's lerp"},
    {"texture-points", 8, "point filtering at the 8 corners (texture cache, exact values), then loads' arithmetic"},
};

/* The field on the device: linear memory for `loads`, a 3-D array behind two texture objects. */
struct Field {
    const float *sdf; /* n³, x fastest */
    cudaTextureObject_t linear, point;
    int n;
    float lo[3], inv_h; /* the cube's corner and 1/Δ_s, as the backend's sdf_geo */
};

/* The grid coordinate of p, false outside [0, n − 1) on an axis (hb_sdf_sample's test). */
__device__ __forceinline__ bool grid_coord(const Field &F, float4 p, float (&gc)[3])
{
    const float u[3] = {p.x, p.y, p.z};
    bool inside = true;
#pragma unroll
    for (int c = 0; c < 3; c++) {
        gc[c] = (u[c] - F.lo[c]) * F.inv_h;
        inside = inside && gc[c] >= 0.f && gc[c] < (float)(F.n - 1);
    }
    return inside;
}

/* φ and ∂φ/∂g (per cell) of the trilinear interpolant of the corners v (k: bit 0 x, bit 1 y,
 * bit 2 z) at the fractions f: hb_sdf_sample's operations in fp32. */
__device__ __forceinline__ float4 trilinear(const float (&v)[8], const float (&f)[3])
{
    float s = 0.f;
#pragma unroll
    for (int k = 0; k < 8; k++) {
        const float wx = (k & 1) ? f[0] : 1.f - f[0];
        const float wy = (k & 2) ? f[1] : 1.f - f[1];
        const float wz = (k & 4) ? f[2] : 1.f - f[2];
        s = s + ((wx * wy) * wz) * v[k];
    }
    float g[3];
#pragma unroll
    for (int c = 0; c < 3; c++) { /* the four edges along c, each weighted by the other two fractions */
        const int a1 = c == 0 ? 1 : 0, a2 = c == 2 ? 1 : 2;
        const int bit = 1 << c, b1 = 1 << a1, b2 = 1 << a2;
        float acc = 0.f;
#pragma unroll
        for (int e = 0; e < 4; e++) {
            const int k0 = ((e & 1) ? b1 : 0) | ((e & 2) ? b2 : 0);
            const float w1 = (e & 1) ? f[a1] : 1.f - f[a1];
            const float w2 = (e & 2) ? f[a2] : 1.f - f[a2];
            acc = acc + (w1 * w2) * (v[k0 | bit] - v[k0]);
        }
        g[c] = acc;
    }
    return make_float4(s, g[0], g[1], g[2]);
}

/* One sample: (φ, ∂φ/∂g_x, ∂φ/∂g_y, ∂φ/∂g_z) at the grid coordinate gc (inside the cube). */
template <int S> __device__ __forceinline__ float4 sample(const Field &F, const float (&gc)[3])
{
    if constexpr (S == LOADS || S == TEX_POINTS) {
        int i[3];
        float f[3], v[8];
#pragma unroll
        for (int c = 0; c < 3; c++) {
            i[c] = (int)gc[c];
            f[c] = gc[c] - (float)i[c];
        }
        if constexpr (S == LOADS) {
            const int n = F.n, nn = n * n;
            const float *b = F.sdf + (i[0] + n * (i[1] + n * i[2]));
#pragma unroll
            for (int k = 0; k < 8; k++) v[k] = __ldg(b + ((k & 1) ? 1 : 0) + ((k & 2) ? n : 0) + ((k & 4) ? nn : 0));
        } else {
            const float x = (float)i[0] + 0.5f, y = (float)i[1] + 0.5f, z = (float)i[2] + 0.5f;
#pragma unroll
            for (int k = 0; k < 8; k++)
                v[k] = tex3D<float>(F.point, x + (float)(k & 1), y + (float)((k >> 1) & 1), z + (float)(k >> 2));
        }
        return trilinear(v, f);
    } else {
        const cudaTextureObject_t t = F.linear;
        const float x = gc[0] + 0.5f, y = gc[1] + 0.5f, z = gc[2] + 0.5f; /* node i at i + 0.5 */
        if constexpr (S == TEX_FORWARD) {
            const float p0 = tex3D<float>(t, x, y, z);
            return make_float4(p0, tex3D<float>(t, x + 1.f, y, z) - p0, tex3D<float>(t, x, y + 1.f, z) - p0,
                               tex3D<float>(t, x, y, z + 1.f) - p0);
        } else if constexpr (S == TEX_CENTRAL) {
            const float p0 = tex3D<float>(t, x, y, z);
            return make_float4(p0, 0.5f * (tex3D<float>(t, x + 1.f, y, z) - tex3D<float>(t, x - 1.f, y, z)),
                               0.5f * (tex3D<float>(t, x, y + 1.f, z) - tex3D<float>(t, x, y - 1.f, z)),
                               0.5f * (tex3D<float>(t, x, y, z + 1.f) - tex3D<float>(t, x, y, z - 1.f)));
        } else { /* TEX_FACES: along each axis the cell's two nodes, the other two axes filtered */
            const float ix = floorf(gc[0]), iy = floorf(gc[1]), iz = floorf(gc[2]);
            const float ax = tex3D<float>(t, ix + 0.5f, y, z), bx = tex3D<float>(t, ix + 1.5f, y, z);
            const float ay = tex3D<float>(t, x, iy + 0.5f, z), by = tex3D<float>(t, x, iy + 1.5f, z);
            const float az = tex3D<float>(t, x, y, iz + 0.5f), bz = tex3D<float>(t, x, y, iz + 1.5f);
            const float gx = bx - ax;
            return make_float4(ax + (gc[0] - ix) * gx, gx, by - ay, bz - az);
        }
    }
}

/* A thread a point: its sample (zeros outside the cube), or for IO_ONLY the point itself. */
template <int S>
__global__ void __launch_bounds__(256)
    k_sample(Field F, const float4 *__restrict__ pts, float4 *__restrict__ out, int64_t q)
{
    const int64_t t = (int64_t)blockIdx.x * blockDim.x + threadIdx.x;
    if (t >= q) return;
    const float4 p = pts[t];
    if constexpr (S == IO_ONLY) {
        out[t] = p;
    } else {
        float gc[3];
        float4 r = make_float4(0.f, 0.f, 0.f, 0.f);
        if (grid_coord(F, p, gc)) r = sample<S>(F, gc);
        out[t] = r;
    }
}

using SampleKernel = void (*)(Field, const float4 *, float4 *, int64_t);
static const SampleKernel kKernels[SAMPLERS] = {k_sample<IO_ONLY>,     k_sample<LOADS>,     k_sample<TEX_FORWARD>,
                                                k_sample<TEX_CENTRAL>, k_sample<TEX_FACES>, k_sample<TEX_POINTS>};

/* Every node fetched through both textures at i + 0.5 against its stored value: worst[0] the
 * largest |difference| of the linear one, worst[1] of the point one (bits of non-negative floats
 * order as unsigned integers). */
__global__ void k_node_check(Field F, unsigned *worst)
{
    const int64_t t = (int64_t)blockIdx.x * blockDim.x + threadIdx.x, n = F.n;
    if (t >= n * n * n) return;
    const float x = (float)(t % n) + 0.5f, y = (float)((t / n) % n) + 0.5f, z = (float)(t / (n * n)) + 0.5f;
    const float v = F.sdf[t];
    atomicMax(&worst[0], __float_as_uint(fabsf(tex3D<float>(F.linear, x, y, z) - v)));
    atomicMax(&worst[1], __float_as_uint(fabsf(tex3D<float>(F.point, x, y, z) - v)));
}

/* ---- the command line ---- */
struct Options {
    std::string obj = "configs/bodies/head.obj", json;
    long long n = 64, band = 4, points = 1LL << 24, repeats = 20;
    unsigned long long seed = 1;
};

static long long parse_int(const char *flag, const char *v, long long lo, long long hi)
{
    errno = 0;
    char *end = nullptr;
    const long long x = strtoll(v, &end, 10);
    if (errno != 0 || end == v || *end != '\0') fail(EXIT_USAGE, "%s takes an integer (got '%s')", flag, v);
    if (x < lo || x > hi) fail(EXIT_USAGE, "%s takes %lld to %lld (got %lld)", flag, lo, hi, x);
    return x;
}

static void usage(FILE *f)
{
    fprintf(f, "usage: sdf-sampling [--obj PATH] [--n N] [--band W] [--points Q] [--seed S] [--repeats R] "
               "[--json PATH]\n"
               "  --obj PATH    closed OBJ mesh (default configs/bodies/head.obj)\n"
               "  --n N         SDF nodes per axis, 8 to 512 (default 64)\n"
               "  --band W      exact within W spacings, 0: everywhere (default 4, as default.colliders)\n"
               "  --points Q    query points, 1 to 2^28 (default 2^24)\n"
               "  --seed S      the points' generator seed (default 1)\n"
               "  --repeats R   timed launches a sampler and order after one warm-up, 1 to 1000 (default 20)\n"
               "  --json PATH   also write every number as JSON\n");
}

static Options parse_args(int argc, char **argv)
{
    Options o;
    for (int a = 1; a < argc; a++) {
        const char *f = argv[a];
        if (strcmp(f, "--help") == 0 || strcmp(f, "-h") == 0) {
            usage(stdout);
            exit(0);
        }
        const bool known = strcmp(f, "--obj") == 0 || strcmp(f, "--n") == 0 || strcmp(f, "--band") == 0 ||
                           strcmp(f, "--points") == 0 || strcmp(f, "--seed") == 0 || strcmp(f, "--repeats") == 0 ||
                           strcmp(f, "--json") == 0;
        if (!known) fail(EXIT_USAGE, "unknown argument '%s' (--help lists them)", f);
        if (a + 1 >= argc) fail(EXIT_USAGE, "%s needs a value", f);
        const char *v = argv[++a];
        if (strcmp(f, "--obj") == 0) o.obj = v;
        else if (strcmp(f, "--json") == 0) o.json = v;
        else if (strcmp(f, "--n") == 0) o.n = parse_int(f, v, 8, 512);
        else if (strcmp(f, "--band") == 0) o.band = parse_int(f, v, 0, 512);
        else if (strcmp(f, "--points") == 0) o.points = parse_int(f, v, 1, 1LL << 28);
        else if (strcmp(f, "--repeats") == 0) o.repeats = parse_int(f, v, 1, 1000);
        else o.seed = (unsigned long long)parse_int(f, v, 0, INT64_MAX);
    }
    return o;
}

/* ---- the query points ---- */
/* SplitMix64's finaliser: the points' generator is counter-based, value(i) = mix64(key + i·γ). */
static uint64_t mix64(uint64_t z)
{
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ULL;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBULL;
    return z ^ (z >> 31);
}
static const uint64_t kGolden = 0x9E3779B97F4A7C15ULL;

static uint32_t spread_bits3(uint32_t v) /* the 10 low bits of v, two zero bits after each */
{
    v &= 0x3ffu;
    v = (v | (v << 16)) & 0x030000FFu;
    v = (v | (v << 8)) & 0x0300F00Fu;
    v = (v | (v << 4)) & 0x030C30C3u;
    v = (v | (v << 2)) & 0x09249249u;
    return v;
}

/* The points: a band cell drawn uniformly, a uniform position in it. random: in the order drawn
 * (random); coherent: the same points sorted by their cell's Morton code (a counting sort, the
 * cells being listed in Morton order). Also the number of band cells. */
static int64_t make_points(const hb_collider &col, const float lo[3], float inv_h, int64_t q, uint64_t seed,
                           std::vector<float4> &random, std::vector<float4> &coherent)
{
    const int64_t n = col.sdf_n;
    const double far = col.band > 0 ? (double)col.band * col.sdf_h : INFINITY;
    std::vector<std::pair<uint32_t, int64_t>> cells; /* (Morton code, x + n·(y + n·z)) of each band cell */
    for (int64_t z = 0; z + 1 < n; z++)
        for (int64_t y = 0; y + 1 < n; y++)
            for (int64_t x = 0; x + 1 < n; x++) {
                const int64_t b = x + n * (y + n * z);
                bool in = true;
                for (int k = 0; k < 8; k++) {
                    const int64_t j = b + ((k & 1) ? 1 : 0) + ((k & 2) ? n : 0) + ((k & 4) ? n * n : 0);
                    in = in && std::fabs((double)col.sdf[j]) < far;
                }
                if (in)
                    cells.push_back(
                        {spread_bits3((uint32_t)x) | spread_bits3((uint32_t)y) << 1 | spread_bits3((uint32_t)z) << 2,
                         b});
            }
    if (cells.empty()) fail(EXIT_USAGE, "no cell of the %lld^3 SDF has its 8 nodes within the band", (long long)n);
    std::sort(cells.begin(), cells.end());
    const uint64_t nc = cells.size(), key = mix64(seed ^ 0x5DF5A3B1ULL);
    std::vector<uint32_t> rank((size_t)q);
    std::vector<int64_t> start(nc + 1, 0);
    random.resize((size_t)q);
    for (int64_t i = 0; i < q; i++) {
        const uint64_t c = 4 * (uint64_t)i;
        const uint64_t r = ((mix64(key + c * kGolden) >> 32) * nc) >> 32; /* counters 4i … 4i + 3 */
        const int64_t b = cells[r].second;
        const int64_t node[3] = {b % n, (b / n) % n, b / (n * n)};
        float u[3];
        for (int a = 0; a < 3; a++) {
            const double f = (double)(mix64(key + (c + 1 + a) * kGolden) >> 40) * 0x1p-24;
            u[a] = (float)(col.sdf_lo[a] + ((double)node[a] + f) * col.sdf_h);
            const float gc = (u[a] - lo[a]) * inv_h; /* the device's arithmetic */
            if (!(gc >= 0.f && gc < (float)(n - 1)))
                u[a] = (float)(col.sdf_lo[a] + ((double)node[a] + 0.5) * col.sdf_h);
        }
        random[(size_t)i] = make_float4(u[0], u[1], u[2], 0.f);
        rank[(size_t)i] = (uint32_t)r;
        start[r + 1]++;
    }
    for (uint64_t r = 0; r < nc; r++) start[r + 1] += start[r];
    coherent.resize((size_t)q);
    for (int64_t i = 0; i < q; i++) coherent[(size_t)start[rank[(size_t)i]]++] = random[(size_t)i];
    return (int64_t)nc;
}

/* ---- results ---- */
struct Row {
    int order, sampler;
    double median_ms = 0, min_ms = 0, samples_per_s = 0, checksum = 0;
    /* against `loads` (NaN for io-only) */
    double max_dphi = NAN, p99_dphi = NAN, max_angle = NAN, p99_angle = NAN;
    int64_t angle_points = 0;
};
static const char *kOrders[2] = {"coherent", "random"};

static double quantile(std::vector<double> &v, double p) /* the value of rank ceil(p·size) (1-based) */
{
    if (v.empty()) return NAN;
    size_t k = (size_t)std::ceil(p * (double)v.size());
    k = k == 0 ? 0 : k - 1;
    std::nth_element(v.begin(), v.begin() + (ptrdiff_t)k, v.end());
    return v[k];
}

static void compare(const std::vector<float4> &ref, const std::vector<float4> &got, Row &r)
{
    std::vector<double> dphi(ref.size()), angle;
    angle.reserve(ref.size());
    double sum = 0;
    for (size_t i = 0; i < ref.size(); i++) {
        const float4 a = ref[i], b = got[i];
        sum += ((double)b.x + (double)b.y) + ((double)b.z + (double)b.w);
        dphi[i] = std::fabs((double)b.x - (double)a.x);
        const double ga[3] = {a.y, a.z, a.w}, gb[3] = {b.y, b.z, b.w};
        const double la = std::sqrt(ga[0] * ga[0] + ga[1] * ga[1] + ga[2] * ga[2]);
        const double lb = std::sqrt(gb[0] * gb[0] + gb[1] * gb[1] + gb[2] * gb[2]);
        if (!(la > 1e-6 && lb > 1e-6)) continue;
        const double cx = ga[1] * gb[2] - ga[2] * gb[1], cy = ga[2] * gb[0] - ga[0] * gb[2],
                     cz = ga[0] * gb[1] - ga[1] * gb[0];
        const double dot = ga[0] * gb[0] + ga[1] * gb[1] + ga[2] * gb[2];
        angle.push_back(std::atan2(std::sqrt(cx * cx + cy * cy + cz * cz), dot) * (180.0 / M_PI));
    }
    r.checksum = sum;
    if (r.sampler == IO_ONLY) return;
    r.max_dphi = *std::max_element(dphi.begin(), dphi.end());
    r.p99_dphi = quantile(dphi, 0.99);
    r.angle_points = (int64_t)angle.size();
    r.max_angle = angle.empty() ? NAN : *std::max_element(angle.begin(), angle.end());
    r.p99_angle = quantile(angle, 0.99);
}

static void json_string(FILE *f, const char *s)
{
    fputc('"', f);
    for (; *s; s++) {
        if (*s == '"' || *s == '\\') fprintf(f, "\\%c", *s);
        else if ((unsigned char)*s < 0x20) fprintf(f, "\\u%04x", (unsigned)(unsigned char)*s);
        else fputc(*s, f);
    }
    fputc('"', f);
}
static void json_number(FILE *f, double x)
{
    if (std::isfinite(x)) fprintf(f, "%.9g", x);
    else fputs("null", f);
}

int main(int argc, char **argv)
{
    const Options o = parse_args(argc, argv);
    FILE *jf = nullptr;
    if (!o.json.empty()) { /* refused before any work: nothing the user has is overwritten */
        FILE *old = fopen(o.json.c_str(), "r");
        if (old) {
            fclose(old);
            fail(EXIT_USAGE, "--json %s: exists (remove it or name another)", o.json.c_str());
        }
    }

    /* the field: the reference's, in double, then rounded to fp32 */
    hb_colliders cols;
    memset(&cols, 0, sizeof cols);
    char err[HB_ERRLEN];
    if (hb_mesh_sdf(o.obj.c_str(), o.n, o.band, &cols.c[0], err, sizeof err) != 0) { /* its messages name --colliders */
        const char *prefix = "--colliders mesh ";
        const bool named = strncmp(err, prefix, strlen(prefix)) == 0;
        fail(EXIT_USAGE, "%s%s", named ? "--obj " : "", named ? err + strlen(prefix) : err);
    }
    cols.n = 1;
    const hb_collider &col = cols.c[0];
    const int n = (int)col.sdf_n;
    const size_t nodes = (size_t)n * n * n;
    std::vector<float> sdf(nodes);
    for (size_t j = 0; j < nodes; j++) sdf[j] = (float)col.sdf[j];
    const float lo[3] = {(float)col.sdf_lo[0], (float)col.sdf_lo[1], (float)col.sdf_lo[2]};
    const float inv_h = (float)(1.0 / col.sdf_h);

    const int64_t q = o.points;
    std::vector<float4> orders[2];
    const int64_t band_cells = make_points(col, lo, inv_h, q, o.seed, orders[1], orders[0]);

    /* the device's copies: linear memory, and a 3-D array with a linear and a point texture */
    int dev = 0;
    CUDA_CHECK(cudaGetDevice(&dev));
    cudaDeviceProp prop;
    CUDA_CHECK(cudaGetDeviceProperties(&prop, dev));
    Field F;
    memset(&F, 0, sizeof F);
    F.n = n;
    for (int c = 0; c < 3; c++) F.lo[c] = lo[c];
    F.inv_h = inv_h;
    float *d_sdf = nullptr;
    CUDA_CHECK(cudaMalloc(&d_sdf, nodes * sizeof(float)));
    CUDA_CHECK(cudaMemcpy(d_sdf, sdf.data(), nodes * sizeof(float), cudaMemcpyHostToDevice));
    F.sdf = d_sdf;
    const cudaChannelFormatDesc ch = cudaCreateChannelDesc<float>();
    const cudaExtent ext = make_cudaExtent((size_t)n, (size_t)n, (size_t)n);
    cudaArray_t arr = nullptr;
    CUDA_CHECK(cudaMalloc3DArray(&arr, &ch, ext));
    cudaMemcpy3DParms cp;
    memset(&cp, 0, sizeof cp);
    cp.srcPtr = make_cudaPitchedPtr(sdf.data(), (size_t)n * sizeof(float), (size_t)n, (size_t)n);
    cp.dstArray = arr;
    cp.extent = ext;
    cp.kind = cudaMemcpyHostToDevice;
    CUDA_CHECK(cudaMemcpy3D(&cp));
    cudaResourceDesc rd;
    memset(&rd, 0, sizeof rd);
    rd.resType = cudaResourceTypeArray;
    rd.res.array.array = arr;
    cudaTextureDesc td;
    memset(&td, 0, sizeof td);
    for (int c = 0; c < 3; c++) td.addressMode[c] = cudaAddressModeClamp;
    td.readMode = cudaReadModeElementType;
    td.normalizedCoords = 0;
    td.filterMode = cudaFilterModeLinear;
    CUDA_CHECK(cudaCreateTextureObject(&F.linear, &rd, &td, nullptr));
    td.filterMode = cudaFilterModePoint;
    CUDA_CHECK(cudaCreateTextureObject(&F.point, &rd, &td, nullptr));

    /* the node check: both textures at i + 0.5 give the stored values */
    unsigned *d_worst = nullptr, worst[2] = {0, 0};
    CUDA_CHECK(cudaMalloc(&d_worst, sizeof worst));
    CUDA_CHECK(cudaMemset(d_worst, 0, sizeof worst));
    k_node_check<<<(unsigned)((nodes + 255) / 256), 256>>>(F, d_worst);
    CUDA_CHECK(cudaGetLastError());
    CUDA_CHECK(cudaMemcpy(worst, d_worst, sizeof worst, cudaMemcpyDeviceToHost));
    float node_err[2];
    memcpy(node_err, worst, sizeof node_err);

    float4 *d_pts = nullptr, *d_out[SAMPLERS];
    CUDA_CHECK(cudaMalloc(&d_pts, (size_t)q * sizeof(float4)));
    for (int s = 0; s < SAMPLERS; s++) CUDA_CHECK(cudaMalloc(&d_out[s], (size_t)q * sizeof(float4)));
    cudaEvent_t ev[SAMPLERS][2];
    for (int s = 0; s < SAMPLERS; s++)
        for (int e = 0; e < 2; e++) CUDA_CHECK(cudaEventCreate(&ev[s][e]));
    const unsigned blocks = (unsigned)((q + 255) / 256);

    std::vector<Row> rows;
    std::vector<float4> ref((size_t)q), got((size_t)q);
    for (int ord = 0; ord < 2; ord++) {
        CUDA_CHECK(cudaMemcpy(d_pts, orders[ord].data(), (size_t)q * sizeof(float4), cudaMemcpyHostToDevice));
        for (int s = 0; s < SAMPLERS; s++) kKernels[s]<<<blocks, 256>>>(F, d_pts, d_out[s], q); /* warm-up */
        CUDA_CHECK(cudaGetLastError());
        CUDA_CHECK(cudaDeviceSynchronize());
        std::vector<std::vector<double>> ms(SAMPLERS);
        for (long long rep = 0; rep < o.repeats; rep++) { /* the samplers in turn, each repeat */
            for (int s = 0; s < SAMPLERS; s++) {
                CUDA_CHECK(cudaEventRecord(ev[s][0]));
                kKernels[s]<<<blocks, 256>>>(F, d_pts, d_out[s], q);
                CUDA_CHECK(cudaEventRecord(ev[s][1]));
            }
            CUDA_CHECK(cudaGetLastError());
            CUDA_CHECK(cudaDeviceSynchronize());
            for (int s = 0; s < SAMPLERS; s++) {
                float t = 0.f;
                CUDA_CHECK(cudaEventElapsedTime(&t, ev[s][0], ev[s][1]));
                ms[s].push_back(t);
            }
        }
        CUDA_CHECK(cudaMemcpy(ref.data(), d_out[LOADS], (size_t)q * sizeof(float4), cudaMemcpyDeviceToHost));
        for (int s = 0; s < SAMPLERS; s++) {
            Row r;
            r.order = ord;
            r.sampler = s;
            std::vector<double> &t = ms[s];
            std::sort(t.begin(), t.end());
            const size_t m = t.size();
            r.median_ms = m % 2 ? t[m / 2] : 0.5 * (t[m / 2 - 1] + t[m / 2]);
            r.min_ms = t[0];
            r.samples_per_s = (double)q / (r.median_ms * 1e-3);
            CUDA_CHECK(cudaMemcpy(got.data(), d_out[s], (size_t)q * sizeof(float4), cudaMemcpyDeviceToHost));
            compare(ref, got, r);
            rows.push_back(r);
        }
    }

    /* the table */
    const double h = col.sdf_h;
    printf("sdf-sampling: %s (sm_%d%d), %s at %d^3, band %lld (h = %.6g cm), %lld points in %lld band cells, "
           "seed %llu, median of %lld repeats\n",
           prop.name, prop.major, prop.minor, o.obj.c_str(), n, (long long)col.band, h, (long long)q,
           (long long)band_cells, o.seed, o.repeats);
    printf("node check (every node fetched at i + 0.5 against its fp32 value): linear max |diff| %.3g cm, "
           "point %.3g cm\n",
           (double)node_err[0], (double)node_err[1]);
    printf("accuracy against loads; gradient angles over points where both |g| > 1e-6 (per cell)\n");
    printf("%-8s  %-15s  %7s  %9s  %9s  %10s  %11s  %11s  %9s  %9s  %9s  %9s  %14s\n", "order", "sampler", "fetches",
           "median ms", "min ms", "Gsamples/s", "max|dphi|cm", "p99|dphi|cm", "max cells", "p99 cells", "max deg",
           "p99 deg", "checksum");
    for (const Row &r : rows) {
        printf("%-8s  %-15s  %7d  %9.4f  %9.4f  %10.3f", kOrders[r.order], kSamplers[r.sampler].name,
               kSamplers[r.sampler].fetches, r.median_ms, r.min_ms, r.samples_per_s * 1e-9);
        if (r.sampler == IO_ONLY) printf("  %11s  %11s  %9s  %9s  %9s  %9s", "-", "-", "-", "-", "-", "-");
        else
            printf("  %11.3g  %11.3g  %9.3g  %9.3g  %9.3g  %9.3g", r.max_dphi, r.p99_dphi, r.max_dphi / h,
                   r.p99_dphi / h, r.max_angle, r.p99_angle);
        printf("  %14.7e\n", r.checksum);
    }
    for (int s = 0; s < SAMPLERS; s++) printf("  %-15s %s\n", kSamplers[s].name, kSamplers[s].what);

    if (!o.json.empty()) { /* written whole to PATH.partial, then renamed */
        g_partial = o.json + ".partial";
        if (!(jf = fopen(g_partial.c_str(), "w"))) {
            const int e = errno;
            g_partial.clear();
            fail(EXIT_USAGE, "--json %s: %s", o.json.c_str(), strerror(e));
        }
        fprintf(jf, "{\n  \"tool\": \"sdf-sampling\",\n  \"revision\": ");
        json_string(jf, HB_GIT_REV);
        fprintf(jf, ",\n  \"build\": ");
        json_string(jf, HB_FLAGS);
        fprintf(jf, ",\n  \"device\": ");
        json_string(jf, prop.name);
        fprintf(jf, ",\n  \"compute_capability\": \"%d.%d\",\n  \"obj\": ", prop.major, prop.minor);
        json_string(jf, o.obj.c_str());
        fprintf(jf, ",\n  \"n\": %d,\n  \"band\": %lld,\n  \"h_cm\": ", n, (long long)col.band);
        json_number(jf, h);
        fprintf(jf, ",\n  \"lo_cm\": [");
        for (int c = 0; c < 3; c++) {
            json_number(jf, col.sdf_lo[c]);
            fputs(c < 2 ? ", " : "]", jf);
        }
        fprintf(jf, ",\n  \"points\": %lld,\n  \"band_cells\": %lld,\n  \"seed\": %llu,\n  \"repeats\": %lld,\n",
                (long long)q, (long long)band_cells, o.seed, o.repeats);
        fprintf(jf, "  \"node_check_max_abs_cm\": {\"linear\": ");
        json_number(jf, node_err[0]);
        fprintf(jf, ", \"point\": ");
        json_number(jf, node_err[1]);
        fprintf(jf, "},\n  \"samplers\": {");
        for (int s = 0; s < SAMPLERS; s++) {
            fprintf(jf, "%s\n    ", s ? "," : "");
            json_string(jf, kSamplers[s].name);
            fprintf(jf, ": {\"fetches\": %d, \"what\": ", kSamplers[s].fetches);
            json_string(jf, kSamplers[s].what);
            fputc('}', jf);
        }
        fprintf(jf, "\n  },\n  \"rows\": [");
        for (size_t i = 0; i < rows.size(); i++) {
            const Row &r = rows[i];
            fprintf(jf, "%s\n    {\"order\": \"%s\", \"sampler\": \"%s\", \"median_ms\": ", i ? "," : "",
                    kOrders[r.order], kSamplers[r.sampler].name);
            json_number(jf, r.median_ms);
            const struct {
                const char *key;
                double v;
            } f[] = {{"min_ms", r.min_ms},
                     {"samples_per_s", r.samples_per_s},
                     {"max_abs_dphi_cm", r.max_dphi},
                     {"p99_abs_dphi_cm", r.p99_dphi},
                     {"max_abs_dphi_cells", r.max_dphi / h},
                     {"p99_abs_dphi_cells", r.p99_dphi / h},
                     {"max_angle_deg", r.max_angle},
                     {"p99_angle_deg", r.p99_angle},
                     {"checksum", r.checksum}};
            for (const auto &kv : f) {
                fprintf(jf, ", \"%s\": ", kv.key);
                json_number(jf, kv.v);
            }
            fprintf(jf, ", \"angle_points\": %lld}", (long long)r.angle_points);
        }
        fprintf(jf, "\n  ]\n}\n");
        if (fclose(jf) != 0) fail(EXIT_RUNTIME, "--json %s: %s", o.json.c_str(), strerror(errno));
        if (rename(g_partial.c_str(), o.json.c_str()) != 0)
            fail(EXIT_RUNTIME, "--json %s: %s", o.json.c_str(), strerror(errno));
        g_partial.clear();
    }

    for (int s = 0; s < SAMPLERS; s++) {
        for (int e = 0; e < 2; e++) CUDA_CHECK(cudaEventDestroy(ev[s][e]));
        CUDA_CHECK(cudaFree(d_out[s]));
    }
    CUDA_CHECK(cudaFree(d_pts));
    CUDA_CHECK(cudaFree(d_worst));
    CUDA_CHECK(cudaDestroyTextureObject(F.linear));
    CUDA_CHECK(cudaDestroyTextureObject(F.point));
    CUDA_CHECK(cudaFreeArray(arr));
    CUDA_CHECK(cudaFree(d_sdf));
    hb_colliders_free(&cols);
    return 0;
}
