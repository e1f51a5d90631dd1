"""Which strands a guided dynamic run simulates (docs/model.md §3.14), as the binaries choose."""

import math

import numpy as np


def guide_count(n, guides):
    """G: a fraction in (0, 1] of n strands rounded half up (at least 1), or a count > 1."""
    g = int(guides) if guides > 1.0 else int(math.floor(guides * n + 0.5))
    return min(max(g, 1), n)


def guide_strands(n, g):
    """Guide j is strand ⌊j·n/g⌋, j = 0 … g − 1."""
    return np.array([(j * n) // g for j in range(g)], dtype=np.int64)
