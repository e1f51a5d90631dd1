/* dynamics_f32.c — dynamics_impl.h for float (one file per precision: they compile in parallel). */
#include "dynamic/dynamics.h"

#include <math.h>

#include "dynamic/precision_f32.h"
#include "dynamic/dynamics_impl.h"
