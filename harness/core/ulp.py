"""ULP distance between floating-point arrays, by integer reinterpretation.

The distance between a and b is the number of representable values of the given
precision stepped over going from a to b: 0 for equal values (and for +0 against −0),
1 for neighbours. Each value's bits are read as an unsigned integer; the sign bit is
split off, so the magnitude bits order the non-negative floats, and
  same sign:      |mag(a) − mag(b)|
  opposite signs: mag(a) + mag(b)   (the steps down to zero and up again)
computed in uint64, where neither can overflow (a magnitude is below 2^63).
NaN has no distance: the caller must treat it as a failure (`nan_mask`).
"""

import numpy as np

_LAYOUT = {
    np.dtype(np.float32): (np.uint32, np.uint32(0x7FFFFFFF)),
    np.dtype(np.float64): (np.uint64, np.uint64(0x7FFFFFFFFFFFFFFF)),
}


def _sign_and_magnitude(x):
    uint, mag_mask = _LAYOUT[x.dtype]
    bits = np.ascontiguousarray(x).view(uint)
    magnitude = (bits & mag_mask).astype(np.uint64)
    negative = bits > mag_mask
    return negative, magnitude


def ulp_distance(a, b, dtype):
    """ULP distance (uint64 array) between a and b measured in `dtype` (float32/float64).

    Both are rounded to `dtype` first (for a mixed fp32/fp64 pair, pass float32: the
    coarser precision). NaN entries give an undefined value: mask them with nan_mask."""
    dtype = np.dtype(dtype)
    if dtype not in _LAYOUT:
        raise ValueError(f"ULP distance is defined here for float32 and float64, not {dtype}")
    with np.errstate(over="ignore", invalid="ignore"):
        a = np.asarray(a).astype(dtype, copy=False)
        b = np.asarray(b).astype(dtype, copy=False)
    neg_a, mag_a = _sign_and_magnitude(a)
    neg_b, mag_b = _sign_and_magnitude(b)
    same = neg_a == neg_b
    larger = np.maximum(mag_a, mag_b)
    smaller = np.minimum(mag_a, mag_b)
    return np.where(same, larger - smaller, mag_a + mag_b)


def coarser(dtype_a, dtype_b):
    """The precision in which a pair's ULPs are counted: the coarser of the two."""
    a, b = np.dtype(dtype_a), np.dtype(dtype_b)
    return a if a.itemsize <= b.itemsize else b
