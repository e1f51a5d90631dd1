/* dynamics_f32.c — dynamics_impl.h for float (one file per precision: they compile in parallel). */
#include "dynamic/dynamics.h"

#include <math.h>

#define REAL float
#define SFX(name) name##_f32
#define DMODEL hb_dyn_model_f32
#define SQRT sqrtf
#define SIN sinf
#define QTABLE(fr) ((fr)->q32)
#define PHASE(fr) ((fr)->phase32)
#include "dynamic/dynamics_impl.h"
