/* model_simd.c — instantiates model_simd_impl.h for float and for double (the `simd`
 * variant of hairsim-cpu; docs/cpu_simd.md).
 *
 * Built with its own flags (Makefile, SIMD_CFLAGS): -O3 -march=x86-64-v3 -fopenmp-simd
 * -fno-math-errno -fno-trapping-math, on top of the reference's -ffp-contract=off and
 * without -ffast-math. How the loops get glibc's vector math (libmvec) without it:
 *
 *  - glibc's <math.h> declares the vector variants of sin, cos, asin, atan2 … (the
 *    `simd("notinbranch")` attribute, bits/math-vector.h) only when __FAST_MATH__ is
 *    defined, and GCC defines that only with all of -ffast-math's value-changing flags
 *    (-funsafe-math-optimizations, -ffinite-math-only, -fno-signed-zeros, …). We declare
 *    the same attribute on the eight functions (fp32's wind atan2, sin and cos are fast_trig.h's),
 *    below: the declarations glibc
 *    makes, without those flags. The vector functions are libmvec's, accurate to 4 ulp
 *    (glibc manual, "Errors in Math Functions").
 *  - -fno-math-errno: sqrt becomes the vector sqrt instruction, and the math builtins
 *    have no side effect (with errno, GCC calls sqrtf for negative arguments, a branch
 *    that blocks vectorisation). No value changes.
 *  - -fno-trapping-math: GCC may then if-convert the branches of a loop, evaluating FP
 *    operations whose result a select discards (we never enable FP traps). No value
 *    changes. Without it only the branch-free loops are vectorised.
 *  - -ffp-contract=off stays (the reference's flags): no FMA contraction; the arithmetic
 *    between the calls is model_simd_impl.h's free arithmetic as written (the roots, x
 *    and the decisions stay the reference's bits).
 *  - A sin and a cos of the same angle in one loop are merged by GCC into a sincos call,
 *    which has no vector variant it can use, and the loop is then not vectorised at all
 *    (with or without -ffast-math): model_simd_impl.h puts them in two loops.
 *
 * Check that the calls are vectorised: objdump -dr build/obj/simd/model_simd.o | grep _ZGV
 * (tests/cpu/test_cpu_simd.py fails on any scalar call to these functions).
 */
#include "simd/model_simd.h"

#include <math.h>
#include <stddef.h>

#include "paper/fast_trig.h"
#include "runtime/philox.h"

#if !defined(__x86_64__) || !defined(__GLIBC__)
#error "model_simd.c needs x86_64 and glibc's libmvec"
#elif !__GLIBC_PREREQ(2, 35)
#error "model_simd.c needs glibc >= 2.35 (libmvec's asin/atan2 vector variants)"
#endif

#define HB_SIMD_DECL __attribute__((__simd__("notinbranch")))
HB_SIMD_DECL float sinf(float);
HB_SIMD_DECL float cosf(float);
HB_SIMD_DECL float asinf(float);
HB_SIMD_DECL float atan2f(float, float);
HB_SIMD_DECL double sin(double);
HB_SIMD_DECL double cos(double);
HB_SIMD_DECL double asin(double);
HB_SIMD_DECL double atan2(double, double);

#define HB_ALIGNED __attribute__((aligned(64)))
#define HB_ASSUME_ALIGNED(p) ((__typeof__(p))__builtin_assume_aligned((p), 64))

#if defined(__AVX512F__)
const char hb_simd_isa[] = "x86-64-v4 (AVX-512)";
#elif defined(__AVX2__) && defined(__FMA__)
const char hb_simd_isa[] = "x86-64-v3 (AVX2 + FMA)";
#else
const char hb_simd_isa[] = "baseline x86-64 (SSE2)";
#endif

/* The fp32 fused pass's strand walk (model_simd_impl.h) holds a vector of lanes' state in
 * registers: a thin layer over the intrinsics of this build's width. Every operation is the
 * IEEE operation the `omp simd` loops vectorise to (no contraction: the products and sums
 * are separate, as -ffp-contract=off makes them there), so the walk gives their bits. */
