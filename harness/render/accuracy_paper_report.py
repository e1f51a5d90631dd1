"""Render the speed-against-accuracy study (studies/accuracy_paper.py measures it): read accuracy.csv,
draw report/accuracy_pareto.png, write report/accuracy.md with studies/accuracy_verdicts_paper.py's
recommendation in words."""

import csv
import json
from pathlib import Path

import numpy as np

from harness import HarnessError
from harness.core.paths import REPORT, display
from harness.io import files
from harness.studies import accuracy_verdicts_paper as verdicts
from harness.studies.accuracy import PAPER_REFERENCE, paper_uses
from harness.studies.accuracy_verdicts_paper import end_to_end


def load_rows(csv_path):
    """The rows of an accuracy.csv, numbers as numbers."""
    ints = ("strands", "points", "frame")
    floats = ("max_err_L", "rms_err_L", "seg_drift", "penetration", "time_ms")
    try:
        with open(csv_path, newline="") as fh:
            rows = list(csv.DictReader(fh))
    except OSError as e:
        raise HarnessError(f"{display(csv_path)}: cannot read ({e.strerror})") from None
    missing = [k for k in ints + floats if rows and k not in rows[0]]
    if missing:
        raise HarnessError(f"{display(csv_path)}: not an accuracy.csv (no column {', '.join(missing)})")
    for r in rows:
        for k in ints:
            r[k] = int(r[k])
        for k in floats:
            r[k] = float(r[k]) if r[k] not in ("", None) else float("nan")
    return rows


def report_from_csv(csv_path, report_dir=None, log=print):
    """Rewrite report/accuracy.md and the Pareto plot from a committed accuracy.csv."""
    rows = load_rows(csv_path)
    if not rows:
        raise HarnessError(f"{display(csv_path)} has no rows")
    report_dir = Path(report_dir or REPORT)
    report_dir.mkdir(parents=True, exist_ok=True)
    mode_rows = [r for r in rows if r["study"] == "mode"]
    res_rows = [r for r in rows if r["study"] == "resolution"]
    strands, points = mode_rows[0]["strands"], mode_rows[0]["points"]
    meta = _env(csv_path)
    res_note = meta.get("resolution_strands")
    gpu_ran = any(r["backend"] == "cuda" for r in mode_rows)
    why = meta.get("gpu_absent") or "no GPU rows in this results file"
    png = pareto_plot(rows, report_dir / "accuracy_pareto.png", strands, points)
    md = write_markdown(rows, report_dir / "accuracy.md", strands, points, res_note, gpu_ran, why)
    log(
        f"wrote {display(png)}, {display(md)} from {display(csv_path)} ({len(mode_rows)} mode rows, "
        f"{len(res_rows)} resolution rows)"
    )
    return md


def _env(csv_path):
    """env.json beside the CSV (recorded by the study), {} when absent or unreadable."""
    try:
        meta = json.loads((Path(csv_path).parent / "env.json").read_text())
    except (OSError, ValueError):
        return {}
    return meta if isinstance(meta, dict) else {}


def pareto_plot(rows, path, strands, points):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(7, 4.5))
    floor = 1e-17
    for r in end_to_end(rows):
        if r["mode"] == PAPER_REFERENCE:
            continue
        err = max(r["max_err_L"], floor)
        ax.scatter(r["time_ms"], err, s=40)
        ax.annotate(r["mode"], (r["time_ms"], err), textcoords="offset points", xytext=(5, 3), fontsize=8)
    res = [r for r in rows if r["study"] == "resolution" and np.isfinite(r["max_err_L"]) and r["max_err_L"] > 0]
    if res:
        ax.plot(
            [r["time_ms"] for r in res],
            [r["max_err_L"] for r in res],
            "k.--",
            lw=0.8,
            label="model resolution P (vs finest, fp64)",
        )
        for r in res:
            ax.annotate(
                r["mode"],
                (r["time_ms"], r["max_err_L"]),
                textcoords="offset points",
                xytext=(4, -9),
                fontsize=7,
                color="0.3",
            )
        ax.legend(fontsize=8, loc="upper left", bbox_to_anchor=(1.01, 1.0), frameon=False)  # beside the data
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlabel(f"time of the scene's stages, median (ms), {strands:,} strands x {points} points")
    ax.set_ylabel("max position error / hair length (end to end)")
    ax.set_title("Speed against accuracy (reference: cpu fp64)")
    ax.grid(True, which="both", alpha=0.3)
    fig.tight_layout()
    files.save_figure(fig, path, dpi=110, bbox_inches="tight")
    plt.close(fig)
    return path


