/* params.c — scene validation (docs/model.md §2.6: bad scenes are refused before any work, with a
 * message naming the flag). */
#include "runtime/params.h"
#include "runtime/cli.h"
#include "runtime/checked.h"

#include <float.h>
#include <math.h>
#include <stdio.h>
#include <string.h>

const char *hb_stage_name(hb_stage s)
{
    switch (s) {
    case HB_STAGE_INIT: return "init";
    case HB_STAGE_WIND: return "wind";
    case HB_STAGE_COLLIDE: return "collide";
    case HB_STAGE_SIMULATE: return "simulate";
    }
    return "?";
}

const char *hb_precision_name(hb_precision p)
{
    return p == HB_FP64 ? "fp64" : "fp32";
}

uint64_t hb_state_bytes(const hb_scene *s)
{
    if (s->n_strands <= 0 || s->points <= 0) return 0;
    uint64_t rows, bytes;
    if (hb_mul_u64((uint64_t)s->n_strands, (uint64_t)s->points, &rows) ||
        hb_mul3_u64(rows, 3u, hb_real_size(s->precision), &bytes))
        return 0;
    return bytes;
}

double hb_wind_angle_reduced(const hb_scene *s)
{
    double a = remainder(s->wind_angle, 2.0 * M_PI); /* [−π, π] */
    if (a <= -M_PI) a += 2.0 * M_PI;
    return a;
}

#define FAIL(...)                                                                                                      \
    do {                                                                                                               \
        snprintf(err, errlen, __VA_ARGS__);                                                                            \
        return -1;                                                                                                     \
    } while (0)

/* The lengths a precision can square without underflow or overflow (docs/decisions/paper-model.md,
 * "Representable scenes"). */
double hb_length_min(hb_precision p)
{
    return p == HB_FP32 ? 1e-18 : 1e-150;
}

double hb_length_max(hb_precision p)
{
    return p == HB_FP32 ? 1e18 : 1e150;
}

static int finite_positive(double v)
{
    return isfinite(v) && v > 0.0;
}

int hb_scene_validate(const hb_scene *s, char *err, size_t errlen)
{
    if (s->n_strands < 1) FAIL("--strands must be at least 1 (got %lld)", (long long)s->n_strands);
    if (s->points < 2) FAIL("--points must be at least 2 (got %lld)", (long long)s->points);
    if (!finite_positive(s->head_radius)) FAIL("--head-radius must be a finite number > 0 (got %g)", s->head_radius);
    if (!finite_positive(s->hair_offset)) FAIL("--hair-offset must be a finite number > 0 (got %g)", s->hair_offset);
    if (!finite_positive(s->hair_length)) FAIL("--hair-length must be a finite number > 0 (got %g)", s->hair_length);
    if (!isfinite(s->face_margin) || s->face_margin < 0.0)
        FAIL("--face-margin must be a finite number >= 0 (got %g)", s->face_margin);
    if (!isfinite(s->wind_strength) || s->wind_strength < 0.0 || s->wind_strength > 1.0)
        FAIL("--wind-strength must be in [0, 1] (got %g)", s->wind_strength);
    if (!isfinite(s->wind_angle)) FAIL("--wind-angle must be a finite number of radians (got %g)", s->wind_angle);
    double ell = hb_segment_length(s);
    /* ℓ = L/(P−1) computed in double may round just below h when the user asked for ℓ = h
     * exactly; a relative allowance of 1e-12 keeps that edge usable. A groom runs no collide
     * stage (init and simulate only), so the rule is the drape's. */
    if (s->groom == HB_GROOM_DRAPE && !s->dyn.per_segment && !(ell >= s->hair_offset * (1.0 - 1e-12)))
        FAIL("--hair-length/(--points - 1) = %g is shorter than --hair-offset %g: a segment could not reach the "
             "shell (docs/model.md §2.5: collide needs l >= h)",
             ell, s->hair_offset);
    /* Every length must square without leaving the precision's normal range, or the
     * model's r², ℓ² and ρ·rc underflow to denormals or zero (docs/decisions/paper-model.md,
     * "fp32_near_denormal_range"). */
    const double lo = hb_length_min(s->precision), hi = hb_length_max(s->precision);
    const struct {
        const char *flag;
        double v;
    } len[] = {
        {"--head-radius", s->head_radius},     {"--hair-offset", s->hair_offset}, {"--hair-length", s->hair_length},
        {"--hair-length/(--points - 1)", ell}, {"--face-margin", s->face_margin},
    };
    for (size_t i = 0; i < sizeof len / sizeof len[0]; i++) {
        if (len[i].v == 0.0 && strcmp(len[i].flag, "--face-margin") == 0) continue;
        if (len[i].v < lo || len[i].v > hi)
            FAIL("%s = %g is outside the lengths %s can square without underflow or overflow [%g, %g]%s", len[i].flag,
                 len[i].v, hb_precision_name(s->precision), lo, hi,
                 s->precision == HB_FP32 ? " (use --precision fp64)" : "");
    }
    if (hb_state_bytes(s) == 0) FAIL("--strands x --points is too large to address");
    return 0;
}

