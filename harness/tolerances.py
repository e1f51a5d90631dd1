"""Every tolerance of the harness, in one place, with the measurement behind each.

Precision kinds: "fp64", "fp32", and "fp32-fastmath" (an fp32 state from a build with
nvcc --use_fast_math: approximate sin/cos/div/sqrt, flush-to-zero). Fast math does not
change double-precision arithmetic in nvcc, so an fp64 state from a fast-math build is
kind "fp64". ε is the machine epsilon of the kind (of the coarser kind for a pair).

WHERE THE ERROR COMES FROM (measured with `python -m harness calibrate`, below). Two
states of one scene differ by the rounding of (a) the root draw and (b) every step along
the strand. (a) is ill-conditioned where the draw takes a square root of a cancelling
difference: x = ±√(R² − z² − y²) has error ≈ ε·R²/|x| (up to √ε·R when x ≈ 0), and
d = √(R² − z²), hence y, has error ≈ ε·R²/d; the whole strand inherits its root's error.
(b) each drape, wind or collide step costs about ε·E, E = R + h + L being the largest
coordinate, and the steps add up along the strand. So a point of a strand whose root is
(x0, y0, z0) gets the per-point unit

    u = ε · ( P·E + R²/max(|x0|, √ε·R) + R²/max(√(x0² + y0²), √ε·R) )

(`point_unit`; the root terms only where the two files' roots differ at all), and a
point is OVER TOLERANCE when the two files put it farther apart
than point_k · u, or when either has a non-finite coordinate there (NaN never passes).
A frame is equivalent when at most `max_over_fraction` of its points are over. That
allowance exists for one reason: the model has discrete decisions (a draped strand starts
to hang when its next angle would pass π; collide moves a point only when it is inside
the shell by more than 16 ε·rc), and a state rounded differently can take the other side
for a strand sitting within rounding of the threshold, which moves the rest of that strand
by up to a segment. None such was seen in the measurements; fp64↔fp64 allows none.

INVARIANTS (invariants.py), per kind: |segment length − ℓ| ≤ segment_k · ε·E, and after
collide no non-root point inside its shell circle by more than shell_k · ε·rc. The
binaries' own collide test leaves points up to 16 ε·rc inside alone (HB_SHELL_ULPS in
c_ref/model.h), so shell_k must be above 16.

MEASUREMENTS, worst over all runs. (1) `python -m harness calibrate --strands 20000
--points 2 8 32 128 256 --seeds 1 2 --other /tmp/hbfma/hairsim-cpu` (and --points 2 8 32
251) on the 2-core dev machine, "other" = c_ref rebuilt with `make BUILD=/tmp/hbfma
CFLAGS_REF="-std=c11 -D_DEFAULT_SOURCE -O3 -march=native -ffp-contract=fast -Wall"` (FMA
contraction); (2) `python -m harness calibrate --strands 20000 --points 2 8 32 251 --seeds
1 --other build/hairsim-cuda[-strict|-fastmath]` on an NVIDIA H200 (CUDA 13.0, sm_90);
paper scene w = 0.5 and gale w = 1, every frame, 0.5–1.4e8 point comparisons per pair:
  pair                      c_ref (1)   FMA c_ref (1)  cuda-strict  cuda    cuda-fastmath
  fp64↔fp64                     —         0.83·u        1.00·u     1.08·u   1.08·u
  fp32↔fp64                  0.88·u       0.88·u        0.88·u     0.88·u   1.05·u
  fp32↔fp32                     —         1.22·u        1.50·u     1.50·u   1.84·u (fast-math↔fp32)
  max error, any pair: 4.7e-6·L (fp32), 1.4e-14·L (fp64); 0 points beyond 1e-3·L anywhere
  segment error:   fp32 ≤ 0.80·ε·E, fast-math ≤ 1.60·ε·E, fp64 ≤ 0.80·ε·E
  shell depth:     fp32 ≤ 17.0·ε·rc, fast-math ≤ 16.5·ε·rc, fp64 ≤ 3.0·ε·rc
                   (the binary leaves up to 16 ε·rc alone)
  `harness bench` on the H200: 167 comparisons (every build × variant × block size ×
  precision, and every stage resumed from the cpu state) at 2000 × 32, all equivalent,
  worst 0.17·u.
So point_k = 4 for fp64↔fp64 and fp32↔fp64 (margin ≥ 3.7×), 6 for fp32↔fp32 (4× over
1.50·u), 8 for fast-math pairs (4.3× over 1.84·u). For the paper scene at P = 32, 4u is
2.1e-5·L … 9.4e-4·L in fp32 (the large end only for a root with x0 ≈ 0 that differs
between the files) and 3.9e-14·L … 4.0e-8·L in fp64. segment_k = 16 is ≥ 10× the worst
measured and the bound tests/invariants_check.py uses (16·ε·(R + L), docs/decisions.md),
so the harness and the test suite agree: 7.9e-5·ℓ in fp32 and 1.5e-13·ℓ in fp64 for the
paper scene at P = 32. shell_k = 32 is the binary's 16 plus a margin of 16 over the
measured excess of ≤ 1 ε·rc, again the tests' bound.
"""
import math
from dataclasses import dataclass

