"""`harness diff` on dynamic files, and `harness stepdiff` (docs/model.md §3).

diff: frames of A and B are paired by **step** (the simulation's frame clock), not by
position in the file, so files written with different --output-every compare at their
common steps. Files of different solvers, or (for --frames all) whose trajectories end at
different steps, cannot be compared (exit 2, as the paper model's different frame counts).
Paper frames are compared as today (diff.compare_frame, the paper
tolerance); simulated frames with the dynamic per-frame rule: a point is over when A and
B put it farther apart than DYN_STEP_K·u, u = ε·E·S·I (E = R + h + L, ε of the coarser
precision, S substeps and I iterations of A), or when either is non-finite. That rule is for ONE frame advanced from the
same input (stepdiff); over many frames two correct builds drift apart (collisions and
the solvers amplify rounding), so a whole-trajectory diff of two backends is expected to
fail after a while and says so frame by frame: use stepdiff to validate a port. Where both
files stored the velocities of a compared step, they are judged by the same rule on
h·|Δv| (the position change a velocity makes in one substep). The observables of every
compared frame are printed side by side (A, B, B − A) and judged by what the two states'
difference allows (observables_ok). Each file's invariants (invariants_dynamic.py) are
checked on its compared frames. Two files written with --render-points (the same P_r and P_s)
are compared on their simulated rows (trajectory.simulated_view), to which every check above
applies, and each file's rendered rows are recomputed from its simulated ones
(lod.check_rendered: bit for bit for the reference build); a rendered file against a plain one
cannot be compared (exit 2). The GPU tests (tests/gpu/test_gpu_dynamic.py) judge with this
same function.

stepdiff: for each chosen simulated frame k of a reference A written with --velocities
all, run BIN --input A --input-frame k --stages simulate --frames 1 into a temporary
directory and compare BIN's new frame with A's frame k + 1 by the rule above.

SPREAD (docs/judge.md): the rule above does not know how sensitive a scene is, so a
one-frame comparison may also be judged against the scene's own spread: the same frame
from the same input by the spread build (build/hairsim-cpu-contract, the C reference with
FMA contraction on) and by the C reference, max |x_spread − x_ref| over the frame (and
h·|Δv| likewise). A point is
then over when it is farther than max(DYN_STEP_K·u, DYN_SPREAD_K·spread) (positions;
velocities with their own spread). `stepdiff`, the bench's validation, the GPU tests and
the stability search judge this way (`spread=True`); each spread is measured once per
reference file and frame in a process (two CPU runs from A's frame: the spread build and
build/hairsim-cpu, so that a wrong frame in A cannot widen its own spread).

Exit status as for diff: 0 equivalent, 1 not, 2 could not compare.
"""

import math
import os
import shutil
import tempfile
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from harness import HarnessError
from harness.check import diff, invariants_dynamic
from harness.check import lod_dynamic as lod
from harness.core import runner, tolerances
from harness.core.paths import build_dir, display
from harness.core.runner import COMPLETED
from harness.core.ulp import coarser, ulp_distance
from harness.io.states import StateError, as_text
from harness.io.trajectory import open_trajectory, simulated_view

OBS_SHOWN = ("stretch_max", "penetration_max", "kinetic_energy", "blown_up_strands")


def is_dynamic_file(path):
    from harness.core import inputs

    inputs.regular(path, "diff:")  # a FIFO would block any reader: refused here, before it
    try:
        with inputs.open_h5(path, "diff:") as f:
            return "parameters" in f and as_text(f["parameters"].attrs.get("model", "paper")) == "dynamic"
    except Exception:
        return False


def step_tolerance(kind_a, kind_b, exact=False):
    if exact:
        return tolerances.EXACT
    return tolerances.PairTolerance(
        point_k=tolerances.DYN_STEP_K[diff_key(kind_a, kind_b)], max_over_fraction=0.0, why=tolerances.DYN_STEP_WHY
    )


def diff_key(kind_a, kind_b):
    # fast math is not a separate dynamic rule yet (no measurement): its fp32 rule applies
    ka, kb = (k.replace("-fastmath", "") for k in (kind_a, kind_b))
    return tuple(sorted((ka, kb)))


