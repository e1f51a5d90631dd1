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
c_ref/paper/model.h), so shell_k must be above 16.

The measurements behind every number (`python -m harness calibrate` on the dev machine and
on an H200, `harness bench`, the simd and GPU test runs) are in docs/harness.md
("Tolerances, and the measurements behind them"), docs/decisions.md and docs/cpu_simd.md;
each tolerance's `why` names its worst measured value and margin.
"""

import math
from dataclasses import dataclass

import numpy as np

KINDS = ("fp64", "fp32", "fp32-fastmath")
EPS = {"fp64": 2.0**-52, "fp32": 2.0**-23, "fp32-fastmath": 2.0**-23}


def extent(head_radius: float, hair_offset: float, hair_length: float) -> float:
    """E = R + h + L: no coordinate of a state is larger."""
    return head_radius + hair_offset + hair_length


def point_unit(
    x0: np.ndarray,
    y0: np.ndarray,
    head_radius: float,
    hair_offset: float,
    hair_length: float,
    points: int,
    eps: float,
    root_differs: bool | np.ndarray = True,
) -> np.ndarray:
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
    point_k: float  # a point is over when |a − b| > point_k · u (point_unit)
    max_over_fraction: float  # fraction of the points of a frame allowed over
    why: str  # the measurement behind it (shown by `harness diff --json`)
    name: str = ""  # a named pair (named_pair), "" for a precision pair


@dataclass(frozen=True)
class InvariantTolerance:
    segment_k: float  # |segment − ℓ| ≤ segment_k · ε · E
    shell_k: float  # after collide: rc − |(y, z)| ≤ shell_k · ε · rc
    why: str


def kind_of(precision: str, fast_math: bool) -> str:
    """The precision kind of a state: fp64, fp32, or fp32-fastmath."""
    if precision == "fp32" and fast_math:
        return "fp32-fastmath"
    return precision


def _key(kind_a: str, kind_b: str) -> tuple[str, ...]:
    return tuple(sorted((kind_a, kind_b)))


PAIRS = {
    _key("fp64", "fp64"): PairTolerance(
        point_k=4.0,
        max_over_fraction=0.0,
        why="measured ≤ 1.08·u (cuda, cuda-strict and FMA-built c_ref vs c_ref, H200 and x86); "
        "4 = margin 3.7×; no branch flips allowed in fp64",
    ),
    _key("fp32", "fp64"): PairTolerance(
        point_k=4.0,
        max_over_fraction=1e-5,
        why="measured ≤ 0.88·u (c_ref and cuda fp32 vs c_ref fp64, 0 flips in 1.4e8 points); "
        "4 = margin 4.5×; ≤ 1e-5 of points may take the other side of a discrete decision",
    ),
    _key("fp32", "fp32"): PairTolerance(
        point_k=6.0,
        max_over_fraction=1e-5,
        why="measured ≤ 1.50·u (cuda and cuda-strict vs c_ref on an H200); 6 = margin 4×; "
        "≤ 1e-5 of points may take the other side of a discrete decision",
    ),
    _key("fp32-fastmath", "fp64"): PairTolerance(
        point_k=8.0,
        max_over_fraction=1e-5,
        why="measured ≤ 1.05·u (cuda-fastmath fp32 vs c_ref fp64 on an H200); 8 = margin 7.6×",
    ),
    _key("fp32-fastmath", "fp32"): PairTolerance(
        point_k=8.0,
        max_over_fraction=1e-5,
        why="measured ≤ 1.84·u (cuda-fastmath vs c_ref fp32 on an H200); 8 = margin 4.3×",
    ),
    _key("fp32-fastmath", "fp32-fastmath"): PairTolerance(
        point_k=8.0,
        max_over_fraction=1e-5,
        why="as fast-math against fp32 (two fast-math builds differ by no more than each from fp32)",
    ),
}

INVARIANTS = {
    "fp64": InvariantTolerance(
        segment_k=16, shell_k=32, why="measured segment ≤ 0.80·ε·E, shell depth ≤ 3.0·ε·rc (binary allows 16)"
    ),
    "fp32": InvariantTolerance(
        segment_k=16, shell_k=32, why="measured segment ≤ 0.80·ε·E, shell depth ≤ 17.0·ε·rc (binary allows 16)"
    ),
    "fp32-fastmath": InvariantTolerance(
        segment_k=16, shell_k=32, why="measured segment ≤ 1.60·ε·E, shell depth ≤ 16.5·ε·rc (cuda-fastmath on an H200)"
    ),
}

# Collide counts of two equivalent states (the record's moved_points) may differ by this
# fraction of the points: a point within rounding of the 16 ε·rc threshold is moved by one
# state and not the other, taking the rest of its strand with it, by far less than any
# position tolerance. The GPU tests' bound, kept as it was; no count difference has been
# recorded (docs/decisions.md).
MOVED_COUNT_FRACTION = 1e-3

# A drawn root lies on the head sphere: | |p0| − R | ≤ ROOT_ON_SPHERE_K · ε · R (the draw
# is a few roundings of R; docs/decisions.md).
ROOT_ON_SPHERE_K = 8

# `harness diff --exact`: bit-identical, for runs that must not differ at all (thread
# count, block size, strand order, the same build twice).
EXACT = PairTolerance(point_k=0.0, max_over_fraction=0.0, why="bit-identical required (--exact)")


# Pairs that the precision kinds do not tell apart: a variant or build against the oracle
# of the same precision. A named pair may be tighter than its precisions' rule, never looser.
NAMED_PAIRS = {
    # simd vs ref, same precision: the free arithmetic (docs/cpu_simd.md) with ref's decisions;
    # sin, cos, asin and atan2 from libmvec or c_ref/paper/fast_trig.h; the roots are bit-identical,
    # so u = ε·P·E.
    ("simd", "fp32"): PairTolerance(
        point_k=4.0,
        max_over_fraction=0.0,
        name="simd",
        why="measured ≤ 1.69·u (simd vs ref, free arithmetic, P = 2, wind; P ≥ 16 ≤ 0.18·u; the same in the "
        "x86-64-v3 and -v4 builds; docs/cpu_simd.md); "
        "4 = margin 2.4×; same roots and decisions, so no point may be over",
    ),
    ("simd", "fp64"): PairTolerance(
        point_k=4.0,
        max_over_fraction=0.0,
        name="simd",
        why="measured ≤ 1.16·u (simd vs ref, free arithmetic, P = 2; both builds; docs/cpu_simd.md); 4 = margin 3.4×",
    ),
    # cuda-strict vs c_ref, same precision: differs only where CUDA's sinf/cosf/asinf/atan2f
    # differ from glibc's; the precision pair's rule (docs/cuda.md, docs/harness.md).
    ("strict", "fp32"): PairTolerance(
        point_k=6.0,
        max_over_fraction=1e-5,
        name="strict",
        why="measured ≤ 1.50·u (cuda-strict vs c_ref fp32, H200); 6 = margin 4×; as fp32↔fp32",
    ),
    ("strict", "fp64"): PairTolerance(
        point_k=4.0,
        max_over_fraction=0.0,
        name="strict",
        why="measured ≤ 1.00·u (cuda-strict vs c_ref fp64, H200); 4 = margin 4×; as fp64↔fp64",
    ),
    # cuda-fastmath fp32 vs an fp32 state (c_ref, strict or normal build)
    ("fast-math", "fp32"): PairTolerance(
        point_k=8.0,
        max_over_fraction=1e-5,
        name="fast-math",
        why="measured ≤ 1.84·u (cuda-fastmath vs c_ref fp32, H200); 8 = margin 4.3×; as fast-math↔fp32",
    ),
}

# The two regressions of docs/decisions.md (short segments, P = 251): after the fixes the
# segment error stays within 2·ε·E (measured ≤ 0.71, 24 before); the shell bound is the
# precisions' own.
SHORT_SEGMENTS = InvariantTolerance(
    segment_k=2,
    shell_k=32,
    why="measured segment ≤ 0.71·ε·E at P = 251 after the half-angle and (rc − a)(rc + a) forms",
)
# Hand-made points inside the shell at the slice poles: collide lifts each onto its shell
# circle (the stability tests' bound was 1e-6·rc, about 8 ε·rc in fp32).
SLICE_POLES = InvariantTolerance(
    segment_k=2, shell_k=8, why="points lifted out by collide land on the shell; segments keep ℓ to a few roundings"
)


def pair_tolerance(kind_a: str, kind_b: str) -> PairTolerance:
    return PAIRS[_key(kind_a, kind_b)]


def named_pair(name: str, precision: str) -> PairTolerance:
    """The tolerance of a named pair ("simd", "strict", "fast-math") at `precision`."""
    try:
        return NAMED_PAIRS[(name, precision)]
    except KeyError:
        known = sorted({n for n, _ in NAMED_PAIRS})
        raise KeyError(f"no named pair '{name}' at {precision} (known: {', '.join(known)})") from None


def invariant_tolerance(kind: str) -> InvariantTolerance:
    return INVARIANTS[kind]


# ---- the dynamic model (docs/model.md §3): harness/check/invariants_dynamic.py, harness/check/diff_dynamic.py ----
# Measured on the 2-core dev machine with build/hairsim-cpu and with "other" = c_ref built
# with FMA contraction (`make BUILD=/tmp/hbfma CFLAGS_REF="-std=c11 -D_DEFAULT_SOURCE -O2
# -march=native -ffp-contract=fast -fno-fast-math -Wall" /tmp/hbfma/hairsim-cpu`), the
# stand-in for a port that rounds differently. Scenes: 1000 strands × 32 points, 30–60
# frames, xpbd and ftl, fp32 and fp64, each of: defaults (S = I = 1, gravity only); the
# dynamic default scene (S = 8, I = 2, bend 1e-6, shape 1e-4 range 0.5, drag 0.5, damping
# 0.5, wind 150 with gusts, nod); shake A = 0.5 S = 4; tilt + wind 300 without collider;
# collision margin 0.5 with I = 3 (and 5000 strands for the kinetic energy's sum order).
#
# Roots: the reference puts every root bit-exactly at Q(t)·X̄0 in all 40 runs (0 ULP). The
# FMA build contracts the rotation's products: ≤ 0.8·ε·R off (nod, shake and tilt,
# A = 0.5 rad, fp32 and fp64) (coordinates near 0 make that
# up to 1e4 ULP, hence a unit of ε·R, not ULPs). DYN_ROOT_K = 4 for non-reference builds.
DYN_ROOT_K = 4.0
# Collider: after a frame no non-root point lies inside R_c by more than 1.63·ε·R_c (fp32)
# and 1.60·ε·R_c (fp64), reference and FMA build alike; 8 is a 4.9× margin.
DYN_PENETRATION_K = 8.0
# FTL segments the collider did not move: |len − ℓ| ≤ 0.45·ε·E in every run (fp32 0.44,
# fp64 0.45, with and without the collider, FMA build 0.42); 4 is a 8.9× margin.
DYN_FTL_SEGMENT_K = 4.0
# Long-range attachments (docs/model.md §3.14): after a frame no point lies farther from its
# root than its bound s_L·k·ℓ by more than 2·ε of the precision, relative (the C reference,
# fp64, 40 strands × 12 points, 8 frames of an 8 Hz nod at A = 0.5 rad with α_s = 1e-3, no
# collider, I = 1, s_L = 1 and 1.05: 1·ε and 2·ε; without LRA the same scene is 2.4 bounds
# beyond). The projection's three roundings and the root's own; 8 is a 4× margin.
DYN_LRA_BOUND_EPS = 8.0
# Sag-free rest (docs/model.md §3.14): the still scene of tests/cpu/test_dynamic_followers.py
# (40 strands × 12 points, L = 30, S = 8, I = 2, α_b = 1e-6, α_g = 1e-4, ρ_g = 1, fp32, 120
# frames = 2 s, the collider on) moves at most 7.8e-5 L (xpbd) and 4.2e-4 L (ftl) from its
# rest shape with --sag-free (xpbd at I = 20, fp64: 2.9e-5 L: the rigid stretch against rest
# segments that are ℓ only to 5e-7), and 6.8e-3 L (xpbd) and 7.7e-3 L (ftl) without it.
# The bound with it: 1e-3 L (2.4× the worse solver); the sag without it: at least 3e-3 L.
DYN_SAGFREE_STILL_MAX_L = 1e-3
DYN_SAG_PLAIN_MIN_L = 3e-3
# Simulated-point LOD (docs/model.md §3.14): the spline through simulated points on a straight
# line stays on it to rounding: over 200 random lines per precision (50 strands each, 2–32
# points unevenly spaced, m = 2–5 rendered points a segment; harness/check/lod_dynamic.py, the same
# operations as the binaries) the farthest rendered point lies 17.7·ε (fp32) and 15.2·ε (fp64)
# of the strand's length off the line through its ends, the rounding of the simulated points
# themselves included; 64 is a 3.6× margin.
# Sag-free rest adds no stiffness (docs/model.md §3.14): the still scene of
# tests/cpu/test_dynamic_sagfree_swing.py (40 strands × 12 points, S = 8, I = 2, α_b = 1e-6,
# α_g = 1e-4, ρ_g = 1, fp32) hit by a steady wind (U = 600 cm/s, c_d = 0.5/s) swings at a median
# tip frequency of 15.70 / 15.70 Hz (xpbd, without / with) and 15.67 / 15.69 Hz (ftl) over 1 s:
# 2.5e-4 and 1.2e-3 relative apart. Damping ratios by observables.damping_fit (the envelope's
# decay): xpbd 0.1050 ± 0.0015 / 0.1053 ± 0.0010 (2.5e-3 apart); ftl 0.1074 ± 0.0026 /
# 0.0712 ± 0.0037, 34% apart, far past the fits' errors: with ftl, sag-free rest changes the
# swing's decay (an open finding; the earlier log-decrement estimator saw 0.1038 / 0.1042), so
# the damping bound holds for xpbd only. Bounds 5e-3 (4× the worse frequency) and 2e-2 (8× the
# xpbd damping ratios' difference).
DYN_SAGFREE_TIP_HZ_REL = 5e-3
DYN_SAGFREE_TIP_DAMPING_REL = 2e-2
DYN_LOD_STRAIGHT_EPS = 64.0
# The CUDA default build's rendering kernel (FMA contraction allowed) against the same
# operations without contraction, from the same simulated points: each rendered coordinate is
# at most 15 operations (knots, 5 weights, 6 lerps) on values bounded by the extent E = R + c_m
# + 2L; 32·ε·E allows each of them two contracted roundings. Derived, not yet measured on a
# GPU (tests/gpu/test_gpu_lod.py measures it).
DYN_LOD_KERNEL_K = 32.0
# Kinetic energy recomputed by the harness (strand by strand in order) against the file's
# (the binary sums in chunks of 1024 strands): bit-equal up to 1000 strands, ≤ 9.9e-15
# relative at 5000 strands (1.55e5 terms), ≤ 3.9e-16 for the FMA build. Rounding errors of
# a sum grow like √n·ε: at 1e6 strands × 31 that extrapolates to ≈ 1.4e-13, so 1e-11 keeps
# a 70× margin there (and 1000× at the sizes measured).
DYN_KINETIC_REL = 1e-11
# stretch_max and penetration_max (computed in double, §3.8) recomputed by the harness: bit
# for bit against the reference in every run (the checks require it there); the FMA build
# contracts the sums of squares: ≤ 1.0·ε64 of 1 + stretch or of R_c (8 runs: nod and
# shake, xpbd and ftl, fp32 and fp64, 30 frames); 8 is an 8× margin.
DYN_OBSERVABLE_K = 8.0
# One frame advanced from the same input (`harness stepdiff`): a point is over when the
# two results differ by more than DYN_STEP_K·ε·E·S·I. FMA build against the reference,
# P = 32, frames 1…38 of 40 of the dynamic default scene: worst 12.7·ε·E at S·I = 16
# (0.79 per substep-iteration; fp32 12.3, fp64 12.7; xpbd 12.7, ftl 10.7); xpbd fp64 at
# S = 2, I = 1: 0.89·ε·E (0.45 per); S = 16, I = 4: 30.3·ε·E (0.47 per); S = I = 1: 0.82.
# So ≤ 0.82·ε·E·S·I everywhere; DYN_STEP_K = 4 is a 4.9× margin. Measured at P = 32 only.
# Over many frames two correct builds drift apart (collisions, the solvers): this rule is
# for one frame from one input, not for whole trajectories.
DYN_STEP_K = {("fp64", "fp64"): 4.0, ("fp32", "fp64"): 4.0, ("fp32", "fp32"): 4.0}
DYN_STEP_WHY = (
    "one frame from the same input: FMA-contracted c_ref against c_ref ≤ 0.82·ε·E·S·I "
    "(xpbd and ftl, fp32 and fp64, S·I = 1 … 64, P = 32); 4 = margin 4.9×"
)
# The scene's own spread (harness/check/diff_dynamic.py, docs/judge.md): the same frame from the
# same input by the spread build (c_ref with FMA contraction, build/hairsim-cpu-contract); a
# point of a one-frame comparison is over only when farther than max(DYN_STEP_K·ε·E·S·I,
# DYN_SPREAD_K × the frame's largest spread), positions and h·|Δv| each with their own spread.
# Measured (2026-11-24, the dev machine, gcc 12.2, `python -m harness judge --gpu no`: 32
# strands, 3 frames, the last 2 stepped, fp32 and fp64): the simd variant against the
# reference on the 25 extreme scenes is ≤ 3.25 × the spread (stiff, fp32; ≤ 2.0 elsewhere),
# and ≤ 0.30·DYN_STEP_K·u; the spread itself ≤ 0.25·DYN_STEP_K·u there and ≤ 0.05 on the
# standard scenes. A 1000-strand, 200-point stiff-bend ftl gale at S = I = 1 (fp64, frames
# 20–30) gave simd ≤ 1.2 × the spread. 16 is a 4.9× margin over the worst ratio; it leaves
# the standard scenes' limit at the rule (16 × 0.05 < 1), so the planted defects keep their
# margins (each caught at ≥ 225 × its limit in fp32 and ≥ 1.3e8 × in fp64, the gust phase
# one substep late aside: 0.27 × in fp32, caught in fp64 only).
DYN_SPREAD_K = 16.0
DYN_SPREAD_WHY = (
    "one frame from the same input: an honest build ≤ 3.25 × the spread of the FMA-contracted c_ref "
    "(simd vs ref, 25 extreme scenes, fp32 and fp64); 16 = margin 4.9×"
)
# fp32 against fp64 of the same scene over a short horizon (tests/cpu/test_dynamic.py): 64
# strands × 16 points, S = I = 2, bend, shape, drag, damping, gusty wind, nod, seeds 1–3,
# xpbd and ftl, collider on and off: max |x32 − x64| ≤ 1.43e-6·L over frames 1–10 (the
# drift grows: up to 1.1e-5·L by frame 20, where a contact went the other way in fp32).
# 1e-5·L over at most 10 frames is a 7× margin.
DYN_FP32_VS_FP64_FRAMES = 10
DYN_FP32_VS_FP64_REL_L = 1e-5

# The paper model's uses (harness/studies/accuracy_verdicts_paper.py picks a mode for each): the
# end-to-end max position error over L each tolerates, this project's statements like the dynamic
# uses' below, not measurements: 1e-5·L (3 µm of a 30-cm strand, below any picture) for
# production runs and benchmarks, 1e-12·L (fp64 rounding over a run, so only fp64 modes) for
# references and validation; and the discretisation error a strand's point count may leave
# against the finest strand, 1e-2·L (3 mm: a clump's width).
PAPER_ACC_USES = ((1e-5, "production runs and benchmarks"), (1e-12, "references and validation"))
PAPER_ACC_RESOLUTION_L = 0.01

# The dynamic accuracy study (`python -m harness accuracy --model dynamic`,
# harness/studies/accuracy_dynamic.py). Its reference is xpbd fp64 with S doubled until, at every frame
# up to the horizon, the RMS difference between S and 2S over all points is under
# DYN_ACC_REF_FACTOR times the smallest RMS error any mode of the study has at that frame:
# the reference's own error is then about a tenth of the smallest error reported, or less
# (the rule, not a measurement; the convergence table of report/dynamic_accuracy.md
# shows it rung by rung, for the max measure too).
DYN_ACC_REF_FACTOR = 0.1
# The world study (harness/studies/accuracy_world_dynamic.py): a grid or collider variant counts as
# "close" to the best of its group when its RMS error against its own converged reference is at
# most WORLD_ACC_ERROR_FACTOR times the group's smallest; the verdict names the cheapest close
# one. A judgement, not a measurement: the quick study's grid errors span about 1.1× between its
# variants (the step's error dominates), its collider errors about 2× (friction off against on).
WORLD_ACC_ERROR_FACTOR = 2.0
# A GPU fp64 reference is used only when its first rung differs from the CPU's by less than
# DYN_ACC_GPU_REF_SHARE of that margin (RMS of GPU − CPU < 0.1 × 0.1 × the smallest RMS
# error, every frame up to the horizon): the GPU's rounding then cannot change a verdict.
DYN_ACC_GPU_REF_SHARE = 0.1
# The Pareto front treats RMS errors within DYN_ACC_FRONT_TIE (relative) as equal, so that
# a slower build or precision is not a front point by rounding alone. Measured (the full
# study on the 2-core dev machine: 256 strands, 1 s, horizon 0.5 s, 168 modes): at equal
# solver, S and I, the worst frame's RMS error of fp32 against fp64 differs by ≤ 1.8e-4
# relative for xpbd, ≤ 1.9e-3 for ftl up to S·I = 32 and 1.1e-2 for ftl at S = 32, I = 4
# (where ftl's error is 0.2·L, far from the front); simd against ref ≤ 9.0e-3 (the same
# mode). 2e-2 is 11× the worst below S = 32 and still far below the factor 1.4–2 between
# neighbouring S.
DYN_ACC_FRONT_TIE = 2e-2
# The recommendation of the study: per use, the budget a mode must meet over the horizon
# (RMS position error over L, stretch_max) and never blow up; the cheapest such mode is
# recommended. These are this project's statements of what each use tolerates, not
# measurements: L = 30 cm, so 5e-2·L is 1.5 cm of RMS drift over the horizon, 1e-2·L
# 3 mm, 2e-3·L 0.6 mm (about the width of a clump of a few dozen hairs). The stretch budgets
# follow the complaints of hair-solver users (stretchy strands): 10 % is visible but
# tolerable in a preview, 2 % is at the edge of what players notice, 0.5 % is not seen.
DYN_ACC_USES = {
    "previews": (5e-2, 0.10, "see the motion at a glance"),
    "games": (1e-2, 0.02, "real-time, stretch must not show"),
    "offline": (2e-3, 0.005, "film quality, close to the converged motion"),
}
# What each use tolerates of the long runs' observables (harness/studies/observables_long_dynamic.py),
# this project's statements like the budgets above: the swing's frequency off by at most this
# share (a quarter is a visibly different hair length in a preview; 10 % players do not read
# as wrong; 3 % an animator matching reference footage would not notice), the mean kinetic
# energy of the motion scene within this factor of the reference's (hair that is visibly livelier
# or deader reads as wrong: ×2 in a preview, ±50 % in a game, ±15 % offline), and rest jitter
# in pixels of what the user sees: the largest frame-to-frame move of any point on a still
# head after settling, at most `jitter_px` of a pixel at `lines` lines of picture with
# DYN_ACC_VIEW_CM of the scene across the picture's height (a head-and-shoulders shot). A
# move of a fraction of a pixel changes an edge pixel's coverage by that fraction: half a
# pixel is tolerable in a 720-line preview, a game's temporal anti-aliasing hides a quarter
# at 1080 lines, a film close-up at 2160 lines shows a tenth on a still frame. Not
# simulating moves nothing (0 px): every move is flicker the simulation adds; the report
# checks each budget against the reference's own largest move (the settled, converged
# motion is not flicker) and flags one that is not looser.
# The damping ratio of the released swing within `damping_rel` of the reference's (how fast the
# swing dies reads as the hair's weight and material: half again is a different hair in a
# preview, a quarter in a game, 10 % offline), judged like the frequency.
DYN_ACC_USES_LONG = {
    "previews": dict(freq_rel=0.25, damping_rel=0.5, kinetic_factor=2.0, jitter_px=0.5, lines=720),
    "games": dict(freq_rel=0.10, damping_rel=0.25, kinetic_factor=1.5, jitter_px=0.25, lines=1080),
    "offline": dict(freq_rel=0.03, damping_rel=0.10, kinetic_factor=1.15, jitter_px=0.1, lines=2160),
}
# What each use allows beyond the reference ensemble's own spread in the metrics that survive
# chaos (harness/check/ensemble_dynamic.py), this project's statements like the budgets above: the tip's
# distribution shifted by the use's RMS budget (the same displacement the pointwise budget
# tolerates, now of the statistics), the silhouette's area off by a share of it (a tenth is a
# visibly fuller head of hair in a preview, 5 % in a game, 2 % offline) and the curvature
# distribution by a share of the mean curvature (a quarter, a tenth, 3 %: the mean curvature of
# straight draped hair is small, about 0.076/cm, so its share moves with the drape's sag, which
# the stretch budget already judges). Statistics are taken over windows of DYN_ENSEMBLE_WINDOW_S
# (a quarter of the nod's and the gusts' period: the motion's phase, not its frame).
DYN_ACC_USES_CHAOS = {
    use: dict(
        tip_L=DYN_ACC_USES[use][0],
        curvature_rel=curv,
        envelope_rel=area,
        kinetic_factor=DYN_ACC_USES_LONG[use]["kinetic_factor"],
    )
    for use, curv, area in (("previews", 0.25, 0.10), ("games", 0.10, 0.05), ("offline", 0.03, 0.02))
}
DYN_ENSEMBLE_WINDOW_S = 0.25
DYN_ACC_VIEW_CM = 40.0  # scene height across the picture (L = 30 cm of hair below a head)


# PREDICTABILITY (harness/check/predictability_dynamic.py, harness/studies/predictability_dynamic.py). A twin
# run's one frame is perturbed by DYN_LYAPUNOV_PERTURBATION_L (RMS over the points, ·L): far
# above fp64's rounding of a coordinate (2.2e-16 × 40 cm ≈ 9e-15 cm, 3e-16·L) and far below any
# error a study ranks, so its growth is the model's own. The rate λ is fitted to ln(separation)
# where the separation lies between DYN_LYAPUNOV_FLOOR × the perturbation (a random
# perturbation first aligns with the growing direction: its first e-fold or two are not the
# rate) and DYN_LYAPUNOV_CEILING_L (eight decades below the motion's size, 1e-4·L = 3 µm: the
# growth is still linear there). These are choices of the method, not measurements; the tests
# (tests/unit/test_predictability.py) recover known rates with them: the tent map's ln 2 per
# step exactly, an unstable linear oscillator's k to 0.5 %.
DYN_LYAPUNOV_PERTURBATION_L = 1e-12
DYN_LYAPUNOV_FLOOR = 10.0
DYN_LYAPUNOV_CEILING_L = 1e-4
DYN_LYAPUNOV_TWINS = 3  # perturbed twins a scene (their log separations averaged); the ensemble's members
# The predictability time: how long a difference of fp32's rounding of a coordinate
# (2⁻²⁴·L, the smallest difference two modes of a study have: fp32 against fp64 of one mode)
# takes to grow to the games budget of the dynamic accuracy study (DYN_ACC_USES, 1e-2·L) at the
# rate λ: ln(1e-2/2⁻²⁴)/λ = 12.0/λ. Beyond it two runs that differ in rounding alone differ by
# more than a game tolerates, so a pointwise error no longer ranks modes: the studies judge
# pointwise errors only up to it and compare statistics (harness/check/ensemble_dynamic.py) beyond.
DYN_PREDICT_SEED_L = 2.0**-24
DYN_PREDICT_TOLERANCE_L = DYN_ACC_USES["games"][0]


def jitter_budget_cm(use: str) -> float:
    """The use's rest-jitter budget (largest frame-to-frame move) in cm."""
    lb = DYN_ACC_USES_LONG[use]
    return lb["jitter_px"] * DYN_ACC_VIEW_CM / lb["lines"]