import numpy as np

KINDS = ("fp64", "fp32", "fp32-fastmath")
EPS = {"fp64": 2.0 ** -52, "fp32": 2.0 ** -23, "fp32-fastmath": 2.0 ** -23}


def extent(head_radius, hair_offset, hair_length):
    """E = R + h + L: no coordinate of a state is larger."""
    return head_radius + hair_offset + hair_length


def point_unit(x0, y0, head_radius, hair_offset, hair_length, points, eps, root_differs=True):
    """The per-strand error unit u (scene units) for roots (x0, y0) (arrays, float64).

    `root_differs` (bool array): the root terms count only for strands whose roots are
    not bit-identical in the two files; an identical root passed no error on (e.g. the 5%
    of roots that the clamp puts exactly at the back pole, where x0 = y0 = 0)."""
    R = head_radius
    floor = math.sqrt(eps) * R
    E = extent(head_radius, hair_offset, hair_length)
    x_term = R * R / np.maximum(np.abs(x0), floor)
    d_term = R * R / np.maximum(np.hypot(x0, y0), floor)
    return eps * (points * E + np.where(root_differs, x_term + d_term, 0.0))


@dataclass(frozen=True)
class PairTolerance:
    point_k: float              # a point is over when |a − b| > point_k · u (point_unit)
    max_over_fraction: float    # fraction of the points of a frame allowed over
    why: str                    # the measurement behind it (shown by `harness diff --json`)


@dataclass(frozen=True)
class InvariantTolerance:
    segment_k: float            # |segment − ℓ| ≤ segment_k · ε · E
    shell_k: float              # after collide: rc − |(y, z)| ≤ shell_k · ε · rc
    why: str


def kind_of(precision, fast_math):
    """The precision kind of a state: fp64, fp32, or fp32-fastmath."""
    if precision == "fp32" and fast_math:
        return "fp32-fastmath"
    return precision


def _key(kind_a, kind_b):
    return tuple(sorted((kind_a, kind_b)))


PAIRS = {
    _key("fp64", "fp64"): PairTolerance(
        point_k=4.0, max_over_fraction=0.0,
        why="measured ≤ 1.08·u (cuda, cuda-strict and FMA-built c_ref vs c_ref, H200 and x86); "
            "4 = margin 3.7×; no branch flips allowed in fp64"),
    _key("fp32", "fp64"): PairTolerance(
        point_k=4.0, max_over_fraction=1e-5,
        why="measured ≤ 0.88·u (c_ref and cuda fp32 vs c_ref fp64, 0 flips in 1.4e8 points); "
            "4 = margin 4.5×; ≤ 1e-5 of points may take the other side of a discrete decision"),
    _key("fp32", "fp32"): PairTolerance(
        point_k=6.0, max_over_fraction=1e-5,
        why="measured ≤ 1.50·u (cuda and cuda-strict vs c_ref on an H200); 6 = margin 4×; "
            "≤ 1e-5 of points may take the other side of a discrete decision"),
    _key("fp32-fastmath", "fp64"): PairTolerance(
        point_k=8.0, max_over_fraction=1e-5,
        why="measured ≤ 1.05·u (cuda-fastmath fp32 vs c_ref fp64 on an H200); 8 = margin 7.6×"),
    _key("fp32-fastmath", "fp32"): PairTolerance(
        point_k=8.0, max_over_fraction=1e-5,
        why="measured ≤ 1.84·u (cuda-fastmath vs c_ref fp32 on an H200); 8 = margin 4.3×"),
    _key("fp32-fastmath", "fp32-fastmath"): PairTolerance(
        point_k=8.0, max_over_fraction=1e-5,
        why="as fast-math against fp32 (two fast-math builds differ by no more than each from fp32)"),
}

