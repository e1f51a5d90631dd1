"""Render the stability map (stability.py measures it): read stability.csv, draw one heatmap
per slice (report/stability_<slice>.png: a panel per backend × solver × precision, each
cell coloured by its verdict and labelled with its stretch), and write
report/dynamic_stability.md, whose boundaries in words are generated from the data."""

import json
from pathlib import Path

import pandas as pd

from harness import HarnessError
from harness.core import tolerances
from harness.core.paths import REPORT, display
from harness.io import files, tables
from harness.studies.stability_slices_dynamic import BLOWN_UP, LEGACY, OTHER, SLICES, VERDICTS, axis

ORDER = VERDICTS + LEGACY + OTHER
COLOURS = {
    "ok": "#9fd89f",
    "over-stretched": "#f5c05a",
    "penetrating": "#b58ad9",
    "escaped": "#e8896a",
    "diverged": "#b52b27",
    "refused": "#bbbbbb",
    "timed out": "#8c8c8c",
    "blown up": "#d9534f",
    "failed": "#555555",
}
# how the words name a verdict ("xpbd fp32 blows up at …")
VERBS = {
    "escaped": "escapes (a point past twice its hanging length, finite)",
    "diverged": "diverges (NaN/Inf)",
    "penetrating": "penetrates the head",
    "over-stretched": "over-stretches",
    "refused": "is refused",
    "timed out": "did not finish within the map's per-cell timeout",
    "blown up": "blows up (a map measured before the split by cause)",
    "failed": "fails",
}
WORST_FIRST = ("diverged", "escaped", *LEGACY, "penetrating", "over-stretched", *OTHER)


def load(csv_path):
    try:
        rows = tables.read_csv(csv_path, dtype={"row": str, "col": str}, keep_default_na=False)
    except (OSError, ValueError) as e:  # ValueError: a parse error, no data, or not text at all
        raise HarnessError(f"{display(csv_path)}: cannot read as a stability CSV ({e})") from None
    need = {"slice", "backend", "build", "solver", "precision", "row", "col", "verdict", "stretch_max"}
    lacks = sorted(need - set(rows.columns))
    if lacks:
        raise HarnessError(f"{display(csv_path)}: not a stability CSV (lacks {', '.join(lacks)})")
    if rows.empty:
        raise HarnessError(f"{display(csv_path)} has no rows")
    bad = sorted(set(rows["verdict"]) - set(ORDER))
    if bad:
        raise HarnessError(f"{display(csv_path)}: unknown verdict(s) {', '.join(bad)}")
    rows["label"] = [b if b == "cpu" else f"cuda-{u}" for b, u in zip(rows["backend"], rows["build"])]
    rows["stretch_max"] = pd.to_numeric(rows["stretch_max"], errors="coerce")
    return rows


def axis_of(name, key):
    """(label, unit) of a slice's axis, from stability.SLICES (the key itself if unknown)."""
    for s in SLICES:
        if s.name == name:
            for a in (s.rows, s.cols):
                if a.key == key:
                    return a.label, a.unit
    a = axis(key)  # a slice over a user's scene (stability --scene) takes the shared axes
    return (a.label, a.unit) if a else (key.lstrip("-"), "")


def ordered(values):
    """Unique values in order of first appearance (the order the map ran them)."""
    return list(dict.fromkeys(values))


def grid(part):
    """(row values, col values, {(row, col): row of the CSV}) of one panel."""
    rows, cols = ordered(part["row"]), ordered(part["col"])
    return rows, cols, {(r.row, r.col): r for r in part.itertuples(index=False)}


