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
 *    the same attribute on the eight functions (fp32's sin and cos are now fast_trig.h's),
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
