/* hostcheck_scene.h — the dynamic and follower host checks' scene: zeroed, N strands × P points
 * on the head of radius 10, the dynamics at their defaults; each check sets the rest. */
#ifndef HB_HOSTCHECK_SCENE_H
#define HB_HOSTCHECK_SCENE_H

#include <stdint.h>
#include <string.h>

#include "runtime/params.h"

inline hb_scene hostcheck_scene(int64_t N, int64_t P, double hair_length, hb_precision precision)
{
    hb_scene s;
    memset(&s, 0, sizeof s);
    s.n_strands = N;
    s.points = P;
    s.head_radius = 10.0;
    s.hair_length = hair_length;
    s.precision = precision;
    hb_dynamics_defaults(&s.dyn);
    return s;
}

#endif
