/* precision_f64.h — as precision_f32.h, for double. */
#define REAL double
#define SFX(name) name##_f64
#define MODEL hb_model_f64
#define SQRT sqrt
#define SIN sin
#define COS cos
#define SINCOS sincos
#define ASIN asin
#define ATAN2 atan2
#define EPS 0x1p-52