@dataclass
class DynDiffResult:
    path_a: str
    path_b: str
    label_a: str
    label_b: str
    pair: str
    tolerance: object
    paper_tolerance: object
    unit: float
    hair_length: float
    frames: list = field(default_factory=list)  # diff.FrameDiff, with .step set
    observables: list = field(default_factory=list)  # per compared simulated frame: dict
    invariants_a: object = None
    invariants_b: object = None
    notes: list = field(default_factory=list)

    @property
    def equivalent(self):
        return (
            all(f.ok for f in self.frames)
            and not any(o.get("failures") for o in self.observables)
            and self.invariants_a.ok
            and self.invariants_b.ok
            and any(f.compared for f in self.frames)
        )

    @property
    def exit_code(self):
        return diff.EXIT_EQUIVALENT if self.equivalent else diff.EXIT_DIFFERENT

    def failures(self):
        out = [diff.frame_failure(f, f"step {f.step}") for f in self.frames if not f.ok]
        for o in self.observables:
            out += [f"step {o['step']}: observable {m}" for m in o.get("failures", [])]
        for label, rep in (("A", self.invariants_a), ("B", self.invariants_b)):
            out += [f"{label} {v.message}" for v in rep.all_violations()]
        if not any(f.compared for f in self.frames):
            out.append("no frame could be compared")
        return out

    def as_dict(self):
        frames = [dict(f.as_dict(), step=f.step) for f in self.frames]
        limits = {"unit": self.unit, "point_limit": self.tolerance.point_k * self.unit}
        limits.update(spread_k=tolerances.DYN_SPREAD_K, spread_why=tolerances.DYN_SPREAD_WHY)
        return diff.result_dict(self, limits, frames, observables=self.observables, notes=self.notes)


@dataclass(frozen=True)
class Spread:
    """A scene's own sensitivity at one step: how far the spread build's frame, advanced from
    the same input, lies from the reference's (largest over the frame's points; cm)."""

    step: int
    position: float  # max |x_spread − x_ref|
    velocity: float  # max h·|v_spread − v_ref| (nan where velocities were not stored)
    binary: str

    def limit(self, floor, velocity=False):
        """max(floor, DYN_SPREAD_K × spread): the judged limit of a point."""
        s = self.velocity if velocity else self.position
        return max(floor, tolerances.DYN_SPREAD_K * s) if math.isfinite(s) else floor


def spread_binary():
    """The spread build (`make cpu` builds it beside build/hairsim-cpu)."""
    return Path(os.environ.get("HAIRBENCH_SPREAD_BIN") or build_dir() / "hairsim-cpu-contract")


_SPREADS = {}


def _step_once(binary, reference, k, out, timeout):
    cmd = [str(binary), "--input", str(reference), "--input-frame", str(k), "--stages", "simulate"]
    cmd += ["--frames", "1", "--output", str(out), "--force", "--quiet"]
    try:
        p = runner.run_command(cmd, timeout=timeout)
    except runner.TimedOut:
        raise HarnessError(f"{display(binary)} did not finish within {timeout} s", code=2) from None
    if p.returncode not in COMPLETED:
        msg = (p.stderr.strip().splitlines() or [f"status {p.returncode}"])[-1]
        raise HarnessError(
            f"cannot measure the spread: {display(binary)} failed on frame {k} of {reference}: {msg}",
            code=diff.EXIT_CANNOT_COMPARE,
        )


def measure_spread(reference, k, binary=None, timeout=None):
    """The Spread of the step after frame k of `reference` (a file written with velocities):
    the spread build's frame against the C reference's (build/hairsim-cpu), both advanced
    from frame k, so a wrong frame k + 1 in the file cannot widen it. None when the spread
    build is not built. Cached per file (path, size, mtime), frame and build in this process."""
    binary = Path(binary) if binary else spread_binary()
    oracle = build_dir() / "hairsim-cpu"
    if not binary.exists() or not oracle.exists():
        return None
    st, bst = os.stat(reference), os.stat(binary)
    key = (str(Path(reference).resolve()), st.st_size, st.st_mtime_ns, int(k), str(binary.resolve()), bst.st_mtime_ns)
    if key in _SPREADS:
        return _SPREADS[key]
    with tempfile.TemporaryDirectory(prefix="hb-spread-") as tmp:
        ref_out, out = Path(tmp) / "oracle.h5", Path(tmp) / "spread.h5"
        _step_once(oracle, reference, k, ref_out, timeout)
        _step_once(binary, reference, k, out, timeout)
        with open_trajectory(ref_out) as a, open_trajectory(out) as b:
            step = int(a.step[-1])
            fd = compare_sim_frame(a, b, a.frame_at_step(step), b.frame_at_step(step), tolerances.EXACT, 1.0, a.dtype)
    vel = fd.velocity_max_abs if getattr(fd, "velocity_compared", False) else float("nan")
    sp = _SPREADS[key] = Spread(step, fd.max_abs, vel, display(binary))
    return sp