def _tie_note(others):
    return f"; a tie within timing noise with {', '.join(others)}" if others else ""


def recommend(rows):
    """Which mode for which use: studies/accuracy_verdicts_paper.py's recommendation in words."""
    rec = verdicts.recommendation(rows)
    fastest = rec.fastest
    if fastest is None:
        return ["No mode other than the reference ran."]
    lines = [
        f"- Fastest overall: **{fastest['mode']}** ({fastest['time_ms']:.2f} ms, end-to-end error "
        f"{fastest['max_err_L']:.1e}·L{_tie_note(rec.fastest_tied_with)})."
    ]
    for u in rec.uses:
        if u.best is not None:
            lines.append(
                f"- For {u.use} (error ≤ {u.limit:.0e}·L): **{u.best['mode']}** ({u.best['time_ms']:.2f} ms, "
                f"{u.best['max_err_L']:.1e}·L{_tie_note(u.tied_with)})."
            )
        else:
            lines.append(f"- For {u.use} (error ≤ {u.limit:.0e}·L): no mode measured here meets it.")
    if rec.enough is not None:
        lines.append(
            f"- Model resolution: {rec.enough['points']} points per strand stay within 1% of L of the "
            f"finest strand measured ({rec.finest_points} points); the discretisation error "
            "dwarfs every precision's rounding error above."
        )
    return lines


def write_markdown(rows, path, strands, points, res_strands, gpu_ok, why):
    fmt = lambda v: "n/a" if v is None or not np.isfinite(v) else f"{v:.2e}"  # noqa: E731
    out = [
        "## Speed against accuracy",
        "",
        f"Paper scene, {strands:,} strands x {points} points; reference `hairsim-cpu --precision fp64`; "
        "errors of the last frame (end to end) and the worst over all frames; time = sum of the stage "
        "medians of a separate timing run (`--repeat`), never a run that also checks.",
        "",
    ]
    if not gpu_ok:
        out += [f"GPU modes absent: {why}.", ""]
    out += [
        "| mode | use | time (ms) | max err / L (end) | rms err / L (end) | worst max err / L | "
        "segment drift | penetration / rc |",
        "|---|---|---|---|---|---|---|---|",
    ]
    uses = paper_uses()
    for r in end_to_end(rows):
        frames = [x for x in rows if x["study"] == "mode" and x["mode"] == r["mode"]]
        worst = max(x["max_err_L"] for x in frames)
        drift = max(x["seg_drift"] for x in frames)
        pen = max(x["penetration"] for x in frames)
        out.append(
            f"| {r['mode']} | {uses.get(r['mode'], '')} | {r['time_ms']:.2f} | {fmt(r['max_err_L'])} | "
            f"{fmt(r['rms_err_L'])} | {fmt(worst)} | {fmt(drift)} | {fmt(pen)} |"
        )
    res = [r for r in rows if r["study"] == "resolution"]
    if res:
        how_many = f"{res_strands:,} strands, " if res_strands else ""
        out += [
            "",
            f"Model resolution ({how_many}fp64, compared with the finest strand along the "
            "curve; timed with "
            f"{res[0]['backend']}/{res[0]['variant']} fp32 at {strands:,} strands):",
            "",
            "| points per strand | time (ms) | max err / L | rms err / L |",
            "|---|---|---|---|",
        ]
        for r in sorted(res, key=lambda r: r["points"]):
            out.append(f"| {r['points']} | {r['time_ms']:.2f} | {fmt(r['max_err_L'])} | {fmt(r['rms_err_L'])} |")
    out += (
        ["", "### Which mode for which use", ""]
        + recommend(rows)
        + ["", "![speed against accuracy](accuracy_pareto.png)", ""]
    )
    files.write_text(path, "\n".join(out))
    return path
