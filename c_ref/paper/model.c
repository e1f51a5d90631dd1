/* model.c — instantiates model_impl.h for float and for double. */
#include "paper/model.h"

#include <math.h>

#include "runtime/philox.h"

#define REAL float
#define SFX(name) name##_f32
#define MODEL hb_model_f32
#define SQRT sqrtf
#define SIN sinf
#define COS cosf
#define ASIN asinf
#define ATAN2 atan2f
#define EPS 0x1p-23f
#include "paper/model_impl.h"
#undef REAL
#undef SFX
#undef MODEL
#undef SQRT
#undef SIN
#undef COS
#undef ASIN
#undef ATAN2
#undef EPS

#define REAL double
#define SFX(name) name##_f64
#define MODEL hb_model_f64
#define SQRT sqrt
#define SIN sin
#define COS cos
#define ASIN asin
#define ATAN2 atan2
#define EPS 0x1p-52
#include "paper/model_impl.h"
