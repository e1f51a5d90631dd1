"""Beside a peer: the same chain scenes in our C reference and in Bender's
PositionBasedDynamics (harness/studies/peer_pypbd_dynamic.py), measured side by side. Measuring only; the
Markdown is harness/render/peer_dynamic_report.py.

The scene: straight chains of P points and length L hanging from a pinned root, tilted by
θ0 from the downward vertical and released from rest (no collider, wind, bend, damping),
built by harness/studies/analytic_runs_dynamic.py and passed to the binary with --input. For each
setting (S substeps, I iterations):

- accuracy, on one chain per tilt over `frames` frames: every frame against our converged
  reference (hairsim-cpu, xpbd, fp64, I = 1, S doubled until the change from S to 2S is
  below REF_FRACTION of the smallest error reported), as max and RMS of |x − x_ref|/L, and
  the stretch max |len/ℓ − 1| (harness.check.invariants_dynamic.observe);
- time per frame at each strand count N (N chains, each tilt in turn, turned about +y):
  hairsim-cpu's simulate median (--repeat) per variant and precision, and the median of
  pypbd's per-frame `step` time, both at the same thread count.

Files: results/peer/accuracy.csv, timing.csv, reference.csv and peer.json (the run's
settings, machine, versions).
"""

import datetime
import math
import os
import platform
import tempfile
from dataclasses import dataclass
from pathlib import Path
from types import SimpleNamespace

import numpy as np

from harness import HarnessError
from harness.check import invariants_dynamic
from harness.core import env, runner, tolerances, variants
from harness.core.paths import RESULTS, binary_path, display
from harness.core.progress import Progress
from harness.io import files
from harness.io.trajectory import open_trajectory
from harness.studies import analytic_runs_dynamic as analytic_runs
from harness.studies import peer_pypbd_dynamic as peer
from harness.studies.peer_verdicts_dynamic import OURS, PEER

SETTINGS = ((8, 1), (32, 1), (8, 4))  # (S, I)
STRANDS = (1, 100, 1000, 10000)
ACCURACY_FIELDS = (
    "substeps",
    "iterations",
    "solver",
    "variant",
    "precision",
    "err_max",
    "err_rms",
    "err_last",
    "stretch_max",
    "blown_up",
    "vs_ours_fp64",
)
TIMING_FIELDS = (
    "substeps",
    "iterations",
    "solver",
    "variant",
    "precision",
    "strands",
    "points",
    "threads",
    "frames_timed",
    "median_ms",
    "min_ms",
    "max_ms",
)
REFERENCE_FIELDS = ("substeps", "change_to_2s")