# ---------------------------------------------------------------------------------------
# ANALYTIC CHECKS of the dynamic model (docs/model.md §4; tests/cpu/test_analytic.py; the full
# S sweeps in docs/analytic.md, made by `python -m harness analytic`). Measured on the
# C reference, fp64, --threads 1, Δt = 1/60 s, g0 = 981 cm/s², --iterations 1, at commit
# 87dab6c's model (dynamics_impl.h). Relative errors are |measured − expected|/expected.
#
# Pendulum (§4.1): P = 2, ℓ = 30 cm, rigid, released from rest; period from the zero
# crossings of z over the first 3 periods, against 4√(ℓ/g)·K(sin²(θ0/2)). At P = 2 the FTL
# pass is the rigid stretch projection and the tip gets no FTL correction, so ftl and xpbd
# are the same scheme (the periods agree to ≤ 1.0e-12 relative over S = 1…128: rounding).
#   θ0 = 0.1: S = 2, 8, 32 → 5.1e-4, 2.9e-5, 1.69e-5 (both solvers)
#   θ0 = 2.0: S = 2, 8, 32 → 0.184, 0.104, 0.0400   (both solvers; mostly the amplitude
#             the position-based step loses: 2.0 rad decays to 1.75 rad by the 4th period at S = 32)
ANALYTIC_PENDULUM_SMALL_REL = 5e-5  # θ0 = 0.1 at S = 32 (measured 1.69e-5; margin 3×)
ANALYTIC_PENDULUM_LARGE_REL = 0.05  # θ0 = 2.0 at S = 32 (measured 0.0400; margin 1.25×:
# the error is a smooth, deterministic ~1/S decay)
ANALYTIC_TREND_SLACK = 0.10  # error(S_next) ≤ (1 + slack)·error(S) along the test's S
# (measured ratios ≤ 0.59 for the pendulum, ≤ 0.10 chain)
ANALYTIC_FTL_XPBD_P2_REL = 1e-11  # |T_ftl − T_xpbd|/T at P = 2 (measured ≤ 1.0e-12 over S = 1…128)
# Wind (§4.2): P = 2 hanging straight down, c_d = 1/s, β = 10/s, no gusts, 8 s (480 frames);
# (U, ψ) = (250, 0), (981, 0), (3000, 0), (981, π), (981, 0.5); S = 1 and 8; both solvers:
# |θ − θ_expected| ≤ 2.2e-13 rad and θ changed by ≤ 1.6e-13 rad over the last second. The
# equilibrium is exact in the discrete scheme at any h, so the tolerance covers only settling
# and rounding. The rounding floor grows like 1/h²: the restoring displacement per substep,
# h²·|a|·δθ, rounds away once it is below the ulp of a coordinate, so the particle can rest
# anywhere within δθ ≈ u·ℓ/(h²·|a|) (u the unit roundoff) of the equilibrium: at S = 64 the
# angle is up to 1.6e-11 rad off (docs/analytic.md), so the test stays at S ≤ 8.
ANALYTIC_WIND_ANGLE_ABS = 2e-12  # rad (9× the worst measured at S ≤ 8)
# Hanging chain (§4.3): L = 30 cm, rigid links, no bend, displaced by 0.3 cm × the continuum
# first mode; ω from the zero crossings of the first-mode coordinate over 4 periods, against
# the linearised discrete chain's ω1 (harness.studies.analytic_dynamic.discrete_chain_omega1). ftl runs with
# --ftl-damping 1: with the default s = 0.9 it converges (in S) to a different frequency,
# 13% (P = 32) and 33% (P = 64) above the chain's (docs/analytic.md).
#   xpbd      P = 32: S = 64, 256 → 6.0e-4, 4.2e-5;  P = 64: 2.4e-3, 1.6e-4
#   ftl, s=1  P = 32: S = 64, 256 → 1.2e-4, 1.2e-5;  P = 64: 4.7e-4, 3.4e-5
ANALYTIC_CHAIN_REL = 5e-4  # at S = 256 against the discrete chain (worst 1.6e-4; 3×)
# Against the continuum ω1 = (j01/2)√(g/L) the allowance is the discretisation gap
# |ω1_discrete/ω1_continuum − 1| (computed: 7.93e-3 at P = 32, 3.94e-3 at P = 64, ≈ 0.25/P)
# plus ANALYTIC_CHAIN_REL.
# fp32 (same runs, --precision fp32): a substep moves a particle by about h²·|a|, and once
# that is a few ulps of a coordinate the step cannot resolve it, so fp32 converges in S only
# up to S ≈ 8 at Δt = 1/60 (docs/analytic.md: at S = 128 the pendulum period is 1.3% off, at
# S = 256 the wind angle 0.13 rad off). The tests check fp32 at S = 8 only:
#   pendulum θ0 = 0.1, S = 8: 4.1e-5 (xpbd), 4.8e-5 (ftl)
#   wind, the five (U, ψ) above, S = 1 and 8: ≤ 8.7e-5 rad (estimate u·ℓ/(h²·|a|) = 3e-4 at S = 8)
ANALYTIC_FP32_PENDULUM_REL = 1.5e-4  # θ0 = 0.1 at S = 8 (worst 4.8e-5; margin 3×)
ANALYTIC_FP32_WIND_ANGLE_ABS = 5e-4  # rad at S ≤ 8 (worst 8.7e-5; below the 3e-4 rounding estimate ×1.7)


