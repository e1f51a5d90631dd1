/* dynamics_f64.c — dynamics_impl.h for double (one file per precision: they compile in parallel). */
#include "dynamic/dynamics.h"

#include <math.h>

#define REAL double
#define SFX(name) name##_f64
#define DMODEL hb_dyn_model_f64
#define SQRT sqrt
#define SIN sin
#define QTABLE(fr) ((fr)->q64)
#define PHASE(fr) ((fr)->phase64)
#include "dynamic/dynamics_impl.h"
