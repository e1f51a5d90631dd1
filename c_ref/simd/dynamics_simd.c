/* dynamics_simd.c — instantiates dynamics_simd_impl.h for float and for double: the
 * simulate stage of the `simd` variant of hairsim-cpu (docs/cpu_simd.md, "The dynamic
 * model").
 *
 * Built with model_simd.c's flags (Makefile, SIMD_CFLAGS): -O3 -march=x86-64-v3
 * -fopenmp-simd -fno-math-errno -fno-trapping-math, on top of the reference's
 * -ffp-contract=off and without -ffast-math. The free arithmetic is written out in
 * dynamics_simd_impl.h (reciprocals, products), not left to the compiler: the reciprocal
 * square roots are below. The one libm call, the sine of the gusts, is glibc's libmvec
 * vector sine (≤ 4 ulp), declared here with the attribute glibc's <math.h> gives it only
 * under -ffast-math (model_simd.c explains why).
 *
 * Check: objdump -dr build/obj/simd/dynamics_simd.o | grep _ZGV lists the vector sines.
 */
#include "simd/dynamics_simd.h"

#include <float.h>
#include <immintrin.h>
#include <math.h>
#include <stddef.h>

#include "dynamic/obs_point.h" /* hb_obs_point: §3.8 per point, shared with the reference */
#include "simd/model_simd.h"

#if !defined(__x86_64__) || !defined(__GLIBC__)
#error "dynamics_simd.c needs x86_64 and glibc's libmvec"
#endif

#define HB_SIMD_DECL __attribute__((__simd__("notinbranch")))
HB_SIMD_DECL float sinf(float);
HB_SIMD_DECL double sin(double);

#define HB_ASSUME_ALIGNED(p) ((__typeof__(p))__builtin_assume_aligned((p), 64))

#if HB_SIMD_DYN_BLOCK % 64 != 0 || HB_SIMD_BLOCK_F32 % HB_SIMD_DYN_BLOCK != 0 ||                                       \
    HB_SIMD_BLOCK_F64 % HB_SIMD_DYN_BLOCK != 0
#error "HB_SIMD_DYN_BLOCK must be a multiple of 64 that divides HB_SIMD_BLOCK_F32 and HB_SIMD_BLOCK_F64"
#endif

int64_t hb_simd_dyn_scratch_reals(int64_t points)
{
    return (14 * points + 8) * (int64_t)HB_SIMD_DYN_BLOCK; /* + 8 rows a point: §3.16's held samples */
}

/* out = 1/√in over one row of lanes. fp32: the hardware estimate (relative error ≤ 1.5·2⁻¹²;
 * AVX-512's 2⁻¹⁴)
 * and one Newton step y·(1.5 − ½·x·y²), about 2e-7 relative; the callers treat |e|² below
 * FLT_MIN as zero, so the estimate's flush of subnormal inputs does not matter. fp64 (AVX2
 * has no estimate for doubles): a square root and one division instead of one of each per
 * component. */
static inline __attribute__((always_inline)) void inv_sqrt_row_f32(const float *restrict in, float *restrict out)
{
#if defined(__AVX512F__) /* dynamics_simd_v4.c: the 14-bit estimate, 16 lanes */
    const __m512 half = _mm512_set1_ps(0.5f), three_halves = _mm512_set1_ps(1.5f);
    for (int j = 0; j < HB_SIMD_DYN_BLOCK; j += 16) {
        const __m512 x = _mm512_load_ps(in + j), y = _mm512_rsqrt14_ps(x);
        const __m512 hxy = _mm512_mul_ps(_mm512_mul_ps(half, x), y);
        _mm512_store_ps(out + j, _mm512_mul_ps(y, _mm512_fnmadd_ps(hxy, y, three_halves)));
    }
#else
    const __m256 half = _mm256_set1_ps(0.5f), three_halves = _mm256_set1_ps(1.5f);
    for (int j = 0; j < HB_SIMD_DYN_BLOCK; j += 8) {
        const __m256 x = _mm256_load_ps(in + j), y = _mm256_rsqrt_ps(x);
        const __m256 hxy = _mm256_mul_ps(_mm256_mul_ps(half, x), y);
        _mm256_store_ps(out + j, _mm256_mul_ps(y, _mm256_fnmadd_ps(hxy, y, three_halves)));
    }
#endif
}

static inline __attribute__((always_inline)) void inv_sqrt_row_f64(const double *restrict in, double *restrict out)
{
#pragma omp simd
    for (int j = 0; j < HB_SIMD_DYN_BLOCK; j++) out[j] = 1.0 / sqrt(in[j]);
}

#include "dynamic/precision_f32.h"
#include "dynamic/contact_impl.h" /* §3.16, §3.17: the grid's and the colliders' per-point operations */
#define INV_SQRT_ROW(in, out) inv_sqrt_row_f32(in, out)
#define TINY FLT_MIN
#include "simd/dynamics_simd_impl.h"
#undef INV_SQRT_ROW
#undef TINY
#include "dynamic/precision_end.h"

#include "dynamic/precision_f64.h"
#include "dynamic/contact_impl.h"
#define INV_SQRT_ROW(in, out) inv_sqrt_row_f64(in, out)
#define TINY DBL_MIN
#include "simd/dynamics_simd_impl.h"
#undef INV_SQRT_ROW
#undef TINY
#include "dynamic/precision_end.h"

#ifndef HB_SIMD_DYN_FNS
#define HB_SIMD_DYN_FNS hb_simd_dyn_v3
#endif
const hb_simd_dyn_fns HB_SIMD_DYN_FNS = {
    hb_simd_dyn_scratch_reals,   hb_simd_dyn_bend_rest_block_f32, hb_simd_dyn_bend_rest_block_f64,
    hb_simd_dyn_frame_block_f32, hb_simd_dyn_frame_block_f64,     hb_simd_dyn_observe_f32,
    hb_simd_dyn_observe_f64,
};
