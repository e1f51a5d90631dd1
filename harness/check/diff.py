"""Compare two state files frame by frame (docs/harness.md, "Equivalence"): `harness diff A.h5 B.h5`.

Per compared frame: the stage, max and RMS absolute error (Euclidean distance of a point
between the files, scene units), max error relative to the hair length L, the ULP
distance of the coordinates (p50, p99, max; counted in the coarser precision of the pair,
after both are rounded to it; errors themselves are computed in float64), the count of
points over tolerance and of non-finite points. Each file's invariants (invariants.py)
are checked on all its frames.

Exit status: 0 equivalent, 1 not equivalent (a frame over tolerance, any NaN/Inf, or an
invariant violated), 2 could not compare (unreadable file, layout mismatch, different N,
P or scene, missing frames, different stages).
"""

import json
import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from harness import HarnessError
from harness.check import invariants
from harness.core import tolerances
from harness.core.ulp import coarser, ulp_distance
from harness.io.states import State, StateError, as_text, open_state

EXIT_EQUIVALENT, EXIT_DIFFERENT, EXIT_CANNOT_COMPARE = 0, 1, 2
# "all", "last", or frame numbers / (frame in A, frame in B) pairs
Frames = str | Sequence[int | tuple[int, int]]
# scene attributes that must agree for a comparison to mean anything
SCENE_ATTRS = ("head_radius", "hair_offset", "hair_length", "face_margin", "seed")


@dataclass
class FrameDiff:
    frame_a: int
    frame_b: int
    stage: str
    compared: bool = True
    note: str = ""
    max_abs: float = 0.0
    rms_abs: float = 0.0
    max_rel_L: float = 0.0
    max_k: float = 0.0  # max of error / u (tolerances.point_unit): over when > point_k
    ulp_p50: float = 0.0
    ulp_p99: float = 0.0
    ulp_max: float = 0.0
    over: int = 0
    allowed_over: int = 0
    nonfinite: int = 0

    @property
    def ok(self) -> bool:
        return not self.compared or (self.nonfinite == 0 and self.over <= self.allowed_over)

    def as_dict(self) -> dict[str, Any]:
        d = dict(self.__dict__)
        d["ok"] = self.ok
        return {k: (None if isinstance(v, float) and not math.isfinite(v) else v) for k, v in d.items()}


@dataclass
class DiffResult:
    path_a: str
    path_b: str
    label_a: str
    label_b: str
    pair: str
    tolerance: tolerances.PairTolerance
    hair_length: float
    limit_range: tuple = (0.0, 0.0)  # smallest and largest point tolerance (scene units)
    frames: list = field(default_factory=list)
    invariants_a: Any = None
    invariants_b: Any = None

    @property
    def equivalent(self) -> bool:
        return (
            all(f.ok for f in self.frames)
            and self.invariants_a.ok
            and self.invariants_b.ok
            and any(f.compared for f in self.frames)
        )

    @property
    def exit_code(self) -> int:
        return EXIT_EQUIVALENT if self.equivalent else EXIT_DIFFERENT

    def failures(self) -> list[str]:
        out = [frame_failure(f, f"frame {f.frame_b}") for f in self.frames if not f.ok]
        for label, rep in (("A", self.invariants_a), ("B", self.invariants_b)):
            out += [f"{label} {v.message}" for v in rep.violations]
        if not any(f.compared for f in self.frames):
            out.append("no frame could be compared")
        return out

    def as_dict(self) -> dict[str, Any]:
        limits = {"point_limit_min": self.limit_range[0], "point_limit_max": self.limit_range[1]}
        limits["max_over_fraction"] = self.tolerance.max_over_fraction
        return result_dict(self, limits, [f.as_dict() for f in self.frames])


def frame_failure(f: Any, where: str) -> str:
    """A frame over its tolerance in one line; `where` names it ("frame 3", "step 12")."""
    if f.nonfinite:
        why = f"{f.nonfinite} non-finite point(s)"
    else:
        why = f"{f.over} point(s) over tolerance (allowed {f.allowed_over})"
    return f"{where} ({f.stage}): {why}, max error {f.max_abs:.3g}"


