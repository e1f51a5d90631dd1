"""`harness compare`'s outputs, drawn from a check.compare_runs.Comparison: the rendered table
(Markdown, also what the command prints), compare.csv and compare.json (every matched figure)
and compare.png (each figure's ratio B/A against its time in A, its within-noise interval
drawn under it, the fail line)."""

from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import matplotlib.ticker  # noqa: E402

from harness.core import tolerances  # noqa: E402
from harness.io import files  # noqa: E402

COLOURS = {"slower": "tab:red", "faster": "tab:green", "within noise": "0.55"}
SHOWN = 25  # rows of each verdict the table lists (the CSV holds them all)


def _side(name, side):
    where = ", ".join(x for x in (side.get("device"), side.get("revision")) if x)
    return f"{name}: `{side['path']}`" + (f" ({where})" if where else "")


def _pct(x):
    return f"{100 * (x - 1):+.1f} %"


def _noise(x, why):
    return f"{100 * x:.2g} % ({why})" if x == x else "not recorded"


def markdown(comp):
    """The comparison as Markdown: the two runs, the counts, then the slower and faster figures
    (largest change first; SHOWN of each at most)."""
    c = comp.counts()
    rule = f"median·(1 ± max({100 * tolerances.TIMING_MAX_RSD:g} %, {tolerances.TIMING_TIE_K:g}·rsd))"
    lines = [
        "# Compare",
        "",
        _side("A (before)", comp.a) + "  ",
        _side("B (after)", comp.b),
        "",
        f"{len(comp.table)} figures matched: **{c['slower']} slower**, **{c['faster']} faster**, "
        f"{c['within noise']} within noise (the two figures' bands, {rule}, overlap). "
        f"Fails (exit 1) when a slower figure's ratio B/A is above {comp.fail_above:g}: "
        + ("**failed**." if comp.failed else "passed."),
    ]
    if comp.noisy_slower():
        lines += [
            "",
            f"{comp.noisy_slower()} slower figures above {comp.fail_above:g} were marked as noise when measured "
            "(a spread above the stopping rule's, a loaded host) and do not fail it: measure them again on a quiet "
            "host.",
        ]
    if comp.only_a or comp.only_b:
        lines += ["", f"Not compared: {len(comp.only_a)} figures only in A, {len(comp.only_b)} only in B."]
    for what, ascending in (("slower", False), ("faster", True)):
        rows = comp.table[comp.table["verdict"] == what].sort_values("ratio", ascending=ascending)
        if rows.empty:
            continue
        lines += ["", f"## {what.capitalize()} ({len(rows)})", ""]
        lines += ["| source | case and stage | A ms | B ms | B/A | within noise | noise A, B | |", "|" + " --- |" * 8]
        for r in rows.head(SHOWN).itertuples():
            flag = "**fails**" if r.fails else (f"noisy: {r.noisy}" if r.noisy else "")
            lines.append(
                f"| {r.source} | `{r.key}` | {r.median_ms_a:.4g} | {r.median_ms_b:.4g} | {_pct(r.ratio)} | "
                f"{_pct(r.within_lo)} … {_pct(r.within_hi)} | {_noise(r.noise_a, r.noise_from_a)}, "
                f"{_noise(r.noise_b, r.noise_from_b)} | {flag} |"
            )
        if len(rows) > SHOWN:
            lines.append(f"| … {len(rows) - SHOWN} more in compare.csv | | | | | | | |")
    return "\n".join(lines) + "\n"


def plot(comp, path):
    """compare.png: ratio B/A (log) against A's time (log), a point a figure coloured by its
    verdict, its within-noise interval as a bar under it; 1 and the fail ratio as lines."""
    t = comp.table
    fig, ax = plt.subplots(figsize=(7.5, 4.5))
    ax.set_xscale("log")
    ax.set_yscale("log")
    top = max(float(t["ratio"].max()), comp.fail_above) * 2  # an unbounded interval drawn to here
    ax.vlines(t["median_ms_a"], t["within_lo"], t["within_hi"].clip(upper=top), color="0.85", lw=2, zorder=1)
    for what, colour in COLOURS.items():
        s = t[t["verdict"] == what]
        ax.scatter(s["median_ms_a"], s["ratio"], s=12, color=colour, label=f"{what} ({len(s)})", zorder=2)
    ax.axhline(1.0, color="0.3", lw=0.8)
    ax.axhline(comp.fail_above, color="tab:red", lw=0.8, ls="--", label=f"fails above {comp.fail_above:g}")
    ax.yaxis.set_major_formatter(matplotlib.ticker.FormatStrFormatter("%g"))
    lo, hi = ax.get_ylim()
    narrow = hi / lo < 10  # within a decade the minor ticks carry the labels
    ax.yaxis.set_minor_formatter(
        matplotlib.ticker.FormatStrFormatter("%g") if narrow else matplotlib.ticker.NullFormatter()
    )
    ax.set_xlabel("A's median time (ms)")
    ax.set_ylabel("B / A (above 1: B slower)")
    ax.set_title("B against A, each figure with its within-noise interval (grey)", fontsize=10)
    ax.legend(loc="upper left", bbox_to_anchor=(1.01, 1.0), fontsize=8, frameon=False)
    try:
        return files.save_figure(fig, path, dpi=110, bbox_inches="tight")
    finally:
        plt.close(fig)


def write(comp, out_dir):
    """compare.md, compare.csv, compare.json and compare.png in `out_dir` (made if absent)."""
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    files.write_text(out / "compare.md", markdown(comp) + "\n![B against A](compare.png)\n")
    files.write_csv(out / "compare.csv", list(comp.table.columns), comp.table.to_dict("records"))
    files.write_json(out / "compare.json", comp.record())
    plot(comp, out / "compare.png")
    return [out / n for n in ("compare.md", "compare.csv", "compare.json", "compare.png")]
