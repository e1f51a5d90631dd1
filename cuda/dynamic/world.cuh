/* cuda/dynamic/world.cuh — the hair–hair grid (docs/model.md §3.16) and the colliders with friction
 * (§3.17) for the CUDA port: c_ref/dynamic/contact_impl.h itself, included once for float and
 * once for double, so the strict build performs the reference's operations on the device
 * (the normal build contracts them into FMAs). The launchers of the grid's kernels are in
 * cuda/dynamic/world.cu.
 */
#ifndef HB_DYN_WORLD_CUH
#define HB_DYN_WORLD_CUH

#include <cuda_runtime.h>
#include <math.h>
#include <stdint.h>

#include "dynamic/world.h"

#include "dynamic/precision_f32.h"
#include "dynamic/contact_impl.h"
#include "dynamic/precision_end.h"
#include "dynamic/precision_f64.h"
#include "dynamic/contact_impl.h"
#include "dynamic/precision_end.h"

namespace hb {
namespace dyn {

template <typename T> struct WorldOf;
template <> struct WorldOf<float> {
    using type = hb_dyn_world_f32;
};
template <> struct WorldOf<double> {
    using type = hb_dyn_world_f64;
};
/* The run's grid and colliders in T, pointing at device memory. */
template <typename T> using World = typename WorldOf<T>::type;

/* §3.17: whether a run's world has the colliders' work: colliders, the head sphere's friction or its
 * bounded depenetration */
template <typename WorldT> HB_HD constexpr bool world_collides(const WorldT &w)
{
    return w.ncol > 0 || w.head_friction || w.bounded;
}
/* §3.16: the lanes kernel applies each point's sample as k_grid_hold took it (docs/cuda.md) for
 * `held`, and for `substep` without colliders: a launch a substep there, so the sample at the
 * launch's start is the one the substep's correction takes (as one substep a frame of `held` is
 * `frame` bit for bit); with colliders the kernel with all the world's code gathers itself */
template <typename WorldT> inline bool lanes_holds_samples(const WorldT &w)
{
    const bool col = world_collides(w);
    return w.grid && (w.grid_friction || w.grid_volume) &&
           (w.grid_rebuild == HB_GRID_HELD || (w.grid_rebuild == HB_GRID_SUBSTEP && !col));
}
/* ... and where `held` has no colliders (a frame one launch of the held kernel), that kernel takes
 * its block's samples itself before its strand loop (hold_block), k_grid_hold not launched */
template <typename WorldT> inline bool lanes_hold_self(const WorldT &w)
{
    return lanes_holds_samples(w) && w.grid_rebuild == HB_GRID_HELD && !world_collides(w);
}

/* The precision's functions of contact_impl.h by overload. */
HB_HD void grid_sample(const World<float> &w, const float *qg, const float *x, float *s)
{
    hb_grid_sample_f32(&w, qg, x, s);
}
HB_HD void grid_sample(const World<double> &w, const double *qg, const double *x, double *s)
{
    hb_grid_sample_f64(&w, qg, x, s);
}
HB_HD void grid_apply(const World<float> &w, float h, int64_t k, const float *s, float *v)
{
    hb_grid_apply_f32(&w, h, k, s, v);
}
HB_HD void grid_apply(const World<double> &w, double h, int64_t k, const double *s, double *v)
{
    hb_grid_apply_f64(&w, h, k, s, v);
}
HB_HD int sdf_sample(const float *sdf, int64_t n, const float *geo, const float *u, float *phi, float *g)
{
    return hb_sdf_sample_f32(sdf, n, geo, u, phi, g);
}
HB_HD int sdf_sample(const double *sdf, int64_t n, const double *geo, const double *u, double *phi, double *g)
{
    return hb_sdf_sample_f64(sdf, n, geo, u, phi, g);
}
HB_HD void collide_one(const World<float> &w, int i, const float *pose, const float *back, float *p, const float *x)
{
    hb_collide_one_f32(&w, i, pose, back, p, x);
}
HB_HD void collide_one(const World<double> &w, int i, const double *pose, const double *back, double *p,
                       const double *x)
{
    hb_collide_one_f64(&w, i, pose, back, p, x);
}
HB_HD void collide_head(const World<float> &w, float rc, const float *back, float *p, const float *x)
{
    hb_collide_head_f32(&w, rc, back, p, x);
}
HB_HD void collide_head(const World<double> &w, double rc, const double *back, double *p, const double *x)
{
    hb_collide_head_f64(&w, rc, back, p, x);
}
/* §3.17 --contact-planes: a point's planes found, carried, met (contact_impl.h) */
HB_HD void contact_find(const World<float> &w, const float *pose, const float *x, float *con)
{
    hb_contact_find_f32(&w, pose, x, con);
}
HB_HD void contact_find(const World<double> &w, const double *pose, const double *x, double *con)
{
    hb_contact_find_f64(&w, pose, x, con);
}
HB_HD void contact_carry(const World<float> &w, const float *back, float *con)
{
    hb_contact_carry_f32(&w, back, con);
}
HB_HD void contact_carry(const World<double> &w, const double *back, double *con)
{
    hb_contact_carry_f64(&w, back, con);
}
HB_HD void contact_one(const World<float> &w, const float *con, const float *back, float *p, const float *x)
{
    hb_contact_one_f32(&w, con, back, p, x);
}
HB_HD void contact_one(const World<double> &w, const double *con, const double *back, double *p, const double *x)
{
    hb_contact_one_f64(&w, con, back, p, x);
}
HB_HD double collider_depth(const World<float> &w, int i, const float *pose, const double *x)
{
    return hb_collider_depth_f32(&w, i, pose, x);
}
HB_HD double collider_depth(const World<double> &w, int i, const double *pose, const double *x)
{
    return hb_collider_depth_f64(&w, i, pose, x);
}

/* ---- the grid's kernels (cuda/dynamic/world.cu) ---- */
/* §3.16 the splat of every point of x, v (canonical [N][P][3]) into mass [n³] and mom [n³][3]
 * (zero: launch_grid_nodes clears the next build's), with the grid rotation qg (device, nullptr:
 * still); the strands taken in the order perm (device, nullptr: as stored). */
template <typename T>
cudaError_t launch_grid_splat(const World<T> &w, const T *qg, const T *x, const T *v, int64_t N, int64_t P,
                              const int64_t *perm, int64_t *mass, int64_t *mom, cudaStream_t stream);
/* §3.16 `held`: every point's sample at x (canonical [N][P][3]) with the grid rotation qg, into
 * held ([N][P][kHeldReals], cuda/dynamic/held.cuh; h: the substep; perm: the strands' order, or
 * nullptr), after launch_grid_nodes (where the lanes kernel does not take them itself: lanes_hold_self). */
template <typename T>
cudaError_t launch_grid_hold(const World<T> &w, const T *qg, T h, const T *x, int64_t N, int64_t P, const int64_t *perm,
                             T *held, cudaStream_t stream);
/* §3.16 the node fields from the sums (target, inv_rho0, neg_kv: volume); clear ([4·n³], not mass's
 * set) zeroed for the next build. */
template <typename T>
cudaError_t launch_grid_nodes(const World<T> &w, const T *qg, const int64_t *mass, const int64_t *mom, int64_t *clear,
                              const T *target, T inv_rho0, T neg_kv, T *node_v, T *node_a, cudaStream_t stream);

} /* namespace dyn */
} /* namespace hb */

#endif