def spreads_for(path_a, a, steps):
    """{step: Spread} for the simulated steps of A that follow a frame one can step from."""
    cand = set(step_candidates(a))
    out = {}
    for s in steps:
        k = a.frame_at_step(s) - 1
        if k in cand:
            sp = measure_spread(path_a, k)
            if sp is not None:
                out[s] = sp
    return out


def _over(dist, finite, limit, exact):
    if exact:
        return (dist > 0) | ~finite
    return ~(dist <= limit) | ~finite


def compare_sim_frame(a, b, fa, fb, tol, unit, ulp_dtype, spread=None):
    """Positions, and the velocities where both files stored them at this step (|Δv|·h, the
    position change a velocity makes in one substep, on the positions' rule); with a Spread,
    each against max(the rule, DYN_SPREAD_K × the spread)."""
    fd = diff.FrameDiff(fa, fb, "simulate")
    exact = tol.point_k == 0.0
    floor = tol.point_k * unit
    fd.limit = spread.limit(floor) if spread and not exact else floor
    fd.spread = spread.position if spread else float("nan")
    xa, xb = a.frame(fa), b.frame(fb)
    finite = np.all(np.isfinite(xa), axis=2) & np.all(np.isfinite(xb), axis=2)
    fd.nonfinite = int((~finite).sum())
    with np.errstate(invalid="ignore", over="ignore"):
        dist = np.sqrt(np.sum((xa.astype(np.float64) - xb.astype(np.float64)) ** 2, axis=2))
    good = finite & np.isfinite(dist)
    if good.any():
        fd.max_abs = float(dist[good].max())
        fd.rms_abs = math.sqrt(float(np.mean(dist[good] ** 2)))
        fd.max_k = fd.max_abs / unit
    else:
        fd.rms_abs = float("nan")
    fd.over = int(_over(dist, finite, fd.limit, exact).sum())
    fd.max_rel_L = fd.max_abs / a.hair_length
    both = np.isfinite(xa) & np.isfinite(xb)
    u = ulp_distance(xa[both], xb[both], ulp_dtype)
    if u.size:
        fd.ulp_max = float(u.max())
        fd.ulp_p50, fd.ulp_p99 = (float(v) for v in np.percentile(u.astype(np.float64), [50, 99]))
    step = int(a.step[fa])
    va, vb = a.velocity_at_step(step), b.velocity_at_step(int(b.step[fb]))
    fd.velocity_compared = va is not None and vb is not None
    if fd.velocity_compared:
        h = fd.velocity_h = float(a.dynamic_params["frame_dt"]) / int(a.dynamic_params["substeps"])
        vfinite = np.all(np.isfinite(va), axis=2) & np.all(np.isfinite(vb), axis=2)
        with np.errstate(invalid="ignore", over="ignore"):
            vdist = h * np.sqrt(np.sum((va.astype(np.float64) - vb.astype(np.float64)) ** 2, axis=2))
        fd.nonfinite += int((~vfinite).sum())
        fd.velocity_max_abs = float(vdist[vfinite].max()) if vfinite.any() else float("nan")
        fd.velocity_limit = spread.limit(floor, velocity=True) if spread and not exact else floor
        fd.velocity_spread = spread.velocity if spread else float("nan")
        fd.velocity_over = int(_over(vdist, vfinite, fd.velocity_limit, exact).sum())
        fd.over += fd.velocity_over
    return fd


