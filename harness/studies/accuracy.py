"""Speed against accuracy, what the two models share: a mode (one binary and variant at a
precision; the dynamic model adds solver, substeps S and iterations I) and the position
error of a run against its reference. The measuring is studies/accuracy_paper.py and
studies/accuracy_dynamic.py; nothing here runs a binary, so the renderers may read it."""

import re
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from harness.core.variants import NO_DYNAMICS, Runner

NO_SIMULATION = NO_DYNAMICS  # hair carried rigidly with the head (docs/model.md §3.13)


def scheme_name(solver, ftl_damping=None):
    """ "xpbd", "ftl s=0.9" (ftl names its s), "rigid"."""
    if solver == "ftl" and ftl_damping is not None and ftl_damping == ftl_damping:
        return f"ftl s={float(ftl_damping):g}"
    return str(solver)


@dataclass(frozen=True)
class Mode:
    runner: Runner  # variant None: the binary's default variant (its --list-variants)
    precision: str
    solver: str | None = None
    substeps: int | None = None
    iterations: int | None = None
    label: str | None = None  # a paper mode's own name
    use: str = ""  # what a user would pick it for, in a few words
    ftl_damping: float | None = None  # ftl's s (docs/model.md §3.7); None for the other solvers

    @property
    def scheme(self):
        """The solver as the study names it: "xpbd", "ftl s=0.9", "rigid"."""
        return scheme_name(self.solver, self.ftl_damping)

    @property
    def name(self):
        if self.label is not None:
            return self.label
        if self.solver == NO_SIMULATION:
            return f"{self.runner.label} {self.solver} {self.precision}"
        return f"{self.runner.label} {self.scheme} S{self.substeps} I{self.iterations} {self.precision}"

    @property
    def tag(self):
        return self.name.replace(" ", "_")

    @property
    def timing_key(self):
        """What its time per frame depends on: all but ftl's s, one factor of the velocity
        update that no kernel branches on (modes alike but for s share one timed run)."""
        return (self.runner, self.precision, self.solver, self.substeps, self.iterations, self.label)

    def columns(self):
        """The mode's columns in a study's rows: its name and what picks its runs."""
        return dict(
            mode=self.name,
            backend=self.runner.backend,
            build=self.runner.build,
            variant=self.runner.variant,
            solver=self.solver,
            ftl_damping=self.ftl_damping,
            substeps=self.substeps,
            iterations=self.iterations,
            precision=self.precision,
        )


# the paper study's modes: the cpu ones run the cpu's default variant (the oracle), the gpu
# ones each build's default variant; accuracy_paper.modes() adds one fp32 mode for each
# other cpu variant the binary declares
PAPER_REFERENCE = "cpu fp64 ref"
PAPER_OTHER_CPU_USE = "fast CPU baseline"
PAPER_MODES = tuple(
    Mode(Runner(backend, build, None), precision, label=label, use=use)
    for label, backend, build, precision, use in (
        (PAPER_REFERENCE, "cpu", "default", "fp64", "ground truth"),
        ("cpu fp32 ref", "cpu", "default", "fp32", "the readable fp32 oracle"),
        ("gpu fp32 strict", "cuda", "strict", "fp32", "validation against the CPU"),
        ("gpu fp32 normal", "cuda", "default", "fp32", "production"),
        ("gpu fp32 fast-math", "cuda", "fastmath", "fp32", "previews"),
        ("gpu fp64", "cuda", "default", "fp64", "reference on the GPU"),
    )
)


def paper_uses():
    """Paper mode name -> what it is for (also for modes read back from a CSV)."""
    return {m.name: m.use for m in PAPER_MODES}


def frame_errors(x, ref, L):
    """RMS and max over the points of |x − ref| / L, for positions [..., N, P, 3]: one value
    per leading index (a float for one frame); NaN where either is not finite."""
    x = np.asarray(x, dtype=np.float64)
    ref = np.asarray(ref, dtype=np.float64)
    with np.errstate(invalid="ignore", over="ignore"):
        d = np.linalg.norm(x - ref, axis=-1)
        rms = np.sqrt(np.mean(d * d, axis=(-2, -1))) / L
        mx = np.max(d, axis=(-2, -1)) / L
    bad = ~np.isfinite(rms) | ~np.isfinite(mx)
    if np.ndim(rms) == 0:
        return (float("nan"), float("nan")) if bad else (float(rms), float(mx))
    rms[bad] = np.nan
    mx[bad] = np.nan
    return rms, mx


# ---- the dynamic study's results (results/dynamic-accuracy/), as the renderer reads them ----