# ---- the simd CPU variant's simulate stage against ref (docs/cpu_simd.md, "The dynamic
# model"; tests/cpu/test_cpu_simd_dynamic.py) ----
# simd computes the model with free arithmetic (rsqrt + one Newton step in fp32, reciprocals
# of the constant denominators), so it is judged as the GPU normal build is: one frame from
# the same input by DYN_STEP_K (harness.check.diff_dynamic.compare), no constant of its own. Measured
# (2026-11-23, gcc 12.2, the tests' scenes: 300 strands × 16 and 33 points from ref
# init,collide states of seeds 1, 7, 123, S = 3, I = 2, every feature set, xpbd and ftl,
# stepping from the last paper frame and from a simulated frame): worst 0.53·ε·E·S·I in fp32
# and in fp64 (xpbd; ftl 0.38 / 0.47), a 7.5× margin under DYN_STEP_K = 4.


# ---- the dynamic model on the GPU (tests/gpu/test_gpu_dynamic.py, harness bench) -----------------
# One simulated frame on the GPU from the CPU's frame k (positions and velocities, --input
# --input-frame), against the CPU's frame k+1, judged by harness.check.diff_dynamic.compare: the
# DYN_STEP_K rule above on positions and on h·|Δv|, the observables within what the two
# states' difference allows. The same function judges `harness stepdiff` and the bench's
# validation, so a test and the bench cannot disagree about a GPU state.
#
# The strict build (no FMA contraction, IEEE division and square root, no flush to zero)
# evaluates the model with +, −, ×, ÷ and sqrt only, each correctly rounded, in the order of
# c_ref/dynamic/dynamics_impl.h (cuda/dynamic/model.cuh; the host check shows the port reproduces the
# C reference bit for bit with glibc's libm). So without gusts it must equal the CPU bit for
# bit, observables included (GPU_DYN_STRICT_EXACT_WITHOUT_GUSTS; the observables' reduction
# is the CPU's, chunk by chunk in strand order); with gusts CUDA's sinf/sin (≤ 2 ulp from
# the correctly rounded value) perturb the wind factor and the frame carries that along.
# Measured on an H200 (tests/gpu/test_gpu_dynamic.py, 1500 strands × 32 and 45 points, S = 8,
# I = 4, every feature, both solvers, strand/warp/warpreg, blocks 32…1024;
# build/gpu_dyn_test_errors.json): worst |Δx|/L 5.0e-7 (normal fp32), 6.3e-7 (fast-math
# fp32), 2.3e-7 (strict fp32, gusts), 1.0e-15 (normal fp64); worst h·|Δv|/L 3.2e-7 (fp32),
# 3.8e-16 (fp64). The DYN_STEP_K rule allows 4·ε·E·S·I = 6.1e-4 cm = 2.0e-5·L in fp32 and
# 1.1e-12 cm = 3.8e-14·L in fp64 there: margins of 32 and 38 over the worst measured.
# A later H200 run (revision ce6aae1, one xdist worker's share of the tests) saw |Δx|/L
# 1.3e-6 (normal fp32), 8.6e-7 (fast-math fp32), 3.4e-15 (normal fp64), h·|Δv|/L 7.3e-7
# (fp32), 1.3e-15 (fp64): margins of 15 and 11, the smallest seen.
GPU_DYN_STRICT_EXACT_WITHOUT_GUSTS = True
# ---- beside a peer: Bender's PositionBasedDynamics (pypbd) on chains (harness/studies/peer_dynamic.py,
# tests/cpu/test_peer.py; the mapping and the differences in docs/decisions.md, "The peer") ----
# The converged reference of `harness peer`: S doubles until the largest change of a point
# from S to 2S is below this fraction of the smallest error the comparison reports.
PEER_REF_FRACTION = 0.1
# The peer runs the same scheme as our xpbd for these chains (docs/decisions.md), so its
# trajectories equal our fp64 runs up to rounding, which the swinging chain amplifies with
# the substeps taken. Measured (pypbd 2.2.2 against hairsim-cpu fp64, P = 32, L = 30 cm,
# rigid, tilts 30°, 60°, 90°, Δt = 1/60 s), max |Δx|/L over 30 frames: S = 8, I = 1:
# 2.1e-13; S = 8, I = 4: 1.5e-13; S = 32: 2.8e-12; S = 128: 6.5e-11; S = 256: 2.4e-10;
# S = 512: 5.3e-10, i.e. at most 3.4e-14·L per substep taken (S × frames). Soft links
# (α = 1e-6 and 1e-4, S = 8, I = 2): 1.4e-13 and 4.2e-13. Over 60 frames at S = 128 the
# drift reached 1.3e-8·L: the rule below is for horizons of ≤ 30 frames.
PEER_SAME_SCHEME_PER_SUBSTEP = 2e-13  # ·L per substep taken (6× the worst measured rate)
# A doubled stiffness (α/2 for α = 1e-6) moved the same run by 0.064·L: the rule separates
# a wrong mapping from rounding by eight orders of magnitude.
# Pendulum (docs/model.md §4.1: P = 2, ℓ = 30 cm, rigid, θ0 = 0.1 and 2.0 rad, S = 8 and 32):
# the peer's period equals ours to ≤ 1.3e-12 relative (both 1.69e-5 from the closed form at
# θ0 = 0.1, S = 32, the ANALYTIC_PENDULUM_SMALL_REL case).
PEER_PERIOD_REL = 1e-11  # |T_peer − T_ours|/T (worst measured 1.3e-12; margin 7.7×)
# A rigid chain (P = 32, tilts 60° and 90°, 30 frames, I = 1) stretches by max |len/ℓ − 1| =
# 0.068 (S = 32), 4.0e-3 (S = 128), 1.17e-3 (S = 256), 3.2e-4 (S = 512), the same in both
# solvers to 1e-12 (they share the scheme): XPBD holds the length as S grows.
PEER_RIGID_STRETCH_S256 = 2e-3  # both solvers at S = 256 (measured 1.17e-3; margin 1.7×)