#include <immintrin.h>
#if defined(__AVX512F__)
typedef __m512 hb_vf;
typedef __m512i hb_vi;
typedef __mmask16 hb_vm;
#define HB_VW 16
#define VSET _mm512_set1_ps
#define VLD _mm512_load_ps
#define VST _mm512_store_ps
#define VADD _mm512_add_ps
#define VSUB _mm512_sub_ps
#define VMUL _mm512_mul_ps
#define VDIV _mm512_div_ps
#define VFMA _mm512_fmadd_ps
#define VSQRT _mm512_sqrt_ps
#define VCMP(a, b, op) _mm512_cmp_ps_mask((a), (b), (op))
#define VSEL(mk, a, b) _mm512_mask_blend_ps((mk), (b), (a)) /* mk ? a : b */
#define MAND(a, b) ((hb_vm)((a) & (b)))
#define MOR(a, b) ((hb_vm)((a) | (b)))
#define MANY(mk) ((mk) != 0)
#define MNONE ((hb_vm)0)
#define VIZERO _mm512_setzero_si512()
#define VICOUNT(c, mk) _mm512_mask_sub_epi32((c), (mk), (c), _mm512_set1_epi32(-1)) /* +1 where mk */
#define VIST(p, c) _mm512_store_si512((void *)(p), (c))
#define VPREFETCH(p) _mm_prefetch((const char *)(p), _MM_HINT_T0)
static inline __attribute__((always_inline)) hb_vm hb_v_bit(hb_vi q, int b)
{
    return _mm512_test_epi32_mask(q, _mm512_set1_epi32(b));
}
static inline __attribute__((always_inline)) hb_vf hb_v_flip(hb_vf x, hb_vi q) /* −x where q & 2 */
{
    return _mm512_castsi512_ps(
        _mm512_xor_si512(_mm512_castps_si512(x), _mm512_slli_epi32(_mm512_and_si512(q, _mm512_set1_epi32(2)), 30)));
}
#define VASI _mm512_castps_si512
#define VIADD1(q) _mm512_add_epi32((q), _mm512_set1_epi32(1))
#else
typedef __m256 hb_vf;
typedef __m256i hb_vi;
typedef __m256 hb_vm;
#define HB_VW 8
#define VSET _mm256_set1_ps
#define VLD _mm256_load_ps
#define VST _mm256_store_ps
#define VADD _mm256_add_ps
#define VSUB _mm256_sub_ps
#define VMUL _mm256_mul_ps
#define VDIV _mm256_div_ps
#define VFMA _mm256_fmadd_ps
#define VSQRT _mm256_sqrt_ps
#define VCMP(a, b, op) _mm256_cmp_ps((a), (b), (op))
#define VSEL(mk, a, b) _mm256_blendv_ps((b), (a), (mk)) /* mk ? a : b */
#define MAND(a, b) _mm256_and_ps((a), (b))
#define MOR(a, b) _mm256_or_ps((a), (b))
#define MANY(mk) (_mm256_movemask_ps(mk) != 0)
#define MNONE _mm256_setzero_ps()
#define VIZERO _mm256_setzero_si256()
#define VICOUNT(c, mk) _mm256_sub_epi32((c), _mm256_castps_si256(mk)) /* +1 where mk (all ones) */
#define VIST(p, c) _mm256_store_si256((void *)(p), (c))
#define VPREFETCH(p) _mm_prefetch((const char *)(p), _MM_HINT_T0)
static inline __attribute__((always_inline)) hb_vm hb_v_bit(hb_vi q, int b)
{
    const hb_vi bb = _mm256_set1_epi32(b);
    return _mm256_castsi256_ps(_mm256_cmpeq_epi32(_mm256_and_si256(q, bb), bb));
}
static inline __attribute__((always_inline)) hb_vf hb_v_flip(hb_vf x, hb_vi q) /* −x where q & 2 */
{
    return _mm256_castsi256_ps(
        _mm256_xor_si256(_mm256_castps_si256(x), _mm256_slli_epi32(_mm256_and_si256(q, _mm256_set1_epi32(2)), 30)));
}
#define VASI _mm256_castps_si256
#define VIADD1(q) _mm256_add_epi32((q), _mm256_set1_epi32(1))
#endif

/* fast_trig.h's hb_atan2_fast on a vector, operation for operation (fp32's wind calls the
 * scalar one in its loop: the same bits) */
