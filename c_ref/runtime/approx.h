/* approx.h — the device's one-instruction approximations that the free arithmetic of both
 * models uses (docs/model.md §1.3): the reciprocal and the reciprocal square root of the MUFU
 * unit in their .ftz forms, which skip the subnormal-input fix-up that rcpf/rsqrtf add in a build
 * without -ftz (a subnormal input reads as 0). On the host, IEEE.
 *
 * HB_FAST_FLOOR: the least input they take as positive; callers test x > HB_FAST_FLOOR, not
 * x > 0 (on the device the least normal float, elsewhere 0).
 */
#ifndef HB_APPROX_H
#define HB_APPROX_H

#include <math.h>

#include "runtime/philox.h" /* HB_HD */

HB_HD float hb_rcp_fast(float x)
{
#if defined(__CUDA_ARCH__)
    float r;
    asm("rcp.approx.ftz.f32 %0, %1;" : "=f"(r) : "f"(x));
    return r;
#else
    return 1.0f / x;
#endif
}

HB_HD float hb_rsqrt_fast(float x)
{
#if defined(__CUDA_ARCH__)
    float r;
    asm("rsqrt.approx.ftz.f32 %0, %1;" : "=f"(r) : "f"(x));
    return r;
#else
    return 1.0f / sqrtf(x);
#endif
}

#if defined(__CUDA_ARCH__)
#define HB_FAST_FLOOR 1.17549435e-38f
#else
#define HB_FAST_FLOOR 0.0f
#endif

#endif
