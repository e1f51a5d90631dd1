"""The invariants of docs/model.md §2.7, checked on every frame of a state file.

  finite      no NaN or Inf anywhere
  roots       the root of every strand is bit-identical to frame 0's (roots never move
              after init)
  x_constant  x is bit-identical along each strand and through every frame (a strand
              lives in its slice plane x = x0)
  segments    every segment length equals ℓ = L/(P−1) within the precision's tolerance
  shell       after a collide frame no non-root point is inside its shell circle, radius
              rc = |(y0, z0)| + h, beyond the tolerance
  skipped     a skipped stage (wind with w = 0) left its frame bit-identical to the last

The tolerances are those of tolerances.py for the file's precision kind. `check` returns
the violations and the worst values seen (which `harness calibrate` reports).
"""

from dataclasses import dataclass, field

import numpy as np

from harness.core import tolerances

STRAND_CHUNK = 1 << 16  # strands read at a time, to bound memory on big files


@dataclass
class Violation:
    frame: int
    stage: str
    invariant: str
    count: int
    worst: float
    message: str

    def as_dict(self):
        return {
            "frame": self.frame,
            "stage": self.stage,
            "invariant": self.invariant,
            "count": self.count,
            "worst": self.worst,
            "message": self.message,
        }


@dataclass
class InvariantReport:
    path: str
    kind: str
    tolerance: tolerances.InvariantTolerance
    violations: list = field(default_factory=list)
    # worst values seen over all frames, in the units of the tolerance (for calibration):
    # segment-length error over ε·E, depth inside the shell over ε·rc (positive = inside)
    worst_segment_k: float = 0.0
    worst_shell_k: float = float("-inf")

    @property
    def ok(self):
        return not self.violations

    def as_dict(self):
        return {
            "path": self.path,
            "kind": self.kind,
            "ok": self.ok,
            "tolerance": {"segment_k": self.tolerance.segment_k, "shell_k": self.tolerance.shell_k},
            "worst_segment_k": self.worst_segment_k,
            "worst_shell_k": (None if self.worst_shell_k == float("-inf") else self.worst_shell_k),
            "violations": [v.as_dict() for v in self.violations],
        }


def _bits(a):
    return a.view(np.uint64 if a.dtype == np.float64 else np.uint32)


def is_collide_frame(state, f):
    # a fused wind frame holds the state after the wind half (the backend keeps it), so
    # only collide frames ("into-previous" ones included) must be outside the shell
    return state.stages[f] == "collide"


def read_strands(state, f, i0, i1):
    """Strands [i0, i1) of frame f as [n][P][3] in the file's dtype."""
    return state.strands(f, i0, i1)


class _Tally:
    """Counts and worst value of one invariant on one frame, over strand chunks."""

    def __init__(self):
        self.count = 0
        self.worst = 0.0

    def add(self, count, worst):
        self.count += int(count)
        if count:
            self.worst = max(self.worst, float(worst))


def check(state, tol=None):
    """Check every frame of an open State; return an InvariantReport."""
    kind = tolerances.kind_of(state.precision, state.fast_math)
    tol = tol or tolerances.invariant_tolerance(kind)
    report = InvariantReport(path=state.path, kind=kind, tolerance=tol)
    ell = state.segment_length
    h = float(state.params["hair_offset"])
    eps = tolerances.EPS[kind]
    seg_unit = eps * tolerances.extent(float(state.params["head_radius"]), h, state.hair_length)
    N, P = state.n_strands, state.points

    for f in range(state.n_frames):
        tallies = {name: _Tally() for name in ("finite", "roots", "x_constant", "segments", "shell", "skipped")}
        collide = is_collide_frame(state, f)
        for i0 in range(0, N, STRAND_CHUNK):
            i1 = min(N, i0 + STRAND_CHUNK)
            cur = read_strands(state, f, i0, i1)
            first = cur if f == 0 else read_strands(state, 0, i0, i1)

            bad = ~np.isfinite(cur)
            tallies["finite"].add(bad.sum(), 1.0)

            moved_root = np.any(_bits(cur[:, 0, :]) != _bits(first[:, 0, :]), axis=1)
            tallies["roots"].add(moved_root.sum(), 1.0)

            x_bits = _bits(np.ascontiguousarray(cur[:, :, 0]))
            x0_bits = _bits(np.ascontiguousarray(first[:, :1, 0]))
            tallies["x_constant"].add((x_bits != x0_bits).sum(), 1.0)

            c = cur.astype(np.float64)
            with np.errstate(invalid="ignore", over="ignore"):
                seg = np.sqrt(np.sum(np.diff(c, axis=1) ** 2, axis=2))
                seg_err = np.abs(seg - ell) / seg_unit
                worst_seg = np.nanmax(seg_err) if seg_err.size else 0.0
                report.worst_segment_k = max(report.worst_segment_k, float(worst_seg))
                over = ~(seg_err <= tol.segment_k)  # NaN counts as over
                tallies["segments"].add(over.sum(), worst_seg if over.any() else 0)

                if collide:
                    r = np.hypot(c[:, 1:, 1], c[:, 1:, 2])
                    rc = np.hypot(c[:, 0, 1], c[:, 0, 2])[:, None] + h
                    depth = (rc - r) / (rc * eps)  # > 0: inside the shell
                    if depth.size:
                        report.worst_shell_k = max(report.worst_shell_k, float(np.nanmax(depth)))
                    inside = ~(depth <= tol.shell_k)
                    tallies["shell"].add(inside.sum(), np.nanmax(depth) if inside.any() else 0)

            if state.skipped[f] and f > 0:
                prev = read_strands(state, f - 1, i0, i1)
                tallies["skipped"].add((_bits(cur) != _bits(prev)).sum(), 1.0)

        stage = state.stages[f]
        total_points = N * P
        messages = {
            "finite": lambda t: f"{t.count} coordinate(s) are NaN or Inf",
            "roots": lambda t: f"{t.count} root(s) moved since frame 0",
            "x_constant": lambda t: f"{t.count} point(s) left their strand's slice plane x = x0",
            "segments": lambda t: (
                f"{t.count} of {N * (P - 1)} segment length(s) differ from ℓ by more "
                f"than {tol.segment_k:g}·ε·E = {tol.segment_k * seg_unit / ell:.2e}·ℓ "
                f"(worst {t.worst:.3g}·ε·E)"
            ),
            "shell": lambda t: (
                f"{t.count} of {total_points} point(s) inside the shell circle by more "
                f"than {tol.shell_k:g}·ε·rc (worst {t.worst:.3g}·ε·rc)"
            ),
            "skipped": lambda t: f"skipped stage changed {t.count} coordinate(s)",
        }
        for name, t in tallies.items():
            if t.count:
                report.violations.append(
                    Violation(f, stage, name, t.count, t.worst, f"frame {f} ({stage}): {messages[name](t)}")
                )
    return report
