/* hair_fuzz.c — libFuzzer target for the HAIR groom reader (c_ref/runtime/groom.c): each input
 * is written to a file and read as `--groom FILE` would read it, with and without a given head
 * centre, at a few point counts and both precisions. Built and run by `make fuzz` under ASan and
 * UBSan (clang -fsanitize=fuzzer,address,undefined); the seed corpus is tests/fuzz/corpus/hair/. */
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "runtime/cli.h"
#include "runtime/groom.h"

/* runtime/host.c's, which the fuzzer does not link: a machine of 1 GiB, so a huge groom is refused */
uint64_t hb_host_memory_available(void)
{
    return 1ull << 30;
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    static char path[64];
    if (!path[0]) snprintf(path, sizeof path, "/tmp/hair_fuzz-%ld.hair", (long)getpid());
    FILE *f = fopen(path, "wb");
    if (!f) return 0;
    fwrite(data, 1, size, f);
    fclose(f);
    static const int64_t points[] = {2, 5, 32};
    for (int k = 0; k < 6; k++) {
        hb_options o;
        hb_default_options(&o);
        o.groom = path;
        o.scene.groom = HB_GROOM_FILE;
        o.scene.points = points[k % 3];
        o.scene.precision = k % 2 ? HB_FP64 : HB_FP32;
        if (k >= 3) o.given |= HB_GIVEN_CENTER; /* the head at the origin, nothing fitted */
        hb_groom g;
        char err[512];
        if (hb_groom_prepare(&o, &g, err, sizeof err) == 0) {
            void *state = malloc(hb_state_bytes(&o.scene));
            if (state) hb_groom_state(&o.scene, &g, state);
            free(state);
        }
        hb_groom_free(&g);
    }
    return 0;
}