def chain_positions(n, points, length, tilts_deg):
    """n chains: chain i tilted by tilts[i mod len] and turned about +y by i golden angles."""
    golden = math.pi * (3.0 - math.sqrt(5.0))
    return np.concatenate(
        [
            analytic_runs.straight_chain_positions(
                points, length, math.radians(tilts_deg[i % len(tilts_deg)]), (i // len(tilts_deg)) * golden
            )
            for i in range(n)
        ]
    )


def _ours(binary, inp, workdir, frames, substeps, iterations, precision, args):
    """Our run from `inp` → positions [F+1][N][P][3] (float64; the start first)."""
    out = Path(workdir) / f"ours_{precision}_{substeps}_{iterations}.h5"
    analytic_runs.simulate(
        binary,
        inp,
        out,
        frames,
        substeps,
        "xpbd",
        gravity=args.gravity,
        iterations=iterations,
        precision=precision,
        extra=("--frame-dt", repr(args.frame_dt), "--stretch-compliance", repr(args.compliance)),
    )
    with open_trajectory(out) as t:
        frames_idx = [t.paper_frames - 1, *t.simulated]
        return np.stack([t.frame(f) for f in frames_idx]).astype(np.float64)


def _errors(x, ref, length):
    """max, RMS and last-frame max of |x − ref|/L over the simulated frames (1 …)."""
    d = np.linalg.norm(x[1:] - ref[1:], axis=-1) / length
    if not np.all(np.isfinite(d)):
        return math.inf, math.inf, math.inf
    return float(d.max()), float(np.sqrt(np.mean(d * d))), float(d[-1].max())


def _observed(x, length):
    """(stretch_max over the frames, most strands blown up in a frame) by harness.check.invariants_dynamic."""
    n, p = x.shape[1], x.shape[2]
    view = SimpleNamespace(
        n_strands=n,
        points=p,
        hair_length=length,
        collider=False,
        collide_radius=0.0,
        colliders=None,  # §3.17: the peer's chains meet no collider
        segment_rest=lambda: length / (p - 1),  # a chain's links are equal (no groom)
    )
    obs = [invariants_dynamic.observe(view, xf) for xf in x[1:]]
    return max(o[0] for o in obs), max(o[3] for o in obs)


def reference(binary, inp, workdir, args, smallest_error, log=print):
    """Our converged reference for the accuracy chains: S doubled from args.ref_start until
    the change from S to 2S is below REF_FRACTION × `smallest_error(x_2S)`. Returns
    (x_ref at 2S, 2S, [(S, change)], converged)."""
    s = args.ref_start
    x_s = _ours(binary, inp, workdir, args.frames, s, 1, "fp64", args)
    table = []
    while True:
        x_2s = _ours(binary, inp, workdir, args.frames, 2 * s, 1, "fp64", args)
        change = _errors(x_s, x_2s, args.length)[0]
        table.append((s, change))
        target = tolerances.PEER_REF_FRACTION * smallest_error(x_2s)
        log(f"peer: reference S = {s} → {2 * s}: change {change:.3g}·L (target {target:.3g}·L)")
        if change <= target:
            return x_2s, 2 * s, table, True
        if 2 * s >= args.ref_max:
            log(f"peer: the reference did not converge by S = {2 * s} (--ref-max); reported as not converged")
            return x_2s, 2 * s, table, False
        s, x_s = 2 * s, x_2s


def accuracy(binary, workdir, args, log=print, step=lambda: None):
    """Rows of accuracy.csv, the reference table and whether it converged."""
    pos = chain_positions(len(args.tilts), args.points, args.length, args.tilts)
    inputs = {
        prec: analytic_runs.write_paper_state(Path(workdir) / f"acc_in_{prec}.h5", pos, args.length, precision=prec)
        for prec in ("fp64", "fp32")
    }
    runs = {}
    for s, i in args.settings:
        for prec in ("fp64", "fp32"):
            runs[(s, i, OURS, prec)] = _ours(binary, inputs[prec], workdir, args.frames, s, i, prec, args)
        runs[(s, i, PEER, "fp64")] = peer.run(
            pos,
            args.length,
            args.frames,
            substeps=s,
            iterations=i,
            compliance=args.compliance,
            frame_dt=args.frame_dt,
            gravity=args.gravity,
            threads=args.threads,
        )[0]
        log(f"peer: accuracy runs S = {s}, I = {i} done")
        step()

    def smallest(x_ref):
        return min(_errors(x, x_ref, args.length)[0] for x in runs.values())

    x_ref, s_ref, table, converged = reference(binary, inputs["fp64"], workdir, args, smallest, log)
    rows = []
    for (s, i, solver, prec), x in runs.items():
        err = _errors(x, x_ref, args.length)
        stretch, blown = _observed(x, args.length)
        ours64 = runs[(s, i, OURS, "fp64")]
        rows.append(
            dict(
                substeps=s,
                iterations=i,
                solver=solver,
                variant="ref" if solver == OURS else "xpbd",
                precision=prec,
                err_max=err[0],
                err_rms=err[1],
                err_last=err[2],
                stretch_max=stretch,
                blown_up=blown,
                vs_ours_fp64=_errors(x, ours64, args.length)[0],
            )
        )
    return rows, s_ref, table, converged


def timing(binary, workdir, args, log=print, step=lambda: None):
    """Rows of timing.csv: per setting and strand count, each variant × precision of ours
    (the binary's declared variants) and the peer."""
    ours_variants = variants.declared("cpu").variants
    rows = []
    for n in args.strands:
        pos = chain_positions(n, args.points, args.length, args.tilts)
        inputs = {
            prec: analytic_runs.write_paper_state(
                Path(workdir) / f"time_in_{n}_{prec}.h5", pos, args.length, precision=prec
            )
            for prec in ("fp64", "fp32")
        }
        for s, i in args.settings:
            base = dict(substeps=s, iterations=i, strands=n, points=args.points, threads=args.threads)
            for variant in ours_variants:
                for prec in ("fp64", "fp32"):
                    rec = runner.run_binary(
                        binary,
                        [
                            "--input",
                            inputs[prec],
                            "--stages",
                            "simulate",
                            "--no-collider",
                            "--solver",
                            "xpbd",
                            "--frames",
                            args.time_frames,
                            "--substeps",
                            s,
                            "--iterations",
                            i,
                            "--gravity",
                            repr(args.gravity),
                            "--frame-dt",
                            repr(args.frame_dt),
                            "--stretch-compliance",
                            repr(args.compliance),
                            "--precision",
                            prec,
                            "--threads",
                            args.threads,
                            "--repeat",
                            args.repeat,
                            "--variant",
                            variant,
                        ],
                        timeout=args.timeout,
                    )
                    st = next(x for x in rec["stages"] if x["stage"] == "simulate")
                    rows.append(
                        dict(
                            base,
                            solver=OURS,
                            variant=variant,
                            precision=prec,
                            frames_timed=len(st.get("times_ms", [])),
                            median_ms=st["median_ms"],
                            min_ms=st["min_ms"],
                            max_ms=st["max_ms"],
                        )
                    )
            _, ms = peer.run(
                pos,
                args.length,
                args.time_frames * args.repeat + 1,
                substeps=s,
                iterations=i,
                compliance=args.compliance,
                frame_dt=args.frame_dt,
                gravity=args.gravity,
                record=False,
                threads=args.threads,
            )
            ms = ms[1:]  # the first step builds pypbd's constraint groups: not a frame's cost
            rows.append(
                dict(
                    base,
                    solver=PEER,
                    variant="xpbd",
                    precision="fp64",
                    frames_timed=len(ms),
                    median_ms=float(np.median(ms)),
                    min_ms=float(ms.min()),
                    max_ms=float(ms.max()),
                )
            )
            log(
                f"peer: timed N = {n}, S = {s}, I = {i}: "
                + ", ".join(
                    f"{r['solver']}/{r['variant']}/{r['precision']} {r['median_ms']:.3f} ms"
                    for r in rows
                    if r["strands"] == n and r["substeps"] == s and r["iterations"] == i
                )
            )
            step()
    return rows


class PeerUnavailable(HarnessError):
    """pypbd cannot be imported here: the comparison is skipped, with this reason."""


def check_args(args):
    if args.points < 2:
        raise HarnessError("peer: --points must be at least 2")
    if not args.length > 0 or not math.isfinite(args.length):
        raise HarnessError("peer: --length must be a finite number > 0")
    if not args.gravity > 0 or not math.isfinite(args.gravity):
        raise HarnessError(
            "peer: --gravity must be > 0 (pypbd's gravity is fixed; the peer maps g0 by the length unit)"
        )
    if not args.compliance >= 0 or not math.isfinite(args.compliance):
        raise HarnessError("peer: --compliance must be a finite number ≥ 0")
    if not args.frame_dt > 0 or not math.isfinite(args.frame_dt):
        raise HarnessError("peer: --frame-dt must be a finite number of seconds > 0")
    if not args.tilts or any(not 0 <= t <= 180 for t in args.tilts):
        raise HarnessError("peer: --tilts are degrees from the downward vertical in [0, 180]")
    if args.ref_start < 1 or args.ref_max < 2 * args.ref_start:
        raise HarnessError("peer: needs 1 ≤ --ref-start and --ref-max ≥ 2 × --ref-start")


@dataclass
class Plan:
    """What the peer comparison runs (the `harness peer` flags, their defaults here)."""

    points: int = 32
    length: float = 30.0
    tilts: tuple = (30.0, 60.0)
    frames: int = 30
    frame_dt: float = 1 / 60
    gravity: float = 981.0
    compliance: float = 0.0
    settings: tuple = ((8, 1), (32, 1), (8, 4))
    strands: tuple = (1, 100, 1000, 10000)
    threads: int = 1
    time_frames: int = 5
    repeat: int = 3
    ref_start: int = 64
    ref_max: int = 16384
    timeout: float | None = None
    out: str | None = None
    argv: list | None = None  # the command's own words, recorded in peer.json


def run_study(args, log=print):
    """The whole comparison (args: a Plan); writes the CSVs and peer.json under args.out,
    returns that dir."""
    check_args(args)
    reason = peer.unavailable()
    if reason:
        raise PeerUnavailable(reason)
    binary = runner.require_binary(binary_path("cpu"))
    out = Path(args.out) if args.out else RESULTS / "peer"
    out.mkdir(parents=True, exist_ok=True)
    with tempfile.TemporaryDirectory(prefix="hairbench-peer-") as workdir:
        with Progress(len(args.settings) * (1 + len(args.strands)), "peer: runs") as bar:
            acc, s_ref, table, converged = accuracy(binary, workdir, args, log, bar.update)
            tim = timing(binary, workdir, args, log, bar.update)
    files.write_csv(out / "accuracy.csv", ACCURACY_FIELDS, acc)
    files.write_csv(out / "timing.csv", TIMING_FIELDS, tim)
    files.write_csv(out / "reference.csv", REFERENCE_FIELDS, [dict(substeps=s, change_to_2s=c) for s, c in table])
    rec = runner.run_binary(binary, ["--strands", 1, "--points", 2, "--stages", "init"])
    meta = {
        "date": datetime.datetime.now(datetime.timezone.utc).isoformat(timespec="seconds"),
        "command": " ".join(["python -m harness peer", *(args.argv or [])]),
        "points": args.points,
        "length": args.length,
        "tilts_deg": list(args.tilts),
        "frames": args.frames,
        "frame_dt": args.frame_dt,
        "gravity": args.gravity,
        "compliance": args.compliance,
        "settings": [list(s) for s in args.settings],
        "strands": list(args.strands),
        "threads": args.threads,
        "time_frames": args.time_frames,
        "repeat": args.repeat,
        "reference_substeps": s_ref,
        "reference_converged": converged,
        "reference_fraction": tolerances.PEER_REF_FRACTION,
        "peer": {"package": "pypbd", "version": peer.version(), "omp_threads": peer.omp_threads()},
        "ours": {
            "binary": display(binary),
            "version": rec.get("version"),
            "git_revision": rec.get("git_revision"),
            "compiler": rec.get("compiler"),
            "flags": rec.get("flags"),
        },
        "machine": {
            "cpu": rec.get("device"),
            "cores": env.usable_cores(),
            "python": platform.python_version(),
            "load_average": list(os.getloadavg()),
        },
    }
    files.write_json(out / "peer.json", meta)
    return out