/* ---- the dynamic model (docs/model.md §3) ----------------------------------------------- */

const char *hb_solver_name(hb_solver s)
{
    return s == HB_SOLVER_FTL ? "ftl" : s == HB_SOLVER_RIGID ? "rigid" : "xpbd";
}

const char *hb_follow_name(hb_follow f)
{
    return f == HB_FOLLOW_ONE ? "one" : "blend3";
}

const char *hb_motion_name(hb_motion m)
{
    switch (m) {
    case HB_MOTION_STILL: return "still";
    case HB_MOTION_NOD: return "nod";
    case HB_MOTION_SHAKE: return "shake";
    case HB_MOTION_TILT: return "tilt";
    case HB_MOTION_TRACK: return "track";
    }
    return "?";
}

/* Defaults (docs/decisions/dynamic-model.md, "Dynamic defaults"): what a flag left out means. */
void hb_dynamics_defaults(hb_dynamics *d)
{
    memset(d, 0, sizeof *d);
    d->frame_dt = 1.0 / 60.0;
    d->substeps = 1;
    d->iterations = 1;
    d->solver = HB_SOLVER_XPBD;
    d->gravity = 981.0;
    d->shape_range = 1.0;
    d->ftl_damping = 0.9;
    d->collider = 1;
    d->gust_frequency = 1.0;
    d->gust_wavelength = 100.0;
    d->motion_amplitude = 0.25;
    d->motion_frequency = 1.0;
    d->follow = HB_FOLLOW_BLEND3;
    d->lra_scale = 1.0;
    d->grid_n = 32;
    d->grid_padding = 2.0;
    d->body_amplitude = 2.0;
    d->body_frequency = 1.0;
    d->collider_sweeps = 1;
}

