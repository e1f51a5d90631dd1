/* cuda/dynamic/lanes_grid.cu — the lanes kernels with the hair–hair grid's code alone (docs/cuda.md
 * "The hair–hair grid and the colliders"): the held sample (kWHeld: `held`, or a grid that applies
 * nothing) and the gather every substep (kWGather: `frame`, `substep`), for each layout; the default
 * scene's feature set (every feature) has its own in fp32 at P ≤ 32 (the generic ones spill there),
 * and the one-wave layout's (lanes_kernel.cuh kWaveG) with the held grid. */
#include "dynamic/lanes_kernel.cuh"

namespace hb {
namespace dyn {

template <typename T, int G, int L, bool Ftl> LanesFn<T> lanes_grid_kernel(unsigned f, int wk)
{
    constexpr unsigned kEvery = HB_F_COUNT - 1u;
    if constexpr (sizeof(T) == 4 && !Ftl && G == 2 && L == 16) {
        if (f == kEvery && wk == kWHeld) return &k_lanes<T, StaticF<kEvery>, G, L, Ftl, false, kWHeld>;
        if (f == kEvery && wk == kWGather) return &k_lanes<T, StaticF<kEvery>, G, L, Ftl, false, kWGather>;
    }
    if (wk == kWHeld) return &k_lanes<T, DynF, G, L, Ftl, false, kWHeld>;
    if (wk == kWGather) return &k_lanes<T, DynF, G, L, Ftl, false, kWGather>;
    return nullptr;
}

template <typename T> LanesFn<T> lanes_wave_held_kernel()
{
    if constexpr (sizeof(T) == 4) return &k_lanes<T, StaticF<HB_F_COUNT - 1u>, kWaveG, kWaveL, false, false, kWHeld>;
    else return nullptr;
}

#define HB_LANES_KIND(T, G, L, Ftl) template LanesFn<T> lanes_grid_kernel<T, G, L, Ftl>(unsigned, int);
HB_LANES_INSTANCES(HB_LANES_LAYOUTS, HB_LANES_KIND)
#undef HB_LANES_KIND
#define HB_LANES_WAVE(T) template LanesFn<T> lanes_wave_held_kernel<T>();
#ifdef HB_DYN_REAL
HB_LANES_WAVE(HB_DYN_REAL)
#else
HB_LANES_WAVE(float)
HB_LANES_WAVE(double)
#endif
#undef HB_LANES_WAVE

} /* namespace dyn */
} /* namespace hb */
