"""The feature-cost table (harness/studies/featurecost_dynamic.py's rows) as Markdown: `markdown(rows)` for
one run, `section(paths)` for the report (the CPU's CSV and, where present, the GPU's),
with what each feature costs alone and inside the full scene.

CSV files live beside a results directory as `featurecost/<backend>[-<build>].csv`
(`csv_paths(results_dir)` finds them; `python -m harness featurecost --out` writes one).
"""

import csv
from pathlib import Path

from harness.core.paths import display
from harness.core.scenes_dynamic import FEATURES, NEEDS

NONE_ROW = "none (gravity, stretch)"


def markdown(rows):
    full = next((r for r in rows if r["row"] == "full"), None)
    first = rows[0]
    where = f"{first['backend']}/{first['variant']}"
    if first.get("threads"):
        where += f", {first['threads']} threads"
    if first.get("block_size"):
        where += f", block {first['block_size']}"
    lines = [
        f"{int(first['strands']):,} strands × {first['points']} points, {first['precision']}, {first['solver']} "
        f"S = {first['substeps']}, I = {first['iterations']}; {where}; {first['device']}",
        "",
        "| case | features compiled in | ms / frame (median) | min … max | spread | point-substeps/s | vs full |"
        + (" instructions / point-substep |" if counted(rows) else ""),
        "| --- | --- | ---: | ---: | ---: | ---: | ---: |" + (" ---: |" if counted(rows) else ""),
    ]
    for r in rows:
        rel = f"{float(r['median_ms']) / float(full['median_ms']):.2f}" if full else "—"
        ips = f" {float(r['instructions_per_point_substep']):.1f} |" if counted(rows) else ""
        lines.append(
            f"| {r['row']} | {r['features']} | {float(r['median_ms']):.3f} | {float(r['min_ms']):.3f} … "
            f"{float(r['max_ms']):.3f} | {_spread(r)} | {float(r['point_substeps_per_s']):.3g} | {rel} |{ips}"
        )
    return "\n".join(lines) + "\n"


def _spread(r):
    """The row's relative standard deviation, "(noise: why)" where core/timing.py flags it."""
    rsd = r.get("rsd")
    text = f"{100 * float(rsd):.2g} %" if rsd not in (None, "") else "—"
    return text + (f" (noise: {r['noisy']})" if r.get("noisy") else "")


def counted(rows):
    """Whether the rows carry callgrind's instruction counts (featurecost --instructions)."""
    return all(r.get("instructions_per_point_substep") not in (None, "") for r in rows)


def _only_row(feature):
    """The row name featurecost.cases gives a feature declared alone (with what it needs)."""
    return f"only {'+'.join(sorted({feature, *NEEDS.get(feature, ())}))}"


def _base_row(feature):
    """The row a feature declared alone is measured against: none, or what it needs alone
    (the wind against drag alone, gusts against wind and drag)."""
    needs = NEEDS.get(feature, ())
    if not needs:
        return NONE_ROW
    return f"only {'+'.join(sorted(needs))}"


def costs(rows):
    """Per feature: (alone: t(only X) − t(its base row), in full: t(full) − t(full − X)) in
    ms, and whether each difference is inside the runs' spread (min … max ranges overlap)."""
    by = {r["row"]: r for r in rows}
    full = by.get("full")
    out = []
    for feat in FEATURES:
        none = by.get(_base_row(feat))
        alone, minus = by.get(_only_row(feat)), by.get(f"full − {feat}")
        a = float(alone["median_ms"]) - float(none["median_ms"]) if alone and none else None
        b = float(full["median_ms"]) - float(minus["median_ms"]) if full and minus else None
        noisy_a = bool(alone and none and (_overlap(alone, none) or _noise(alone, none)))
        noisy_b = bool(full and minus and (_overlap(full, minus) or _noise(full, minus)))
        out.append((feat, a, noisy_a, b, noisy_b))
    return out


def _noise(*rows):
    """Whether any row's time is flagged as noise (core/timing.py; rows measured before it: no)."""
    return any(r.get("noisy") for r in rows)