int hb_dynamics_validate(const hb_dynamics *d, char *err, size_t errlen)
{
    const struct {
        const char *flag;
        double v;
        int positive;
    } nonneg[] = {
        {"--frame-dt", d->frame_dt, 1},
        {"--gravity", d->gravity, 0},
        {"--drag", d->drag, 0},
        {"--damping", d->damping, 0},
        {"--stretch-compliance", d->stretch_compliance, 0},
        {"--bend-compliance", d->bend_compliance, 0},
        {"--shape-compliance", d->shape_compliance, 0},
        {"--collision-margin", d->collision_margin, 0},
        {"--wind-speed", d->wind_speed, 0},
        {"--gust-amplitude", d->gust_amplitude, 0},
        {"--gust-frequency", d->gust_frequency, 0},
        {"--gust-wavelength", d->gust_wavelength, 1},
        {"--motion-amplitude", d->motion_amplitude, 0},
        {"--motion-frequency", d->motion_frequency, 0},
        {"--grid-padding", d->grid_padding, 0},
        {"--grid-volume", d->grid_volume, 0},
        {"--depenetration-speed", d->depen_speed, 0},
        {"--contact-planes", d->contact_margin, 0},
        {"--body-amplitude", d->body_amplitude, 0},
        {"--body-frequency", d->body_frequency, 0},
    };
    for (size_t i = 0; i < sizeof nonneg / sizeof nonneg[0]; i++) {
        double v = nonneg[i].v;
        if (!isfinite(v) || v < 0.0 || (nonneg[i].positive && v == 0.0))
            FAIL("%s must be a finite number %s 0 (got %g)", nonneg[i].flag, nonneg[i].positive ? ">" : ">=", v);
    }
    if (d->substeps < 1) FAIL("--substeps must be at least 1 (got %lld)", (long long)d->substeps);
    if (d->iterations < 1) FAIL("--iterations must be at least 1 (got %lld)", (long long)d->iterations);
    if (d->substeps > HB_COUNT_MAX)
        FAIL("--substeps must be at most %d (got %lld)", HB_COUNT_MAX, (long long)d->substeps);
    if (d->iterations > HB_COUNT_MAX)
        FAIL("--iterations must be at most %d (got %lld)", HB_COUNT_MAX, (long long)d->iterations);
    if (!(d->shape_range > 0.0 && d->shape_range <= 1.0))
        FAIL("--shape-range must be in (0, 1] (got %g)", d->shape_range);
    if (!(d->ftl_damping >= 0.0 && d->ftl_damping <= 1.0))
        FAIL("--ftl-damping must be in [0, 1] (got %g)", d->ftl_damping);
    if (d->guided && !(isfinite(d->guides) && d->guides > 0.0 && (d->guides <= 1.0 || d->guides == floor(d->guides))))
        FAIL("--guides must be a fraction in (0, 1] or a whole count > 1 (got %g)", d->guides);
    if (d->lra && !(isfinite(d->lra_scale) && d->lra_scale >= 1.0))
        FAIL("--lra scale must be a finite number >= 1 (got %g)", d->lra_scale);
    if (d->grid && (d->grid_n < HB_GRID_N_MIN || d->grid_n > HB_GRID_N_MAX))
        FAIL("--grid must be from %d to %d nodes per axis (got %lld)", HB_GRID_N_MIN, HB_GRID_N_MAX,
             (long long)d->grid_n);
    if (d->grid_box_given)
        for (int c = 0; c < 3; c++)
            if (!(d->grid_box[c] < d->grid_box[c + 3]))
                FAIL("--grid-box needs X0 < X1, Y0 < Y1 and Z0 < Z1 (got %g >= %g on axis %c)", d->grid_box[c],
                     d->grid_box[c + 3], "xyz"[c]);
    for (int c = 0; c < 2; c++)
        if (!(d->grid_friction[c] >= 0.0 && d->grid_friction[c] <= 1.0))
            FAIL("--grid-friction must be in [0, 1] (got %g)", d->grid_friction[c]);
    if (!(d->friction[0] >= 0.0 && d->friction[1] >= 0.0 && d->friction[1] <= d->friction[0] &&
          isfinite(d->friction[0])))
        FAIL("--friction needs 0 <= MU_K <= MU_S, finite (got %g,%g)", d->friction[0], d->friction[1]);
    if (d->depen_declared && !(d->depen_speed > 0.0))
        FAIL("--depenetration-speed must be > 0 (got %g)", d->depen_speed);
    if (d->planes_declared && !(d->contact_margin > 0.0))
        FAIL("--contact-planes must be > 0 (got %g)", d->contact_margin);
    if (d->planes_declared && !d->colliders_path)
        FAIL("--contact-planes needs --colliders (the planes are the file's colliders)");
    if (d->collide_once && d->solver != HB_SOLVER_XPBD)
        FAIL("--collide-once needs --solver xpbd (ftl meets the colliders once a substep already, in its follow-the-"
             "leader pass)");
    if (d->collider_sweeps < 1 || d->collider_sweeps > HB_COLLIDER_SWEEPS_MAX)
        FAIL("--collider-sweeps must be from 1 to %d (got %lld)", HB_COLLIDER_SWEEPS_MAX,
             (long long)d->collider_sweeps);
    /* h = Δt/S and α/h² must stay normal numbers in double */
    const double h = d->frame_dt / (double)d->substeps;
    if (!(h >= HB_SUBSTEP_MIN_S && h <= HB_SUBSTEP_MAX_S))
        FAIL("--frame-dt / --substeps = %g s is outside the substep lengths this model takes [%g, %g]", h,
             HB_SUBSTEP_MIN_S, HB_SUBSTEP_MAX_S);
    return 0;
}

/* The dynamic model's derived constants (docs/model.md §3.4), computed in double and
 * rounded once to the working precision, must be finite there, and the lengths it squares
 * must stay in the precision's range; else the first substep makes NaN (docs/decisions/testing.md,
 * "dynamic_constant_overflow"). Only the constants a run evaluates are checked. */
static int fits(double v, hb_precision p)
{
    return p == HB_FP32 ? isfinite((float)v) : isfinite(v);
}

int hb_dynamics_validate_time(const hb_scene *s, double t_end, char *err, size_t errlen)
{
    const hb_dynamics *d = &s->dyn;
    const int gust = d->wind_speed > 0.0 && d->drag > 0.0 && d->gust_amplitude > 0.0;
    const double w = 2.0 * M_PI * d->motion_frequency; /* evaluated as (2πf)·t */
    if (d->motion != HB_MOTION_STILL && !(isfinite(w) && isfinite(w * t_end)))
        FAIL("2 pi x --motion-frequency x t = %g at t = %g s overflows fp64 (largest %g)", w * t_end, t_end, DBL_MAX);
    if (gust && !isfinite(d->gust_frequency * t_end))
        FAIL("--gust-frequency x t = %g at t = %g s overflows fp64 (largest %g)", d->gust_frequency * t_end, t_end,
             DBL_MAX);
    return 0;
}

