/* model.c — instantiates points_impl.h (one point's step) and model_impl.h (the stages) for
 * float and for double. */
#include "paper/model.h"

#include <math.h>

#include "runtime/philox.h"

#include "paper/precision_f32.h"
#include "paper/points_impl.h"
#include "paper/model_impl.h"
#include "paper/precision_end.h"

#include "paper/precision_f64.h"
#include "paper/points_impl.h"
#include "paper/model_impl.h"
#include "paper/precision_end.h"
