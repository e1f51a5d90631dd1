"""The peer comparison (results/peer/, written by harness/studies/peer_dynamic.py) as a Markdown section and
one plot. Rendering only; `section(results_dir, out_dir)` is what report.py calls, and
`write(results_dir, report_dir)` writes report/peer.md on its own.

"Where the peer wins" words studies/peer_verdicts_dynamic.py's verdict: time against our fastest
fp64 run at each (S, I, N), error and stretch against ours at the same precision, and against our fp32.
"""

import json
import os
from pathlib import Path

from harness import HarnessError
from harness.core import tolerances
from harness.core.paths import REPORT, RESULTS, display
from harness.io import files, tables
from harness.studies import peer_verdicts_dynamic as verdicts
from harness.studies.peer_verdicts_dynamic import OURS, PEER


def load(results_dir):
    d = Path(results_dir)
    need = [d / n for n in ("accuracy.csv", "timing.csv", "reference.csv", "peer.json")]
    missing = [display(p) for p in need if not p.exists()]
    if missing:
        raise HarnessError(f"peer report: missing {', '.join(missing)} (run `python -m harness peer`)")
    try:
        return (
            tables.read_csv(need[0]),
            tables.read_csv(need[1]),
            tables.read_csv(need[2]),
            json.loads(need[3].read_text()),
        )
    except (ValueError, OSError) as e:
        raise HarnessError(f"peer report: cannot read {display(d)}: {e}") from None


def accuracy_table(acc):
    lines = [
        "| S | I | solver | precision | max err / L | RMS err / L | last frame max / L | stretch max | "
        "vs our fp64 run (max / L) |",
        "| ---: | ---: | --- | --- | ---: | ---: | ---: | ---: | ---: |",
    ]
    for _, r in acc.sort_values(["substeps", "iterations", "solver", "precision"]).iterrows():
        who = f"ours ({r['variant']})" if r["solver"] == OURS else PEER
        blown = f" (**{int(r['blown_up'])} blown up**)" if r["blown_up"] else ""
        lines.append(
            f"| {r['substeps']} | {r['iterations']} | {who} | {r['precision']} | {r['err_max']:.3g} | "
            f"{r['err_rms']:.3g} | {r['err_last']:.3g} | {r['stretch_max']:.3g}{blown} | {r['vs_ours_fp64']:.2g} |"
        )
    return lines


def timing_table(tim):
    tim = tim.assign(label=tim.apply(verdicts.label, axis=1))
    labels = sorted(tim["label"].unique(), key=lambda s: (s.startswith(PEER), s))
    lines = [
        "| S | I | strands | " + " | ".join(labels) + " | pypbd ÷ our fastest fp64 |",
        "| ---: | ---: | ---: |" + " ---: |" * (len(labels) + 1),
    ]
    for (s, i, n), g in tim.groupby(["substeps", "iterations", "strands"]):
        cells = []
        for lab in labels:
            v = g[g["label"] == lab]["median_ms"]
            cells.append(f"{float(v.iloc[0]):.3g}" if len(v) else "—")
        lines.append(f"| {s} | {i} | {n:,} | " + " | ".join(cells) + f" | {verdicts.time_ratio(g):.2g}× |")
    return lines