def observables_ok(row, fd, seg_len, exact):
    """Failures of one compared frame's observables. They are computed in double from each
    state, so they may differ only as the states do: equal bits where exact; else stretch
    by at most 2·max|Δx|/ℓ, penetration by max|Δx|, kinetic energy (where the velocities
    were compared) by ½·max|Δv|·(√(2·KE_a) + √(2·KE_b)), each plus DYN_OBSERVABLE_K·ε64 of
    the value for the double sums."""
    bad = []
    slack = lambda v: tolerances.DYN_OBSERVABLE_K * tolerances.EPS["fp64"] * max(abs(v), 1.0)  # noqa: E731
    bounds = {"stretch_max": 2.0 * fd.max_abs / seg_len, "penetration_max": fd.max_abs}
    if getattr(fd, "velocity_compared", False) and math.isfinite(fd.velocity_max_abs):
        dv = fd.velocity_max_abs / fd.velocity_h
        ka, kb = row["kinetic_energy"]["a"], row["kinetic_energy"]["b"]
        bounds["kinetic_energy"] = 0.5 * dv * (math.sqrt(2.0 * max(ka, 0.0)) + math.sqrt(2.0 * max(kb, 0.0)))
    for name, bound in bounds.items():
        va, vb = row[name]["a"], row[name]["b"]
        if math.isnan(va) and math.isnan(vb):
            continue
        ok = va == vb if exact else abs(vb - va) <= bound + slack(va)
        if not ok:
            bad.append(f"{name} {va!r} vs {vb!r}" + ("" if exact else f" (allowed ±{bound + slack(va):.3g})"))
    if row["blown_up_strands"]["a"] != row["blown_up_strands"]["b"]:
        bad.append(f"blown_up_strands {row['blown_up_strands']['a']} vs {row['blown_up_strands']['b']}")
    return bad


def check_same_run(a, b, frames):
    """Raise StateError when A and B cannot be compared (exit 2): other solvers, or, for
    frames 'all', trajectories of different lengths (the paper model's 'frame counts
    differ'); a different --output-every alone is compared at the common steps."""
    sa, sb = (as_text(t.dynamic_params.get("solver", "")) for t in (a, b))
    if a.is_dynamic and b.is_dynamic and sa != sb:
        raise StateError(f"different solvers: A is {sa}, B is {sb} (compare solvers with harness accuracy)")
    if frames == "all" and (a.is_dynamic or b.is_dynamic):
        la, lb = int(a.step[-1]), int(b.step[-1])
        if la != lb:
            raise StateError(
                f"frame counts differ: A has {a.n_frames} frames to step {la}, B has {b.n_frames} to step "
                f"{lb} (missing frames; use --frames last or --frame K to compare a part)"
            )


def _pick_steps(a, b, frames):
    common = sorted(set(a.step.tolist()) & set(b.step.tolist()))
    if not common:
        raise StateError("A and B have no step in common (nothing to compare)")
    if frames == "all":
        return common
    if frames == "last":
        return [common[-1]]
    missing = [s for s in frames if s not in common]
    if missing:
        raise StateError(f"step(s) {missing} are not written in both files (common steps: {common[0]} … {common[-1]})")
    return list(frames)