def result_dict(r: Any, limits: dict[str, Any], frames: list[Any], **extra: Any) -> dict[str, Any]:
    """The JSON of a comparison, the paper's (DiffResult) or the dynamic model's: `limits`
    the tolerance's own numbers, `extra` what the model adds after the frames."""
    return {
        "a": r.path_a,
        "b": r.path_b,
        "label_a": r.label_a,
        "label_b": r.label_b,
        "pair": r.pair,
        "equivalent": r.equivalent,
        "exit_code": r.exit_code,
        "tolerance": {"point_k": r.tolerance.point_k, **limits, "why": r.tolerance.why},
        "frames": frames,
        **extra,
        "invariants_a": r.invariants_a.as_dict(),
        "invariants_b": r.invariants_b.as_dict(),
        "failures": r.failures(),
    }


def parse_frames(spec: str | None) -> str | list[int]:
    """'all' | 'last' | comma-separated frame indices (negative from the end)."""
    spec = (spec or "all").strip()
    if spec in ("all", "last"):
        return spec
    try:
        return [int(s) for s in spec.split(",") if s.strip()]
    except ValueError:
        raise HarnessError(f"--frames must be 'all', 'last' or frame numbers like '3' or '1,3', not '{spec}'") from None


def frame_pairs(a: State, b: State, frames: Frames = "all", align_last: bool = False) -> list[tuple[int, int]]:
    """The (frame in A, frame in B) pairs to compare; StateError if they do not exist."""
    Fa, Fb = a.n_frames, b.n_frames
    if frames == "last":
        return [(Fa - 1, Fb - 1)]
    if frames == "all":
        if Fa != Fb and not align_last:
            raise StateError(
                f"frame counts differ: A has {Fa}, B has {Fb} (missing frames; "
                f"use --align-last, --frames last or --frame K to compare a part)"
            )
        n = min(Fa, Fb)
        return [(Fa - n + i, Fb - n + i) for i in range(n)]
    pairs = []
    if isinstance(frames, str):
        raise StateError(f"frames must be 'all', 'last' or frame numbers, not '{frames}'")
    for k in frames:
        ka, kb = k if isinstance(k, tuple) else (k, k)  # (frame in A, frame in B), or one for both
        for path, count, kk in ((a.path, Fa, ka), (b.path, Fb, kb)):
            if not -count <= kk < count:
                raise StateError(f"{path}: has no frame {kk} (it has {count})")
        pairs.append((ka % Fa, kb % Fb))
    return pairs


def check_comparable(a: State, b: State) -> None:
    """Raise StateError when A and B are not states of the same scene."""
    if (a.n_strands, a.points) != (b.n_strands, b.points):
        raise StateError(
            f"different sizes: A has {a.n_strands} strands × {a.points} points, B has {b.n_strands} × {b.points}"
        )
    for key in SCENE_ATTRS:
        va, vb = a.params.get(key), b.params.get(key)
        if va is None or vb is None:
            continue
        try:
            same = float(va) == float(vb)
        except (TypeError, ValueError):
            same = as_text(va) == as_text(vb)
        if not same:
            raise StateError(f"different scenes: {key} is {va} in A and {vb} in B")


def strand_units(a: State, b: State, i0: int, i1: int, eps: float) -> np.ndarray:
    """The error unit u of strands [i0, i1) (tolerances.point_unit), from both files'
    roots: the larger of the two (the smaller |x0| gives the larger unit), with the root
    terms only where the roots differ."""
    R, h = float(a.params["head_radius"]), float(a.params["hair_offset"])
    ra = invariants.read_strands(a, 0, i0, i1)[:, 0, :]
    rb = invariants.read_strands(b, 0, i0, i1)[:, 0, :]
    differs = np.any(ra.astype(np.float64) != rb.astype(np.float64), axis=1) | ~np.all(
        np.isfinite(ra) & np.isfinite(rb), axis=1
    )
    units = [
        tolerances.point_unit(
            r[:, 0].astype(np.float64), r[:, 1].astype(np.float64), R, h, a.hair_length, a.points, eps, differs
        )
        for r in (ra, rb)
    ]
    with np.errstate(invalid="ignore"):
        return np.fmax(units[0], units[1])


