/* dyn_sagfree.h — sag-free rest (docs/model.md §3.13): the shape targets' rest positions that
 * hold the groom's rest shape in static equilibrium under gravity. Host side, once per run,
 * shared by every backend (the CUDA binary links it). */
#ifndef HB_DYN_SAGFREE_H
#define HB_DYN_SAGFREE_H

#include "runtime/params.h"

#ifdef __cplusplus
extern "C" {
#endif

/* δ = α_g·g0/D in double (D = 1 + h·(c_d + β) with drag or damping declared, else 1). */
double hb_sagfree_offset(const hb_scene *s);
/* out (canonical [N·P][3], the scene's precision) = the rest shape with every non-root point
 * raised by δ along ŷ, each coordinate computed in double and rounded once. */
void hb_sagfree_targets(const hb_scene *s, const void *rest, void *out);

#ifdef __cplusplus
}
#endif
#endif