def compare(path_a, path_b, frames="all", exact=False, check_paper=True, spread=False):
    """Compare two files (either may be dynamic) at their common steps; DynDiffResult.
    spread=True: B's simulated frames were each advanced by one frame from A's previous
    frame, and are judged against A's spread there too (module docstring)."""
    with open_trajectory(path_a) as a_file, open_trajectory(path_b) as b_file:
        check_same_rendering(a_file, b_file)
        a, b = simulated_view(a_file), simulated_view(b_file)  # a LOD file: its simulated rows
        diff.check_comparable(a, b)
        check_same_run(a, b, frames)
        steps = _pick_steps(a, b, frames)
        kind_a = tolerances.kind_of(a.precision, a.fast_math)
        kind_b = tolerances.kind_of(b.precision, b.fast_math)
        eps = max(tolerances.EPS[kind_a], tolerances.EPS[kind_b])
        R, h = float(a.params["head_radius"]), float(a.params["hair_offset"])
        SI = 1
        if a.is_dynamic:  # the error of one frame grows with its substeps × iterations
            SI = int(a.dynamic_params["substeps"]) * int(a.dynamic_params.get("iterations", 1))
        unit = eps * tolerances.extent(R, h, a.hair_length) * SI
        tol = step_tolerance(kind_a, kind_b, exact)
        ptol = tolerances.EXACT if exact else tolerances.pair_tolerance(kind_a, kind_b)
        res = DynDiffResult(
            str(path_a),
            str(path_b),
            a.label,
            b.label,
            f"{kind_a}↔{kind_b}" + (" (exact)" if exact else ""),
            tol,
            ptol,
            unit,
            a.hair_length,
        )
        for key in sorted(set(a.dynamic_params) | set(b.dynamic_params)):
            va, vb = a.dynamic_params.get(key), b.dynamic_params.get(key)
            if as_text(va) != as_text(vb) and key not in ("simulated_frames", "output_every"):
                res.notes.append(f"{key}: A {va}, B {vb}")
        spreads = spreads_for(path_a, a, steps) if spread and not exact and a.is_dynamic else {}
        if spread and not exact and not spreads:
            res.notes.append(f"spread not measured ({display(spread_binary())} not built or no frame to step from)")
        oa, ob = a.observables.set_index("step"), b.observables.set_index("step")
        used_a, used_b = [], []
        for s in steps:
            fa, fb = a.frame_at_step(s), b.frame_at_step(s)
            sa, sb = a.stages[fa], b.stages[fb]
            if (sa == "simulate") != (sb == "simulate"):
                raise StateError(f"step {s} is '{sa}' in A but '{sb}' in B")
            if sa == "simulate":
                fd = compare_sim_frame(a, b, fa, fb, tol, unit, coarser(a.dtype, b.dtype), spreads.get(s))
                row = {"step": s, "time": float(a.time[fa])}
                for name in OBS_SHOWN:
                    va = float(oa.loc[s, name]) if s in oa.index else float("nan")
                    vb = float(ob.loc[s, name]) if s in ob.index else float("nan")
                    row[name] = {"a": va, "b": vb, "diff": vb - va}
                row["failures"] = observables_ok(row, fd, a.hair_length / (a.points - 1), exact)
                res.observables.append(row)
            else:
                fd = diff.compare_frame(a, b, fa, fb, ptol, eps, coarser(a.dtype, b.dtype))
            fd.step = s
            res.frames.append(fd)
            used_a.append(fa)
            used_b.append(fb)
        # roots bit-exact for the reference build, within DYN_ROOT_K·ε·R for any other
        res.invariants_a = invariants_dynamic.check(
            a, exact=invariants_dynamic.is_reference_build(a), frames=used_a, paper=check_paper
        )
        res.invariants_b = invariants_dynamic.check(
            b, exact=invariants_dynamic.is_reference_build(b), frames=used_b, paper=check_paper
        )
        for t, used, rep in ((a_file, used_a, res.invariants_a), (b_file, used_b, res.invariants_b)):
            if t.render_points:  # the rendered rows: recomputed from the simulated ones (§3.14)
                rep.violations += lod.check_rendered(t, invariants_dynamic.is_reference_build(t), used)[0]
    return res


def check_same_rendering(a, b):
    """Raise StateError (exit 2) unless both files or neither were written with --render-points,
    with the same P_r and P_s: a rendered point has no simulated counterpart to compare with."""
    if (a.render_points, a.simulated_points) != (b.render_points, b.simulated_points):

        def what(t):
            return (
                f"{t.simulated_points} points rendered as {t.render_points}"
                if t.render_points
                else f"{t.points} points"
            )

        raise StateError(f"A has {what(a)} a strand, B {what(b)}: compare files rendered alike")


def _g(x):
    return f"{x:11.4g}" if isinstance(x, float) and math.isfinite(x) else f"{x!s:>11}"


