/* cuda/dynamic/lanes_world_xpbd.cu — the lanes kernels with all of the world's code (lanes_world.cuh)
 * for xpbd's layouts (ftl's: lanes_world_ftl.cu). */
#include "dynamic/lanes_world.cuh"

namespace hb {
namespace dyn {
HB_LANES_INSTANCES(HB_LANES_LAYOUTS_XPBD, HB_LANES_WORLD)
} /* namespace dyn */
} /* namespace hb */