# ---- verdicts of the dynamic stability map (harness/studies/stability_dynamic.py, docs/decisions.md
# "Stability map of the dynamic model") ------------------------------------------------------
# These are not rounding tolerances but the lines a cell of the map is judged by; they live
# here because every number that judges a result does. Each is taken over every frame of
# the map's horizon (observables of docs/model.md §3.8, computed by the binary).
#
# Over-stretched: stretch_max > STABILITY_STRETCH_MAX (a segment 10 % longer or shorter than
# ℓ). Hair keratin is elastic only to about 2 % strain; a strand drawn 10 % longer than its
# rest length reads as rubber in an animation. The bound is a judgement of what is visible,
# far above rounding (the rigid FTL chain of the still scene measures ≤ 1.2e-3 at S ≥ 2, the
# collider moving a point it had placed) and far below the failures the map exists to find
# (xpbd at S = 1 on the still scene: 14.4, i.e. 1440 %, and blown up).
STABILITY_STRETCH_MAX = 0.10
# Penetrating: penetration_max > STABILITY_PENETRATION_REL · R_c (1e-3·R_c = 0.1 mm at the
# default R = 10 cm, about one hair diameter). The contract's own bound after a frame is
# DYN_PENETRATION_K·ε·R_c (rounding, ≤ 1e-6·R_c in fp32); a cell between the two is a
# contract violation that the map's check column reports, not a visible penetration. The
# collider is a projection run last in every iteration (xpbd) and on every FTL point, so
# the map measured ≤ 1.9e-7·R_c in all 844 CPU cells: no cell is penetrating.
STABILITY_PENETRATION_REL = 1e-3
# Blown up: the model's own definition (§3.8: NaN/Inf, or a point farther than 2L from its
# root), the files' blown_up_strands observable; no bound of the harness.