def format_result(r):
    lines = [f"A: {r.path_a} ({r.label_a})", f"B: {r.path_b} ({r.label_b})"]
    if r.tolerance.point_k:
        lines.append(
            f"tolerance {r.pair}: a simulated point is over when A and B differ by more than "
            f"{r.tolerance.point_k:g}·ε·E·S·I = {r.tolerance.point_k * r.unit:.3g} "
            f"({r.tolerance.point_k * r.unit / r.hair_length:.1e}·L), for one frame from the same "
            f"input (stepdiff); paper frames: the paper rule"
        )
    else:
        lines.append(f"tolerance {r.pair}: {r.tolerance.why}")
    for n in r.notes:
        lines.append(f"note: {n}" if n.startswith("spread") else f"note: parameters differ: {n}")
    if any(math.isfinite(getattr(f, "spread", float("nan"))) for f in r.frames):
        lines.append(
            f"spread: a point is over when farther than max(the rule, {tolerances.DYN_SPREAD_K:g} × the scene's "
            f"spread), the spread measured by {display(spread_binary())} from the same input"
        )
    lines.append(
        f"{'step':>5} {'stage':8} {'max abs':>10} {'rms':>10} {'max/L':>10} {'max/u':>9} "
        f"{'ulp p50':>8} {'ulp p99':>8} {'ulp max':>10} {'spread':>10} {'limit':>10} {'over':>7} "
        f"{'nan/inf':>7}  verdict"
    )
    for f in r.frames:
        lim = getattr(f, "limit", float("nan"))
        lines.append(
            f"{f.step:>5} {f.stage:8} {f.max_abs:10.3e} {f.rms_abs:10.3e} {f.max_rel_L:10.3e} "
            f"{f.max_k:9.3g} {f.ulp_p50:8.0f} {f.ulp_p99:8.0f} {f.ulp_max:10.3g} "
            f"{getattr(f, 'spread', float('nan')):10.3e} {lim:10.3e} {f.over:7d} "
            f"{f.nonfinite:7d}  {'ok' if f.ok else 'FAIL'}"
        )
    if r.observables:
        lines.append("observables (A, B, B − A):")
        lines.append(f"{'step':>5} {'time':>8} " + " ".join(f"{n:>35}" for n in OBS_SHOWN))
        for row in r.observables:
            cells = [f"{_g(row[n]['a'])} {_g(row[n]['b'])} {_g(row[n]['diff'])}" for n in OBS_SHOWN]
            lines.append(f"{row['step']:>5} {row['time']:8.4f} " + " ".join(f"{c:>35}" for c in cells))
    for label, rep in (("A", r.invariants_a), ("B", r.invariants_b)):
        vs = rep.all_violations()
        lines.append(f"invariants {label} ({rep.kind}): " + ("all hold" if not vs else f"{len(vs)} violated"))
        lines += [f"  {v.message}" for v in vs[:10]]
    lines.append("verdict: EQUIVALENT" if r.equivalent else "verdict: NOT EQUIVALENT: " + "; ".join(r.failures()[:3]))
    return "\n".join(lines)


def run(path_a, path_b, frames="all", exact=False, as_json=False, out=print):
    """`harness diff` when either file is dynamic; `frames` numbers are steps here."""
    chosen = diff.parse_frames(frames) if isinstance(frames, str) else frames
    return diff.report(lambda: compare(path_a, path_b, chosen, exact), format_result, path_a, path_b, as_json, out)


# ---- stepdiff ----------------------------------------------------------------------------


def parse_frame_range(spec, candidates):
    """'all' | 'K' | 'K..' | 'K..L' | '..L' | comma list of those; numbers are frame indices
    of A; returns the chosen members of `candidates` (sorted). Every frame a selection names
    or spans must be a candidate, in both forms (K, and each frame of K..L): one that cannot
    be stepped from is an error, never dropped; an open end is the first or last candidate."""
    spec = (spec or "all").strip()
    if spec == "all":
        return list(candidates)
    chosen = set()
    for part in spec.split(","):
        part = part.strip()
        try:
            if ".." in part:
                lo, hi = part.split("..", 1)
                lo = int(lo) if lo.strip() else min(candidates, default=0)
                hi = int(hi) if hi.strip() else max(candidates, default=-1)
                picked = list(range(lo, hi + 1))
            else:
                picked = [int(part)]
        except ValueError:
            raise HarnessError(f"--frames must be 'all', K, K..L, K.. or ..L (frame indices), not '{spec}'") from None
        bad = [k for k in picked if k not in candidates]
        if bad:
            named = _span(bad) if len(bad) > 2 else ", ".join(map(str, bad))
            raise HarnessError(
                f"--frames {part}: frame(s) {named} of the reference cannot be stepped from (each must be "
                f"a simulated frame, or the last paper frame, with stored velocities whose next frame is "
                f"written; candidates: {_span(candidates)})"
            )
        chosen |= set(picked)
    if not chosen:
        raise HarnessError(f"--frames {spec} selects no frame (candidates: {_span(candidates)})")
    return sorted(chosen)


def _span(c):
    return f"{c[0]} … {c[-1]}" if c else "none"


