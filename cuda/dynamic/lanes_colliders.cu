/* cuda/dynamic/lanes_colliders.cu — the lanes kernels with the colliders of docs/model.md §3.17 alone (kWCol: exact, or the head
 * sphere's friction or bounded depenetration alone), for each layout; the default scene's feature set
 * (every feature) has its own in fp32 at P ≤ 32 (the generic one spills there). */
#include "dynamic/lanes_kernel.cuh"

namespace hb {
namespace dyn {

template <typename T, int G, int L, bool Ftl> LanesFn<T> lanes_colliders_kernel(unsigned f)
{
    constexpr unsigned kEvery = HB_F_COUNT - 1u;
    if constexpr (sizeof(T) == 4 && !Ftl && G == 2 && L == 16)
        if (f == kEvery) return &k_lanes<T, StaticF<kEvery>, G, L, Ftl, false, kWCol>;
    return &k_lanes<T, DynF, G, L, Ftl, false, kWCol>;
}

#define HB_LANES_KIND(T, G, L, Ftl) template LanesFn<T> lanes_colliders_kernel<T, G, L, Ftl>(unsigned);
HB_LANES_INSTANCES(HB_LANES_LAYOUTS, HB_LANES_KIND)
#undef HB_LANES_KIND

} /* namespace dyn */
} /* namespace hb */