# ---------------------------------------------------------------------------------------
# OBSERVABLES of the accuracy study (harness/check/observables_dynamic.py) on runs with known answers
# (tests/cpu/test_observables_runs.py). Measured on the C reference, fp64, --threads 1,
# Δt = 1/60 s, g0 = 981 cm/s², xpbd, pendulum P = 2, ℓ = 30 cm, θ0 = 0.05, 400 frames.
# Tip frequency (spectral peak, Hann window, 16× zero padding, parabola through the log
# peak) against 1/T(θ0): S = 16 and 64 → −4.34e-5, −4.34e-5 relative (the estimator's floor,
# not the scheme's).
OBS_TIP_FREQUENCY_REL = 2e-4  # measured 4.3e-5; margin 4×
# Damping ratio (observables.damping_fit: the decay of the swing's envelope) with --damping
# 0.5 against β/(2ω0): S = 64, 256 → +1.68e-2, +4.06e-3, the fit's standard error 1.1e-6
# (the scheme's own damping adds: undamped, ζ is 3.0e-3 at S = 16 and 7.6e-4 at S = 64).
OBS_DAMPING_RATIO_REL = 1e-2  # at S = 256 (measured 4.1e-3; margin 2.5×)
# Energy (½|v|² + g0·y per particle) of the undamped pendulum: xpbd loses, never gains, a
# share of the swing energy g0·ℓ·(1 − cos θ0) that falls like 1/S: over 400 frames
# S = 16, 64 → 0.203, 0.0551 (ratio 3.68 for 4× the substeps).
OBS_PENDULUM_ENERGY_LOSS_S64 = 0.08  # measured 0.0551; margin 1.45× (a smooth deterministic drift)
OBS_FIRST_ORDER_RATIO = (3.0, 5.0)  # loss(S = 16)/loss(S = 64), first order: 4 (measured 3.68)
# --solver rigid against an independent numpy rotation of the rest shape (fp64): both round
# the same products differently, a few ulps of 30 cm.
OBS_RIGID_ROTATION_ABS_L = 1e-13
# A strand resting on nothing (no gravity, no collider, still head, 8 strands × 8 points,
# S = 4, 30 frames, fp64): rigid does not move a bit; xpbd and ftl move points by at most
# 4.6e-14 and 3.6e-14 cm from frame to frame (the init shape's segments differ from ℓ by rounding).
OBS_REST_MOVE_ABS_L = 1e-14  # of L = 30 cm: 3e-13 cm (measured 4.6e-14 cm; margin 6.5×)
# The swing (harness.check.observables_dynamic.swing) of a hanging chain, P = 32, L = 30 cm, displaced
# 0.3 cm along the continuum first mode, xpbd fp64 S = 256, 300 frames (5.5 periods), against the
# linearised discrete chain's ω1/2π: −1.33e-4 relative (the scheme's 4e-5, tolerances above,
# plus the spectral estimate's floor over 5.5 periods).
OBS_CHAIN_SWING_FREQUENCY_REL = 5e-4  # measured 1.33e-4; margin 3.8×

