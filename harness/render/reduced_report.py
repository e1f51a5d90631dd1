"""The reduced-model trades (harness/studies/reduced.py's CSV) as Markdown: guide fraction ×
scheme, LRA on/off, simulated points P_s against rendered points P_r (LOD), and sag-free rest
(the still groom's displacement, the tip's swing frequency), each row's error against the fully
simulated finer reference and its time per frame on every binary that timed it;
`section(path)` for report/dynamic.md.

Recommendations are read off the measured rows with fixed error budgets on the RMS error
over the hair length L (docs/decisions/reduced-models.md): a preview takes the fewest guides
and the fewest simulated points within PREVIEW_BUDGET, a game within GAME_BUDGET, an offline
render simulates every strand and every point.
"""

import csv
from pathlib import Path

from harness.core.paths import display

PREVIEW_BUDGET = 0.05
GAME_BUDGET = 0.02


def _table_head(intro, header, rule):
    """A paragraph, then a Markdown table's header and rule."""
    return ["", intro, "", header, rule]


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
        key = (r["study"], r["solver"], r["iterations"], r["guides"], r["follow"], r["lra"], str(r.get("sag_free", 0)),
               str(r.get("points", "")))  # fmt: skip
        ms = float(r["median_ms"])
        if r.get("render_ms") not in (None, ""):
            ms += float(r["render_ms"])  # LOD: the frame and its rendering
        out.setdefault(key, (r, {}))[1][col] = ms
    return cols, out


def _fmt_ms(d, col):
    return f"{d[col]:.3f}" if col in d else "—"


def _points(r):
    """P_s as the LOD table writes it: "9", or "33 (all)" where every written point is simulated."""
    return f"{r['points']}" + (" (all)" if int(r["points"]) == int(r["render_points"]) else "")


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
        lines += _table_head(
            "Sag-free rest: the scene held still (no head motion, no wind, every point in shape); how far the "
            "groom moves from its rest shape:",
            "| solver | sag-free | rest rms / L | rest max / L | " + " | ".join(f"{c} ms" for c in cols) + " |",
            "| --- | --- | ---: | ---: |" + " ---: |" * len(cols),
        )
        for (_st, solver, _i, _g, _f, _l, on, _p), (r, t) in sag:
            lines.append(
                f"| {solver} | {'on' if on == '1' else 'off'} | {float(r['rest_rms_L']):.3g} | "
                f"{float(r['rest_max_L']):.3g} | " + " | ".join(_fmt_ms(t, c) for c in cols) + " |"
            )
    freq = [(k, v) for k, v in cases.items() if k[0] == "sagfreq"]
    if freq:
        lines += _table_head(
            "Sag-free rest leaves the dynamics alone: the same still scene hit at t = 0 by a steady wind (a step "
            "load); the median over strands of the tip's swing frequency and damping ratio:",
            "| solver | sag-free | tip Hz | tip damping ratio |",
            "| --- | --- | ---: | ---: |",
        )
        for (_st, solver, *_rest, on, _p), (r, _t) in freq:
            lines.append(
                f"| {solver} | {'on' if on == '1' else 'off'} | {float(r['tip_hz']):.4g} | "
                f"{float(r['tip_damping']):.3g} |"
            )
    if any(k[0] == "lod" for k in cases):
        pr = next(r["render_points"] for k, (r, _t) in cases.items() if k[0] == "lod")
        lines += [
            "",
            f"Simulated-point LOD: P_s points simulated, {pr} written (a centripetal Catmull–Rom spline through "
            f"the simulated ones, --render-points); errors against {pr} points simulated; times are the frame's "
            "plus its rendering:",
            "",
            *_table(
                cases,
                cols,
                "lod",
                ("solver", "P_s", "rms err / L", "max err / L"),
                "| --- | ---: | ---: | ---: |",
                lambda k, r: (k[1], _points(r), *_errs(r)),
            ),
        ]
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

    lod = [r for r in rows if r["study"] == "lod" and r["solver"] == "xpbd" and r["backend"] == "cpu"]

    def fewest_points(budget):
        ok = [r for r in lod if float(r["rms_err_L"]) <= budget]
        return min(ok, key=lambda r: (int(r["points"]), float(r["rms_err_L"]))) if ok else None

    out = []
    for who, budget in (("a preview", PREVIEW_BUDGET), ("a game", GAME_BUDGET)):
        r = fewest(budget)
        if r is None:
            line = f"- For {who} (rms error ≤ {budget:g} L): no measured guide fraction is within it here"
        else:
            scheme = r["follow"] or "every strand simulated"
            line = (
                f"- For {who} (rms error ≤ {budget:g} L): {float(r['guides']):.0%} guides, {scheme} "
                f"(measured {float(r['rms_err_L']):.3g} L)"
            )
        p = fewest_points(budget)
        if lod and p is None:
            line += "; no measured P_s is within it"
        elif p is not None and int(p["points"]) != int(p["render_points"]):
            line += (
                f"; {p['points']} simulated points rendered as {p['render_points']} "
                f"(measured {float(p['rms_err_L']):.3g} L)"
            )
        elif p is not None:
            line += "; every point simulated (fewer points were not within it)"
        out.append(line + ".")
    lra = {(r["iterations"], r["lra"]): float(r["rms_err_L"]) for r in rows if r["study"] == "lra"}
    helps = [i for (i, on) in lra if on == "1" and lra[(i, "1")] < lra.get((i, "0"), float("inf"))]
    note = f"LRA lowered the error at I = {', '.join(sorted(helps))}" if helps else "LRA did not lower the error here"
    out.append(
        f"- For an offline render: every strand and every point simulated, and LRA only where it helps ({note})."
    )
    sag = {(r["solver"], str(r.get("sag_free"))): float(r["rest_max_L"]) for r in rows if r["study"] == "sagfree"}
    hz = {str(r.get("sag_free")): float(r["tip_hz"]) for r in rows if r["study"] == "sagfreq" and r["solver"] == "xpbd"}
    if ("xpbd", "0") in sag and ("xpbd", "1") in sag:
        line = (
            f"- Sag-free rest for every scene with shape (preview, game and offline alike): the still groom moved at "
            f"most {sag[('xpbd', '1')]:.3g} L with it and {sag[('xpbd', '0')]:.3g} L without (xpbd)"
        )
        if "0" in hz and "1" in hz:
            line += f"; the tip swings at {hz['1']:.4g} Hz with it and {hz['0']:.4g} Hz without"
        out.append(line + ".")
    return out


def section(path):
    """The report's section from the study's CSV (or how to measure it)."""
    lines = ["## Modelling less: guides and followers, long-range attachments, sag-free rest, simulated-point LOD", ""]
    p = Path(path)
    if not p.exists():
        return lines + [
            f"Not measured here: this results directory has no `{display(p)}` (the study is newer than the run); "
            f"`python -m harness reduced --out {display(p)}` or `make bench` measures it."
        ]
    lines += [
        "docs/model.md §3.14.",
        "",
        markdown(read(p)).rstrip(),
    ]
    return lines
