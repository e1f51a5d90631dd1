/* philox.h — Philox4x32-10 counter-based RNG (Salmon et al., SC'11, "Parallel random
 * numbers: as easy as 1, 2, 3"; the algorithm and constants as published with Random123)
 * and the draw → uniform conversion of docs/model.md §1.4.
 *
 * Header-only so that the C reference and the CUDA port compile the *same* integer code:
 * every backend, thread count, block size and strand split draws identical bits. Checked
 * against Random123's published known-answer vectors by `hairsim-cpu --self-test rng`
 * (tests/cpu/test_rng.py).
 *
 * Stream layout (docs/model.md §1.4):
 *   key     = { seed low 32 bits, seed high 32 bits }
 *   counter = { strand low 32 bits, strand high 32 bits, draw / 4, 0 }
 *   draw d of strand i is word d % 4 of philox(counter(i, d / 4), key).
 */
#ifndef HB_PHILOX_H
#define HB_PHILOX_H

#include <stdint.h>

#ifdef __CUDACC__
#define HB_HD __host__ __device__ __forceinline__
#else
#define HB_HD static inline
#endif

#define HB_PHILOX_M0 0xD2511F53u
#define HB_PHILOX_M1 0xCD9E8D57u
#define HB_PHILOX_W0 0x9E3779B9u /* golden ratio */
#define HB_PHILOX_W1 0xBB67AE85u /* sqrt(3) - 1 */

HB_HD void hb_mulhilo32(uint32_t a, uint32_t b, uint32_t *hi, uint32_t *lo)
{
    uint64_t p = (uint64_t)a * (uint64_t)b;
    *hi = (uint32_t)(p >> 32);
    *lo = (uint32_t)p;
}

/* One Philox4x32 round: two 32x32→64 multiplies, a swap and a xor with the key. */
HB_HD void hb_philox_round(uint32_t c[4], const uint32_t k[2])
{
    uint32_t hi0, lo0, hi1, lo1;
    hb_mulhilo32(HB_PHILOX_M0, c[0], &hi0, &lo0);
    hb_mulhilo32(HB_PHILOX_M1, c[2], &hi1, &lo1);
    uint32_t n0 = hi1 ^ c[1] ^ k[0];
    uint32_t n2 = hi0 ^ c[3] ^ k[1];
    c[0] = n0;
    c[1] = lo1;
    c[2] = n2;
    c[3] = lo0;
}

/* Philox4x32 with `rounds` rounds: out = f(ctr, key). The key is bumped by the Weyl
 * constants before every round after the first. */
HB_HD void hb_philox4x32(int rounds, const uint32_t ctr[4], const uint32_t key[2], uint32_t out[4])
{
    uint32_t c[4] = {ctr[0], ctr[1], ctr[2], ctr[3]};
    uint32_t k[2] = {key[0], key[1]};
    for (int r = 0; r < rounds; r++) {
        if (r > 0) {
            k[0] += HB_PHILOX_W0;
            k[1] += HB_PHILOX_W1;
        }
        hb_philox_round(c, k);
    }
    out[0] = c[0];
    out[1] = c[1];
    out[2] = c[2];
    out[3] = c[3];
}

/* The four 32-bit draws 4*block … 4*block+3 of strand `strand` under `seed`. */
HB_HD void hb_draw_block(uint64_t seed, uint64_t strand, uint32_t block, uint32_t out[4])
{
    const uint32_t key[2] = {(uint32_t)seed, (uint32_t)(seed >> 32)};
    const uint32_t ctr[4] = {(uint32_t)strand, (uint32_t)(strand >> 32), block, 0u};
    hb_philox4x32(10, ctr, key, out);
}

/* A 32-bit draw → uniform in [0, 1) with 24 random bits: (x >> 8) · 2^-24, integer
 * operations and a power-of-two scale only. The value is exact in float and in double, so
 * fp32 and fp64 runs start from the same draws (docs/model.md §1.4). */
HB_HD double hb_u01(uint32_t x)
{
    return (double)(x >> 8) * (1.0 / 16777216.0);
}

#endif
