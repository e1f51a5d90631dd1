"""The report's pictures (PNG, matplotlib Agg), from a results directory.

  speedup_<precision>.png      wind+collide speedup against strands (log x), one line per
                               block size and one panel per GPU variant, over two named
                               baselines: CPU ref single thread and the fastest CPU variant
                               on all cores (results_data.BASELINES)
  block_size_<precision>.png   wind+collide time against block size (the paper's 32 vs 64)
  bandwidth_<precision>.png    fraction of the measured copy bandwidth against strands (CPU
                               rows, and each GPU variant at its best block size)
  fig1_initialized.png         the paper's Fig. 1 redrawn from an HDF5 state: side view
  fig2_after_wind.png          the paper's Fig. 2 (after wind + collide), same view
Without GPU rows the GPU panels say so instead of staying blank.
"""

from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from harness.core.paths import REPORT, output_dir  # noqa: E402
from harness.io import (
    files,
    results_data,  # noqa: E402
)

FIGURE_DRAWN = 160  # strands drawn of them


def _save(fig, path):
    path.parent.mkdir(parents=True, exist_ok=True)
    try:
        return files.save_figure(fig, path, dpi=110, bbox_inches="tight")
    finally:
        plt.close(fig)


def _note(ax, text):
    ax.text(0.5, 0.5, text, ha="center", va="center", wrap=True, transform=ax.transAxes, fontsize=9, color="0.3")


def speedup_plot(cases, precision, points, out_dir, gpu_note):
    c = cases[(cases["precision"] == precision) & (cases["points"] == points)].dropna(subset=["pair_ms"])
    gpu = c[c["backend"] == "cuda"]
    cpu = c[c["backend"] == "cpu"]
    variants = sorted(gpu["variant"].unique()) or ["(no GPU rows)"]
    fig, axes = plt.subplots(2, len(variants), figsize=(5.2 * len(variants), 7.5), squeeze=False, sharex=True)
    for row, which in enumerate(("single", "all")):
        base = results_data.cpu_baseline(c, which)
        bname = results_data.BASELINES[which]
        for col, variant in enumerate(variants):
            ax = axes[row][col]
            ax.set_xscale("log")
            ax.set_yscale("log")  # speedups span orders of magnitude, and < 1 at small N
            ax.axhline(1.0, color="0.6", lw=0.8)
            lines = []
            if which == "single":  # the other CPU configurations, as dashed lines
                for label, g in cpu.groupby("label"):
                    if label != "CPU ref 1 thread":
                        lines.append((label, g, "--", "s"))
            if gpu.empty:
                _note(ax, f"GPU rows absent:\n{gpu_note}")
            else:
                for (build, block), g in gpu[gpu["variant"] == variant].groupby(["build", "block_size"]):
                    extra = "" if build in ("", "default") else f" ({build})"
                    lines.append((f"block {block}{extra}", g, "-" if not extra else ":", "o"))
            for label, g, style, marker in lines:
                g = g.sort_values("strands")
                keys = [(precision, points, n) for n in g["strands"]]
                pts = [(n, base[k] / t) for n, k, t in zip(g["strands"], keys, g["pair_ms"]) if k in base.index]
                if pts:
                    ax.plot(*zip(*pts), style, marker=marker, ms=3, label=label)
            ax.set_title(f"{'GPU ' + variant if not gpu.empty else 'speedup'} over {bname}", fontsize=9)
            ax.set_ylabel(f"speedup over {bname}", fontsize=8)
            ax.grid(True, which="both", alpha=0.3)
            if ax.get_legend_handles_labels()[0]:
                ax.legend(fontsize=7)
    for ax in axes[-1]:
        ax.set_xlabel("strands")
    fig.suptitle(f"wind + collide speedup, {precision}, {points} points per strand", fontsize=11)
    return _save(fig, out_dir / f"speedup_{precision}.png")