def where_the_peer_wins(acc, tim, frames, ref_uncertainty):
    """Sentences from the verdict (studies/peer_verdicts_dynamic.py): time, then error and stretch
    (`frames`: the accuracy horizon; `ref_uncertainty`: the reference's last change from S to 2S, ·L)."""
    v = verdicts.verdict(acc, tim, frames, ref_uncertainty)
    out = []
    if v.wins:
        out.append(
            "**Time: the peer is faster** than our fastest fp64 run at "
            + ", ".join(f"S = {s}, I = {i}, N = {n:,} ({1 / r:.2g}× faster)" for (s, i, n), r in v.wins)
            + "."
        )
    if v.cases and len(v.wins) < v.cases:
        out.append(
            f"Time: {'elsewhere ' if v.wins else ''}our fastest fp64 run is {min(v.lose):.2g}–{max(v.lose):.2g}× "
            f"faster than the peer ({len(v.lose)} of {v.cases} (S, I, N) cases)."
        )
    if v.worst is not None and v.same_scheme:
        out.append(
            f"Error and stretch: the peer's trajectories equal our fp64 runs to {v.worst:.2g}·L at worst, "
            "the rounding drift of one scheme (docs/decisions.md), so neither wins on accuracy at equal "
            "S and I."
        )
    elif v.worst is not None:
        out.append(
            f"Error and stretch: the peer's trajectories depart from our fp64 runs by up to {v.worst:.2g}·L, "
            f"more than the rounding drift measured for ≤ 30 frames "
            f"({tolerances.PEER_SAME_SCHEME_PER_SUBSTEP:g}·L per substep): the columns above tell which "
            "is closer to the reference."
        )
    for lab, cases in v.faster_than_each.items():
        out.append(
            f"Time: the peer is faster than our `{lab}` at "
            + ", ".join(f"S = {s}, I = {i}, N = {n:,} ({r:.2g}×)" for (s, i, n), r in cases)
            + "."
        )
    if v.better_than_fp32:
        out.append(
            "Error: against our fp32 runs (pypbd runs in double only) the peer's is smaller by more than the "
            "reference's uncertainty at "
            + ", ".join(
                f"S = {s}, I = {i} ({theirs:.3g} vs {ours:.3g}·L)" for (s, i), theirs, ours in v.better_than_fp32
            )
            + "."
        )
    elif v.fp32:
        out.append(
            "Error: our fp32 runs are within the reference's uncertainty "
            f"({ref_uncertainty:.2g}·L) of the peer's double-precision error at every setting."
        )
    return out


