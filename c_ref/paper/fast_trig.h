/* fast_trig.h — the fp32 atan2 and sincos of the paper model's free arithmetic (the normal
 * and fast-math CUDA builds, cuda/paper/model.cuh; the simd variant, model_simd_impl.h).
 *
 * Branch-free polynomials for the bounded arguments the model produces, with no slow path:
 *   hb_atan2_fast(y, x)          any finite y, x; relative error of the polynomial 1.5e-8
 *                                (a minimax fit of atan on [0, 1], odd, degree 17), returns
 *                                exactly ±0, ±fl(π/2), ±fl(π) on the axes as atan2f does, so
 *                                the wind's exactly-opposite rule sees the reference's angles;
 *   hb_sincos_fast(x, &s, &c)    |x| ≤ 2^10: one quadrant reduction (two-part π/2 with fused
 *                                multiply-adds), degree-7 sin and degree-8 cos on [−π/4, π/4]
 *                                (polynomial error below 2e-9).
 * Measured against double-precision libm (every float x in [−2π, 2π]; atan2: 1e8 random
 * pairs over 2^±10): sin 1.4 ulp, cos 7.2e-8 absolute (0.6 ulp of 1), atan2 2.4 ulp. The
 * coefficients were fitted for this file (Lawson's minimax in double, rounded to float).
 *
 * Plain C (static inline, vectorisable in `omp simd` loops: selects, no calls but fmaf) and
 * CUDA (__host__ __device__). HB_FAST_QUOT is the one division: on the device a product with
 * the approximate reciprocal (1 ulp), elsewhere IEEE.
 */
#ifndef HB_FAST_TRIG_H
#define HB_FAST_TRIG_H

#include <math.h>
#include <stdint.h>
#include <string.h>

#include "runtime/approx.h" /* hb_rcp_fast, HB_FAST_FLOOR */
#include "runtime/philox.h" /* HB_HD */

#if defined(__CUDA_ARCH__)
#define HB_FAST_QUOT(a, b) ((a)*hb_rcp_fast(b))
#else
#define HB_FAST_QUOT(a, b) ((a) / (b))
#endif

HB_HD float hb_atan2_fast(float y, float x)
{
    const float ax = fabsf(x), ay = fabsf(y);
    const float hi = ay > ax ? ay : ax, lo = ay > ax ? ax : ay;
    const float a = hi > HB_FAST_FLOOR ? HB_FAST_QUOT(lo, hi) : 0.0f; /* in [0, 1] */
    const float s = a * a;
    float p = 2.84985569e-3f;
    p = fmaf(p, s, -1.60685014e-2f);
    p = fmaf(p, s, 4.26913276e-2f);
    p = fmaf(p, s, -7.50427991e-2f);
    p = fmaf(p, s, 1.06409274e-1f);
    p = fmaf(p, s, -1.42036423e-1f);
    p = fmaf(p, s, 1.99926198e-1f);
    p = fmaf(p, s, -3.33330721e-1f);
    p = fmaf(p, s, 1.0f);
    float r = a * p;                                /* atan(lo / hi) in [0, π/4] */
    r = ay > ax ? 1.57079632679489661923f - r : r;  /* [0, π/2] */
    r = x < 0.0f ? 3.14159265358979323846f - r : r; /* [0, π] */
    return copysignf(r, y);
}

HB_HD void hb_sincos_fast(float x, float *sn, float *cs)
{
    /* j = rint(x·2/π) through the 1.5·2^23 shift: its low bits are the quadrant q */
    const float shifted = x * 0.636619772367581343076f + 12582912.0f;
    int32_t q;
#if defined(__CUDA_ARCH__)
    q = __float_as_int(shifted);
#else
    memcpy(&q, &shifted, sizeof q);
#endif
    const float j = shifted - 12582912.0f;
    float r = fmaf(j, -1.57079637050628662109f, x); /* fl(π/2) */
    r = fmaf(j, 4.37113900018624283e-8f, r);        /* π/2 − fl(π/2) */
    const float r2 = r * r;
    float ps = -1.94956403e-4f;
    ps = fmaf(ps, r2, 8.33197869e-3f);
    ps = fmaf(ps, r2, -1.66666508e-1f);
    const float sr = fmaf(ps * r2, r, r);
    float pc = 2.44384555e-5f;
    pc = fmaf(pc, r2, -1.38873677e-3f);
    pc = fmaf(pc, r2, 4.16666456e-2f);
    pc = fmaf(pc, r2, -0.5f);
    const float cr = fmaf(pc, r2, 1.0f);
    const int32_t odd = q & 1;
    const float s0 = odd ? cr : sr, c0 = odd ? sr : cr;
    *sn = (q & 2) ? -s0 : s0;
    *cs = ((q + 1) & 2) ? -c0 : c0;
}

#endif
