/* backend_dyn.cu — the simulate stage of the CUDA backend (the hb_backend hooks dyn_load,
 * dyn_frame, dyn_observe, dyn_fetch_velocity, dyn_loop; docs/cuda.md "The dynamic model"),
 * on the backend state of backend_cuda.cuh.
 *
 * Variants that run simulate:
 *   strand  one thread per strand; the state, velocities and rest shape point-major
 *           X|Y|Z [P][N] (as soa/fused), bend rest lengths [P−2][N]; p, λ, d in a thread's
 *           interleaved scratch (9·P reals per resident thread; the grid is capped at the
 *           threads the device holds at once, each thread takes strands grid-strided).
 *   warp    one warp per strand; the state, velocities and rest shape canonical [N][P][3]
 *           (as paper: a strand's 3P reals are contiguous, so the warp's loads coalesce),
 *           bend rest lengths [N][P−2]; x, v, p, λ, d of the frame in shared memory.
 *   warpreg as warp in memory; lane k holds point k's x, v, p, λ, d and rest in registers
 *           for the whole frame, neighbours exchange through shuffles (P ≤ 32).
 *
 * Device memory of simulate: velocities, rest shape, bend rest lengths, a saved copy of the
 * velocities for repeats, the strand variant's scratch, the frame's tables ([S][9] + [S])
 * and the observables' per-chunk partials. Counted in setup's cudaMemGetInfo check.
 *
 * Timing: dyn_frame uploads the frame's rotation and phase tables (cudaMemcpyAsync on the
 * stream, before the start event: not part of r->ms, but of the end-to-end cost of a frame),
 * then records the events immediately around the one kernel launch.
 */

#include <cuda_runtime.h>

#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include <vector>

#include "backend_cuda.cuh"
#include "check.cuh"
#include "dynamic/held.cuh"
#include "dynamic/kernels.cuh"
#include "dynamic/lod.cuh"
#include "dynamic/post.cuh"
#include "dynamic/dyn_followers.h"
#include "dynamic/dyn_sagfree.h"
#include "dynamic/world_host.h"
#include "runtime/checked.h"
#include "runtime/host.h"

namespace hbd = hb::dyn;