def span(values, chosen, label, unit):
    """Consecutive runs of `chosen` among the axis `values`, in words: "S ≤ 2", "S ≥ 32",
    "S = 4 … 16", "S = 8"."""
    runs, cur = [], []
    for v in values:
        if v in chosen:
            cur.append(v)
        elif cur:
            runs.append(cur)
            cur = []
    if cur:
        runs.append(cur)
    u = f" {unit}" if unit else ""
    words = []
    for run in runs:
        if len(run) == len(values):
            words.append(f"every {label}")
        elif run[0] == values[0] and len(run) > 1:
            words.append(f"{label} ≤ {run[-1]}{u}")
        elif run[-1] == values[-1] and len(run) > 1:
            words.append(f"{label} ≥ {run[0]}{u}")
        elif len(run) == 1:
            words.append(f"{label} = {run[0]}{u}")
        else:
            words.append(f"{label} = {run[0]} … {run[-1]}{u}")
    return " and ".join(words)


def boundaries(part, slice_name):
    """The panel's boundaries in words: for each verdict other than ok, where it occurs,
    along the rows for each group of columns that behave alike."""
    rows, cols, at = grid(part)
    row_key, col_key = part["row_key"].iloc[0], part["col_key"].iloc[0]
    rl, ru = axis_of(slice_name, row_key)
    cl, cu = axis_of(slice_name, col_key)
    found = []
    for v in WORST_FIRST:
        where = {c: [r for r in rows if (r, c) in at and at[(r, c)].verdict == v] for c in cols}
        if not any(where.values()):
            continue
        groups = []  # consecutive columns with the same rows
        for c in cols:
            if groups and groups[-1][1] == where[c]:
                groups[-1][0].append(c)
            else:
                groups.append(([c], where[c]))
        parts = [f"{span(rows, set(rs), rl, ru)} ({span(cols, set(cs), cl, cu)})" for cs, rs in groups if rs]
        found.append(f"{VERBS[v]} at {'; '.join(parts)}")
    ok = [(r, c) for r in rows for c in cols if (r, c) in at and at[(r, c)].verdict == "ok"]
    if not found:
        return "ok in every cell"
    if not ok:
        found.append("ok in no cell")
    return "; ".join(found)


def percent(stretch):
    """A stretch as the heatmap writes it: 1.2%, 26%, 346%."""
    p = 100 * stretch
    return f"{p:.1f}%" if p < 10 else f"{p:.0f}%"


def heatmap(rows, slice_name, path):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.colors import ListedColormap
    from matplotlib.patches import Patch

    part = rows[rows["slice"] == slice_name]
    labels = ordered(part["label"])
    combos = [(s, p) for s in ordered(part["solver"]) for p in ordered(part["precision"])]
    fig, axes = plt.subplots(
        len(labels), len(combos), figsize=(3.3 * len(combos), 2.9 * len(labels) + 0.8), squeeze=False
    )
    cmap = ListedColormap([COLOURS[v] for v in ORDER])
    for i, lab in enumerate(labels):
        for j, (solver, prec) in enumerate(combos):
            ax = axes[i][j]
            panel = part[(part["label"] == lab) & (part["solver"] == solver) & (part["precision"] == prec)]
            rv, cv, at = grid(panel)
            codes = [[ORDER.index(at[(r, c)].verdict) if (r, c) in at else -1 for c in cv] for r in rv]
            ax.imshow(codes, cmap=cmap, vmin=0, vmax=len(ORDER) - 1, aspect="auto", origin="lower")
            for y, r in enumerate(rv):
                for x, c in enumerate(cv):
                    cell = at.get((r, c))
                    if cell is None:
                        continue
                    s = cell.stretch_max
                    note = "–" if cell.verdict in OTHER else "×" if cell.verdict in BLOWN_UP + LEGACY else percent(s)
                    ax.text(x, y, note, ha="center", va="center", fontsize=6.5)
            ax.set_xticks(range(len(cv)), cv, fontsize=7, rotation=45)
            ax.set_yticks(range(len(rv)), rv, fontsize=7)
            cl, cu = axis_of(slice_name, panel["col_key"].iloc[0])
            rl, ru = axis_of(slice_name, panel["row_key"].iloc[0])
            ax.set_xlabel(f"{cl} ({cu})" if cu else cl, fontsize=8)
            ax.set_ylabel(f"{rl} ({ru})" if ru else rl, fontsize=8)
            ax.set_title(f"{lab} · {solver} · {prec}", fontsize=9)
    title = next((s.title for s in SLICES if s.name == slice_name), slice_name)
    fig.suptitle(f"Stability: {title}. Cells: verdict; text: max stretch over the horizon (× blown up)", fontsize=10)
    fig.legend(
        handles=[Patch(color=COLOURS[v], label=v) for v in ORDER if v in set(part["verdict"]) or v in VERDICTS],
        loc="lower center",
        ncol=6,
        fontsize=8,
        frameon=False,
    )
    fig.tight_layout(rect=(0, 0.05, 1, 0.96))
    path.parent.mkdir(parents=True, exist_ok=True)
    try:
        return files.save_figure(fig, path, dpi=100)
    finally:
        plt.close(fig)