# ---------------------------------------------------------------------------------------
# THE HAIR–HAIR GRID (docs/model.md §3.16; tests/cpu/test_hair_grid.py, tests/cpu/c/grid_known.c).
# A point adds rint((w·v)·2^10) to a node's momentum: a rounding of at most half of 2^-10 cm/s
# a contribution, so a node velocity V = P/M of points that all sit on the node is off their
# mean by at most that (measured on 200 points at one node: 2.1e-5 cm/s; a uniform field of
# 2000 points moved by at most 8.5e-4 cm/s, the Galilean shift's residue 2.8e-4 cm/s).
GRID_FIXED_POINT_VELOCITY = 2.0**-10  # cm/s a contribution (twice the rounding bound)

# The shipped example groom (configs/grooms/example.hair, tests/cpu/test_example_groom.py): the
# curly groom's init computed in double and written as float32. Made again on another machine,
# a libm that rounds a sine a few double ulps apart moves a float32 coordinate only where it sits
# on a rounding boundary, and then by one float32 ulp. Measured: 0 ulps (the file made again on
# the 2-core development machine equals the committed one bit for bit).
GROOM_EXAMPLE_ULPS = 1

# ---- the renderer (harness/render/gl, tests/unit/test_render.py) ---------------------------
# One step of an 8-bit channel: the shading tests compare a channel with its formula within
# 1.5 of it (the rounding to 8 bits is half a step; llvmpipe's fp32 shading adds far less).
RENDER_QUANTUM = 1.0 / 255.0
# The committed small scene (160×120) against a new render of it: at most `fraction` of the
# pixels may differ by more than `level` (0–255) in a channel, and the mean |Δ| over all
# channels at most `mean`. Measured (Mesa 22.3.6): llvmpipe with 1 or 2 threads, 128- or
# 256-bit vectors, 2 or 4 MSAA samples draws it identically (0 pixels, mean 0); without
# anti-aliasing (llvmpipe 0 samples, or softpipe) 6.6 % of the pixels differ by more than 24
# and the mean is 3.65. The bounds lie between: another driver's 4× MSAA passes, a renderer
# that lost its anti-aliasing (or its shading) fails.
RENDER_REFERENCE = {"level": 24, "fraction": 0.02, "mean": 2.0}

