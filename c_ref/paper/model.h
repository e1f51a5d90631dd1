/* model.h — the paper model (docs/model.md §2) on one strand, in fp32 and fp64.
 *
 * A strand is P points of (x, y, z) at `s[3k + c]` (the canonical strand-major layout:
 * strand i starts at state + 3·P·i). Every function here is pure and touches one strand,
 * so the results cannot depend on thread count or strand order; backend_cpu.c loops over
 * strands. The math is written once, in model_impl.h (the stages) and points_impl.h (one
 * point's step, shared with the CUDA port's strict build), and instantiated for float and
 * double by model.c.
 */
#ifndef HB_MODEL_H
#define HB_MODEL_H

#include <stdint.h>

#include "runtime/params.h"

#ifdef __cplusplus
extern "C" {
#endif

/* The scene's numbers rounded once to the working precision (docs/model.md §1.3). */
typedef struct {
    uint64_t seed;
    int64_t points;
    float head_radius, hair_offset, face_margin, seg_len, wind_strength, wind_angle;
} hb_model_f32;

typedef struct {
    uint64_t seed;
    int64_t points;
    double head_radius, hair_offset, face_margin, seg_len, wind_strength, wind_angle;
} hb_model_f64;

/* Relative rounding allowance of the collide test: a point counts as inside the shell
 * only when its slice radius is below rc·(1 − HB_SHELL_ULPS·ε) (docs/model.md §2.5;
 * docs/decisions/testing.md). */
#define HB_SHELL_ULPS 16

/* The scene's numbers rounded once to the working precision (docs/model.md §1.3): derived
 * values in double, then each rounded once to float (model_host.c). */
void hb_model_round(const hb_scene *s, hb_model_f32 *m32, hb_model_f64 *m64);

/* init = place the root from the RNG, then drape; drape alone re-drapes from s[0..2]. */
void hb_init_strand_f32(const hb_model_f32 *m, uint64_t strand, float *s);
void hb_drape_strand_f32(const hb_model_f32 *m, float *s);
void hb_wind_strand_f32(const hb_model_f32 *m, float *s);
int64_t hb_collide_strand_f32(const hb_model_f32 *m, float *s);

void hb_init_strand_f64(const hb_model_f64 *m, uint64_t strand, double *s);
void hb_drape_strand_f64(const hb_model_f64 *m, double *s);
void hb_wind_strand_f64(const hb_model_f64 *m, double *s);
int64_t hb_collide_strand_f64(const hb_model_f64 *m, double *s);

#ifdef __cplusplus
}
#endif
#endif