namespace hb_cuda {

struct DynState {
    int64_t S;
    void *vel, *vel_saved, *rest, *bend_rest, *scratch, *q, *ph;
    hbd::ObsPartial *d_obs;
    hbd::ObsPartial *h_obs;
    hb_obs_partial *h_part;
    int64_t nchunks;
    int grid;
    hbd::DModel<float> m32;
    hbd::DModel<double> m64;
    hbd::ObsScene obs;
    /* §3.14 guides and followers (cuda/dynamic/post.cu): the plan on the host and the device */
    int guided;
    hb_followers fl;
    int64_t *d_guide, *d_follower, *d_src;
    void *d_w;
    void *shape_rest; /* --sag-free: the rest shape the frame kernels read (root, shape targets) */
    void *seg_rest;   /* §3.15 a groom's ℓ_k in the variant's layout ([P−1][N] strand, [N][P−1] warp) */
    double *seg64;    /* and in double [N][P−1], for the observables */
    /* §3.14 --render-points: a rendered frame and its velocities, canonical [N·P_r][3] */
    uint64_t render_bytes;
    void *d_render, *d_vrender;
    /* §3.16 the grid and §3.17 the colliders: the host tables, their device copies, the grid's
     * sums and node fields, the frame's pose tables, and the world struct on the device (for
     * the observables) */
    hb_host_world hw;
    int64_t *g_mass; /* two sets of sums [4·n³] (mass, then momentum): g_cur, zero, the next build's */
    int g_cur;
    void *g_node_v, *g_node_a, *g_target, *g_ftab;
    void *g_held; /* §3.16 `held`: each point's sample for the frame */
    int *c_kind, *c_frame;
    int64_t *c_sdf_n;
    void *c_mu, *c_geo, *c_sdf_ptrs;
    void *c_sdf[HB_MAX_COLLIDERS];
    void *f_pose, *f_back, *f_qs;
    void *d_world;
    void *perm;     /* lanes: the strands' order (hb_grid_order) */
    void *contacts; /* lanes, --contact-planes, a frame in several launches: each point's planes */
    uint64_t pose_bytes, back_bytes;
};

int dyn_is_strand_major(const cuda_impl *c)
{
    return c->variant == V_PAPER || c->variant == V_WARP || c->variant == V_WARPREG || c->variant == V_LANES;
}

static int dyn_is_warp(const cuda_impl *c)
{
    return c->variant == V_WARP || c->variant == V_WARPREG || c->variant == V_LANES;
}

/* The variant's layouts of the state (and of velocities and rest shape). */
static hbd::Layout dyn_layout(const cuda_impl *c)
{
    if (dyn_is_warp(c)) return hbd::Layout{3 * c->P, 3, 1};
    return hbd::Layout{1, c->N, c->N * c->P};
}
static hbd::Layout1 dyn_bend_layout(const cuda_impl *c)
{
    if (dyn_is_warp(c)) return hbd::Layout1{c->P - 2 > 0 ? c->P - 2 : 0, 1};
    return hbd::Layout1{1, c->N};
}

/* Grid of the strand variant: one thread a strand, at most as many threads as the device
 * holds at once (the scratch is sized for them). */
static int dyn_strand_grid(int64_t N, int block, int64_t resident)
{
    int64_t g = (N + block - 1) / block;
    const int64_t cap = resident / block > 0 ? resident / block : 1;
    if (g > cap) g = cap;
    return (int)(g < 1 ? 1 : g);
}

/* Bytes of device memory simulate adds (0 when it is not in the stage list); refuses a
 * warp-variant block that does not fit in shared memory. */
int dyn_plan(cuda_impl *c, const hb_options *o, int need_save, uint64_t *bytes, char *err, size_t errlen)
{
    *bytes = 0;
    int on = 0;
    for (int i = 0; i < o->n_stages; i++) on |= o->stages[i] == HB_STAGE_SIMULATE;
    if (!on) return 0;
    if (c->variant != V_STRAND && !dyn_is_warp(c)) {
        snprintf(err, errlen, "internal error: variant without simulate reached the simulate setup");
        return -1;
    }
    DynState *d = (DynState *)calloc(1, sizeof *d);
    if (!d) {
        snprintf(err, errlen, "out of host memory");
        return HB_EXIT_MEMORY;
    }
    c->dyn = d;
    const hb_scene *s = &o->scene;
    hb_dyn_model_f32 m32;
    hb_dyn_model_f64 m64;
    hb_dyn_round(s, &m32, &m64);
    d->m32 = hbd::dmodel_from<float>(m32);
    d->m64 = hbd::dmodel_from<double>(m64);
    d->obs = hbd::obs_scene(s);
    d->S = s->dyn.substeps;
    if (!hbd::valid_features(m64.features)) {
        snprintf(err, errlen, "internal error: feature set %u has no kernel", m64.features);
        return -1;
    }
    const uint64_t rs = hb_real_size(s->precision);
    const int64_t N = c->N, P = c->P;
    cudaDeviceProp prop;
    HB_CUDA(cudaGetDeviceProperties(&prop, 0));
    uint64_t need = sat_add(c->bytes, c->bytes); /* velocities, rest shape */
    if (need_save) need = sat_add(need, c->bytes);
    need = sat_add(need, hb_mul_sat(hb_mul_sat((uint64_t)N, (uint64_t)(P - 2 > 0 ? P - 2 : 1)), rs));
    need = sat_add(need, hb_mul_sat((uint64_t)d->S, 10u * rs));
    d->nchunks = (N + hbd::kObsChunk - 1) / hbd::kObsChunk;
    need = sat_add(need, hb_mul_sat((uint64_t)d->nchunks, sizeof(hbd::ObsPartial)));
    d->guided = s->dyn.guided;
    if (s->dyn.sag_free) need = sat_add(need, c->bytes); /* the raised shape targets */
    if (s->dyn.per_segment)                              /* §3.15 a groom's ℓ_k, working precision and double */
        need = sat_add(need, hb_mul_sat(hb_mul_sat((uint64_t)N, (uint64_t)(P - 1)), rs + 8u));
    if (s->dyn.render_points) {
        d->render_bytes = hb_mul_sat(hb_mul_sat((uint64_t)N, (uint64_t)s->dyn.render_points), 3u * rs);
        need = sat_add(need, hb_mul_sat(d->render_bytes, 2u));
    }
    if (d->guided) /* guide and follower numbers, up to 3 guides and weights a follower */
        need = sat_add(need, hb_mul_sat((uint64_t)N, 8u + 3u * (8u + rs)));
    if (s->dyn.grid) { /* §3.16 the sums and the node fields */
        const uint64_t nodes = (uint64_t)s->dyn.grid_n * (uint64_t)s->dyn.grid_n * (uint64_t)s->dyn.grid_n;
        need = sat_add(need, hb_mul_sat(nodes, 32u + 9u * rs));
    }
    need = sat_add(need, hb_host_world_bytes(s, 0)); /* §3.17 the meshes' fields */
    if (c->variant == V_LANES && s->dyn.planes_declared && s->dyn.grid && s->dyn.grid_rebuild == HB_GRID_SUBSTEP)
        need = sat_add(need, hb_mul_sat(hb_mul_sat((uint64_t)N, (uint64_t)P), HB_CONTACT_POINT * rs)); /* the planes */
    if (c->variant == V_STRAND) {
        const int64_t resident = (int64_t)prop.multiProcessorCount * prop.maxThreadsPerMultiProcessor;
        d->grid = dyn_strand_grid(N, c->block, resident);
        need = sat_add(need, hb_mul_sat(hb_mul_sat((uint64_t)d->grid * (uint64_t)c->block * 9u, (uint64_t)P), rs));
    } else if (c->variant == V_LANES) {
        if (P > hbd::kLanesMaxPoints) { /* the driver refuses it first, from the variant table */
            snprintf(err, errlen, "internal error: lanes with %lld points", (long long)P);
            return -1;
        }
        d->grid = 0; /* launch_frame_lanes sizes its grid */
    } else if (c->variant == V_WARPREG) {
        if (P > hbd::kWarpregMaxPoints) { /* the driver refuses it first, from the variant table */
            snprintf(err, errlen, "internal error: warpreg with %lld points", (long long)P);
            return -1;
        }
        const int wpb = c->block / 32;
        const int64_t g = (N + wpb - 1) / wpb;
        d->grid = (int)(g > 2147483647 ? 2147483647 : g);
    } else {
        const int wpb = c->block / 32;
        const int64_t g = (N + wpb - 1) / wpb;
        d->grid = (int)(g > 2147483647 ? 2147483647 : g);
        const size_t smem =
            (s->precision == HB_FP32 ? hbd::warp_smem_bytes<float>(P) : hbd::warp_smem_bytes<double>(P)) * (size_t)wpb;
        if (smem > prop.sharedMemPerBlockOptin) {
            snprintf(
                err, errlen,
                "--variant warp keeps each strand in shared memory: %lld points x %d strands a block (--block-size "
                "%d) need %.1f KB, more than the %.1f KB a block may have on %s; use a smaller --block-size or "
                "--variant strand",
                (long long)P, wpb, c->block, (double)smem / 1024.0, (double)prop.sharedMemPerBlockOptin / 1024.0,
                c->device);
            return HB_EXIT_USAGE;
        }
    }
    *bytes = need;
    return 0;
}

int dyn_alloc(cuda_impl *c, int need_save, char *err, size_t errlen)
{
    DynState *d = c->dyn;
    if (!d) return 0;
    const uint64_t rs = hb_real_size(c->scene.precision);
    const int64_t P = c->P;
    int rc;
    if ((rc = device_alloc(&d->vel, c->bytes, c, "velocities", err, errlen))) return rc;
    if ((rc = device_alloc(&d->rest, c->bytes, c, "rest shape", err, errlen))) return rc;
    if (need_save && (rc = device_alloc(&d->vel_saved, c->bytes, c, "saved velocities", err, errlen))) return rc;
    if ((rc = device_alloc(&d->bend_rest, hb_mul_sat(hb_mul_sat((uint64_t)c->N, (uint64_t)(P - 2 > 0 ? P - 2 : 1)), rs),
                           c, "bend rest lengths", err, errlen)))
        return rc;
    if (c->scene.dyn.per_segment) { /* §3.15 */
        const uint64_t nseg = hb_mul_sat((uint64_t)c->N, (uint64_t)(P - 1));
        if ((rc = device_alloc(&d->seg_rest, hb_mul_sat(nseg, rs), c, "stretch rest lengths", err, errlen))) return rc;
        if ((rc = device_alloc((void **)&d->seg64, hb_mul_sat(nseg, 8u), c, "stretch rest lengths", err, errlen)))
            return rc;
    }
    if ((rc = device_alloc(&d->q, hb_mul_sat((uint64_t)d->S, 9u * rs), c, "rotation table", err, errlen))) return rc;
    if ((rc = device_alloc(&d->ph, hb_mul_sat((uint64_t)d->S, rs), c, "phase table", err, errlen))) return rc;
    if ((rc = device_alloc((void **)&d->d_obs, hb_mul_sat((uint64_t)d->nchunks, sizeof(hbd::ObsPartial)), c,
                           "observables", err, errlen)))
        return rc;
    if (c->variant == V_STRAND &&
        (rc = device_alloc(&d->scratch,
                           hb_mul_sat(hb_mul_sat((uint64_t)d->grid * (uint64_t)c->block * 9u, (uint64_t)P), rs), c,
                           "per-thread scratch", err, errlen)))
        return rc;
    if (d->render_bytes && ((rc = device_alloc(&d->d_render, d->render_bytes, c, "rendered points", err, errlen)) ||
                            (rc = device_alloc(&d->d_vrender, d->render_bytes, c, "rendered velocities", err, errlen))))
        return rc;
    d->h_obs = (hbd::ObsPartial *)malloc((size_t)hb_mul_sat((uint64_t)d->nchunks, sizeof *d->h_obs));
    d->h_part = (hb_obs_partial *)malloc((size_t)hb_mul_sat((uint64_t)d->nchunks, sizeof *d->h_part));
    if (!d->h_obs || !d->h_part) {
        snprintf(err, errlen, "out of host memory for the observables");
        return HB_EXIT_MEMORY;
    }
    return 0;
}

void dyn_free(cuda_impl *c)
{
    DynState *d = c->dyn;
    if (!d) return;
    void *ptrs[] = {d->vel,        d->vel_saved, d->rest,    d->bend_rest,  d->scratch,  d->q,
                    d->ph,         d->d_obs,     d->d_guide, d->d_follower, d->d_src,    d->d_w,
                    d->shape_rest, d->seg_rest,  d->seg64,   d->d_render,   d->d_vrender};
    for (void *p : ptrs)
        if (p) cudaFree(p);
    /* both sets of sums lie in g_mass's allocation */
    void *world[] = {d->g_mass, d->g_node_v, d->g_node_a, d->g_target, d->g_ftab, d->g_held,
                     d->c_kind, d->c_frame,  d->c_sdf_n,  d->c_mu,     d->c_geo,  d->c_sdf_ptrs,
                     d->f_pose, d->f_back,   d->f_qs,     d->d_world,  d->perm,   d->contacts};
    for (void *p : world)
        if (p) cudaFree(p);
    for (void *p : d->c_sdf)
        if (p) cudaFree(p);
    hb_host_world_free(&d->hw);
    free(d->h_obs);
    free(d->h_part);
    hb_followers_free(&d->fl);
    free(d);
    c->dyn = NULL;
}

int dyn_save(cuda_impl *c, char *err, size_t errlen)
{
    DynState *d = c->dyn;
    if (!d) return 0;
    if (!d->vel_saved) {
        snprintf(err, errlen, "internal error: save without a saved-velocity buffer");
        return -1;
    }
    HB_CUDA(cudaMemcpy(d->vel_saved, d->vel, (size_t)c->bytes, cudaMemcpyDeviceToDevice));
    return 0;
}

int dyn_restore(cuda_impl *c, char *err, size_t errlen)
{
    DynState *d = c->dyn;
    if (!d) return 0;
    if (!d->vel_saved) {
        snprintf(err, errlen, "internal error: restore without saved velocities");
        return -1;
    }
    HB_CUDA(cudaMemcpy(d->vel, d->vel_saved, (size_t)c->bytes, cudaMemcpyDeviceToDevice));
    return 0;
}

/* canonical host array -> the variant's layout in `dst` (through the staging buffer for
 * the point-major strand variant) */
template <typename T>
static int dyn_upload(cuda_impl *c, void *dst, const void *canonical, const char *what, char *err, size_t errlen)
{
    if (dyn_is_warp(c)) {
        HB_CUDA_AS(cudaMemcpy(dst, canonical, (size_t)c->bytes, cudaMemcpyHostToDevice), what);
        return 0;
    }
    c->inter_valid = 0;
    HB_CUDA_AS(cudaMemcpy(c->staging, canonical, (size_t)c->bytes, cudaMemcpyHostToDevice), what);
    HB_CUDA_AS(hb::launch_to_point_major<T>((const T *)c->staging, point_major<T>(c, dst), c->N, c->P, 0),
               "the canonical-to-point-major kernel launch (simulate)");
    HB_CUDA_AS(cudaDeviceSynchronize(), what);
    return 0;
}

template <typename T> static hbd::DModel<T> &dyn_model(DynState *d);
template <> hbd::DModel<float> &dyn_model<float>(DynState *d)
{
    return d->m32;
}
template <> hbd::DModel<double> &dyn_model<double>(DynState *d)
{
    return d->m64;
}

/* a host table to a new device array (nothing for n = 0) */
static int dev_copy(void **dst, const void *src, size_t n, cuda_impl *c, const char *what, char *err, size_t errlen)
{
    if (n == 0) return 0;
    int rc;
    if ((rc = device_alloc(dst, n, c, what, err, errlen))) return rc;
    HB_CUDA_AS(cudaMemcpy(*dst, src, n, cudaMemcpyHostToDevice), what);
    return 0;
}

/* §3.16–3.17: the run's grid and colliders planned on the host (world_host.c, the same tables as
 * the C reference's), copied to the device; the world struct points at the device copies. */
template <typename T> static int dyn_world_load(cuda_impl *c, const void *rest, char *err, size_t errlen)
{
    DynState *d = c->dyn;
    hbd::DModel<T> &m = dyn_model<T>(d);
    hb_host_world_free(&d->hw);
    if (hb_host_world_make(&d->hw, &c->scene, rest, 0, err, errlen)) return HB_EXIT_USAGE;
    if (!d->hw.on) return 0;
    const hb_host_world *hw = &d->hw;
    hbd::World<T> w = *(const hbd::World<T> *)(sizeof(T) == 4 ? (const void *)&hw->w32 : (const void *)&hw->w64);
    const size_t rs = sizeof(T);
    const int64_t nodes = hw->nodes;
    int rc;
    if (c->scene.dyn.grid) {
        /* two sets of sums, each mass then momentum: a build splats into the zero set and its node
         * kernel zeroes the other for the next build, so that no build waits on a memset */
        if ((rc = device_alloc((void **)&d->g_mass, (uint64_t)nodes * 64u, c, "grid sums", err, errlen))) return rc;
        HB_CUDA_AS(cudaMemset(d->g_mass, 0, (size_t)nodes * 64u), "zeroing the grid sums");
        d->g_cur = 0;
        if (c->scene.dyn.grid_friction_declared &&
            (rc = device_alloc(&d->g_node_v, (uint64_t)nodes * 4u * rs, c, "grid velocities", err, errlen)))
            return rc;
        if (c->scene.dyn.grid_volume_declared &&
            (rc = device_alloc(&d->g_node_a, (uint64_t)nodes * 4u * rs, c, "grid accelerations", err, errlen)))
            return rc;
        if ((rc = dev_copy(&d->g_target, hw->target, hw->target ? (size_t)nodes * rs : 0, c, "grid targets", err,
                           errlen)) ||
            (rc = dev_copy(&d->g_ftab, hw->ftab, hw->ftab ? (size_t)c->P * rs : 0, c, "friction profile", err, errlen)))
            return rc;
        w.ftab = (const T *)d->g_ftab;
        w.node_v = (const T *)d->g_node_v;
        w.node_a = (const T *)d->g_node_a;
        if (c->variant == V_LANES && hbd::lanes_hold_self(w)) {
            m.hold_self = 1;
        } else if (c->variant == V_LANES && hbd::lanes_holds_samples(w)) {
            if ((rc = device_alloc(&d->g_held, (uint64_t)c->N * (uint64_t)c->P * hbd::kHeldReals * rs, c,
                                   "the grid's held samples", err, errlen)))
                return rc;
            m.held = (const T *)d->g_held;
        }
    }
    const int nc = hw->ncol;
    if (nc > 0) {
        std::vector<const void *> ptrs((size_t)nc, nullptr);
        for (int i = 0; i < nc; i++)
            if (hw->sdf[i]) {
                const size_t n3 = (size_t)(hw->sdf_n[i] * hw->sdf_n[i] * hw->sdf_n[i]);
                if ((rc = dev_copy(&d->c_sdf[i], hw->sdf[i], n3 * rs, c, "a mesh's SDF", err, errlen))) return rc;
                ptrs[(size_t)i] = d->c_sdf[i];
            }
        if ((rc = dev_copy((void **)&d->c_kind, hw->kind, (size_t)nc * sizeof(int), c, "colliders", err, errlen)) ||
            (rc = dev_copy((void **)&d->c_frame, hw->frame, (size_t)nc * sizeof(int), c, "colliders", err, errlen)) ||
            (rc = dev_copy((void **)&d->c_sdf_n, hw->sdf_n, (size_t)nc * 8u, c, "colliders", err, errlen)) ||
            (rc = dev_copy(&d->c_mu, hw->mu, (size_t)nc * 2u * rs, c, "colliders", err, errlen)) ||
            (rc = dev_copy(&d->c_geo, hw->sdf_geo, (size_t)nc * 4u * rs, c, "colliders", err, errlen)) ||
            (rc = dev_copy(&d->c_sdf_ptrs, ptrs.data(), (size_t)nc * sizeof(void *), c, "colliders", err, errlen)))
            return rc;
        w.col_kind = d->c_kind;
        w.col_frame = d->c_frame;
        w.col_mu = (const T *)d->c_mu;
        w.sdf = (const T *const *)d->c_sdf_ptrs;
        w.sdf_n = d->c_sdf_n;
        w.sdf_geo = (const T *)d->c_geo;
    }
    if (hb_dyn_has_world(&c->scene)) {
        d->pose_bytes = (uint64_t)d->S * (uint64_t)(nc > 0 ? nc : 1) * HB_COL_POSE * rs;
        d->back_bytes = (uint64_t)d->S * HB_COL_BACK * rs;
        if ((rc = device_alloc(&d->f_pose, d->pose_bytes, c, "collider poses", err, errlen)) ||
            (rc = device_alloc(&d->f_back, d->back_bytes, c, "collider poses", err, errlen)))
            return rc;
    }
    if ((rc = device_alloc(&d->f_qs, 9u * rs, c, "grid rotation", err, errlen))) return rc;
    if (c->variant == V_LANES) { /* the strands by their roots' place: a block's points share nodes */
        double lo[3], hi[3];
        for (int k = 0; k < 3; k++) {
            lo[k] = c->scene.dyn.grid ? hw->plan.lo[k] : -2.0 * (c->scene.head_radius + c->scene.hair_length);
            hi[k] = c->scene.dyn.grid ? hw->plan.hi[k] : 2.0 * (c->scene.head_radius + c->scene.hair_length);
        }
        std::vector<int64_t> perm((size_t)c->N);
        if (hb_grid_order(&c->scene, rest, lo, hi, perm.data())) {
            snprintf(err, errlen, "out of host memory for the strands' order");
            return HB_EXIT_MEMORY;
        }
        if ((rc = dev_copy(&d->perm, perm.data(), perm.size() * 8u, c, "the strands' order", err, errlen))) return rc;
        m.perm = (const int64_t *)d->perm;
    }
    if ((rc = dev_copy(&d->d_world, &w, sizeof w, c, "the world", err, errlen))) return rc;
    m.has_world = 1;
    m.world = w;
    m.pose = (const T *)d->f_pose;
    m.back = (const T *)d->f_back;
    m.qs = (const T *)d->f_qs;
    d->obs.ncol = nc;
    if (sizeof(T) == 4) d->obs.w32 = (const hbd::World<float> *)d->d_world;
    else d->obs.w64 = (const hbd::World<double> *)d->d_world;
    return 0;
}

template <typename T>
static int dyn_load_t(cuda_impl *c, const void *velocity, const void *rest, char *err, size_t errlen)
{
    DynState *d = c->dyn;
    if (velocity) {
        if (dyn_upload<T>(c, d->vel, velocity, "uploading the velocities", err, errlen)) return -1;
    } else {
        HB_CUDA(cudaMemset(d->vel, 0, (size_t)c->bytes));
    }
    if (dyn_upload<T>(c, d->rest, rest, "uploading the rest shape", err, errlen)) return -1;
    HB_CUDA_AS(hbd::launch_bend_rest<T>((const T *)d->rest, dyn_layout(c), (T *)d->bend_rest, dyn_bend_layout(c), c->N,
                                        c->P, 0),
               "the bend-rest-length kernel launch");
    if (d->seg_rest) { /* §3.15: a groom's ℓ_k, computed on the host as for every backend */
        const int64_t N = c->N, P = c->P, ns = N * (P - 1);
        std::vector<double> s64((size_t)ns);
        std::vector<T> sw((size_t)ns), rows;
        hb_dyn_seg_rest(&c->scene, rest, s64.data(), sw.data());
        const T *src = sw.data();
        hbd::DModel<T> &m = dyn_model<T>(d);
        m.seg_rest = (const T *)d->seg_rest;
        if (c->variant == V_STRAND) { /* point-major [P−1][N] */
            rows.resize((size_t)ns);
            for (int64_t i = 0; i < N; i++)
                for (int64_t k = 0; k < P - 1; k++) rows[(size_t)(k * N + i)] = sw[(size_t)(i * (P - 1) + k)];
            src = rows.data();
            m.seg_is = 1;
            m.seg_s = N;
        } else { /* warp: canonical [N][P−1] */
            m.seg_is = P - 1;
            m.seg_s = 1;
        }
        HB_CUDA(cudaMemcpy(d->seg_rest, src, (size_t)ns * sizeof(T), cudaMemcpyHostToDevice));
        HB_CUDA(cudaMemcpy(d->seg64, s64.data(), (size_t)ns * sizeof(double), cudaMemcpyHostToDevice));
        d->obs.seg64 = d->seg64;
    }
    if (c->scene.dyn.sag_free) { /* §3.14: the raised shape targets, made on the host */
        std::vector<unsigned char> targets((size_t)c->bytes);
        hb_sagfree_targets(&c->scene, rest, targets.data());
        int rc;
        if (!d->shape_rest && (rc = device_alloc(&d->shape_rest, c->bytes, c, "sag-free targets", err, errlen)))
            return rc;
        if (dyn_upload<T>(c, d->shape_rest, targets.data(), "uploading the sag-free targets", err, errlen)) return -1;
    }
    if (d->guided) { /* §3.14: the plan from the rest shape, once, to the device */
        for (void *p : {(void *)d->d_guide, (void *)d->d_follower, (void *)d->d_src, d->d_w})
            if (p) cudaFree(p);
        d->d_guide = d->d_follower = d->d_src = NULL;
        d->d_w = NULL;
        hb_followers_free(&d->fl);
        if (hb_followers_plan(&c->scene, rest, &d->fl, err, errlen)) return HB_EXIT_MEMORY;
        const hb_followers *fl = &d->fl;
        const uint64_t nf = (uint64_t)(fl->n_followers > 0 ? fl->n_followers : 1), nw = nf * (uint64_t)fl->width;
        int rc;
        if ((rc = device_alloc((void **)&d->d_guide, (uint64_t)fl->n_guides * 8u, c, "guide list", err, errlen)) ||
            (rc = device_alloc((void **)&d->d_follower, nf * 8u, c, "follower list", err, errlen)) ||
            (rc = device_alloc((void **)&d->d_src, nw * 8u, c, "followers' guides", err, errlen)) ||
            (rc = device_alloc(&d->d_w, nw * sizeof(T), c, "followers' weights", err, errlen)))
            return rc;
        const void *w = sizeof(T) == sizeof(float) ? (const void *)fl->w32 : (const void *)fl->w64;
        HB_CUDA(cudaMemcpy(d->d_guide, fl->guide, (size_t)fl->n_guides * 8u, cudaMemcpyHostToDevice));
        HB_CUDA(cudaMemcpy(d->d_follower, fl->follower, (size_t)nf * 8u, cudaMemcpyHostToDevice));
        HB_CUDA(cudaMemcpy(d->d_src, fl->src, (size_t)nw * 8u, cudaMemcpyHostToDevice));
        HB_CUDA(cudaMemcpy(d->d_w, w, (size_t)nw * sizeof(T), cudaMemcpyHostToDevice));
    }
    if (dyn_world_load<T>(c, rest, err, errlen)) return -1;
    if (c->variant == V_WARP) {
        const size_t smem = hbd::warp_smem_bytes<T>(c->P) * (size_t)(c->block / 32);
        HB_CUDA_AS(hbd::prepare_warp<T>(d->m64.features, smem), "raising the warp kernel's shared-memory limit");
    }
    if (c->variant == V_LANES) {
        HB_CUDA_AS(hbd::prepare_lanes<T>(d->m64.features, d->m64.solver, c->P, c->block, c->scene.dyn.per_segment != 0,
                                         d->hw.on != 0),
                   "raising the lanes kernel's shared-memory limit");
        bool wave = false;
        HB_CUDA_AS(hbd::lanes_wave<T>(dyn_model<T>(d), c->N, c->block, &wave), "choosing the lanes kernel's layout");
        dyn_model<T>(d).wave = wave;
        HB_CUDA_AS(hbd::lanes_layout<T>(dyn_model<T>(d), c->block, c->layout), "the lanes kernel's layout");
    }
    if (c->variant == V_LANES && d->hw.on && dyn_model<T>(d).world.planes) {
        /* §3.17 --contact-planes: a frame in several launches (the grid built every substep, or more
         * substeps than the staged colliders fit) keeps each point's planes between them */
        int launches = 1;
        HB_CUDA_AS(hbd::lanes_launches<T>(dyn_model<T>(d), c->block, &launches),
                   "planning the lanes kernel's launches");
        if (launches > 1 || (c->scene.dyn.grid && c->scene.dyn.grid_rebuild == HB_GRID_SUBSTEP)) {
            const uint64_t n = hb_mul_sat(hb_mul_sat((uint64_t)c->N, (uint64_t)c->P), HB_CONTACT_POINT * sizeof(T));
            int rc;
            if ((rc = device_alloc(&d->contacts, n, c, "the contact planes", err, errlen))) return rc;
            dyn_model<T>(d).contacts = (T *)d->contacts;
        }
    }
    HB_CUDA_AS(cudaDeviceSynchronize(), "dyn_load (cudaDeviceSynchronize)");
    return 0;
}

int cuda_dyn_load(hb_backend *b, const void *velocity, const void *rest, char *err, size_t errlen)
{
    cuda_impl *c = (cuda_impl *)b->impl;
    if (!c->dyn) {
        snprintf(err, errlen, "internal error: simulate was not set up");
        return -1;
    }
    const int rc = c->scene.precision == HB_FP32 ? dyn_load_t<float>(c, velocity, rest, err, errlen)
                                                 : dyn_load_t<double>(c, velocity, rest, err, errlen);
    memcpy(b->layout, c->layout, sizeof b->layout);
    return rc;
}

/* One frame's kernel on `stream`, with the frame's tables q [S][9] and ph [S] on the device;
 * in a guided run (§3.14) only the guides, then the followers' placement kernel. */
template <typename T>
static cudaError_t dyn_launch(cuda_impl *c, const hbd::DModel<T> &m, const void *q, const void *ph, cudaStream_t stream)
{
    DynState *d = c->dyn;
    const int64_t *map = d->guided ? d->d_guide : nullptr;
    const int64_t n_run = d->guided ? d->fl.n_guides : c->N;
    const T *rest = (const T *)(d->shape_rest ? d->shape_rest : d->rest); /* root and shape targets */
    cudaError_t e;
    if (c->variant == V_STRAND)
        e = hbd::launch_frame_strand<T>(m, (const T *)q, (const T *)ph, (T *)c->state, (T *)d->vel, rest,
                                        (const T *)d->bend_rest, (T *)d->scratch, c->N, d->grid, c->block, stream, map,
                                        n_run);
    else if (c->variant == V_LANES)
        e = hbd::launch_frame_lanes<T>(m, (const T *)q, (const T *)ph, (T *)c->state, (T *)d->vel, rest,
                                       (const T *)d->bend_rest, c->N, c->block, stream);
    else if (c->variant == V_WARPREG)
        e = hbd::launch_frame_warpreg<T>(m, (const T *)q, (const T *)ph, (T *)c->state, (T *)d->vel, rest,
                                         (const T *)d->bend_rest, c->N, d->grid, c->block, stream, map, n_run);
    else
        e = hbd::launch_frame_warp<T>(m, (const T *)q, (const T *)ph, (T *)c->state, (T *)d->vel, rest,
                                      (const T *)d->bend_rest, c->N, d->grid, c->block, stream, map, n_run);
    if (e != cudaSuccess || !d->guided) return e;
    const T *qe = c->scene.dyn.motion != HB_MOTION_STILL ? (const T *)q + 9 * (d->S - 1) : nullptr;
    return hbd::launch_place_followers<T>(m, qe, (T *)c->state, (T *)d->vel, (const T *)d->rest, dyn_layout(c),
                                          d->d_follower, d->d_src, (const T *)d->d_w, d->fl.width, d->fl.n_followers,
                                          stream);
}

/* §3.16 the grid built from the current state with the rotation qg (device; nullptr: still). */
template <typename T>
static cudaError_t dyn_grid_build(cuda_impl *c, const hbd::DModel<T> &m, const T *qg, cudaStream_t st)
{
    DynState *d = c->dyn;
    const hb_host_world *hw = &d->hw;
    const int64_t nodes = hw->nodes;
    int64_t *mass = d->g_mass + 4 * nodes * d->g_cur, *clear = d->g_mass + 4 * nodes * (1 - d->g_cur);
    cudaError_t e = hbd::launch_grid_splat<T>(m.world, qg, (const T *)c->state, (const T *)d->vel, c->N, c->P, m.perm,
                                              mass, mass + nodes, st);
    if (e != cudaSuccess) return e;
    e = hbd::launch_grid_nodes<T>(m.world, qg, mass, mass + nodes, clear, (const T *)d->g_target, (T)hw->inv_rho0,
                                  (T)hw->neg_kv, (T *)d->g_node_v, (T *)d->g_node_a, st);
    d->g_cur = 1 - d->g_cur;
    if (e != cudaSuccess || !d->g_held) return e;
    return hbd::launch_grid_hold<T>(m.world, qg, m.h, (const T *)c->state, c->N, c->P, m.perm, (T *)d->g_held, st);
}

/* A frame: without the grid its one kernel; with it the grid's build first, once (`frame`), or
 * before each substep's launch (`substep`, docs/model.md §3.16). */
template <typename T> static cudaError_t dyn_frame_launches(cuda_impl *c, const hbd::DModel<T> &m, cudaStream_t st)
{
    DynState *d = c->dyn;
    if (!c->scene.dyn.grid) return dyn_launch<T>(c, m, d->q, d->ph, st);
    const int still = c->scene.dyn.motion == HB_MOTION_STILL;
    const int64_t S = d->S, step = c->scene.dyn.grid_rebuild == HB_GRID_SUBSTEP ? 1 : S;
    for (int64_t j0 = 0; j0 < S; j0 += step) {
        const T *qg = still ? nullptr : j0 == 0 ? (const T *)d->f_qs : (const T *)d->q + 9 * (j0 - 1);
        cudaError_t e = dyn_grid_build<T>(c, m, qg, st);
        if (e != cudaSuccess) return e;
        hbd::DModel<T> ms = m;
        ms.j0 = (int)j0;
        ms.j1 = (int)(j0 + step);
        if ((e = dyn_launch<T>(c, ms, d->q, d->ph, st)) != cudaSuccess) return e;
    }
    return cudaSuccess;
}

cudaError_t dyn_launch_tables(cuda_impl *c, const void *q, const void *ph, cudaStream_t stream)
{
    return c->scene.precision == HB_FP32 ? dyn_launch<float>(c, c->dyn->m32, q, ph, stream)
                                         : dyn_launch<double>(c, c->dyn->m64, q, ph, stream);
}

void dyn_position_strides(const cuda_impl *c, int64_t s[3])
{
    const hbd::Layout l = dyn_layout(c);
    s[0] = l.is, s[1] = l.ks, s[2] = l.cs;
}

static const char *dyn_launch_name(const cuda_impl *c)
{
    return c->variant == V_STRAND    ? "the simulate kernel launch (strand)"
           : c->variant == V_WARPREG ? "the simulate kernel launch (warpreg)"
           : c->variant == V_LANES   ? "the simulate kernel launch (lanes)"
                                     : "the simulate kernel launch (warp)";
}

int cuda_dyn_frame(hb_backend *b, const hb_dyn_frame *f, hb_stage_result *r, char *err, size_t errlen)
{
    cuda_impl *c = (cuda_impl *)b->impl;
    DynState *d = c->dyn;
    const int fp32 = c->scene.precision == HB_FP32;
    const size_t rs = fp32 ? sizeof(float) : sizeof(double);
    if (f->substeps != d->S) {
        snprintf(err, errlen, "internal error: a frame of %lld substeps for a run of %lld", (long long)f->substeps,
                 (long long)d->S);
        return -1;
    }
    /* the frame's tables: enqueued before the start event, so not in r->ms */
    HB_CUDA(cudaMemcpyAsync(d->q, fp32 ? (const void *)f->q32 : (const void *)f->q64, (size_t)d->S * 9u * rs,
                            cudaMemcpyHostToDevice, 0));
    HB_CUDA(cudaMemcpyAsync(d->ph, fp32 ? (const void *)f->phase32 : (const void *)f->phase64, (size_t)d->S * rs,
                            cudaMemcpyHostToDevice, 0));
    if (d->f_pose) { /* §3.17 the colliders' poses and back-transforms, with the frame's tables */
        HB_CUDA(cudaMemcpyAsync(d->f_pose, fp32 ? (const void *)f->pose32 : (const void *)f->pose64,
                                (size_t)d->pose_bytes, cudaMemcpyHostToDevice, 0));
        HB_CUDA(cudaMemcpyAsync(d->f_back, fp32 ? (const void *)f->back32 : (const void *)f->back64,
                                (size_t)d->back_bytes, cudaMemcpyHostToDevice, 0));
        const size_t last = (size_t)(d->S - 1) * (size_t)(f->ncol > 0 ? f->ncol : 1) * HB_COL_POSE;
        if (fp32) d->obs.pose32 = (const float *)d->f_pose + last;
        else d->obs.pose64 = (const double *)d->f_pose + last;
    }
    if (d->f_qs)
        HB_CUDA(cudaMemcpyAsync(d->f_qs, fp32 ? (const void *)f->qs32 : (const void *)f->qs64, 9u * rs,
                                cudaMemcpyHostToDevice, 0));
    HB_CUDA_AS(hold_stream(0), "the hold kernel launch");
    HB_CUDA(cudaEventRecord(c->ev0, 0));
    const cudaError_t e = fp32 ? dyn_frame_launches<float>(c, d->m32, 0) : dyn_frame_launches<double>(c, d->m64, 0);
    HB_CUDA_AS(e, dyn_launch_name(c));
    HB_CUDA(cudaEventRecord(c->ev1, 0));
    HB_CUDA_AS(cudaEventSynchronize(c->ev1), "the simulate kernel (cudaEventSynchronize)");
    float ms = 0.0f;
    HB_CUDA(cudaEventElapsedTime(&ms, c->ev0, c->ev1));
    r->ms = (double)ms;
    r->moved_points = -1;
    r->consumed = 1;
    return 0;
}

int cuda_dyn_observe(hb_backend *b, hb_observables *obs, char *err, size_t errlen)
{
    cuda_impl *c = (cuda_impl *)b->impl;
    DynState *d = c->dyn;
    if (c->scene.precision == HB_FP32)
        HB_CUDA_AS(hbd::launch_observe<float>(d->obs, (const float *)c->state, (const float *)d->vel, dyn_layout(c),
                                              c->N, d->d_obs, 0),
                   "the observables kernel launch");
    else
        HB_CUDA_AS(hbd::launch_observe<double>(d->obs, (const double *)c->state, (const double *)d->vel, dyn_layout(c),
                                               c->N, d->d_obs, 0),
                   "the observables kernel launch");
    HB_CUDA(cudaMemcpy(d->h_obs, d->d_obs, (size_t)d->nchunks * sizeof *d->h_obs, cudaMemcpyDeviceToHost));
    for (int64_t i = 0; i < d->nchunks; i++) {
        d->h_part[i].stretch_max = d->h_obs[i].stretch_max;
        d->h_part[i].penetration_max = d->h_obs[i].penetration_max;
        d->h_part[i].v2_sum = d->h_obs[i].v2_sum;
        d->h_part[i].blown = (int64_t)d->h_obs[i].blown;
    }
    hb_dyn_reduce(d->h_part, d->nchunks, c->P, c->N, obs); /* chunks in index order */
    return 0;
}

int cuda_dyn_fetch_velocity(hb_backend *b, void *canonical, char *err, size_t errlen)
{
    cuda_impl *c = (cuda_impl *)b->impl;
    DynState *d = c->dyn;
    if (dyn_is_warp(c)) {
        HB_CUDA(cudaMemcpy(canonical, d->vel, (size_t)c->bytes, cudaMemcpyDeviceToHost));
        return 0;
    }
    c->inter_valid = 0;
    if (c->scene.precision == HB_FP32)
        HB_CUDA_AS(hb::launch_to_canonical<float>(point_major<float>(c, d->vel), (float *)c->staging, c->N, c->P, 0),
                   "the point-major-to-canonical kernel launch (velocities)");
    else
        HB_CUDA_AS(hb::launch_to_canonical<double>(point_major<double>(c, d->vel), (double *)c->staging, c->N, c->P, 0),
                   "the point-major-to-canonical kernel launch (velocities)");
    HB_CUDA(cudaMemcpy(canonical, c->staging, (size_t)c->bytes, cudaMemcpyDeviceToHost));
    return 0;
}

/* --render-points (docs/model.md §3.14): the rendered points of the current state by
 * cuda/dynamic/lod.cu's kernel, timed by events around its launch; then copied to the host. */
int cuda_dyn_render(hb_backend *b, void *position, void *velocity, double *ms, char *err, size_t errlen)
{
    cuda_impl *c = (cuda_impl *)b->impl;
    DynState *d = c->dyn;
    if (!d || !d->d_render) {
        snprintf(err, errlen, "internal error: --render-points without its device buffers");
        return -1;
    }
    const int64_t pr = c->scene.dyn.render_points;
    cudaError_t e;
    HB_CUDA(cudaEventRecord(c->ev0, 0));
    if (c->scene.precision == HB_FP32)
        e = hbd::launch_lod_render<float>((const float *)c->state, velocity ? (const float *)d->vel : nullptr,
                                          dyn_layout(c), c->N, c->P, pr, (float *)d->d_render, (float *)d->d_vrender,
                                          0);
    else
        e = hbd::launch_lod_render<double>((const double *)c->state, velocity ? (const double *)d->vel : nullptr,
                                           dyn_layout(c), c->N, c->P, pr, (double *)d->d_render, (double *)d->d_vrender,
                                           0);
    HB_CUDA_AS(e, "the rendering kernel launch (--render-points)");
    HB_CUDA(cudaEventRecord(c->ev1, 0));
    HB_CUDA_AS(cudaEventSynchronize(c->ev1), "the rendering kernel (cudaEventSynchronize)");
    float f = 0.0f;
    HB_CUDA(cudaEventElapsedTime(&f, c->ev0, c->ev1));
    *ms = f;
    HB_CUDA(cudaMemcpy(position, d->d_render, (size_t)d->render_bytes, cudaMemcpyDeviceToHost));
    if (velocity) HB_CUDA(cudaMemcpy(velocity, d->d_vrender, (size_t)d->render_bytes, cudaMemcpyDeviceToHost));
    return 0;
}

/* ---- --frame-loop: frames back to back, as an application runs them ---------------------- */
struct LoopRes {
    void *hq = nullptr, *hp = nullptr, *dq = nullptr, *dp = nullptr;
    cudaStream_t st = nullptr;
    cudaGraph_t g = nullptr;
    cudaGraphExec_t ge = nullptr;
    ~LoopRes()
    { /* errors ignored: after a fault the context may be unusable */
        if (ge) cudaGraphExecDestroy(ge);
        if (g) cudaGraphDestroy(g);
        if (st) cudaStreamDestroy(st);
        if (hq) cudaFreeHost(hq);
        if (hp) cudaFreeHost(hp);
        if (dq) cudaFree(dq);
        if (dp) cudaFree(dp);
    }
};

/* Enqueues n frames on r.st: each frame's tables from pinned host memory, then its kernel. */
static cudaError_t dyn_enqueue_loop(cuda_impl *c, LoopRes &r, int n, size_t tq, size_t tp)
{
    const int fp32 = c->scene.precision == HB_FP32;
    for (int i = 0; i < n; i++) {
        char *dq = (char *)r.dq + (size_t)i * tq, *dp = (char *)r.dp + (size_t)i * tp;
        cudaError_t e = cudaMemcpyAsync(dq, (char *)r.hq + (size_t)i * tq, tq, cudaMemcpyHostToDevice, r.st);
        if (e == cudaSuccess) e = cudaMemcpyAsync(dp, (char *)r.hp + (size_t)i * tp, tp, cudaMemcpyHostToDevice, r.st);
        if (e == cudaSuccess)
            e = fp32 ? dyn_launch<float>(c, c->dyn->m32, dq, dp, r.st)
                     : dyn_launch<double>(c, c->dyn->m64, dq, dp, r.st);
        if (e != cudaSuccess) return e;
    }
    return cudaSuccess;
}

int cuda_dyn_loop(hb_backend *b, const hb_dyn_frame *plans, int n, double *ms, double *graph_ms, char *err,
                  size_t errlen)
{
    cuda_impl *c = (cuda_impl *)b->impl;
    DynState *d = c->dyn;
    const int fp32 = c->scene.precision == HB_FP32;
    const size_t rs = fp32 ? sizeof(float) : sizeof(double);
    const size_t tq = (size_t)d->S * 9u * rs, tp = (size_t)d->S * rs;
    LoopRes r;
    HB_CUDA(cudaMallocHost(&r.hq, tq * (size_t)n));
    HB_CUDA(cudaMallocHost(&r.hp, tp * (size_t)n));
    HB_CUDA(cudaMalloc(&r.dq, tq * (size_t)n));
    HB_CUDA(cudaMalloc(&r.dp, tp * (size_t)n));
    for (int i = 0; i < n; i++) {
        memcpy((char *)r.hq + (size_t)i * tq, fp32 ? (const void *)plans[i].q32 : (const void *)plans[i].q64, tq);
        memcpy((char *)r.hp + (size_t)i * tp, fp32 ? (const void *)plans[i].phase32 : (const void *)plans[i].phase64,
               tp);
    }
    HB_CUDA(cudaStreamCreateWithFlags(&r.st, cudaStreamNonBlocking));
    HB_CUDA(cudaDeviceSynchronize());
    /* launched one by one: a warm-up pass, then the timed one */
    for (int pass = 0; pass < 2; pass++) {
        const double t0 = hb_now_ms();
        HB_CUDA_AS(dyn_enqueue_loop(c, r, n, tq, tp), dyn_launch_name(c));
        HB_CUDA_AS(cudaStreamSynchronize(r.st), "the frame loop (cudaStreamSynchronize)");
        *ms = (hb_now_ms() - t0) / (double)n;
    }
    /* the same n frames captured once as a graph: a warm-up replay, then the timed one */
    HB_CUDA(cudaStreamBeginCapture(r.st, cudaStreamCaptureModeThreadLocal));
    const cudaError_t ce = dyn_enqueue_loop(c, r, n, tq, tp);
    const cudaError_t ee = cudaStreamEndCapture(r.st, &r.g);
    HB_CUDA_AS(ce, "capturing the frame loop");
    HB_CUDA_AS(ee, "cudaStreamEndCapture (the frame loop)");
    HB_CUDA(cudaGraphInstantiate(&r.ge, r.g, 0));
    HB_CUDA(cudaGraphUpload(r.ge, r.st));
    for (int pass = 0; pass < 2; pass++) {
        const double t0 = hb_now_ms();
        HB_CUDA(cudaGraphLaunch(r.ge, r.st));
        HB_CUDA_AS(cudaStreamSynchronize(r.st), "the frame loop's graph (cudaStreamSynchronize)");
        *graph_ms = (hb_now_ms() - t0) / (double)n;
    }
    return 0;
}

} // namespace hb_cuda