# ---------------------------------------------------------------------------------------
# MOTION TRACKS (--head-motion track, docs/model.md §3.2). A sinusoid θ(t) = A·sin(2πft)
# sampled every δ seconds and played as a track: slerp between two rotations about one axis
# moves the angle linearly in time, so its angle is off by at most δ²/8·max|θ''| =
# δ²/8·A·(2πf)² (linear interpolation's error bound), and a point at distance r from the head
# centre by at most r times that; plus the rounding of the samples' and the sinusoid's
# cosines and sines, TRACK_ROUND_K·ε·r. A derived bound, not a fit: measured on the C
# reference (fp64, 40 strands × 16 points, 30 frames, rigid: every point carried with the
# head) at δ = 1e-3 s, the worst point 4.09e-5 cm against its bound 4.95e-5 cm (r = 40.1 cm);
# at δ = 2e-3 s four times that, as a second-order interpolation gives.
TRACK_ROUND_K = 64.0


def track_sampling_bound(delta: float, amplitude: float, frequency: float, radius: object, kind: str) -> np.ndarray:
    """The most a point at distance `radius` from the head centre may differ between a sinusoidal
    motion and the same sinusoid sampled every `delta` seconds and played as a track."""
    angle = delta * delta / 8.0 * amplitude * (2.0 * math.pi * frequency) ** 2
    return np.asarray(radius, dtype=np.float64) * (angle + TRACK_ROUND_K * EPS[kind])