def step_candidates(ref):
    """Frames k of A with velocities whose frame k + 1 is the next simulated step."""
    out = []
    for k in range(ref.n_frames - 1):
        s = int(ref.step[k])
        if k < ref.paper_frames - 1:
            continue
        if k >= ref.paper_frames and ref.velocity_at_step(s) is None:
            continue
        if int(ref.step[k + 1]) == s + 1 and ref.stages[k + 1] == "simulate":
            out.append(k)
    return out


def stepdiff(reference, binary, flags=(), frames="all", exact=False, keep=None, timeout=None, out=print, spread=True):
    """The `harness stepdiff` command; returns the exit status. `spread`: judge each frame
    against the scene's spread too (the module docstring), measured by the spread build."""
    from harness.core.runner import require_binary

    binary = require_binary(binary)
    with open_trajectory(reference) as ref:
        if not ref.is_dynamic:
            raise HarnessError(
                f"cannot compare: {reference}: not a dynamic file (model attribute is not 'dynamic')",
                code=diff.EXIT_CANNOT_COMPARE,
            )
        cand = step_candidates(ref)
        if not cand:
            raise HarnessError(
                f"cannot compare: {reference}: no frame to step from (write the reference with "
                f"--velocities all and --output-every 1)",
                code=diff.EXIT_CANNOT_COMPARE,
            )
        chosen = parse_frame_range(frames, cand)
        steps = {k: int(ref.step[k + 1]) for k in chosen}
    tmp = Path(keep) if keep else Path(tempfile.mkdtemp(prefix="hb-stepdiff-"))
    tmp.mkdir(parents=True, exist_ok=True)
    worst = 0
    lines = [f"reference {reference}, binary {binary} {' '.join(flags)}".rstrip()]
    use_spread = spread and not exact and spread_binary().exists()
    if spread and not exact and not use_spread:
        lines.append(f"note: spread not measured ({display(spread_binary())} not built: make cpu); the rule alone")
    lines.append(
        f"{'frame':>5} {'step':>5} {'max abs':>10} {'max/u':>9} {'ulp max':>10} {'spread':>10} {'limit':>10} "
        f"{'over':>6}  verdict"
    )
    try:
        for k in chosen:
            o = tmp / f"step{k}.h5"
            cmd = [
                str(binary),
                "--input",
                str(reference),
                "--input-frame",
                str(k),
                "--stages",
                "simulate",
                "--frames",
                "1",
                *flags,
                "--output",
                str(o),
                "--force",
                "--quiet",
            ]
            try:
                p = runner.run_command(cmd, timeout=timeout)
            except runner.TimedOut:
                raise HarnessError(f"{binary.name} did not finish within {timeout} s", code=2) from None
            if p.returncode not in COMPLETED:
                msg = (p.stderr.strip().splitlines() or ["no message"])[-1]
                raise HarnessError(
                    f"cannot compare: {binary.name} exited with status {p.returncode} on frame {k}: {msg}",
                    code=diff.EXIT_CANNOT_COMPARE,
                )
            try:
                res = compare(reference, o, [steps[k]], exact, check_paper=False, spread=use_spread)
            except StateError as e:
                raise HarnessError(f"cannot compare: {e}", code=diff.EXIT_CANNOT_COMPARE) from None
            f = res.frames[0]
            ok = res.equivalent
            worst = max(worst, 0 if ok else 1)
            lines.append(
                f"{k:>5} {steps[k]:>5} {f.max_abs:10.3e} {f.max_k:9.3g} {f.ulp_max:10.3g} "
                f"{getattr(f, 'spread', float('nan')):10.3e} {getattr(f, 'limit', float('nan')):10.3e} {f.over:6d}  "
                f"{'ok' if ok else 'FAIL: ' + '; '.join(res.failures()[:2])}"
            )
    finally:
        if not keep:
            shutil.rmtree(tmp, ignore_errors=True)
    lines.append(
        "verdict: "
        + ("EQUIVALENT" if worst == 0 else "NOT EQUIVALENT")
        + (
            " (exact)"
            if exact
            else " (one frame from the same input; limit max(DYN_STEP_K·ε·E·S·I"
            + (", DYN_SPREAD_K × spread))" if use_spread else "))")
        )
    )
    out("\n".join(lines))
    return worst