int hb_dynamics_validate_scene(const hb_scene *s, char *err, size_t errlen)
{
    const hb_dynamics *d = &s->dyn;
    const hb_precision p = s->precision;
    const char *name = hb_precision_name(p);
    const char *hint = p == HB_FP32 ? " (use --precision fp64)" : "";
    const double h = d->frame_dt / (double)d->substeps;
    const int wind = d->wind_speed > 0.0 && d->drag > 0.0, gust = wind && d->gust_amplitude > 0.0;
    const int bend = d->bend && s->points >= 3; /* P = 2 has no bend constraint */
    const int shape = d->shape && floor(d->shape_range * (double)(s->points - 1)) >= 1.0; /* K ≥ 1 */
    const double hi = hb_length_max(p);
    const double rc = s->head_radius + d->collision_margin;
    if (d->grid && (uint64_t)s->n_strands * (uint64_t)s->points > HB_GRID_POINTS_MAX)
        FAIL("--grid: --strands x --points must be at most 2^31 points, the bound that keeps the grid's fixed-point "
             "sums from overflowing (docs/model.md §3.16)");
    /* the largest acceleration of the velocity step, c_d·U·(1 + A_g) for the wind's share */
    const double wind_a = wind ? d->drag * d->wind_speed * (1.0 + (gust ? d->gust_amplitude : 0.0)) : 0.0;
    const struct {
        const char *what;
        double v;
        int used;
    } c[] = {
        {"--gravity", d->gravity, 1},
        {"--stretch-compliance / h^2 (h = --frame-dt / --substeps)", d->stretch_compliance / (h * h),
         d->solver == HB_SOLVER_XPBD},
        {"--bend-compliance / h^2 (h = --frame-dt / --substeps)", d->bend_compliance / (h * h), bend},
        {"--shape-compliance / h^2 (h = --frame-dt / --substeps)", d->shape_compliance / (h * h), shape},
        {"--drag x --wind-speed x (1 + --gust-amplitude)", wind_a, wind},
        {"h (--gravity + --drag x --wind-speed x (1 + --gust-amplitude))", h * (d->gravity + wind_a), 1},
        /* the gust's phase at a point as far out as a strand that has not blown up reaches */
        {"2 pi / --gust-wavelength x (--head-radius + --collision-margin + 2 --hair-length)",
         2.0 * M_PI / d->gust_wavelength * (rc + 2.0 * s->hair_length), gust},
    }; /* 1 + h·(c_d + β) may be Inf: v/Inf = 0 is the limit of infinite drag */
    for (size_t i = 0; i < sizeof c / sizeof c[0]; i++)
        if (c[i].used && !fits(c[i].v, p))
            FAIL("%s = %g overflows %s (largest %g)%s", c[i].what, c[i].v, name, p == HB_FP32 ? FLT_MAX : DBL_MAX,
                 hint);
    if (d->render_points) { /* §3.14: simulated-point LOD */
        const int64_t ps = s->points, pr = d->render_points;
        uint64_t rows;
        if (pr <= ps || (pr - 1) % (ps - 1) != 0)
            FAIL("--render-points %lld must exceed --points %lld with %lld - 1 a multiple of %lld - 1 (e.g. %lld)",
                 (long long)pr, (long long)ps, (long long)pr, (long long)ps, (long long)(2 * ps - 1));
        if (hb_mul_u64((uint64_t)s->n_strands, (uint64_t)pr, &rows) || hb_mul_u64(rows, 3u * 8u, &rows))
            FAIL("--strands x --render-points is too large to address");
    }
    if (d->guided && d->guides > 1.0 && d->guides > (double)s->n_strands)
        FAIL("--guides %g is more than the %lld strands", d->guides, (long long)s->n_strands);
    if (d->collider && !(rc <= hi))
        FAIL("--head-radius + --collision-margin = %g is beyond the lengths %s can square (at most %g)%s", rc, name, hi,
             hint);
    /* how far a point at rest moves in one substep: h·v after v = h·a/D */
    const double fall = h * h * (d->gravity + wind_a) / (d->drag_declared ? 1.0 + h * (d->drag + d->damping) : 1.0);
    if (!(fall <= hi))
        FAIL("one substep moves a point by h^2 (--gravity + --drag x --wind-speed x (1 + --gust-amplitude)) / "
             "(1 + h (--drag + --damping)) = %g, beyond the lengths %s can square (at most %g): more --substeps%s",
             fall, name, hi, p == HB_FP32 ? " or --precision fp64" : "");
    return 0;
}
