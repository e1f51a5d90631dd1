/* dynamics_simd.c — instantiates dynamics_simd_impl.h for float and for double: the
 * simulate stage of the `simd` variant of hairsim-cpu (docs/cpu_simd.md, "The dynamic
 * model").
 *
 * Built with model_simd.c's flags (Makefile, SIMD_CFLAGS): -O3 -march=x86-64-v3
 * -fopenmp-simd -fno-math-errno -fno-trapping-math, on top of the reference's
 * -ffp-contract=off and without -ffast-math: the arithmetic is dynamics_impl.h's,
 * operation for operation (IEEE sqrt and division, no FMA contraction), so without gusts
 * the result is the `ref` variant's bits. The one libm call, the sine of the gusts, is
 * glibc's libmvec vector sine (≤ 4 ulp), declared here with the attribute glibc's
 * <math.h> gives it only under -ffast-math (model_simd.c explains why).
 *
 * Check: objdump -dr build/obj/dynamics_simd.o | grep _ZGV lists the vector sines.
 */
#include "dynamics_simd.h"

#include <math.h>
#include <stddef.h>

#include "model_simd.h"

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
    return (6 * points + 3) * (int64_t)HB_SIMD_DYN_BLOCK;
}

#define REAL float
#define SFX(name) name##_f32
#define DMODEL hb_dyn_model_f32
#define SQRT sqrtf
#define SIN sinf
#define QTABLE(fr) ((fr)->q32)
#define PHASE(fr) ((fr)->phase32)
#include "dynamics_simd_impl.h"
#undef REAL
#undef SFX
#undef DMODEL
#undef SQRT
#undef SIN
#undef QTABLE
#undef PHASE

#define REAL double
#define SFX(name) name##_f64
#define DMODEL hb_dyn_model_f64
#define SQRT sqrt
#define SIN sin
#define QTABLE(fr) ((fr)->q64)
#define PHASE(fr) ((fr)->phase64)
#include "dynamics_simd_impl.h"