INVARIANTS = {
    "fp64": InvariantTolerance(
        segment_k=16, shell_k=32,
        why="measured segment ≤ 0.80·ε·E, shell depth ≤ 3.0·ε·rc (binary allows 16)"),
    "fp32": InvariantTolerance(
        segment_k=16, shell_k=32,
        why="measured segment ≤ 0.80·ε·E, shell depth ≤ 17.0·ε·rc (binary allows 16)"),
    "fp32-fastmath": InvariantTolerance(
        segment_k=16, shell_k=32,
        why="measured segment ≤ 1.60·ε·E, shell depth ≤ 16.5·ε·rc (cuda-fastmath on an H200)"),
}

# `harness diff --exact`: bit-identical, for runs that must not differ at all (thread
# count, block size, strand order, the same build twice).
EXACT = PairTolerance(point_k=0.0, max_over_fraction=0.0, why="bit-identical required (--exact)")


def pair_tolerance(kind_a, kind_b):
    return PAIRS[_key(kind_a, kind_b)]


def invariant_tolerance(kind):
    return INVARIANTS[kind]


# ---- the simd CPU variant's simulate stage against ref (docs/cpu_simd.md, "The dynamic
# model"; tests/test_cpu_simd_dynamic.py) ----
# Without gusts simd is ref's bits (positions, velocities, observables): no tolerance, the
# tests compare with np.array_equal. With gusts the sine is libmvec's (≤ 4 ulp) and the
# runs drift by roundings: each quantity within k units, ε the precision's epsilon,
# E = R + h + L, h = Δt/S the substep, ℓ the segment length.
@dataclass(frozen=True)
class SimdDynTolerance:
    position_k: float       # |Δx| ≤ k·ε·E at every point of every frame
    velocity_k: float       # |Δv| ≤ k·ε·E/h (v = Δp/h: a position rounding over h)
    kinetic_energy_k: float  # |ΔKE| ≤ k·ε·KE, every frame
    stretch_k: float        # |Δ stretch_max| ≤ k·ε·E/ℓ
    penetration_k: float    # |Δ penetration_max| ≤ k·ε·E
    why: str


# Measured (2026-11-22, gcc 12.2, glibc 2.36; the tests' runs: 300 strands × 33 points from
# ref init,collide states of seeds 1, 7, 123, 10 frames of S = 3, I = 2, xpbd and ftl,
# wind 300 + drag 1 + gust (A_g 0.8, f 3, λ 20) with the collider, and every feature on),
# worst over all of them, fp32 / fp64: positions 4.79 / 6.38 ε·E, velocities 1.6 / 1.8 ε·E/h,
# kinetic energy 0.30 / 1.52 ε·KE, stretch_max 0 / 0.19 ε·E/ℓ, penetration_max 0.05 / 0 ε·E.
# The bounds hold for such SHORT runs only: the difference is a rounding of the gust sine
# that the dynamics carries on, and a freely swinging strand (wind and gusts, no shape)
# amplifies it: after 60 frames of the same runs positions differed by up to 149 / 189 ε·E,
# velocities 47 / 38 ε·E/h, kinetic energy 6.4 / 19 ε·KE (2,000 strands × 32 points, S = 8,
# I = 2, 30 frames, the same gusts, fp32: up to 253 ε·E). With every feature on (shape holds the
# strands; 2,000 × 32, S = 8, I = 2, 60 frames) positions stayed ≤ 2.4 ε·E at every 10th
# frame, but the kinetic energy, small there, differed by up to 101 ε·KE.
# Margins over the 10-frame worst: 2.5× (positions), 4.4×, 5.3×, 5×, 20×.
SIMD_DYN_GUST = SimdDynTolerance(
    position_k=16.0, velocity_k=8.0, kinetic_energy_k=8.0, stretch_k=1.0, penetration_k=1.0,
    why="runs of ≤ 10 frames: measured ≤ 6.38 ε·E, 1.8 ε·E/h, 1.52 ε·KE, 0.19 ε·E/ℓ, 0.05 ε·E")
SIMD_DYN_GUST_MAX_FRAMES = 10  # the horizon the bounds were measured for