static inline __attribute__((always_inline)) hb_vf hb_v_atan2(hb_vf y, hb_vf x)
{
    const hb_vf sign = VSET(-0.0f);
#if defined(__AVX512F__)
    const hb_vf ax = _mm512_andnot_ps(sign, x), ay = _mm512_andnot_ps(sign, y);
#else
    const hb_vf ax = _mm256_andnot_ps(sign, x), ay = _mm256_andnot_ps(sign, y);
#endif
    const hb_vm yg = VCMP(ay, ax, _CMP_GT_OQ);
    const hb_vf hi = VSEL(yg, ay, ax), lo = VSEL(yg, ax, ay);
    const hb_vf a = VSEL(VCMP(hi, VSET(HB_FAST_FLOOR), _CMP_GT_OQ), VDIV(lo, hi), VSET(0.0f));
    const hb_vf s = VMUL(a, a);
    hb_vf p = VSET(2.84985569e-3f);
    p = VFMA(p, s, VSET(-1.60685014e-2f));
    p = VFMA(p, s, VSET(4.26913276e-2f));
    p = VFMA(p, s, VSET(-7.50427991e-2f));
    p = VFMA(p, s, VSET(1.06409274e-1f));
    p = VFMA(p, s, VSET(-1.42036423e-1f));
    p = VFMA(p, s, VSET(1.99926198e-1f));
    p = VFMA(p, s, VSET(-3.33330721e-1f));
    p = VFMA(p, s, VSET(1.0f));
    hb_vf r = VMUL(a, p);
    r = VSEL(yg, VSUB(VSET(1.57079632679489661923f), r), r);
    r = VSEL(VCMP(x, VSET(0.0f), _CMP_LT_OQ), VSUB(VSET(3.14159265358979323846f), r), r);
#if defined(__AVX512F__) /* copysignf(r, y) */
    return _mm512_or_ps(_mm512_andnot_ps(sign, r), _mm512_and_ps(sign, y));
#else
    return _mm256_or_ps(_mm256_andnot_ps(sign, r), _mm256_and_ps(sign, y));
#endif
}

/* fast_trig.h's hb_sincos_fast on a vector, operation for operation (the sign selects as
 * sign flips: the same bits) */
static inline __attribute__((always_inline)) void hb_v_sincos(hb_vf x, hb_vf *sn, hb_vf *cs)
{
    const hb_vf shifted = VADD(VMUL(x, VSET(0.636619772367581343076f)), VSET(12582912.0f));
    const hb_vi q = VASI(shifted);
    const hb_vf j = VSUB(shifted, VSET(12582912.0f));
    hb_vf r = VFMA(j, VSET(-1.57079637050628662109f), x);
    r = VFMA(j, VSET(4.37113900018624283e-8f), r);
    const hb_vf r2 = VMUL(r, r);
    hb_vf ps = VSET(-1.94956403e-4f);
    ps = VFMA(ps, r2, VSET(8.33197869e-3f));
    ps = VFMA(ps, r2, VSET(-1.66666508e-1f));
    const hb_vf sr = VFMA(VMUL(ps, r2), r, r);
    hb_vf pc = VSET(2.44384555e-5f);
    pc = VFMA(pc, r2, VSET(-1.38873677e-3f));
    pc = VFMA(pc, r2, VSET(4.16666456e-2f));
    pc = VFMA(pc, r2, VSET(-0.5f));
    const hb_vf cr = VFMA(pc, r2, VSET(1.0f));
    const hb_vm odd = hb_v_bit(q, 1);
    *sn = hb_v_flip(VSEL(odd, cr, sr), q);
    *cs = hb_v_flip(VSEL(odd, sr, cr), VIADD1(q));
}

#include "paper/precision_f32.h"
#include "paper/points_impl.h" /* the roots: the reference's own hb_root_place */
#define ITYPE int32_t
#define BLOCK HB_SIMD_BLOCK_F32
#define FAST_TRIG 1
#include "simd/model_simd_impl.h"
#include "paper/precision_end.h"
#undef ITYPE
#undef BLOCK
#undef FAST_TRIG

#include "paper/precision_f64.h"
#include "paper/points_impl.h" /* the roots: the reference's own hb_root_place */
#define ITYPE int64_t
#define BLOCK HB_SIMD_BLOCK_F64
#define FAST_TRIG 0
#include "simd/model_simd_impl.h"
#include "paper/precision_end.h"
#undef ITYPE
#undef BLOCK
#undef FAST_TRIG

#ifndef HB_SIMD_MODEL_FNS
#define HB_SIMD_MODEL_FNS hb_simd_model_v3
#endif
const hb_simd_model_fns HB_SIMD_MODEL_FNS = {
    hb_simd_isa,
    hb_simd_init_block_f32,
    hb_simd_init_block_f64,
    hb_simd_wind_block_f32,
    hb_simd_wind_block_f64,
    hb_simd_collide_block_f32,
    hb_simd_collide_block_f64,
    hb_simd_wind_collide_block_f32,
    hb_simd_wind_collide_block_f64,
};