def _overlap(r, s):
    return float(r["min_ms"]) <= float(s["max_ms"]) and float(s["min_ms"]) <= float(r["max_ms"])


def cost_table(rows):
    """Each feature's cost alone (against `none`, or against what it needs: the wind against
    drag alone, gusts against wind and drag) and inside the full scene."""
    full = next((r for r in rows if r["row"] == "full"), None)
    lines = [
        "| feature | alone: only it − base (ms) | % of base | in the full scene: full − (full − it) (ms) | % of full |",
        "| --- | ---: | ---: | ---: | ---: |",
    ]

    def cell(v, base, noisy):
        if v is None or base is None:
            return "—", "—"
        mark = " (within spread or noise)" if noisy else ""
        return f"{v:+.3f}{mark}", f"{100 * v / float(base['median_ms']):+.0f} %"

    by = {r["row"]: r for r in rows}
    for feat, a, na, b, nb in costs(rows):
        ca, pa = cell(a, by.get(_base_row(feat)), na)
        cb, pb = cell(b, full, nb)
        lines.append(f"| {feat} | {ca} | {pa} | {cb} | {pb} |")
    return lines


def read_csv(path):
    with open(path, newline="") as f:
        return list(csv.DictReader(f))


def csv_paths(results_dir):
    """The feature-cost CSVs beside a results directory: cpu first, then the cuda builds."""
    d = Path(results_dir).parent / "featurecost"
    if not d.is_dir():
        return []
    found = sorted(d.glob("*.csv"), key=lambda p: (not p.stem.startswith("cpu"), p.stem))
    return found


def section(paths):
    """The report's feature-cost section from CSV files (cpu first; a GPU's where present)."""
    lines = [
        "## Model only what a scene requires: what each feature costs",
        "",
        "Time per frame of the default dynamic scene with every feature undeclared (gravity and "
        "stretch only), each declared alone (with what it needs: gusts ride on the wind, the wind "
        "on drag), each removed from the full scene, and the full scene (`python -m harness "
        "featurecost`). A feature is removed by leaving its flags out, so the binary compiles it "
        "out (docs/model.md §3.9): an undeclared feature should cost nothing, so `none` should be "
        "the fastest row. Each feature's cost is given alone (its row less `none`, or less the row "
        "of what it needs) and inside the full scene (`full` less `full − it`); differences inside "
        "the two runs' min … max spread, or flagged as noise (core/timing.py: a relative standard deviation "
        "above 0.5 % or a host loaded by others), are marked and decide nothing.",
        "",
    ]
    if not paths:
        return lines + ["Not measured with these results (no `featurecost/*.csv` beside them).", ""]
    for path in paths:
        rows = read_csv(path)
        if not rows:
            lines += [f"`{display(path)}` holds no rows.", ""]
            continue
        first = rows[0]
        lines += [f"### {first['backend']} ({display(path)})", "", markdown(rows).rstrip("\n"), ""]
        lines += cost_table(rows) + [""]
        none = next((r for r in rows if r["row"] == NONE_ROW), None)
        if none:
            faster = [
                r["row"]
                for r in rows
                if r is not none and float(r["max_ms"]) < float(none["min_ms"])  # beyond the spread
            ]
            if faster:
                lines += [
                    f"Faster than `none` beyond the spread: {', '.join(faster)}. Undeclared features "
                    "cost nothing only if no row is; this one is not explained by the features and "
                    "needs a look (machine load, or code layout of the specialised loops).",
                    "",
                ]
            else:
                lines += ["No row is faster than `none` beyond the runs' spread.", ""]
        dearer = [feat for feat, _, _, b, noisy in costs(rows) if b is not None and b < 0 and not noisy]
        if dearer:
            lines += [
                f"Slower without it than `full`, beyond the spread: {', '.join(dearer)}. A feature "
                "removed cannot cost time, so these rows are not additive here: the cases run one "
                "after another (a drift of the machine's speed between them shows this way) and each "
                "moves the hair differently (the state sets how many points collide or are pulled); "
                "these runs do not tell which. Read this table's differences as no finer than that.",
                "",
            ]
    return lines