# ---------------------------------------------------------------------------------------
# HONEST TIMINGS (harness/core/timing.py, docs/decisions/honest-timings.md). A figure is noise
# when its relative standard deviation is above TIMING_MAX_RSD (nvbench's default stopping
# criterion, 0.5 %: a figure that never reaches it within the rule's timeout is reported with
# the spread it had), or when other processes used more than TIMING_OTHER_CORES cores on
# average while it ran (/proc/stat's busy time less the harness's and its children's own): the
# idle H200 node's background is far below it, and on the 2-core development machine, shared
# with other jobs, others used 2.0 cores throughout (measured over three 3 s windows: 1.997,
# 1.999, 2.001), which marks every figure measured there. A GPU figure is noise too when the
# GPU was TIMING_GPU_BUSY_PCT % busy just before its round (another process's kernels).
TIMING_MAX_RSD = 0.005
TIMING_OTHER_CORES = 0.5
TIMING_GPU_BUSY_PCT = 10.0
# Two figures tie when their bands, median·(1 ± max(TIMING_MAX_RSD, TIMING_TIE_K·rsd)),
# overlap: two standard deviations each side, about 95 % of a normal spread.
TIMING_TIE_K = 2.0

# A tip swings (observables.swings) when its dominant frequency fits OBS_SWING_MIN_PERIODS
# whole periods into the signal and it crosses its mean 2·2 − 1 = 3 times: the damping fit
# needs two periods (four half-period windows), and a drift's spectral peak sits at its lowest
# bins (the long runs printed 6.5e-5 Hz for modes that do not swing), never a frequency of the
# hair. A choice of the method, not a measurement.
OBS_SWING_MIN_PERIODS = 2