def block_size_plot(cases, precision, points, out_dir, gpu_note):
    """One panel per GPU variant (default build): time against block size at the two
    largest strand counts, IQR as error bars, 32 and 64 marked (the paper's finding)."""
    c = cases[
        (cases["precision"] == precision)
        & (cases["points"] == points)
        & (cases["backend"] == "cuda")
        & cases["build"].isin(["", "default"])
    ].dropna(subset=["pair_ms"])
    variants = sorted(c["variant"].unique()) or [None]
    fig, axes = plt.subplots(1, len(variants), figsize=(4.6 * len(variants), 4.2), squeeze=False)
    for ax, variant in zip(axes[0], variants):
        ax.set_xscale("log", base=2)
        ax.set_xticks([32, 64, 128, 256, 512, 1024], ["32", "64", "128", "256", "512", "1024"])
        if variant is None:
            _note(ax, f"no GPU rows: the paper's block-size finding (32 vs 64) needs a GPU.\n{gpu_note}")
        else:
            g = c[c["variant"] == variant]
            for n in sorted(g["strands"].unique())[-2:]:  # the two largest strand counts
                gg = g[g["strands"] == n].sort_values("block_size")
                ax.errorbar(
                    gg["block_size"],
                    gg["pair_ms"],
                    yerr=gg["pair_iqr_ms"] / 2,
                    marker="o",
                    ms=3,
                    capsize=2,
                    label=f"N = {n:,}",
                )
            for b in (32, 64):
                ax.axvline(b, color="0.8", lw=0.8, zorder=0)
            ax.legend(fontsize=7)
            ax.set_ylim(bottom=0)
        ax.set_title(f"GPU {variant}" if variant else "GPU", fontsize=10)
        ax.set_xlabel("threads per block")
        ax.grid(True, which="both", alpha=0.3)
    axes[0][0].set_ylabel("wind + collide median (ms), bars: IQR")
    fig.suptitle(f"time against block size (the paper: 64 beat 32), {precision}, {points} points", fontsize=10)
    return _save(fig, out_dir / f"block_size_{precision}.png")


def bandwidth_plot(rows, precision, points, out_dir, gpu_note):
    r = rows[
        (rows["precision"] == precision) & (rows["points"] == points) & rows["stage"].isin(["wind", "collide"])
    ].copy()
    fig, axes = plt.subplots(1, 2, figsize=(11, 4.2), squeeze=False)
    r = r[(r["backend"] == "cpu") | r["build"].isin(["", "default"])]
    best = best_blocks(r)
    r = r[(r["backend"] == "cpu") | r.apply(lambda x: best.get(x["variant"]) == x["block_size"], axis=1)]
    if r.empty:
        r = r.assign(label=[], frac=[])
    else:
        r["label"] = r.apply(results_data.case_label, axis=1)
        r["frac"] = np.asarray(r["bandwidth_fraction"], dtype=float)
    for ax, stage in zip(axes[0], ("wind", "collide")):
        s = r[(r["stage"] == stage) & (r["fused"] != "into-previous")]
        if "stage_index" in s and not s.empty:
            # the collide after wind (the paper's timed pair), not the one after init
            last = s.groupby("case_id")["stage_index"].transform("max")
            s = s[s["stage_index"] == last]
        drawn = False
        for label, g in s.groupby("label"):
            g = g.sort_values("strands").dropna(subset=["frac"])
            if g.empty:
                continue
            ax.plot(g["strands"], g["frac"], marker="o", ms=3, label=label)
            drawn = True
        if not drawn:
            _note(ax, "no bandwidth fractions: the copy bandwidth was not measured")
        elif not (rows["backend"] == "cuda").any():
            ax.text(
                0.02,
                0.97,
                f"GPU rows absent: {gpu_note}",
                transform=ax.transAxes,
                va="top",
                fontsize=7,
                color="0.3",
                wrap=True,
            )
        ax.set_xscale("log")
        ax.set_xlabel("strands")
        ax.set_ylabel("fraction of measured copy bandwidth")
        ax.set_title(f"{stage} (fused pairs under wind)" if stage == "wind" else stage, fontsize=10)
        ax.grid(True, which="both", alpha=0.3)
        if drawn:
            ax.legend(fontsize=6)
    fig.suptitle(
        f"roofline: bytes the stage must move / time, over the device's copy bandwidth ({precision}, {points} points)",
        fontsize=10,
    )
    return _save(fig, out_dir / f"bandwidth_{precision}.png")


