/* cuda/dynamic/lanes_world_ftl.cu — the lanes kernels with all of the world's code (kWAll: the hair–hair grid with
 * the colliders, exact or as contact planes, chosen at run time; a groom's world run, with its
 * per-segment rest lengths), for each of ftl's layouts (xpbd's: lanes_world_xpbd.cu). */
#include "dynamic/lanes_kernel.cuh"

namespace hb {
namespace dyn {

template <typename T, int G, int L, bool Ftl> LanesFn<T> lanes_world_kernel(bool seg)
{
    return seg ? &k_lanes<T, DynF, G, L, Ftl, true, kWAll> : &k_lanes<T, DynF, G, L, Ftl, false, kWAll>;
}

#define HB_LANES_KIND(T, G, L, Ftl) template LanesFn<T> lanes_world_kernel<T, G, L, Ftl>(bool);
/* the Makefile compiles this file once per precision (-DHB_DYN_REAL), side by side */
#ifdef HB_DYN_REAL
HB_LANES_LAYOUTS_FTL(HB_LANES_KIND, HB_DYN_REAL)
#else
HB_LANES_LAYOUTS_FTL(HB_LANES_KIND, float)
HB_LANES_LAYOUTS_FTL(HB_LANES_KIND, double)
#endif
#undef HB_LANES_KIND

} /* namespace dyn */
} /* namespace hb */