RESULTS_NAME = "dynamic-accuracy"
# the world study's (studies/accuracy_world_dynamic.py): its folder, its CSV, and the scene whose grid and
# body it and the dynamic sweep's body groups take (configs/scenes/body.toml)
WORLD_RESULTS_NAME = "accuracy-world"
WORLD_CSV_NAME = "world.csv"
BODY_SCENE = "body"
DEFAULT_SCENE = "dynamic"  # the study's scene whose results and page carry no scene name


def scene_tag(scene):
    """'' for the default dynamic scene, else the scene's name (a path's stem) in letters,
    digits, '-' and '_': what keeps one scene's study apart from another's."""
    name = re.sub(r"[^A-Za-z0-9_-]+", "-", Path(str(scene)).stem).strip("-")
    return "" if name in ("", DEFAULT_SCENE) else name


def results_name(scene):
    """The study's results folder for a scene: dynamic-accuracy, or dynamic-accuracy-<scene>."""
    tag = scene_tag(scene)
    return f"{RESULTS_NAME}-{tag}" if tag else RESULTS_NAME


CSV_NAME = "dynamic_accuracy.csv"
# the frame budget's throughput curves of the study's modes (studies/budget_curves_dynamic.py)
CURVES_NAME = "budget-curves"
# The columns that name a dynamic mode and its run's size, in the order the studies' CSVs keep
# (budget_curves_dynamic.py, observables_long_dynamic.py).
MODE_COLUMNS = (
    "mode",
    "backend",
    "build",
    "variant",
    "solver",
    "ftl_damping",
    "substeps",
    "iterations",
    "precision",
    "strands",
    "points",
)
CURVES_CSV = "curves.csv"


def curves_name(scene):
    """The budget curves' folder for a scene: budget-curves, or budget-curves-<scene>."""
    tag = scene_tag(scene)
    return f"{CURVES_NAME}-{tag}" if tag else CURVES_NAME


ANALYTIC_NAME = "analytic.json"  # studies/analytic_table_dynamic.measure's data
ANALYTIC_MD = "analytic.md"  # the same as Markdown tables, kept by a study from before #47
# the reference family of the contract (docs/model.md §3.6), in its working precision fp64
REF_SOLVER, REF_PRECISION, REF_ITERATIONS = "xpbd", "fp64", 1

COLUMNS = (
    "study",  # mode | reference | gpu_check
    "mode",
    "backend",
    "build",
    "variant",
    "solver",
    "substeps",
    "iterations",
    "precision",
    "strands",
    "points",
    "frame",  # simulated frame, counted from 1
    "time_s",
    "rms_err_L",
    "max_err_L",
    "stretch_max",
    "penetration_max",
    "blown_up_strands",
    "time_per_frame_ms",  # the simulate stage's median over frames × repeats
    "time_per_frame_min_ms",  # its fastest (on a shared machine the median can be preempted)
    "time_strands",
    "threads",
    "block_size",
    "device",
    "ref_substeps",  # the reference rung compared with (mode, gpu_check) or 2S (reference)
)
# added with the no-simulation baseline and ftl's s axis: a table written before them (a
# committed reference run) still reads, these columns empty
LATER_COLUMNS = (
    "ftl_damping",  # ftl's s; empty for the other solvers
    "verdict",  # ok | diverged (NaN/Inf) | escaped (a point past 2L): blown up, split by cause
    "err_p50_L",  # percentiles over the points of |x − x_ref|/L
    "err_p95_L",
    "err_p99_L",
    "stretch_p99",  # 99th percentile over the segments of |len/ℓ − 1|
    "kinetic",  # per non-root particle: ½|v|² (cm²/s²)
    "potential",  # per non-root particle: g0·y (cm²/s²)
    "iou_front",  # silhouette overlap with the reference, seen from the front and the side
    "iou_side",
)
REQUIRED_COLUMNS = COLUMNS
COLUMNS = COLUMNS + LATER_COLUMNS
# the rows' `study`: mode | reference (the ladder, S against 2S) | gpu_check | ref_error (the
# final rung against two more doublings, and the Richardson estimate of what is left)


def smallest(errors):
    """Per frame, the smallest finite error over modes ({name: [F]}); NaN where none."""
    stack = np.array([e for e in errors.values()], dtype=np.float64)
    if stack.size == 0:
        return np.array([])
    with np.errstate(invalid="ignore"):
        stack[~np.isfinite(stack)] = np.inf
        out = stack.min(axis=0)
    out[~np.isfinite(out)] = np.nan
    return out


def holds_until(ok, times):
    """The last time up to which every frame passes; 0.0 when the first frame fails."""
    ok = np.asarray(ok, dtype=bool)
    bad = np.flatnonzero(~ok)
    if bad.size == 0:
        return float(times[-1]) if len(times) else 0.0
    return float(times[bad[0] - 1]) if bad[0] > 0 else 0.0
