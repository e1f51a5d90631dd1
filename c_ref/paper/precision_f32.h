/* precision_f32.h — the names the paper model's math is written in (paper/points_impl.h,
 * paper/model_impl.h, simd/model_simd_impl.h), for float; precision_end.h removes them. Included by the files that
 * instantiate the math (paper/model.c, simd/model_simd.c). */
#define REAL float
#define SFX(name) name##_f32
#define MODEL hb_model_f32
#define SQRT sqrtf
#define SIN sinf
#define COS cosf
#define SINCOS sincosf /* the device's (points_impl.h) */
#define ASIN asinf
#define ATAN2 atan2f
#define EPS 0x1p-23f
