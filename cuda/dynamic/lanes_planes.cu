/* cuda/dynamic/lanes_planes.cu — the lanes kernels with the colliders as contact planes alone (kWCol | kWPlanes,
 * docs/cuda.md "Contact planes in the lanes kernel"), for each layout; the default scene's feature
 * set (every feature) has its own in fp32 at P ≤ 32. */
/* the contact planes' collision step in one loop for every sweep count: 46.8 ms a 4M frame against
 * 48.1 with the one-sweep step compiled apart (docs/cuda.md "Contact planes in the lanes kernel") */
#define HB_LANES_ONE_SWEEP 0
#include "dynamic/lanes_kernel.cuh"

namespace hb {
namespace dyn {

template <typename T, int G, int L, bool Ftl> LanesFn<T> lanes_planes_kernel(unsigned f)
{
    constexpr unsigned kEvery = HB_F_COUNT - 1u;
    if constexpr (sizeof(T) == 4 && !Ftl && G == 2 && L == 16)
        if (f == kEvery) return &k_lanes<T, StaticF<kEvery>, G, L, Ftl, false, kWCol | kWPlanes>;
    return &k_lanes<T, DynF, G, L, Ftl, false, kWCol | kWPlanes>;
}

#define HB_LANES_KIND(T, G, L, Ftl) template LanesFn<T> lanes_planes_kernel<T, G, L, Ftl>(unsigned);
HB_LANES_INSTANCES(HB_LANES_LAYOUTS, HB_LANES_KIND)
#undef HB_LANES_KIND

} /* namespace dyn */
} /* namespace hb */
