"""The reduced-model trades (harness/studies/reduced.py's CSV) as Markdown: guide fraction ×
scheme and LRA on/off, each row's error against the fully simulated finer reference and its
time per frame on every binary that timed it; `section(path)` for report/dynamic.md.

Recommendations are read off the measured rows with fixed error budgets on the RMS error
over the hair length L (docs/decisions/reduced-models.md): a preview takes the fewest guides
within PREVIEW_BUDGET, a game within GAME_BUDGET, an offline render simulates every strand.
"""

import csv
from pathlib import Path

from harness.core.paths import display

PREVIEW_BUDGET = 0.05
GAME_BUDGET = 0.02


def read(path):
    with open(path, newline="") as f:
        return list(csv.DictReader(f))


def _times(rows):
    """{(case key): {backend/variant: ms}} and the timing columns in order."""
    cols, out = [], {}
    for r in rows:
        col = f"{r['backend']}/{r['variant']}"
        if col not in cols:
            cols.append(col)
        key = (r["study"], r["solver"], r["iterations"], r["guides"], r["follow"], r["lra"], str(r.get("sag_free", 0)))
        out.setdefault(key, (r, {}))[1][col] = float(r["median_ms"])
    return cols, out


def _fmt_ms(d, col):
    return f"{d[col]:.3f}" if col in d else "—"


def _errs(r):
    return f"{float(r['rms_err_L']):.3g}", f"{float(r['max_err_L']):.3g}"


def _table(cases, cols, study, head, align, cells):
    """A Markdown table of one study's cases: `head` and `cells(key, row)` first, then a time
    column per backend."""
    lines = [
        "| " + " | ".join(head) + " | " + " | ".join(f"{c} ms" for c in cols) + " |",
        align + " ---: |" * len(cols),
    ]
    for key, (r, t) in cases.items():
        if key[0] == study:
            lines.append(
                "| " + " | ".join(map(str, cells(key, r))) + " | " + " | ".join(_fmt_ms(t, c) for c in cols) + " |"
            )
    return lines


def markdown(rows):
    if not rows:
        return "No rows.\n"
    cols, cases = _times(rows)
    first = rows[0]
    sizes = ", ".join(sorted({f"{r['backend']} at {int(r['time_strands']):,} strands" for r in rows}))
    lines = [
        f"Checked runs: {int(first['strands']):,} strands, fp32, S = {first['substeps']}; errors against every "
        f"strand simulated (xpbd, fp64, finer S). Times per frame ({sizes}, median):",
        "",
        *_table(
            cases,
            cols,
            "guides",
            ("solver", "guides", "scheme", "rms err / L", "max err / L"),
            "| --- | ---: | --- | ---: | ---: |",
            lambda k, r: (k[1], f"{float(k[3]):.0%}", k[4] or "all simulated", *_errs(r)),
        ),
        "",
        "Long-range attachments under a fast nod, few iterations (xpbd):",
        "",
        *_table(
            cases,
            cols,
            "lra",
            ("I", "LRA", "rms err / L", "max err / L", "stretch_max"),
            "| ---: | --- | ---: | ---: | ---: |",
            lambda k, r: (k[2], "on" if int(k[5]) else "off", *_errs(r), f"{float(r['stretch_max']):.3g}"),
        ),
    ]
    sag = [(k, v) for k, v in cases.items() if k[0] == "sagfree"]
    if sag:
        lines += [
            "",
            "Sag-free rest: the scene held still (no head motion, no wind, every point in shape); how far the "
            "groom moves from its rest shape:",
            "",
            "| solver | sag-free | rest rms / L | rest max / L | " + " | ".join(f"{c} ms" for c in cols) + " |",
            "| --- | --- | ---: | ---: |" + " ---: |" * len(cols),
        ]
        for (_st, solver, _i, _g, _f, _l, on), (r, t) in sag:
            lines.append(
                f"| {solver} | {'on' if on == '1' else 'off'} | {float(r['rest_rms_L']):.3g} | "
                f"{float(r['rest_max_L']):.3g} | " + " | ".join(_fmt_ms(t, c) for c in cols) + " |"
            )
    lines += ["", *recommend(rows)]
    return "\n".join(lines) + "\n"


def recommend(rows):
    """One line each for a preview, a game and an offline render, from the xpbd guide rows."""
    guide = [r for r in rows if r["study"] == "guides" and r["solver"] == "xpbd" and r["backend"] == "cpu"]

    def fewest(budget):
        ok = [r for r in guide if float(r["rms_err_L"]) <= budget]
        if not ok:
            return None
        return min(ok, key=lambda r: (float(r["guides"]), float(r["rms_err_L"])))

    out = []
    for who, budget in (("a preview", PREVIEW_BUDGET), ("a game", GAME_BUDGET)):
        r = fewest(budget)
        if r is None:
            out.append(f"- For {who} (rms error ≤ {budget:g} L): no measured guide fraction is within it here.")
        else:
            scheme = r["follow"] or "every strand simulated"
            out.append(
                f"- For {who} (rms error ≤ {budget:g} L): {float(r['guides']):.0%} guides, {scheme} "
                f"(measured {float(r['rms_err_L']):.3g} L)."
            )
    lra = {(r["iterations"], r["lra"]): float(r["rms_err_L"]) for r in rows if r["study"] == "lra"}
    helps = [i for (i, on) in lra if on == "1" and lra[(i, "1")] < lra.get((i, "0"), float("inf"))]
    note = f"LRA lowered the error at I = {', '.join(sorted(helps))}" if helps else "LRA did not lower the error here"
    out.append(f"- For an offline render: every strand simulated, and LRA only where it helps ({note}).")
    sag = {(r["solver"], str(r.get("sag_free"))): float(r["rest_max_L"]) for r in rows if r["study"] == "sagfree"}
    if ("xpbd", "0") in sag and ("xpbd", "1") in sag:
        out.append(
            f"- Sag-free rest for every scene with shape: the still groom moved at most {sag[('xpbd', '1')]:.3g} L "
            f"with it and {sag[('xpbd', '0')]:.3g} L without (xpbd)."
        )
    return out


def section(path):
    """The report's section from the study's CSV (or how to measure it)."""
    lines = ["## Modelling less: guides and followers, long-range attachments", ""]
    p = Path(path)
    if not p.exists():
        return lines + [
            f"Not measured here: this results directory has no `{display(p)}` (the study is newer than the run); "
            f"`python -m harness reduced --out {display(p)}` or `make bench` measures it."
        ]
    lines += [
        "docs/model.md §3.14. Simulated-point LOD and sag-free rest are not built yet (no rows).",
        "",
        markdown(read(p)).rstrip(),
    ]
    return lines