def backend_agreement(rows):
    """Lines comparing each GPU build's verdicts with the CPU's, cell by cell."""
    keys = ["slice", "solver", "precision", "row", "col"]
    cpu = rows[rows["label"] == "cpu"].set_index(keys)["verdict"]
    lines = []
    for lab in ordered(rows["label"]):
        if lab == "cpu":
            continue
        other = rows[rows["label"] == lab].set_index(keys)["verdict"]
        common = cpu.index.intersection(other.index)
        differ = [k for k in common if cpu[k] != other[k]]
        lines.append(f"- **{lab}**: the same verdict as the CPU in {len(common) - len(differ)} of {len(common)} cells.")
        for k in differ[:12]:
            lines.append(f"  - {' '.join(map(str, k))}: cpu {cpu[k]}, {lab} {other[k]}")
        if len(differ) > 12:
            lines.append(f"  - … and {len(differ) - 12} more")
    return lines


def write_markdown(rows, path, info, pngs):
    bound_s = tolerances.STABILITY_STRETCH_MAX
    bound_p = tolerances.STABILITY_PENETRATION_REL
    lines = [
        "# Stability of the dynamic model at the extremes",
        "",
        "Made by `python -m harness stability` (harness/studies/stability_dynamic.py measures, "
        'harness/render/stability_dynamic_report.py renders); how to read it: docs/harness.md, "Stability map".',
        "",
        f"Each cell is one run of {info.get('strands', '?')} strands over {info.get('frames', '?')} frames "
        "(Δt = 1/60 s) of the base scene with one or two parameters changed; its verdict is the first of: "
        "**diverged** (a strand blown up in some frame, docs/model.md §3.8, and a NaN or Inf in the last "
        "frame), **escaped** (a point farther from its root than twice the length the strand hangs at under "
        "its own weight in some frame — 2L, or for a soft xpbd chain 2(L + α_s·g0·P(P − 1)/2) — every number "
        "finite: large but bounded, as an iteration-starved run is; the substeps-iterations slice shows where "
        "more iterations bring it back; a soft chain that settles at its static length is judged by its "
        "stretch), "
        f"**penetrating** (penetration_max > {bound_p:g}·R_c), **over-stretched** "
        f"(stretch_max > {bound_s:g}, i.e. {100 * bound_s:.0f} %), else **ok** (bounds and their reasons: "
        "harness/core/tolerances.py STABILITY_*).",
        "",
    ]
    where = info.get("cpu_model") or "?"
    gpus = info.get("gpus") or []
    lines.append(
        f"Measured on {where} ({info.get('cpu_cores', '?')} cores)"
        + (f" and {gpus[0]['name']}" if gpus else "")
        + f", {info.get('date', '?')}, revision {info.get('git_revision', '?')}: "
        f"{len(rows)} cells in {info.get('seconds', '?')} s with {info.get('jobs', '?')} jobs"
        + (" (`--quick`: a coarser grid)" if info.get("quick") else "")
        + "."
    )
    labels = ordered(rows["label"])
    if labels == ["cpu"]:
        lines.append("No GPU build ran here (no GPU, or none built): CPU cells only.")
    lines.append("")
    lines += ["## Boundaries", ""]
    for s in ordered(rows["slice"]):
        part = rows[rows["slice"] == s]
        title = next((x.title for x in SLICES if x.name == s), s)
        base = next((x.scene for x in SLICES if x.name == s), "the scene named in its title")
        lines += [f"### {title}", "", f"Base scene `{base}`; picture: [{pngs[s].name}]({pngs[s].name}).", ""]
        for lab in labels:
            for solver in ordered(part["solver"]):
                for prec in ordered(part["precision"]):
                    panel = part[(part["label"] == lab) & (part["solver"] == solver) & (part["precision"] == prec)]
                    if panel.empty:
                        continue
                    lines.append(f"- **{lab} {solver} {prec}** {boundaries(panel, s)}.")
        lines += ["", f"![{title}]({pngs[s].name})", ""]
    counts = rows.groupby(["label", "verdict"]).size().unstack(fill_value=0)
    lines += ["## Verdicts per backend", "", "| backend | " + " | ".join(c for c in ORDER if c in counts) + " |"]
    lines.append("| --- |" + " --- |" * sum(c in counts for c in ORDER))
    for lab in labels:
        lines.append(f"| {lab} | " + " | ".join(str(int(counts.loc[lab, c])) for c in ORDER if c in counts) + " |")
    lines.append("")
    if len(labels) > 1:
        lines += ["## GPU builds against the CPU", "", *backend_agreement(rows), ""]
    viol = rows[rows["violations"].astype(str) != ""]
    lines += ["## Contract checks", ""]
    lines.append(
        "The last frame of every cell goes through harness.check.invariants_dynamic (roots at Q(t)·X̄0, no point "
        "inside the collider, FTL segments, observables that agree with the positions, no NaN/Inf)."
    )
    if viol.empty:
        lines.append("No cell violated them.")
    else:
        lines.append(f"{len(viol)} cell(s) violated them:")
        lines.append("")
        for r in viol.itertuples(index=False):
            lines.append(
                f"- {r.label} {r.slice} {r.solver} {r.precision} {r.row_key} {r.row}, {r.col_key} {r.col}: "
                f"{r.violations} (verdict {r.verdict})"
            )
    other = rows[rows["verdict"].isin(OTHER)]
    if not other.empty:
        lines += ["", "Cells the binary did not run:", ""]
        for r in other.itertuples(index=False):
            lines.append(f"- {r.label} {r.slice} {r.solver} {r.precision} {r.row}, {r.col}: {r.message}")
    lines.append("")
    path.parent.mkdir(parents=True, exist_ok=True)
    return files.write_text(path, "\n".join(lines))


def report_from_csv(csv_path, report_dir=None, log=print):
    """Draw the heatmaps and write report/dynamic_stability.md from a stability.csv."""
    csv_path = Path(csv_path)
    rows = load(csv_path)
    try:
        info = json.loads((csv_path.parent / "env.json").read_text())
    except (OSError, ValueError):
        info = {}
    report_dir = Path(report_dir or REPORT)
    pngs = {s: heatmap(rows, s, report_dir / f"stability_{s}.png") for s in ordered(rows["slice"])}
    md = write_markdown(rows, report_dir / "dynamic_stability.md", info, pngs)
    log(f"wrote {display(md)} and {len(pngs)} heatmap(s) from {display(csv_path)}")
    return md


def section(results_dir, report_dir=None):
    """The report's lines for the stability map: report/dynamic_stability.md drawn again from
    results_dir/stability.csv, its heading one level down."""
    md = report_from_csv(Path(results_dir) / "stability.csv", report_dir=report_dir, log=lambda *_: None)
    lines = md.read_text().splitlines()
    return ["#" + ln if ln.startswith("#") else ln for ln in lines]
