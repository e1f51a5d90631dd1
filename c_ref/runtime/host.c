/* host.c — small host-side helpers every backend and the driver share. */
#include "runtime/host.h"

#include <stdio.h>
#include <time.h>

double hb_now_ms(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return 1e3 * (double)ts.tv_sec + 1e-6 * (double)ts.tv_nsec;
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

uint64_t hb_host_memory_available(void)
{
    FILE *f = fopen("/proc/meminfo", "r");
    if (!f) return 0;
    char line[256];
    unsigned long long kb = 0;
    while (fgets(line, sizeof line, f))
        if (sscanf(line, "MemAvailable: %llu kB", &kb) == 1) break;
    fclose(f);
    return (uint64_t)kb * 1024u;
}
