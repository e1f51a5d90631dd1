/* host.h — small host-side helpers every backend and the driver share. */
#ifndef HB_HOST_H
#define HB_HOST_H

#include <stddef.h>
#include <stdint.h>

#include "model.h"
#include "params.h"

#ifdef __cplusplus
extern "C" {
#endif

/* Monotonic wall-clock time in milliseconds. */
double hb_now_ms(void);

/* The paper model's numbers rounded once to the working precision (docs/model.md §1.3):
 * derived values in double, then each rounded once to float. */
void hb_model_round(const hb_scene *s, hb_model_f32 *m32, hb_model_f64 *m64);

/* The one-line "does not fit" message: "the state needs X GB of <kind> memory (N strands x
 * P points, fp32<detail>) but only Y GB is <available | free on DEVICE>". */
void hb_memory_message(char *err, size_t errlen, const hb_scene *s, const char *kind, uint64_t need, uint64_t avail,
                       const char *detail, const char *device);

#ifdef __cplusplus
}
#endif
#endif
