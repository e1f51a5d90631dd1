/* host.h — small host-side helpers every backend and the driver share. */
#ifndef HB_HOST_H
#define HB_HOST_H

#include <stddef.h>
#include <stdint.h>

#include "runtime/params.h"

#ifdef __cplusplus
extern "C" {
#endif

/* Monotonic wall-clock time in milliseconds. */
double hb_now_ms(void);

/* Bytes of host memory available for a new allocation (MemAvailable); 0 if unknown. */
uint64_t hb_host_memory_available(void);

/* The one-line "does not fit" message: "the state needs X GB of <kind> memory (N strands x
 * P points, fp32<detail>) but only Y GB is <available | free on DEVICE>". */
void hb_memory_message(char *err, size_t errlen, const hb_scene *s, const char *kind, uint64_t need, uint64_t avail,
                       const char *detail, const char *device);

#ifdef __cplusplus
}
#endif
#endif