def plot(tim, out_dir):
    """Time per frame against strands, one line per runner, the first setting."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    tim = tim.assign(label=tim.apply(verdicts.label, axis=1))
    s, i = tim.iloc[0]["substeps"], tim.iloc[0]["iterations"]
    g = tim[(tim["substeps"] == s) & (tim["iterations"] == i)]
    fig, ax = plt.subplots(figsize=(6, 4))
    for lab, h in g.groupby("label"):
        h = h.sort_values("strands")
        ax.plot(h["strands"], h["median_ms"], marker="o", label=lab, ls="--" if lab.startswith(PEER) else "-")
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlabel("chains (strands)")
    ax.set_ylabel("ms per frame (median)")
    ax.set_title(
        f"chains of {int(g.iloc[0]['points'])} points, S = {s}, I = {i}, {int(g.iloc[0]['threads'])} thread(s)"
    )
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=8)
    path = Path(out_dir) / "peer_time.png"
    try:
        return files.save_figure(fig, path, dpi=100, bbox_inches="tight")
    finally:
        plt.close(fig)


def section(results_dir, out_dir, missing_ok=False):
    """The report's lines for the peer comparison (and its plot in out_dir). With
    `missing_ok`, results that are absent give a short note saying why instead of an error."""
    if missing_ok and not (Path(results_dir) / "peer.json").exists():
        from harness.studies.peer_pypbd_dynamic import unavailable

        why = unavailable() or f"no {display(Path(results_dir) / 'peer.json')}: run `python -m harness peer`"
        return ["## Beside a peer: PositionBasedDynamics (pypbd)", "", f"Not measured here: {why}.", ""]
    acc, tim, ref, meta = load(results_dir)
    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    png = plot(tim, out_dir)
    m = meta.get("machine", {})
    tilts = ", ".join(f"{t:g}°" for t in meta["tilts_deg"])
    conv = "converged" if meta["reference_converged"] else "**not converged** (the errors below are bounded by it)"
    last = ref.iloc[-1]
    lines = [
        "## Beside a peer: PositionBasedDynamics (pypbd)",
        "",
        f"The same chain scenes in Bender's PositionBasedDynamics (PyPI `pypbd` {meta['peer']['version']}, "
        f"XPBD distance constraints, double precision) and in ours (`{meta['ours']['binary']}`, "
        f"git {meta['ours']['git_revision']}). Chains of {meta['points']} points, L = {meta['length']:g} cm, a pinned "
        f"root, unit masses, tilted {tilts} from the downward vertical and released from rest; compliance "
        f"{meta['compliance']:g}, g0 = {meta['gravity']:g} cm/s², Δt = {meta['frame_dt']:.6g} s; no collider, wind, "
        "bend or damping. Parameter mapping and what differs between the solvers: docs/decisions.md "
        '("The peer"). Made by `'
        + meta["command"].strip()
        + f"` on {m.get('cpu')} ({m.get('cores')} CPUs visible, load "
        f"average {', '.join(f'{x:.1f}' for x in m.get('load_average', []))} at the end), {meta['date']}.",
        "",
        f"**Reference:** our `xpbd` fp64, I = 1, at S = {meta['reference_substeps']}: the change from S = "
        f"{int(last['substeps'])} was {last['change_to_2s']:.2g}·L, {conv} (criterion: below "
        f"{meta['reference_fraction']:g} of the smallest error reported).",
        "",
        "| S | max change to 2S / L |",
        "| ---: | ---: |",
        *[f"| {int(r['substeps'])} | {r['change_to_2s']:.3g} |" for _, r in ref.iterrows()],
        "",
        f"### Accuracy over {meta['frames']} frames ({meta['frames'] * meta['frame_dt']:.3g} s)",
        "",
        "Errors are |x − x_ref| / L over every point of every simulated frame; stretch is max |len/ℓ − 1|.",
        "",
        *accuracy_table(acc),
        "",
        f"### Time per frame (ms, median), {meta['threads']} thread(s) each",
        "",
        f"Ours: the simulate stage's median over {meta['time_frames']} frames × {meta['repeat']} repeats "
        f"(`--repeat`); pypbd: the median of {meta['time_frames'] * meta['repeat']} successive `step` calls "
        f"(after one untimed step), OpenMP threads {meta['peer'].get('omp_threads')}.",
        "",
        "What each side's time includes. **Ours**: the backend's frame call alone: the loop over the strands "
        "of one frame's S substeps (the head rotations and gust phases of the frame are computed before the "
        "clock starts; the observables, the fetch and the file write after it stops). **pypbd**: the whole "
        "Python `TimeStepController.step` call: the call from Python into its C++ module and, inside it, its "
        "own bookkeeping per substep (its time-step controller, clearing and integrating accelerations, the "
        "velocity update, its collision detection called with nothing to do) around the same distance "
        "constraints. So the ratio compares our compute loop with a complete step of a general-purpose "
        "library, not two equal kernels; at few strands the fixed per-call cost dominates pypbd's time.",
        "",
        *timing_table(tim),
        "",
        f"![peer time per frame]({os.path.relpath(png, out_dir)})",
        "",
        "### Where the peer wins",
        "",
        "Not measured here: what the peer offers that we do not (other constraint types, rigid bodies, "
        "mesh collisions), listed in docs/decisions.md.",
        "",
        *[f"- {s}" for s in where_the_peer_wins(acc, tim, meta["frames"], float(last["change_to_2s"]))],
        "",
    ]
    return lines


def write(results_dir=None, report_dir=None):
    """report/peer.md from results/peer/."""
    results_dir = Path(results_dir) if results_dir else RESULTS / "peer"
    out_dir = Path(report_dir) if report_dir else REPORT
    lines = section(results_dir, out_dir)
    path = out_dir / "peer.md"
    return files.write_text(path, "\n".join(lines) + "\n")
