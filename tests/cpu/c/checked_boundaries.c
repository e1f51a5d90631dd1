/* checked_boundaries.c — c_ref/runtime/checked.h at the edges of 64 bits; exits non-zero on a miss. */
#include <stdio.h>

#include "runtime/checked.h"

static int misses;
#define EXPECT(cond)                                                                                                   \
    do {                                                                                                               \
        if (!(cond)) {                                                                                                 \
            fprintf(stderr, "miss: %s (line %d)\n", #cond, __LINE__);                                                  \
            misses++;                                                                                                  \
        }                                                                                                              \
    } while (0)

int main(void)
{
    uint64_t r;
    const uint64_t max = UINT64_MAX, half = UINT64_C(1) << 32;
    EXPECT(hb_mul_u64(0, max, &r) == 0 && r == 0);
    EXPECT(hb_mul_u64(1, max, &r) == 0 && r == max);
    EXPECT(hb_mul_u64(half - 1, half + 1, &r) == 0 && r == max); /* 2^64 - 1 */
    EXPECT(hb_mul_u64(half, half, &r) == -1 && r == max);
    EXPECT(hb_mul_u64(max / 3, 3, &r) == 0 && r == max);
    EXPECT(hb_mul_u64(max / 3 + 1, 3, &r) == -1);
    EXPECT(hb_mul3_u64(UINT64_C(9007199254740989), 2048, 8, &r) == -1 && r == max);
    EXPECT(hb_mul3_u64(UINT64_C(1) << 20, UINT64_C(1) << 20, UINT64_C(1) << 23, &r) == 0 && r == UINT64_C(1) << 63);
    EXPECT(hb_mul3_u64(UINT64_C(1) << 20, UINT64_C(1) << 20, UINT64_C(1) << 24, &r) == -1);
    EXPECT(hb_add_u64(max - 1, 1, &r) == 0 && r == max);
    EXPECT(hb_add_u64(max, 1, &r) == -1 && r == max);
    EXPECT(hb_mul_sat(half, half) == max && hb_mul_sat(3, 5) == 15);
    EXPECT(hb_add_sat(max, max) == max && hb_add_sat(2, 3) == 5);
    printf("%d misses\n", misses);
    return misses != 0;
}