def compare_frame(
    a: State, b: State, fa: int, fb: int, tol: tolerances.PairTolerance, eps: float, ulp_dtype: Any
) -> FrameDiff:
    stage_a, stage_b = a.stages[fa], b.stages[fb]
    if stage_a != stage_b:
        raise StateError(f"frame {fa} of A is '{stage_a}' but frame {fb} of B is '{stage_b}' (different stage lists)")
    # a fused wind frame holds the state after the wind half (the cuda backend keeps it,
    # docs/interfaces.md), so it is compared like any wind frame
    fd = FrameDiff(fa, fb, stage_a)
    N, P = a.n_strands, a.points
    fd.allowed_over = int(math.floor(tol.max_over_fraction * N * P))
    sum_sq, n_finite = 0.0, 0
    ulps = []
    for i0 in range(0, N, invariants.STRAND_CHUNK):
        i1 = min(N, i0 + invariants.STRAND_CHUNK)
        xa = invariants.read_strands(a, fa, i0, i1)
        xb = invariants.read_strands(b, fb, i0, i1)
        finite = np.all(np.isfinite(xa), axis=2) & np.all(np.isfinite(xb), axis=2)
        fd.nonfinite += int((~finite).sum())
        with np.errstate(invalid="ignore", over="ignore"):
            dist = np.sqrt(np.sum((xa.astype(np.float64) - xb.astype(np.float64)) ** 2, axis=2))
            unit = strand_units(a, b, i0, i1, eps)[:, None]
            k = dist / unit
        good = finite & np.isfinite(k)
        if good.any():
            fd.max_abs = max(fd.max_abs, float(dist[good].max()))
            fd.max_k = max(fd.max_k, float(k[good].max()))
            sum_sq += float(np.sum(dist[good] ** 2))
            n_finite += int(good.sum())
        if tol.point_k == 0.0:  # exact: any difference is over
            over = (dist > 0) | ~finite
        else:
            over = ~(k <= tol.point_k) | ~finite
        fd.over += int(over.sum())
        both = np.isfinite(xa) & np.isfinite(xb)
        ulps.append(ulp_distance(xa[both], xb[both], ulp_dtype))
    fd.rms_abs = math.sqrt(sum_sq / n_finite) if n_finite else float("nan")
    fd.max_rel_L = fd.max_abs / a.hair_length
    u = np.concatenate(ulps) if ulps else np.zeros(0, np.uint64)
    if u.size:
        fd.ulp_max = float(u.max())
        fd.ulp_p50, fd.ulp_p99 = (float(v) for v in np.percentile(u.astype(np.float64), [50, 99]))
    return fd


def compare(
    path_a: str | Path,
    path_b: str | Path,
    frames: Frames = "all",
    align_last: bool = False,
    exact: bool = False,
    tolerance: tolerances.PairTolerance | None = None,
) -> DiffResult:
    """Compare two files; return a DiffResult. StateError (exit 2) if they cannot be.

    `frames`: "all", "last", or a list of frame numbers or (frame in A, frame in B) pairs.
    `tolerance`: a PairTolerance to use instead of the one of the files' precision kinds
    (tolerances.named_pair: a tighter rule for a pair the precisions do not tell apart)."""
    with open_state(path_a) as a, open_state(path_b) as b:
        check_comparable(a, b)
        pairs = frame_pairs(a, b, frames, align_last)
        kind_a = tolerances.kind_of(a.precision, a.fast_math)
        kind_b = tolerances.kind_of(b.precision, b.fast_math)
        tol = tolerances.EXACT if exact else (tolerance or tolerances.pair_tolerance(kind_a, kind_b))
        eps = max(tolerances.EPS[kind_a], tolerances.EPS[kind_b])
        result = DiffResult(
            path_a=str(path_a),
            path_b=str(path_b),
            label_a=a.label,
            label_b=b.label,
            pair=f"{kind_a}↔{kind_b}" + (" (exact)" if exact else f" ({tolerance.name})" if tolerance else ""),
            tolerance=tol,
            hair_length=a.hair_length,
        )
        R, h = float(a.params["head_radius"]), float(a.params["hair_offset"])
        # the unit's range: a root with |x0| = R (smallest) to one with x0 = y0 = 0 (largest)
        lo = tol.point_k * tolerances.point_unit(np.array([R]), np.array([0.0]), R, h, a.hair_length, a.points, eps)[0]
        hi = (
            tol.point_k * tolerances.point_unit(np.array([0.0]), np.array([0.0]), R, h, a.hair_length, a.points, eps)[0]
        )
        result.limit_range = (float(lo), float(hi))
        for fa, fb in pairs:
            result.frames.append(compare_frame(a, b, fa, fb, tol, eps, coarser(a.dtype, b.dtype)))
        result.invariants_a = invariants.check(a)
        result.invariants_b = invariants.check(b)
    return result


