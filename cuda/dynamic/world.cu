/* cuda/dynamic/world.cu — the hair–hair grid's kernels (docs/model.md §3.16; the design in docs/cuda.md
 * "The hair–hair grid"): the splat of every point into 64-bit fixed-point sums, whose order
 * changes no bit, and the node fields. */
#include "dynamic/world.cuh"

#include "dynamic/chain.cuh" /* the grid's kernels and the lanes kernel after them: programmatic dependents */
#include "dynamic/held.cuh"

#include <atomic>
#include <climits>
#include <cstdint>
#include <type_traits>

namespace hb {
namespace dyn {
namespace {

template <typename T> struct Splat;
template <> struct Splat<float> {
    __device__ static void node(int64_t j, const World<float> &w, const int64_t *mass, const int64_t *mom,
                                const float *target, float inv_rho0, float neg_kv, const float *qg, float *nv,
                                float *na)
    {
        hb_grid_node_f32(j, w.gn, mass, mom, target, inv_rho0, neg_kv, w.gsc, qg, nv, na);
    }
};
template <> struct Splat<double> {
    __device__ static void node(int64_t j, const World<double> &w, const int64_t *mass, const int64_t *mom,
                                const double *target, double inv_rho0, double neg_kv, const double *qg, double *nv,
                                double *na)
    {
        hb_grid_node_f64(j, w.gn, mass, mom, target, inv_rho0, neg_kv, w.gsc, qg, nv, na);
    }
};

/* The splat (docs/cuda.md "The hair–hair grid"). A block takes kSplatStrands neighbouring
 * strands (the order perm; nullptr: as stored), whole or, where whole strands would leave SMs idle
 * (few strands), a run of their points (blockIdx.y: a strand's points lie along it over many cells,
 * neighbouring strands' points of one run close together); its threads take the points a strand's
 * run at a time, a lane a point, so that every load of x and v coalesces. Pass 1 finds the block's
 * box of cells. Where no node can receive more than 2^16 shares, pass 2 adds each point's fixed-point shares in shared
 * memory by native 32-bit shared atomics (exact: see kSplatWindowPoints): a mass share in one word
 * with the carries out of it counted in another, a momentum share in one signed word where the
 * block's speeds bound its sums, else split into its low 16 bits and the rest; in a window over
 * the box where its nodes fit, else in a hash table of the nodes the block touches; then one
 * 64-bit global atomic a touched node and channel. A share whose node finds no slot, or a block
 * past the share bound, adds to the grid directly. Integer sums: no order changes a bit. */
#ifndef HB_SPLAT_STRANDS
#define HB_SPLAT_STRANDS 64
#endif
#ifndef HB_SPLAT_WINDOW
#define HB_SPLAT_WINDOW 1024
#endif
constexpr int kSplatStrands = HB_SPLAT_STRANDS, kSplatWarps = 8; /* strands a block, its warps */
/* blocks an SM holds (fp32: 48 registers, as its shared memory allows; fp64: as many as it needs) */
template <typename T> constexpr int kSplatMinBlocks = sizeof(T) == 4 ? 5 : 1;
constexpr int kWindow = HB_SPLAT_WINDOW; /* nodes: 2 × 32 bits × 4 channels each (32 KB at 1024) */
/* the word (channel c: mass, p_x, p_y, p_z; part: low, high — for mass: the sum modulo 2^32, its
 * carries) of window node i, each (channel, part) array whole so that a warp's lanes at different
 * nodes use different banks: with one momentum word a share (Single) the five used (mass low, mass
 * carries, p_x, p_y, p_z) of kWindowSingle nodes, else all eight of kWindow */
constexpr int kWindowSingle = kWindow * 8 / 5;
template <bool Single> struct WindowAt {
    __device__ __forceinline__ int operator()(int c, int part, int i) const
    {
        return Single ? (c == 0 ? part : c + 1) * kWindowSingle + i : (2 * c + part) * kWindow + i;
    }
};
/* The hash table in the window's memory: kHashSlots keys (a node's index; kEmpty: none), then the
 * eight (channel, part) arrays of kHashSlots words (HashAt). A node takes the first free slot from its
 * hash on (linear probing, claimed by a shared compare-and-swap); past kHashProbes slots, none. */
constexpr int kHashSlots = (kWindow * 8 / 9) & ~31;
constexpr int kHashProbes = 32;
static_assert(kHashSlots >= 32, "HB_SPLAT_WINDOW too small for the hash table");
constexpr unsigned kEmpty = 0xffffffffu; /* no node: indices are below n³ ≤ 2^31 */
struct HashAt {
    __device__ __forceinline__ int operator()(int c, int part, int i) const { return (2 * c + part) * kHashSlots + i; }
};
__device__ __forceinline__ int hash_slot(unsigned *keys, unsigned node)
{
    unsigned s = __umulhi(node * 2654435761u, (unsigned)kHashSlots);
    for (int p = 0; p < kHashProbes; p++) {
        const unsigned k = *reinterpret_cast<volatile unsigned *>(keys + s);
        if (k == node) return (int)s;
        if (k == kEmpty) {
            const unsigned was = atomicCAS(keys + s, kEmpty, node);
            if (was == kEmpty || was == node) return (int)s;
        }
        s = s + 1 == (unsigned)kHashSlots ? 0u : s + 1;
    }
    return -1;
}
/* At most this many shares reach a window node (one a point): a momentum share's low parts
 * (< 2^16 each) sum below 2^32 and its high parts (|x| ≤ 2^30, so |x >> 16| ≤ 2^14) within ±2^31;
 * the mass shares (≤ 2^24 each) carry at most 2^16·2^24/2^32 = 256 times out of their word. */
constexpr int64_t kSplatWindowPoints = 65536;

/* contact_impl.h's cell and weights of a point by precision: the cell's coordinates come whole, so
 * that no division takes them back out of a node index */
template <typename T> struct Cell;
template <> struct Cell<float> {
    __device__ static int at(const World<float> &w, const float *qg, const float *x, int64_t *i, float *f)
    {
        return hb_grid_cell_f32(qg, w.glo, w.gsc, w.gn, x, i, f);
    }
    __device__ static void weights(const float *f, float *wt) { hb_grid_weights_f32(f, wt); }
};
template <> struct Cell<double> {
    __device__ static int at(const World<double> &w, const double *qg, const double *x, int64_t *i, double *f)
    {
        return hb_grid_cell_f64(qg, w.glo, w.gsc, w.gn, x, i, f);
    }
    __device__ static void weights(const double *f, double *wt) { hb_grid_weights_f64(f, wt); }
};

template <typename T> __device__ __forceinline__ bool finite3(const T *p)
{
    return isfinite(p[0]) && isfinite(p[1]) && isfinite(p[2]);
}

/* A fixed-point share: HB_RINT64 of x, whose |x| ≤ 2^30 (mass ≤ 2^24, momentum ≤ 2^20·2^10), so
 * the 32-bit conversion to nearest, ties to even, gives the same integer in one instruction. */
__device__ __forceinline__ int share_of(float x)
{
    return __float2int_rn(x);
}
__device__ __forceinline__ int share_of(double x)
{
    return __double2int_rn(x);
}

/* one share x (|x| ≤ 2^30) into channel c of node or slot i: low 16 bits, then the rest */
template <class At> __device__ __forceinline__ void words_add(unsigned *win, At at, int c, int i, int x)
{
    atomicAdd(win + at(c, 0, i), (unsigned)x & 0xffffu);
    atomicAdd(reinterpret_cast<int *>(win) + at(c, 1, i), x >> 16);
}
/* a mass share sm (0 ≤ sm ≤ 2^24) into node or slot i: one word summed modulo 2^32, and the
 * carries out of it counted in the other (each add wraps at most once; rare) */
template <class At> __device__ __forceinline__ void mass_add(unsigned *win, At at, int i, int sm)
{
    const unsigned was = atomicAdd(win + at(0, 0, i), (unsigned)sm);
    if (was + (unsigned)sm < was) atomicAdd(win + at(0, 1, i), 1u);
}
/* a corner's mass share sm and momentum shares sp into node or slot i (`single`: a momentum
 * share in one signed word) */
template <class At>
__device__ __forceinline__ void corner_add(unsigned *win, At at, int i, int sm, const int (&sp)[3], bool single)
{
    mass_add(win, at, i, sm);
    if (single)
        for (int c = 0; c < 3; c++) atomicAdd(reinterpret_cast<int *>(win) + at(1 + c, 0, i), sp[c]);
    else
        for (int c = 0; c < 3; c++) words_add(win, at, 1 + c, i, sp[c]);
}
/* node or slot i's four 64-bit sums; false where all are zero */
template <class At>
__device__ __forceinline__ bool corner_sums(const unsigned *win, At at, int i, bool single, int64_t (&sum)[4])
{
    const int *wi = reinterpret_cast<const int *>(win);
    bool any = false;
    for (int c = 0; c < 4; c++) {
        sum[c] = c == 0   ? (int64_t)win[at(0, 1, i)] * 4294967296 + (int64_t)win[at(0, 0, i)]
                 : single ? (int64_t)wi[at(c, 0, i)]
                          : (int64_t)wi[at(c, 1, i)] * 65536 + (int64_t)win[at(c, 0, i)];
        any |= sum[c] != 0;
    }
    return any;
}
/* node j's sums into the grid */
__device__ __forceinline__ void node_flush(int64_t j, const int64_t (&sum)[4], int64_t *mass, int64_t *mom)
{
    if (sum[0]) atomicAdd((unsigned long long *)&mass[j], (unsigned long long)sum[0]);
    for (int c = 0; c < 3; c++)
        if (sum[1 + c]) atomicAdd((unsigned long long *)&mom[3 * j + c], (unsigned long long)sum[1 + c]);
}

template <typename T>
__global__ void __launch_bounds__(kSplatWarps * 32, kSplatMinBlocks<T>)
    k_grid_splat(World<T> w, const T *qg, const T *x, const T *v, int64_t N, int P, int spb, int pk,
                 const int64_t *perm, int64_t *mass, int64_t *mom)
{
    extern __shared__ unsigned win[];  /* the window: [channel: mass, p_x, p_y, p_z][low, high][node] (WindowAt);
                                         hashed: keys[kHashSlots], then the table's arrays (HashAt) */
    __shared__ int lo[3], hi[3], vmax; /* vmax: the bits of the block's largest |v| component (≥ 0) */
    wait_for_previous();
    const int lane = (int)(threadIdx.x & 31u);
    const int64_t s0 = (int64_t)blockIdx.x * spb;
    const int ns = N - s0 < spb ? (int)(N - s0) : spb;
    /* the block's points: k0 … k0 + nk − 1 of each of its strands; item i is point k0 + i % pk of
     * strand i / pk, so that at pk = 32 a warp takes a strand's 32 points */
    const int k0 = (int)blockIdx.y * pk, nk = P - k0 < pk ? P - k0 : pk, items = ns * pk;
    const int pks = (pk & (pk - 1)) == 0 ? __ffs(pk) - 1 : -1; /* log2 pk, or −1 */
    auto strand_of = [&](int i) { return pks >= 0 ? i >> pks : i / pk; };
    auto point_of = [&](int i) { return k0 + (pks >= 0 ? i & (pk - 1) : i % pk); };
    const int64_t n = w.gn;
    /* item i's point: its x and v, its cell (whole) and place in it; false where it adds nothing (past its
     * strand's run, not finite, outside the grid) */
    auto cell_of = [&](int i, const T *&xp, const T *&vp, int64_t(&cb)[3], T(&f)[3]) {
        const int st_i = strand_of(i), k = point_of(i);
        if (k >= k0 + nk) return false;
        const int64_t st = perm ? perm[s0 + st_i] : s0 + st_i;
        const int64_t r = st * P + k;
        xp = x + 3 * r;
        vp = v + 3 * r;
        return finite3(xp) && finite3(vp) && Cell<T>::at(w, qg, xp, cb, f) != 0;
    };
    if (threadIdx.x < 3) lo[threadIdx.x] = INT_MAX, hi[threadIdx.x] = -1;
    if (threadIdx.x == 0) vmax = 0;
    __syncthreads();
    /* pass 1: the block's box of cells (points whose x is finite and in the grid) and its largest
     * clamped |v| component */
    int cl[3] = {INT_MAX, INT_MAX, INT_MAX}, ch[3] = {-1, -1, -1};
    float vm = 0.0f;
    for (int i = (int)threadIdx.x; i < items; i += kSplatWarps * 32) {
        const T *xp, *vp;
        int64_t c[3];
        T f[3];
        if (!cell_of(i, xp, vp, c, f)) continue;
        for (int a = 0; a < 3; a++) {
            cl[a] = min(cl[a], (int)c[a]);
            ch[a] = max(ch[a], (int)c[a] + 1);
            vm = fmaxf(vm, fminf((float)fabs(vp[a]), (float)HB_GRID_VEL_CLAMP));
        }
    }
    { /* non-negative floats order as their bits */
        const int vb = __reduce_max_sync(0xffffffffu, __float_as_int(vm));
        if (lane == 0 && vb > 0) atomicMax(&vmax, vb);
    }
    for (int a = 0; a < 3; a++) { /* the warp's extremes first: one shared atomic a warp */
        const int mn = __reduce_min_sync(0xffffffffu, cl[a]), mx = __reduce_max_sync(0xffffffffu, ch[a]);
        if (lane == 0 && mx >= 0) {
            atomicMin(&lo[a], mn);
            atomicMax(&hi[a], mx);
        }
    }
    __syncthreads();
    if (hi[0] < 0) return; /* no point of the block in the grid */
    const int ex = hi[0] - lo[0] + 1, ey = hi[1] - lo[1] + 1, ez = hi[2] - lo[2] + 1;
    /* the window's strides (y, z), both odd so that points a row or a plane apart (a hanging strand's
     * neighbours) meet in different banks, and the box's nodes, padding included */
    const int64_t sy64 = ex | 1, sz64 = (sy64 * ey) | 1, nb64 = sz64 * ez;
    const bool bounded = (int64_t)ns * nk <= kSplatWindowPoints;
    /* `single`: a momentum share is |rint(w·v·2^10)| ≤ |v|·2^10 + 1 (w ≤ 1) and a node takes at
     * most one a point, so while ns·P·(vmax·2^10 + 1) < 2^31 the block's momentum sums fit one
     * signed 32-bit word a node (exact, one atomic a share); else the split words as for mass */
    const bool single =
        bounded && (double)ns * nk * ((double)__int_as_float(vmax) * HB_GRID_MOM_SCALE + 1.0) < 2147483647.0;
    const bool windowed = bounded && nb64 <= (single ? kWindowSingle : kWindow), hashed = bounded && !windowed;
    const int sy = (int)sy64, sz = (int)sz64, nw = windowed ? (int)nb64 : 0;
    /* the box-local node of corner c8 of the cell whose lowest corner is box node wb */
    auto corner_in_box = [&](int wb, int c8) {
        return wb + ((c8 & 1) ? 1 : 0) + ((c8 & 2) ? sy : 0) + ((c8 & 4) ? sz : 0);
    };
    unsigned *const keys = win, *const slots = win + kHashSlots;
    if (windowed)
        for (int i = threadIdx.x; i < nw; i += blockDim.x)
            for (int a = 0; a < (single ? 5 : 8); a++) win[a * (single ? kWindowSingle : kWindow) + i] = 0u;
    if (hashed)
        for (int i = threadIdx.x; i < kHashSlots; i += blockDim.x) {
            keys[i] = kEmpty;
            for (int a = 0; a < 8; a++)
                if (!single || a < 2 || (a & 1) == 0) slots[a * kHashSlots + i] = 0u;
        }
    __syncthreads();
    /* pass 2: each point's shares (hb_grid_splat_point: the reference's integers). The common
     * block (its window, one momentum word a share) runs a loop of its own (Fast), so that no
     * corner chooses its path. A momentum share is w·(v·2^10): scaling by a power of two is exact,
     * so it is the reference's (w·v)·2^10. */
    static_assert(HB_GRID_MOM_SCALE == 1024.0, "the momentum shares' scaling is exact only for a power of two");
    auto pass2 = [&](auto fast) {
        constexpr bool Fast = decltype(fast)::value;
        for (int i = (int)threadIdx.x; i < items; i += kSplatWarps * 32) {
            const T *xp, *vp;
            int64_t cb[3];
            T f[3], wt[8], vs[3];
            /* hb_grid_splat_point's shares, a corner at a time (fewer registers, the same integers) */
            if (!cell_of(i, xp, vp, cb, f)) continue;
            Cell<T>::weights(f, wt);
            for (int c = 0; c < 3; c++) {
                const T lim = (T)HB_GRID_VEL_CLAMP;
                vs[c] = (vp[c] < -lim ? -lim : vp[c] > lim ? lim : vp[c]) * (T)HB_GRID_MOM_SCALE;
            }
            /* the cell's lowest corner: its window node (32-bit: the window holds ≤ kWindowSingle nodes), its node */
            const int wb = ((int)cb[0] - lo[0]) + sy * ((int)cb[1] - lo[1]) + sz * ((int)cb[2] - lo[2]);
            const int64_t b = cb[0] + n * (cb[1] + n * cb[2]);
#pragma unroll
            for (int c8 = 0; c8 < 8; c8++) {
                int sp[3];
                const int sm = share_of(wt[c8] * (T)HB_GRID_MASS_SCALE);
                for (int c = 0; c < 3; c++) sp[c] = share_of(wt[c8] * vs[c]);
                if (Fast) { /* windowed, single */
                    corner_add(win, WindowAt<true>{}, corner_in_box(wb, c8), sm, sp, true);
                } else if (windowed) { /* not single */
                    corner_add(win, WindowAt<false>{}, corner_in_box(wb, c8), sm, sp, false);
                } else {
                    const int64_t j = hb_grid_corner_f64(b, n, c8);
                    const int slot = hashed ? hash_slot(keys, (unsigned)j) : -1;
                    if (slot >= 0) {
                        corner_add(slots, HashAt{}, slot, sm, sp, single);
                    } else {
                        atomicAdd((unsigned long long *)&mass[j], (unsigned long long)(int64_t)sm);
                        for (int c = 0; c < 3; c++)
                            atomicAdd((unsigned long long *)&mom[3 * j + c], (unsigned long long)(int64_t)sp[c]);
                    }
                }
            }
        }
    };
    if (windowed && single) pass2(std::true_type{});
    else pass2(std::false_type{});
    if (!bounded) return;
    __syncthreads();
    /* box node j's node in the grid */
    auto node_of = [&](int j) {
        return (j % sz % sy + lo[0]) + n * ((j % sz / sy + lo[1]) + n * (int64_t)(j / sz + lo[2]));
    };
    int64_t sum[4];
    if (windowed) {
        for (int i = threadIdx.x; i < nw; i += blockDim.x) /* padding: never added to */
            if (single ? corner_sums(win, WindowAt<true>{}, i, true, sum)
                       : corner_sums(win, WindowAt<false>{}, i, false, sum))
                node_flush(node_of(i), sum, mass, mom);
        return;
    }
    for (int i = threadIdx.x; i < kHashSlots; i += blockDim.x)
        if (keys[i] != kEmpty && corner_sums(slots, HashAt{}, i, single, sum))
            node_flush((int64_t)keys[i], sum, mass, mom);
}

template <typename T>
__global__ void k_grid_nodes(World<T> w, const T *qg, const int64_t *mass, const int64_t *mom, int64_t *clear,
                             const T *target, T inv_rho0, T neg_kv, T *node_v, T *node_a)
{
    wait_for_previous();
    const int64_t j = (int64_t)blockIdx.x * blockDim.x + threadIdx.x, nodes = w.gn * w.gn * w.gn;
    if (j >= nodes) return;
    Splat<T>::node(j, w, mass, mom, target, inv_rho0, neg_kv, qg, node_v, node_a);
    clear[j] = 0;
    for (int c = 0; c < 3; c++) clear[nodes + 3 * j + c] = 0;
}

/* §3.16 `held`: a block takes kHoldStrands neighbouring strands in the strands' order (perm) and
 * kHoldPoints·kHoldRounds of their points; a warp samples one point index across its 32 strands
 * (a round), whose points lie close together (the order follows the roots), so a corner's load is
 * shared by the warp where a strand's own points would each need a cell of their own. Positions
 * come in and samples go out through shared memory, a strand's run of points contiguous (rows
 * padded against bank conflicts), a thread's loads all issued before its first store (the loop's
 * trip count fixed by the block's shape). The root's sample (k = 0) is written but never applied. */
/* rounds a thread: two in the free builds (faster at 4M strands, bit-identical: docs/cuda.md's designs
 * table), one in the strict build (its 8 reals a point, as tested) */
#ifndef HB_HOLD_ROUNDS
#define HB_HOLD_ROUNDS (kGridFree ? 2 : 1)
#endif
constexpr int kHoldStrands = 32, kHoldPoints = 8, kHoldRounds = HB_HOLD_ROUNDS;
template <typename T>
__global__ void __launch_bounds__(kHoldStrands *kHoldPoints)
    k_grid_hold(World<T> w, const T *qg, T h, const T *x, int64_t N, int P, const int64_t *perm, T *held)
{
    constexpr int R = kHeldReals, NB = kHoldPoints * kHoldRounds; /* the block's points */
    constexpr int XW = 3 * NB + 1, HW = R * NB + 1;               /* row widths */
    constexpr int NT = kHoldStrands * kHoldPoints, NX = kHoldStrands * 3 * NB, NH = kHoldStrands * R * NB;
    __shared__ T xs[kHoldStrands * XW];
    __shared__ T hs[kHoldStrands * HW];
    __shared__ int64_t xo[kHoldStrands], ho[kHoldStrands]; /* each strand's first real in x and in held */
    wait_for_previous();
    const int t = threadIdx.x;
    const int64_t s0 = (int64_t)blockIdx.x * kHoldStrands;
    const int k0 = (int)blockIdx.y * NB;
    const int ns = (int)(N - s0 < kHoldStrands ? N - s0 : kHoldStrands), nk = P - k0 < NB ? P - k0 : NB;
    if (t < kHoldStrands) {
        const int64_t st = t < ns ? (perm ? perm[s0 + t] : s0 + t) : 0;
        xo[t] = (st * P + k0) * 3;
        ho[t] = (st * P + k0) * R;
    }
    __syncthreads();
    /* fp32 where every strand's run starts on 16 bytes (P a multiple of 4, the arrays aligned): the
     * positions come in and the samples go out four reals an instruction */
    bool vec = false;
    if constexpr (sizeof(T) == 4) {
        vec = (P & 3) == 0 && ((reinterpret_cast<uintptr_t>(x) | reinterpret_cast<uintptr_t>(held)) & 15) == 0;
        if (vec) { /* a strand's run: 3·NB/4 float4 (nk is then a multiple of 4: whole float4s) */
            constexpr int RX = 3 * NB / 4, NX4 = NX / 4, Q = (NX4 + NT - 1) / NT;
            float4 xr[Q];
#pragma unroll
            for (int q = 0; q < Q; q++) {
                const int i = t + q * NT, u = i / RX, r = i % RX;
                if (i < NX4 && u < ns && 4 * r < 3 * nk) xr[q] = *reinterpret_cast<const float4 *>(x + xo[u] + 4 * r);
            }
#pragma unroll
            for (int q = 0; q < Q; q++) {
                const int i = t + q * NT, u = i / RX, r = i % RX;
                if (i < NX4 && u < ns && 4 * r < 3 * nk) {
                    T *d = xs + u * XW + 4 * r;
                    d[0] = xr[q].x, d[1] = xr[q].y, d[2] = xr[q].z, d[3] = xr[q].w;
                }
            }
        }
    }
    if (!vec) { /* the positions: every load in flight at once, then into shared memory */
        T xr[(NX + NT - 1) / NT];
#pragma unroll
        for (int q = 0; q < (NX + NT - 1) / NT; q++) {
            const int i = t + q * NT, u = i / (3 * NB), r = i % (3 * NB);
            if (i < NX && u < ns && r < 3 * nk) xr[q] = x[xo[u] + r];
        }
#pragma unroll
        for (int q = 0; q < (NX + NT - 1) / NT; q++) {
            const int i = t + q * NT, u = i / (3 * NB), r = i % (3 * NB);
            if (i < NX && u < ns && r < 3 * nk) xs[u * XW + r] = xr[q];
        }
    }
    __syncthreads();
    const int u = t & 31;
#pragma unroll 1
    for (int r = 0; r < kHoldRounds; r++) {
        const int kk = (t >> 5) + r * kHoldPoints;
        if (u >= ns || kk >= nk) break;
        const T *p = xs + u * XW + 3 * kk;
        const Sample<T> s = grid_sample_xyz(w, qg, p[0], p[1], p[2]);
        T *o = hs + u * HW + R * kk;
        if constexpr (kGridFree) {
            const Node4<T> c = held_correction(w, h, k0 + kk, s);
            o[0] = c.x, o[1] = c.y, o[2] = c.z, o[3] = c.w;
        } else {
            o[0] = s.a.x, o[1] = s.a.y, o[2] = s.a.z, o[3] = s.a.w;
            o[4] = s.b.x, o[5] = s.b.y, o[6] = s.b.z, o[7] = s.b.w;
        }
    }
    __syncthreads();
    if constexpr (sizeof(T) == 4) {
        if (vec) { /* a strand's run: R·NB/4 float4 */
            constexpr int RH = R * NB / 4, NH4 = NH / 4;
#pragma unroll
            for (int q = 0; q < (NH4 + NT - 1) / NT; q++) {
                const int i = t + q * NT, v = i / RH, r = i % RH;
                if (i < NH4 && v < ns && 4 * r < R * nk) {
                    const T *c = hs + v * HW + 4 * r;
                    *reinterpret_cast<float4 *>(held + ho[v] + 4 * r) = make_float4(c[0], c[1], c[2], c[3]);
                }
            }
            return;
        }
    }
#pragma unroll
    for (int q = 0; q < (NH + NT - 1) / NT; q++) {
        const int i = t + q * NT, v = i / (R * NB), r = i % (R * NB);
        if (i < NH && v < ns && r < R * nk) held[ho[v] + r] = hs[v * HW + r];
    }
}

constexpr int kSplatDevices = 64; /* devices whose attributes launch_grid_splat keeps */
#ifndef HB_SPLAT_MIN_POINTS
#define HB_SPLAT_MIN_POINTS 8
#endif
constexpr int kSplatMinPoints = HB_SPLAT_MIN_POINTS; /* the shortest run of a strand's points a splat block takes */
constexpr int64_t kSplatRunStrands = 2048;           /* the fewest strands whose blocks take runs of points */

int blocks_for(int64_t items, int block)
{
    const int64_t g = (items + block - 1) / block;
    return (int)(g < 1 ? 1 : g > 2147483647 ? 2147483647 : g);
}

} /* namespace */

template <typename T>
cudaError_t launch_grid_splat(const World<T> &w, const T *qg, const T *x, const T *v, int64_t N, int64_t P,
                              const int64_t *perm, int64_t *mass, int64_t *mom, cudaStream_t stream)
{
    cudaError_t e;
    /* the device's SM count and the kernel's shared-memory attribute asked once a device */
    const size_t smem = (size_t)kWindow * 8 * sizeof(unsigned);
    int dev = 0, sms = 0;
    if ((e = cudaGetDevice(&dev)) != cudaSuccess) return e;
    static std::atomic<int> sms_of[kSplatDevices], ready[kSplatDevices];
    const int slot = dev < kSplatDevices ? dev : -1;
    if (slot >= 0 && (ready[slot].load() >> (sizeof(T) == 4 ? 0 : 1) & 1)) {
        sms = sms_of[slot].load();
    } else {
        if ((e = cudaDeviceGetAttribute(&sms, cudaDevAttrMultiProcessorCount, dev)) != cudaSuccess ||
            (e = cudaFuncSetAttribute(k_grid_splat<T>, cudaFuncAttributeMaxDynamicSharedMemorySize, (int)smem)) !=
                cudaSuccess)
            return e;
        if (slot >= 0) {
            sms_of[slot].store(sms);
            ready[slot].fetch_or(sizeof(T) == 4 ? 1 : 2);
        }
    }
    /* kSplatStrands whole strands a block; where that leaves SMs idle (fewer than four blocks an SM),
     * half the strands and half the points (down to kSplatMinPoints) in turn, strands first, down
     * to one strand a warp: a run of neighbouring strands' points lies close together, so that a
     * block's box shrinks with its run (10,000 strands: 32 strands of 16 points, docs/cuda.md).
     * Below kSplatRunStrands strands (a frame bound by its launches) whole strands only. */
    int spb = kSplatStrands, pk = (int)P;
    const bool runs = N >= kSplatRunStrands;
    for (int step = 0; (N + spb - 1) / spb * ((P + pk - 1) / pk) < 4 * (int64_t)sms; step++) {
        if ((step % 2 == 0 || !runs) && spb > kSplatWarps) spb /= 2;
        else if (runs && pk >= 2 * kSplatMinPoints) pk = (pk + 1) / 2;
        else if (spb > kSplatWarps) spb /= 2;
        else break;
    }
    const int64_t blocks = (N + spb - 1) / spb;
    const dim3 grid((unsigned)(blocks < 1 ? 1 : blocks), (unsigned)((P + pk - 1) / pk));
    return launch_chained(k_grid_splat<T>, grid, dim3(kSplatWarps * 32), smem, stream, w, qg, x, v, N, (int)P, spb, pk,
                          perm, mass, mom);
}

template <typename T>
cudaError_t launch_grid_nodes(const World<T> &w, const T *qg, const int64_t *mass, const int64_t *mom, int64_t *clear,
                              const T *target, T inv_rho0, T neg_kv, T *node_v, T *node_a, cudaStream_t stream)
{
    return launch_chained(k_grid_nodes<T>, dim3((unsigned)blocks_for(w.gn * w.gn * w.gn, 256)), dim3(256), 0, stream, w,
                          qg, mass, mom, clear, target, inv_rho0, neg_kv, node_v, node_a);
}

template <typename T>
cudaError_t launch_grid_hold(const World<T> &w, const T *qg, T h, const T *x, int64_t N, int64_t P, const int64_t *perm,
                             T *held, cudaStream_t stream)
{
    const dim3 grid((unsigned)((N + kHoldStrands - 1) / kHoldStrands),
                    (unsigned)((P + kHoldPoints * kHoldRounds - 1) / (kHoldPoints * kHoldRounds)));
    return launch_chained(k_grid_hold<T>, grid, dim3(kHoldStrands * kHoldPoints), 0, stream, w, qg, h, x, N, (int)P,
                          perm, held);
}

template cudaError_t launch_grid_hold<float>(const World<float> &, const float *, float, const float *, int64_t,
                                             int64_t, const int64_t *, float *, cudaStream_t);
template cudaError_t launch_grid_hold<double>(const World<double> &, const double *, double, const double *, int64_t,
                                              int64_t, const int64_t *, double *, cudaStream_t);
template cudaError_t launch_grid_splat<float>(const World<float> &, const float *, const float *, const float *,
                                              int64_t, int64_t, const int64_t *, int64_t *, int64_t *, cudaStream_t);
template cudaError_t launch_grid_splat<double>(const World<double> &, const double *, const double *, const double *,
                                               int64_t, int64_t, const int64_t *, int64_t *, int64_t *, cudaStream_t);
template cudaError_t launch_grid_nodes<float>(const World<float> &, const float *, const int64_t *, const int64_t *,
                                              int64_t *, const float *, float, float, float *, float *, cudaStream_t);
template cudaError_t launch_grid_nodes<double>(const World<double> &, const double *, const int64_t *, const int64_t *,
                                               int64_t *, const double *, double, double, double *, double *,
                                               cudaStream_t);

} /* namespace dyn */
} /* namespace hb */
