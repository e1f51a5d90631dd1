/* tmath.cuh — the math library by floating type for both models' CUDA templates: the float
 * functions for float, the double ones for double (glibc's on the host, CUDA's on the device). */
#ifndef HB_TMATH_CUH
#define HB_TMATH_CUH

#include <math.h>

#if defined(__CUDACC__)
#define HB_TMATH __host__ __device__ __forceinline__
#else
#define HB_TMATH inline
#endif

/* NAME(x) calls FNf for float and FN for double */
#define HB_TMATH_1(NAME, FN)                                                                                           \
    HB_TMATH float NAME(float x)                                                                                       \
    {                                                                                                                  \
        return FN##f(x);                                                                                               \
    }                                                                                                                  \
    HB_TMATH double NAME(double x)                                                                                     \
    {                                                                                                                  \
        return FN(x);                                                                                                  \
    }

namespace hb {

HB_TMATH_1(m_sqrt, sqrt)
HB_TMATH_1(m_sin, sin)
HB_TMATH_1(m_asin, asin)
HB_TMATH float m_atan2(float y, float x)
{
    return atan2f(y, x);
}
HB_TMATH double m_atan2(double y, double x)
{
    return atan2(y, x);
}

} /* namespace hb */

#endif