def format_result(r: DiffResult) -> str:
    t = r.tolerance
    lines = [f"A: {r.path_a} ({r.label_a})", f"B: {r.path_b} ({r.label_b})"]
    if t.point_k:
        lo, hi = r.limit_range
        lines.append(
            f"tolerance {r.pair}: a point is over when it differs by more than "
            f"{t.point_k:g}·u, u = ε·(P·E + R²/|x0| + R²/|(x0,y0)|) per strand "
            f"({lo:.2g} … {hi:.2g}, i.e. {lo / r.hair_length:.1e}·L … "
            f"{hi / r.hair_length:.1e}·L); at most {t.max_over_fraction:.4%} of points may be over"
        )
    else:
        lines.append(f"tolerance {r.pair}: {t.why}")
    head = (
        f"{'frame':>5} {'stage':8} {'max abs':>10} {'rms':>10} {'max/L':>10} {'max/u':>8} "
        f"{'ulp p50':>8} {'ulp p99':>8} {'ulp max':>10} {'over':>7} {'nan/inf':>7}  verdict"
    )
    lines.append(head)
    for f in r.frames:
        frame = f"{f.frame_a}" if f.frame_a == f.frame_b else f"{f.frame_a}/{f.frame_b}"
        if not f.compared:
            lines.append(f"{frame:>5} {f.stage:8} {f.note}")
            continue
        lines.append(
            f"{frame:>5} {f.stage:8} {f.max_abs:10.3e} {f.rms_abs:10.3e} {f.max_rel_L:10.3e} {f.max_k:8.3g} "
            f"{f.ulp_p50:8.0f} {f.ulp_p99:8.0f} {f.ulp_max:10.3g} {f.over:7d} {f.nonfinite:7d}  "
            f"{'ok' if f.ok else 'FAIL'}"
        )
    for label, rep in (("A", r.invariants_a), ("B", r.invariants_b)):
        if rep.ok:
            lines.append(f"invariants {label} ({rep.kind}): all hold")
        else:
            lines.append(f"invariants {label} ({rep.kind}): {len(rep.violations)} violated")
            lines += [f"  {v.message}" for v in rep.violations]
    if r.equivalent:
        lines.append("verdict: EQUIVALENT")
    else:
        lines.append("verdict: NOT EQUIVALENT: " + "; ".join(r.failures()[:3]))
    return "\n".join(lines)


def run(
    path_a: str | Path,
    path_b: str | Path,
    frames: Frames = "all",
    as_json: bool = False,
    out: Callable[[str], Any] = print,
    **options: Any,
) -> int:
    """`harness diff` on two paper-model files (`options`: compare()'s align_last, exact and
    tolerance); returns the exit status (dynamic files: harness/check/diff_dynamic.py, picked by
    the command line)."""
    chosen = parse_frames(frames) if isinstance(frames, str) else frames
    return report(lambda: compare(path_a, path_b, chosen, **options), format_result, path_a, path_b, as_json, out)


def report(
    comparison: Callable[[], Any],
    text: Callable[[Any], str],
    path_a: str | Path,
    path_b: str | Path,
    as_json: bool,
    out: Callable[[str], Any],
) -> int:
    """Run a comparison and print it (as text or JSON); its exit status. Either model's
    files: a StateError is exit 2 (EXIT_CANNOT_COMPARE), in one line or in the JSON."""
    try:
        result = comparison()
    except StateError as e:
        if as_json:
            out(json.dumps({"a": str(path_a), "b": str(path_b), "exit_code": EXIT_CANNOT_COMPARE, "error": str(e)}))
        raise HarnessError(f"cannot compare: {e}", code=EXIT_CANNOT_COMPARE) from None
    out(json.dumps(result.as_dict(), indent=1, ensure_ascii=False) if as_json else text(result))
    return int(result.exit_code)
