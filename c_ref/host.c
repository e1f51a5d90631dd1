/* host.c — small host-side helpers every backend and the driver share. */
#include "host.h"

#include <stdio.h>
#include <time.h>

double hb_now_ms(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return 1e3 * (double)ts.tv_sec + 1e-6 * (double)ts.tv_nsec;
}

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

void hb_memory_message(char *err, size_t errlen, const hb_scene *s, const char *kind, uint64_t need, uint64_t avail,
                       const char *detail, const char *device)
{
    char where[300];
    if (device) snprintf(where, sizeof where, "free on %s", device);
    else snprintf(where, sizeof where, "available");
    snprintf(err, errlen,
             "the state needs %.2f GB of %s memory (%lld strands x %lld points, %s%s) but only %.2f GB is %s",
             1e-9 * (double)need, kind, (long long)s->n_strands, (long long)s->points, hb_precision_name(s->precision),
             detail ? detail : "", 1e-9 * (double)avail, where);
}
