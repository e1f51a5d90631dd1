/* cuda/dynamic/lanes_world.cuh — the picker of the lanes kernels with all of the world's code (kWAll: the
 * hair–hair grid with the colliders, exact or as contact planes, chosen at run time; a groom's world run,
 * with its per-segment rest lengths), instantiated for a solver's layouts in lanes_world_xpbd.cu and
 * lanes_world_ftl.cu. Included by those two alone: lanes.cu only declares it (lanes_kernel.cuh). */
#ifndef HB_DYN_LANES_WORLD_CUH
#define HB_DYN_LANES_WORLD_CUH

#include "dynamic/lanes_kernel.cuh"

namespace hb {
namespace dyn {

template <typename T, int G, int L, bool Ftl> LanesFn<T> lanes_world_kernel(bool seg)
{
    return seg ? &k_lanes<T, DynF, G, L, Ftl, true, kWAll> : &k_lanes<T, DynF, G, L, Ftl, false, kWAll>;
}

#define HB_LANES_WORLD(T, G, L, Ftl) template LanesFn<T> lanes_world_kernel<T, G, L, Ftl>(bool);

} /* namespace dyn */
} /* namespace hb */

#endif
