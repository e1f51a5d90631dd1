/* dynamics_f64.c — dynamics_impl.h for double (one file per precision: they compile in parallel). */
#include "dynamic/dynamics.h"

#include <math.h>

#include "dynamic/precision_f64.h"
#include "dynamic/dynamics_impl.h"
