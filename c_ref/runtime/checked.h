/* checked.h — every integer product that sizes memory or a loop goes through these, so a
 * product too large for 64 bits is refused instead of wrapping (docs/interfaces.md,
 * "Sizes"). Host code only (C and the CUDA files' host side). */
#ifndef HB_CHECKED_H
#define HB_CHECKED_H

#include <stdint.h>

/* a·b into *out; 0, or −1 (and *out = UINT64_MAX) when it does not fit in 64 bits. */
static inline int hb_mul_u64(uint64_t a, uint64_t b, uint64_t *out)
{
    if (__builtin_mul_overflow(a, b, out)) {
        *out = UINT64_MAX;
        return -1;
    }
    return 0;
}

/* a·b·c, checked the same way. */
static inline int hb_mul3_u64(uint64_t a, uint64_t b, uint64_t c, uint64_t *out)
{
    uint64_t ab;
    if (hb_mul_u64(a, b, &ab)) {
        *out = UINT64_MAX;
        return -1;
    }
    return hb_mul_u64(ab, c, out);
}

/* a + b, checked the same way. */
static inline int hb_add_u64(uint64_t a, uint64_t b, uint64_t *out)
{
    if (__builtin_add_overflow(a, b, out)) {
        *out = UINT64_MAX;
        return -1;
    }
    return 0;
}

/* a·b saturated at UINT64_MAX: for byte counts that a memory check then refuses. */
static inline uint64_t hb_mul_sat(uint64_t a, uint64_t b)
{
    uint64_t r;
    hb_mul_u64(a, b, &r);
    return r;
}

/* a + b saturated at UINT64_MAX. */
static inline uint64_t hb_add_sat(uint64_t a, uint64_t b)
{
    uint64_t r;
    hb_add_u64(a, b, &r);
    return r;
}

#endif
