/* model_host.c — the paper model's numbers of a run, rounded once on the host (docs/model.md
 * §1.3); every backend starts from them. */
#include "paper/model.h"

void hb_model_round(const hb_scene *s, hb_model_f32 *m32, hb_model_f64 *m64)
{
    *m64 = (hb_model_f64){s->seed,          s->points,
                          s->head_radius,   s->hair_offset,
                          s->face_margin,   hb_segment_length(s),
                          s->wind_strength, hb_wind_angle_reduced(s)};
    *m32 = (hb_model_f32){s->seed,
                          s->points,
                          (float)m64->head_radius,
                          (float)m64->hair_offset,
                          (float)m64->face_margin,
                          (float)m64->seg_len,
                          (float)m64->wind_strength,
                          (float)m64->wind_angle};
}