def best_blocks(rows):
    """GPU variant → the block size with the smallest wind+collide time at the largest N."""
    g = rows[(rows["backend"] == "cuda") & rows["stage"].isin(["wind", "collide"])]
    if g.empty:
        return {}
    g = g[g["strands"] == g["strands"].max()]
    t = g.groupby(["variant", "block_size"])["median_ms"].sum().reset_index()
    return {v: int(tt.loc[tt["median_ms"].idxmin(), "block_size"]) for v, tt in t.groupby("variant")}


def hair_figures(state_path, out_dir):
    """Fig. 1 (hair initialized) and Fig. 2 (hair after wind) from a paper-scene state."""
    from harness.io.states import open_state

    out = []
    with open_state(state_path) as s:
        stages = s.stages
        after_init = stages.index("collide") if "collide" in stages else 0
        after_wind = len(stages) - 1 if "wind" in stages else None
        R = float(s.params["head_radius"])
        rng = np.random.default_rng(0)
        pick = np.sort(rng.choice(s.n_strands, size=min(FIGURE_DRAWN, s.n_strands), replace=False))
        for name, frame, title in (
            ("fig1_initialized.png", after_init, "Fig. 1: hair initialized"),
            ("fig2_after_wind.png", after_wind, "Fig. 2: hair after wind"),
        ):
            fig, ax = plt.subplots(figsize=(5.5, 6.2))
            if frame is None:
                _note(ax, "this state has no wind stage")
            else:
                x = s.frame(frame)[pick].astype(float)
                for strand in x:
                    ax.plot(strand[:, 2], strand[:, 1], lw=0.6, color="saddlebrown", alpha=0.6)
                ax.add_patch(plt.Circle((0, 0), R, fill=False, color="k", lw=1.2))
                ax.annotate("face →", (R * 0.55, -R * 0.1), fontsize=8, color="0.3")
                ax.set_title(
                    f"{title} (frame {frame}: after {' + '.join(stages[: frame + 1])})\n"
                    f"{len(pick)} of {s.n_strands} strands, side view: projected along x, so a strand\n"
                    "drawn inside the head's outline lies beside the head, at another x",
                    fontsize=9,
                )
            ax.set_aspect("equal")
            ax.set_xlabel("z (toward the face)")
            ax.set_ylabel("y (up)")
            ax.grid(True, alpha=0.2)
            out.append(_save(fig, Path(out_dir) / name))
    return out


def make_all(results_dir, report_dir=None):
    """Every plot of a results directory; returns the paths written."""
    rows, env = results_data.load(results_dir)  # refused before a folder is made
    out_dir = output_dir(report_dir if report_dir else REPORT, "--report-dir")
    cases = results_data.per_case(rows)
    gpu_note = results_data.gpu_absent_reason(env)
    written = []
    points = results_data.main_points(cases)
    for precision in sorted(cases["precision"].unique()) if not cases.empty else []:
        written.append(speedup_plot(cases, precision, points, out_dir, gpu_note))
        written.append(block_size_plot(cases, precision, points, out_dir, gpu_note))
        written.append(bandwidth_plot(rows, precision, points, out_dir, gpu_note))
    state = Path(results_dir) / results_data.FIGURE_STATE  # made by the bench (studies/sweep.py)
    if state.exists():
        written += hair_figures(state, out_dir)
    return written
