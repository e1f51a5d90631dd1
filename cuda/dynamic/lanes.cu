/* cuda/dynamic/lanes.cu — the lanes variant of the dynamic model's frame (docs/cuda.md "The lanes
 * variant"): the kernel without the world's code for each feature set and layout, the choice of a
 * run's kernel, its shape and its launches. The kernel itself is lanes_kernel.cuh's k_lanes; its
 * instances with the world's code are compiled in objects of their own (lanes_kernel.cuh).
 */
#include "dynamic/lanes_kernel.cuh"

namespace hb {
namespace dyn {
namespace {

/* ---- dispatch: the layout from the solver and P, the kernel from the feature mask ----
 * xpbd: 16 lanes a strand, G = 2, 4, 8. ftl, whose follow-the-leader pass runs lane after
 * lane: fewer lanes a strand with more points each (docs/cuda.md "The lanes variant"):
 * P ≤ 32 at HB_LANES_FTL_G points a lane, P ≤ 64 at 8 points on 8 lanes, else as xpbd.
 * The two layouts of P ≤ 32 have kernels of their own for the specialised feature sets. */
template <typename T, int G, int L, bool Ftl, unsigned F> constexpr LanesFn<T> lanes_entry()
{
    constexpr bool own = (!Ftl && G == 2 && L == 16) || (Ftl && G == kFtlG && L == kFtlL);
    if constexpr (!valid_mask(F)) return nullptr;
    else if constexpr (own && specialised_mask(F)) return &k_lanes<T, StaticF<F>, G, L, Ftl, false, 0>;
    else return &k_lanes<T, DynF, G, L, Ftl, false, 0>;
}
template <typename T, int G, int L, bool Ftl, unsigned... Fs> struct LanesTable {
    static constexpr LanesFn<T> fn[sizeof...(Fs)] = {lanes_entry<T, G, L, Ftl, Fs>()...};
};
template <typename T, int G, int L, bool Ftl, unsigned... Fs>
LanesTable<T, G, L, Ftl, Fs...> lanes_table_of(std::integer_sequence<unsigned, Fs...>);
template <typename T, int G, int L, bool Ftl>
using LanesTableT = decltype(lanes_table_of<T, G, L, Ftl>(std::make_integer_sequence<unsigned, HB_F_COUNT>()));

/* The kernel of a run, its points a lane, its lanes a strand and its shared memory a warp. */
template <typename T> struct LanesPick {
    LanesFn<T> fn;
    int g, lanes;
    int64_t warp_reals;
    int64_t plane_reals; /* a warp's contact planes (--contact-planes) */
};
/* a groom (seg) runs the generic kernel of its layout with per-segment rest lengths; a run with
 * the grid or colliders (wk, a set of kW…) the generic kernel with the world's code it needs (a
 * groom's: all of it), compiled in the objects lanes_kernel.cuh names */
template <typename T, int G, int L, bool Ftl> LanesPick<T> pick(unsigned f, int64_t P, bool seg, int wk)
{
    LanesFn<T> fn = LanesTableT<T, G, L, Ftl>::fn[f];
    if (wk && seg) wk = kWAll;
    if (wk == kWAll) fn = lanes_world_kernel<T, G, L, Ftl>(seg);
    else if (wk == kWCol) fn = lanes_colliders_kernel<T, G, L, Ftl>(f);
    else if (wk == (kWCol | kWPlanes)) fn = lanes_planes_kernel<T, G, L, Ftl>(f);
    else if (wk) fn = lanes_grid_kernel<T, G, L, Ftl>(f, wk);
    else if (seg) fn = &k_lanes<T, DynF, G, L, Ftl, true, 0>;
    return LanesPick<T>{fn, G, L, lanes_warp_reals<T, G, L>(P) + ((wk & kWHeld) ? lanes_held_reals<T, G>() : 0),
                        lanes_plane_reals<G>()};
}
/* The world's code a run needs (docs/cuda.md "The hair–hair grid and the colliders"): none
 * without a world; the held grid alone (or a grid that applies nothing); the grid's gather alone
 * (`frame`, `substep`); the colliders alone, exact or as contact planes; else all of it. */
template <typename T> int world_kind(const DModel<T> &m)
{
    if (!m.has_world) return 0;
    const World<T> &w = m.world;
    const bool col = world_collides(w);
    const bool apply = w.grid && (w.grid_friction || w.grid_volume);
    if (apply && col) return kWAll;
    if (apply && !lanes_holds_samples(w)) return kWGather;
    return !col ? kWHeld : w.planes ? kWCol | kWPlanes : kWCol;
}
template <typename T> LanesPick<T> lanes_pick(unsigned f, int solver, int64_t P, bool seg, int world)
{
    if (!valid_mask(f) || P < 2 || P > kLanesMaxPoints) return LanesPick<T>{nullptr, 0, 0, 0, 0};
    if (solver == HB_SOLVER_FTL) {
        if (P <= 32) return pick<T, kFtlG, kFtlL, true>(f, P, seg, world);
        if (P <= 64) return pick<T, 8, 8, true>(f, P, seg, world);
        return pick<T, 8, 16, true>(f, P, seg, world);
    }
    if (P <= 32) return pick<T, 2, 16, false>(f, P, seg, world);
    if (P <= 64) return pick<T, 4, 16, false>(f, P, seg, world);
    return pick<T, 8, 16, false>(f, P, seg, world);
}
/* The one-wave layout's kernel (lanes_kernel.cuh kWaveG) where a run may take it: fp32 xpbd at
 * P ≤ 32 with every feature (the default scene's set), no groom, no world or the held grid alone;
 * else fn is nullptr */
template <typename T> LanesPick<T> wave_pick(unsigned f, int solver, int64_t P, bool seg, int wk)
{
    if constexpr (sizeof(T) == 4) {
        constexpr unsigned kEvery = HB_F_COUNT - 1u;
        if (solver != HB_SOLVER_FTL && P >= 2 && P <= 32 && !seg && f == kEvery && (wk == 0 || wk == kWHeld))
            return LanesPick<T>{
                wk ? lanes_wave_held_kernel<T>() : &k_lanes<T, StaticF<kEvery>, kWaveG, kWaveL, false, false, 0>,
                kWaveG, kWaveL, lanes_warp_reals<T, kWaveG, kWaveL>(P) + (wk ? lanes_held_reals<T, kWaveG>() : 0),
                lanes_plane_reals<kWaveG>()};
    }
    return LanesPick<T>{nullptr, 0, 0, 0, 0};
}
/* a run's threads a block: half the variant's block in the one-wave layout (the same strands a block) */
template <typename T> int run_block(const DModel<T> &m, int block)
{
    return m.wave ? block / 2 : block;
}
/* a run's kernel: the one-wave layout's where lanes_wave chose it (m.wave), else lanes_pick's */
template <typename T> LanesPick<T> run_pick(const DModel<T> &m, int wk)
{
    const bool seg = m.seg_rest != nullptr;
    return m.wave ? wave_pick<T>(m.features, m.solver, m.points, seg, wk)
                  : lanes_pick<T>(m.features, m.solver, m.points, seg, wk);
}
/* the strands one wave of kernel k takes on this device at b threads a block and smem bytes */
template <typename T> cudaError_t wave_strands(const LanesPick<T> &k, int b, size_t smem, int64_t &strands)
{
    int per_sm = 0, dev = 0, sms = 0;
    cudaError_t e = cudaOccupancyMaxActiveBlocksPerMultiprocessor(&per_sm, k.fn, b, smem);
    if (e == cudaSuccess) e = cudaGetDevice(&dev);
    if (e == cudaSuccess) e = cudaDeviceGetAttribute(&sms, cudaDevAttrMultiProcessorCount, dev);
    strands = (int64_t)per_sm * sms * (b / 32) * (32 / k.lanes);
    return e;
}

} /* namespace */

template <typename T>
cudaError_t prepare_lanes(unsigned features, int solver, int64_t P, int block, bool seg, bool world)
{
    for (int wk : {kWHeld, kWGather, kWCol, kWCol | kWPlanes, kWAll}) { /* a world's run launches one of these */
        const LanesPick<T> k = lanes_pick<T>(features, solver, P, seg, world ? wk : 0);
        if (!k.fn) return cudaErrorInvalidValue;
        int bytes = (int)((size_t)(block / 32) * (size_t)k.warp_reals * sizeof(T)), dev = 0;
        cudaError_t e = cudaSuccess;
        if (world && (wk & kWCol)) { /* with the staged colliders: up to the device's limit (launch_frame_lanes) */
            if ((e = cudaGetDevice(&dev)) != cudaSuccess) return e;
            if ((e = cudaDeviceGetAttribute(&bytes, cudaDevAttrMaxSharedMemoryPerBlockOptin, dev)) != cudaSuccess)
                return e;
        }
        e = cudaFuncSetAttribute(k.fn, cudaFuncAttributeMaxDynamicSharedMemorySize, bytes);
        if (e != cudaSuccess || !world) return e;
    }
    return cudaSuccess;
}

/* §3.17 the block and the substeps a launch of a run's kernel k with block `block`: the staged colliders
 * take at most kColStageBytes a block, within the device's limit: fewer substeps a launch (x and v
 * carry all state between launches, and m.contacts the contact planes), and only where one substep
 * does not fit beside the warps' areas, fewer warps a block (the same results). chunk: the frame's
 * substeps without colliders. */
template <typename T>
static cudaError_t lanes_shape(const DModel<T> &m, const LanesPick<T> &k, int wk, int block, int &b, int &chunk,
                               size_t &smem)
{
    const bool col = lanes_col_on<T>(wk, m);
    const int64_t warp = k.warp_reals + (col && m.world.planes ? k.plane_reals : 0);
    const int j1 = m.j1 < 0 ? (int)m.substeps : m.j1;
    const size_t per = sizeof(T) * (size_t)lanes_col_reals(m.world.ncol, 1);
    b = block;
    chunk = j1 - m.j0;
    if (col) {
        int dev = 0, optin = 0;
        cudaError_t e = cudaGetDevice(&dev);
        if (e == cudaSuccess) e = cudaDeviceGetAttribute(&optin, cudaDevAttrMaxSharedMemoryPerBlockOptin, dev);
        if (e != cudaSuccess) return e;
        for (;;) {
            const size_t used = (size_t)(b / 32) * (size_t)warp * sizeof(T);
            const size_t room = used < (size_t)optin ? (size_t)optin - used : 0;
            const size_t budget = room < (size_t)kColStageBytes ? room : (size_t)kColStageBytes;
            if (budget >= per) {
                chunk = (int)(budget / per);
                break;
            }
            if (b < 64) return cudaErrorInvalidConfiguration;
            b = (b / 64) * 32; /* half the warps */
        }
    }
    smem = (size_t)(b / 32) * (size_t)warp * sizeof(T);
    return cudaSuccess;
}

template <typename T> cudaError_t lanes_launches(const DModel<T> &m, int block, int *launches)
{
    const int wk = world_kind(m);
    const LanesPick<T> k = run_pick(m, wk);
    if (!k.fn) return cudaErrorInvalidValue;
    int b = 0, chunk = 0;
    size_t smem = 0;
    const cudaError_t e = lanes_shape(m, k, wk, run_block(m, block), b, chunk, smem);
    if (e != cudaSuccess) return e;
    const int nj = (m.j1 < 0 ? (int)m.substeps : m.j1) - m.j0;
    *launches = nj <= chunk ? 1 : (nj + chunk - 1) / chunk;
    return cudaSuccess;
}

/* The one-wave layout (docs/cuda.md "The lanes variant"): taken where the run may take it (wave_pick),
 * its block of `block` threads holds whole warps at half of them (the same strands a block), and N
 * strands need more than one wave of lanes_pick's kernel but fit one wave of its own; its kernel's
 * shared-memory limit raised then. */
template <typename T> cudaError_t lanes_wave(const DModel<T> &m, int64_t N, int block, bool *wave)
{
    *wave = false;
    const int wk = world_kind(m);
    const LanesPick<T> k = lanes_pick<T>(m.features, m.solver, m.points, m.seg_rest != nullptr, wk);
    const LanesPick<T> w = wave_pick<T>(m.features, m.solver, m.points, m.seg_rest != nullptr, wk);
    if (!k.fn || !w.fn || block % 64 != 0) return cudaSuccess;
    int b = 0, chunk = 0, bw = 0;
    size_t smem = 0, sw = 0;
    int64_t n = 0, nw = 0;
    cudaError_t e;
    if ((e = lanes_shape(m, k, wk, block, b, chunk, smem)) != cudaSuccess ||
        (e = lanes_shape(m, w, wk, block / 2, bw, chunk, sw)) != cudaSuccess ||
        (e = wave_strands(k, b, smem, n)) != cudaSuccess || (e = wave_strands(w, bw, sw, nw)) != cudaSuccess)
        return e;
    if (N <= n || N > nw) return cudaSuccess;
    if ((e = cudaFuncSetAttribute(w.fn, cudaFuncAttributeMaxDynamicSharedMemorySize, (int)sw)) != cudaSuccess) return e;
    *wave = true;
    return cudaSuccess;
}

template <typename T> cudaError_t lanes_layout(const DModel<T> &m, int block, int layout[4])
{
    const int wk = world_kind(m);
    const LanesPick<T> k = run_pick(m, wk);
    if (!k.fn) return cudaErrorInvalidValue;
    int b = 0, chunk = 0;
    size_t smem = 0;
    int64_t strands = 0;
    cudaError_t e = lanes_shape(m, k, wk, run_block(m, block), b, chunk, smem);
    if (e != cudaSuccess) return e;
    const int j1 = m.j1 < 0 ? (int)m.substeps : m.j1;
    if (lanes_col_on<T>(wk, m)) /* a launch's staged colliders (launch_frame_lanes) */
        smem += (size_t)lanes_col_reals(m.world.ncol, chunk < j1 - m.j0 ? chunk : j1 - m.j0) * sizeof(T);
    if ((e = wave_strands(k, b, smem, strands)) != cudaSuccess) return e;
    layout[0] = k.g;
    layout[1] = k.lanes;
    layout[2] = b;
    layout[3] = strands > 2147483647 ? 2147483647 : (int)strands;
    return cudaSuccess;
}

template <typename T>
cudaError_t launch_frame_lanes(const DModel<T> &m, const T *q, const T *phase, T *x, T *v, const T *rest,
                               const T *bend_rest, int64_t N, int block, cudaStream_t stream)
{
    const int wk = world_kind(m);
    const LanesPick<T> k = run_pick(m, wk);
    if (!k.fn) return cudaErrorInvalidValue;
    const bool col = lanes_col_on<T>(wk, m);
    const int j1 = m.j1 < 0 ? (int)m.substeps : m.j1;
    int b = 0, chunk = 0;
    size_t smem = 0;
    cudaError_t e = lanes_shape(m, k, wk, run_block(m, block), b, chunk, smem);
    if (e != cudaSuccess) return e;
    /* the contact planes of a frame in several launches are kept in m.contacts (backend_dyn.cu) */
    if (col && m.world.planes && (m.j0 > 0 || j1 < (int)m.substeps || chunk < j1 - m.j0) && !m.contacts)
        return cudaErrorInvalidValue;
    const int64_t per_block = (int64_t)(b / 32) * (32 / k.lanes);
    const int64_t g = (N + per_block - 1) / per_block;
    const int grid = (int)(g < 1 ? 1 : g > 2147483647 ? 2147483647 : g);
    DModel<T> mc = m;
    /* the held kernel takes the strands in the order m.perm where it samples them itself (hold_block:
     * the frame's samples at its start, its block's strands in one pass), else as stored */
    if (m.hold_self && (g != grid || m.j0 != 0 || chunk < j1)) return cudaErrorInvalidValue;
    if (wk == kWHeld && !m.hold_self) mc.perm = nullptr;
    do { /* one launch at least, as before */
        mc.j1 = chunk < j1 - mc.j0 ? mc.j0 + chunk : j1;
        const size_t cb = col ? (size_t)lanes_col_reals(m.world.ncol, mc.j1 - mc.j0) * sizeof(T) : 0;
        /* a programmatic dependent of the kernel before it (the grid's hold, or the launch before) */
        if ((e = launch_chained(k.fn, dim3((unsigned)grid), dim3((unsigned)b), smem + cb, stream, mc, q, phase, x, v,
                                rest, bend_rest, N)) != cudaSuccess)
            return e;
        if ((e = cudaGetLastError()) != cudaSuccess) return e;
        mc.j0 = mc.j1;
    } while (mc.j0 < j1);
    return cudaSuccess;
}

#define HB_LANES_INSTANTIATE(T)                                                                                        \
    template cudaError_t prepare_lanes<T>(unsigned, int, int64_t, int, bool, bool);                                    \
    template cudaError_t lanes_launches<T>(const DModel<T> &, int, int *);                                             \
    template cudaError_t lanes_wave<T>(const DModel<T> &, int64_t, int, bool *);                                       \
    template cudaError_t lanes_layout<T>(const DModel<T> &, int, int[4]);                                              \
    template cudaError_t launch_frame_lanes<T>(const DModel<T> &, const T *, const T *, T *, T *, const T *,           \
                                               const T *, int64_t, int, cudaStream_t);
/* the Makefile compiles this file once per precision (-DHB_DYN_REAL), side by side */
#ifdef HB_DYN_REAL
HB_LANES_INSTANTIATE(HB_DYN_REAL)
#else
HB_LANES_INSTANTIATE(float)
HB_LANES_INSTANTIATE(double)
#endif
#undef HB_LANES_INSTANTIATE

} /* namespace dyn */
} /* namespace hb */
