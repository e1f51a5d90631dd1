"""The reduced-model trades (harness/studies/reduced_dynamic.py's CSV and references.csv beside it) as
Markdown: guide fraction × scheme at each strand count with the guide spacing, LRA on/off, simulated
points P_s against rendered points P_r (LOD), and sag-free rest (the still groom's displacement at
each shape range, the tip's swing), each row's error against a converged, fully simulated reference
up to the pointwise horizon, its statistics against the reference ensemble over the whole run, its
stretch against each segment's own rest length, and its time per frame on every binary that timed
it; `section(path)` for report/dynamic.md.

The recommendations word studies/reduced_verdicts_dynamic.py's picks (per use and strand count the
fewest guides, and the fewest simulated points, within the use's budgets); each names its scene,
horizon and strand count.
"""

import csv
import math
from pathlib import Path

from harness.core import tolerances
from harness.core.paths import display
from harness.io.tables import cell as _f
from harness.studies import reduced_verdicts_dynamic as verdicts
from harness.studies.reduced_verdicts_dynamic import DISTANCES


def read(path):
    with open(path, newline="") as f:
        return list(csv.DictReader(f))


def _g(v, digits=3):
    return "—" if not math.isfinite(v) else f"{v:.{digits}g}"


def _key(r):
    return (r["study"], r["solver"], r["strands"], r["iterations"], r["guides"], r["follow"], r["lra"],
            str(r.get("sag_free", 0)), str(r.get("shape_range", "")), str(r.get("points", "")))  # fmt: skip


def _times(rows):
    """{case key: (row, {backend/variant: ms})} and the timing columns in order."""
    cols, out = [], {}
    for r in rows:
        col = f"{r['backend']}/{r['variant']}"
        if col not in cols:
            cols.append(col)
        ms = _f(r, "median_ms")
        if r.get("render_ms") not in (None, ""):
            ms += _f(r, "render_ms")  # LOD: the frame and its rendering
        out.setdefault(_key(r), (r, {}))[1][col] = ms
    return cols, out


def _table(cases, cols, study, head, cells):
    lines = [
        "| " + " | ".join(head) + " | " + " | ".join(f"{c} ms" for c in cols) + " |",
        "|" + " --- |" * (len(head) + len(cols)),
    ]
    for key, (r, t) in cases.items():
        if key[0] == study:
            ms = " | ".join(f"{t[c]:.3f}" if c in t else "—" for c in cols)
            lines.append("| " + " | ".join(map(str, cells(r))) + " | " + ms + " |")
    return lines


def _errs(r):
    return _g(_f(r, "rms_err_L")), _g(_f(r, "max_err_L"))


def _stats(r):
    return tuple(_g(_f(r, m)) for m in DISTANCES)


def _rate(r, tp):
    """λ as the references table writes it: 'no growth', '≥ x' (a lower bound) or x."""
    if math.isinf(tp):
        return "no growth"
    return ("≥ " if str(r.get("lyapunov_lower_bound")) == "True" else "") + _g(_f(r, "lyapunov_per_s"))


def _rms_words(r, horizon):
    if horizon == 0:
        return "no frame judged pointwise"
    return f"rms {_g(_f(r, 'rms_err_L'))}·L up to {_g(horizon)} s"


def _converged(r):
    """How long the ladder's rule holds from the start (s); older files without the column: yes/no."""
    if r.get("converged_s") not in (None, ""):
        return _g(_f(r, "converged_s"))
    return "yes" if str(r.get("converged")) == "True" else "**no**"


def references_lines(refs):
    if not refs:
        return []
    out = [
        "References (every strand and point simulated, xpbd, fp64, I = 1): S doubled until S and 2S differ by "
        f"less than {tolerances.DYN_ACC_REF_FACTOR:g} × the smallest error of the rows each ranks, at every written "
        "frame up to T_p, or the plan's largest S; three perturbed twins of the finest run give the scene's Lyapunov "
        "rate λ and predictability time T_p. A rung's own error grows with the scene's sensitivity as any "
        "perturbation does, so a reference may hold the rule early and not late: the pointwise horizon is the "
        'written frames within T_p over which the rule holds from the start ("converged over"), none where it '
        "fails at the first. The finest rung, the rung before it and the twins are the ensemble whose spread the "
        "statistics are judged against:",
        "",
        "| scene | strands | ran on | S | ladder (worst RMS of S − 2S within T_p, ÷ smallest row error) | λ (1/s) | "
        "T_p (s) | converged over (s) | pointwise horizon (s) | spread: tip / curvature / area |",
        "| --- | ---: | --- | ---: | --- | ---: | ---: | ---: | ---: | --- |",
    ]
    for r in refs:
        tp = _f(r, "predictability_s")
        out.append(
            f"| {r['scene']} | {int(r['strands']):,} | {r.get('build', '')} | {r['substeps']} | "
            f"{r['ladder']} | {_rate(r, tp)} | "
            f"{'beyond the run' if math.isinf(tp) else _g(tp)} | {_converged(r)} | {_g(_f(r, 'horizon_s'))} | "
            + " / ".join(_g(_f(r, f"{m}_spread")) for m in DISTANCES)
            + " |"
        )
    return out + [""]


def markdown(rows, refs=()):
    if not rows:
        return "No rows.\n"
    cols, cases = _times(rows)
    first = rows[0]
    sizes = ", ".join(sorted({f"{r['backend']} at {int(r['time_strands']):,} strands" for r in rows}))
    lines = [
        f"Checked runs: fp32, S = {first['substeps']}, {_g(_f(first, 'seconds'))} s; errors are the worst written "
        "frame up to the pointwise horizon, statistics (W1 of the tip's and the curvature's distributions, the "
        "silhouette's area; harness/check/ensemble_dynamic.py) over the whole run, stretch against each segment's own "
        f"rest length. Times per frame ({sizes}, median).",
        "",
        *references_lines(refs),
        "Guides and followers (guide spacing: the mean distance from a follower's root to its nearest guide's):",
        "",
        *_table(
            cases,
            cols,
            "guides",
            (
                "solver",
                "strands",
                "guides",
                "spacing (cm)",
                "scheme",
                "rms err / L",
                "max err / L",
                "stretch max (ℓ_k)",
                "stretch of followers",
                "tip W1 / L",
                "curvature W1",
                "area",
            ),  # fmt: skip
            lambda r: (
                r["solver"],
                f"{int(r['strands']):,}",
                f"{_f(r, 'guides'):.0%} ({r['guide_count']})",
                _g(_f(r, "guide_spacing_cm")),
                r["follow"] or "all simulated",
                *_errs(r),
                _g(_f(r, "stretch_max_k")),
                _g(_f(r, "stretch_followers")),
                *_stats(r),
            ),  # fmt: skip
        ),
        "",
        "Long-range attachments under a fast nod, few iterations (LRA bound excess: the largest |x_k − x_0| over "
        "its bound k·ℓ, less 1, in the output; moved: how far LRA moved the output from the same row without it):",
        "",
        *_table(
            cases,
            cols,
            "lra",
            ("solver", "I", "LRA", "rms err / L", "max err / L", "stretch max (ℓ_k)", "bound excess", "moved (cm)"),
            lambda r: (
                r["solver"],
                r["iterations"],
                "on" if int(r["lra"]) else "off",
                *_errs(r),
                _g(_f(r, "stretch_max_k")),
                _g(_f(r, "lra_excess")),
                _g(_f(r, "lra_moved_cm")),
            ),  # fmt: skip
        ),
    ]
    lines += _sag_lines(cases, cols)
    if any(k[0] == "lod" for k in cases):
        pr = next(r["render_points"] for k, (r, _t) in cases.items() if k[0] == "lod")
        lines += [
            "",
            f"Simulated-point LOD: P_s points simulated, {pr} written (a centripetal Catmull–Rom spline through the "
            f"simulated ones, --render-points); errors against {pr} points simulated; stretch of the rendered points "
            "against the rendered rest shape; times are the frame's plus its rendering:",
            "",
            *_table(
                cases,
                cols,
                "lod",
                (
                    "solver",
                    "P_s",
                    "rms err / L",
                    "max err / L",
                    "stretch max (rendered)",
                    "tip W1 / L",
                    "curvature W1",
                    "area",
                ),  # fmt: skip
                lambda r: (r["solver"], _points(r), *_errs(r), _g(_f(r, "stretch_max_k")), *_stats(r)),
            ),
        ]
    lines += ["", *recommend(rows, refs)]
    return "\n".join(lines) + "\n"


def _points(r):
    """P_s as the LOD table writes it: "9", or "33 (all)" where every written point is simulated."""
    return f"{r['points']}" + (" (all)" if int(r["points"]) == int(r["render_points"]) else "")


def _sag_lines(cases, cols):
    out = []
    if any(k[0] == "sagfree" for k in cases):
        out += [
            "",
            "Sag-free rest: the scene held still (no head motion, no wind); how far the groom moves from its rest "
            "shape, at the shipped shape range and with every point in shape:",
            "",
            *_table(
                cases,
                cols,
                "sagfree",
                ("solver", "shape range", "sag-free", "rest rms / L", "rest max / L"),
                lambda r: (
                    r["solver"],
                    r["shape_range"],
                    "on" if str(r["sag_free"]) == "1" else "off",
                    _g(_f(r, "rest_rms_L")),
                    _g(_f(r, "rest_max_L")),
                ),  # fmt: skip
            ),
        ]
    if any(k[0] == "sagfreq" for k in cases):
        out += [
            "",
            "Whether sag-free rest changes the dynamics: the same still scene (shape range 1) hit at t = 0 by a "
            "steady wind (a step load); the median over the strands that swing of the tip's frequency and damping "
            "ratio (—: no strand swings):",
            "",
            *_table(
                cases,
                cols,
                "sagfreq",
                ("solver", "sag-free", "tip Hz", "tip damping ratio"),
                lambda r: (
                    r["solver"],
                    "on" if str(r["sag_free"]) == "1" else "off",
                    _g(_f(r, "tip_hz"), 4),
                    _g(_f(r, "tip_damping")),
                ),  # fmt: skip
            ),
        ]
    return out


MISS_WORDS = {"blown_up": "blown up", "rms_err_L": "RMS error", "stretch": "stretch", "tip_L": "tip W1",
              "curvature_rel": "curvature W1", "envelope_rel": "area"}  # fmt: skip


def _misses(r, fails):
    """The measures a row misses a use by, each with the row's value."""
    out = []
    for m in fails:
        v = verdicts.stretch_of(r) if m == "stretch" else math.nan if m == "blown_up" else _f(r, m)
        out.append(MISS_WORDS[m] + ("" if math.isnan(v) else f" {_g(v)}"))
    return ", ".join(out)


def recommend(rows, refs=()):
    """Per use, studies/reduced_verdicts_dynamic.py's picks: at each strand count the fewest guides
    and at the LOD's strand count the fewest simulated points that pass it; LRA where it lowers the
    error without raising the stretch; sag-free by how much of the sag it removes at each shape range."""
    out = []
    for pick in verdicts.recommendations(rows, refs):
        parts = []
        for g in pick.guides:
            r, n = g.row, g.strands
            if r is None and g.full_fails:
                parts.append(
                    f"at {n:,} strands the scene's step misses it with every strand simulated "
                    f"({_misses(g.full, g.full_fails)}), so no guide fraction is recommended"
                )
                continue
            if r is None:
                parts.append(f"at {n:,} strands no guide fraction passes")
                continue
            stretch = verdicts.stretch_of(r)
            parts.append(
                f"at {n:,} strands {_f(r, 'guides'):.0%} guides ({r['guide_count']}, "
                f"{_g(_f(r, 'guide_spacing_cm'))} cm apart), {r['follow'] or 'every strand simulated'} "
                f"({_rms_words(r, g.horizon)}, stretch {_g(stretch)})"
            )
        p = pick.lod
        if p is not None:
            parts.append(
                f"{p['points']} simulated points rendered as {p['render_points']}"
                if int(p["points"]) != int(p["render_points"])
                else "every point simulated (fewer were not within it)"
            )
        elif pick.lod_full_fails:
            parts.append(
                "no P_s is recommended: the step misses it with every point simulated "
                f"({_misses(pick.lod_full, pick.lod_full_fails)})"
            )
        elif pick.lod_measured:
            parts.append("no P_s passes")
        budget = pick.budget
        head = (
            f"- **{pick.use}** (rms ≤ {budget[0]:g}·L, stretch ≤ {budget[1]:.1%}, statistics within the ensemble's "
            "spread plus the use's allowance; the default scene, xpbd): "
        )
        out.append(head + "; ".join(parts) + ".")
    cpu = [r for r in rows if r["backend"] == "cpu"]
    out += _lra_lines(cpu) + _sag_recommendation(cpu)
    return out


LRA_MEASURE = {"rms_err_L": "RMS error", "tip_L": "tip W1 against the ensemble (no frame judged pointwise)"}


def _lra_lines(rows):
    out = []
    for v in verdicts.lra_verdicts(rows):
        r, off = v.on, v.off
        out.append(
            f"- LRA, {v.solver}, I = {v.iterations}, fast nod: {LRA_MEASURE[v.measure]} {_g(_f(off, v.measure))} → "
            f"{_g(_f(r, v.measure))}·L ({'lower' if v.lower else 'not lower'}), largest stretch "
            f"{_g(_f(off, 'stretch_max_k'))} → {_g(_f(r, 'stretch_max_k'))} "
            f"({'not raised' if v.not_raised else 'raised'}), bound excess in the output "
            f"{_g(_f(off, 'lra_excess'))} → {_g(_f(r, 'lra_excess'))}, output moved up to {_g(_f(r, 'lra_moved_cm'))} "
            f"cm: {'use it here' if v.worth_it else 'not worth it here'}."
        )
    return out


def _swing_words(hz):
    """Per solver, the tip's median frequency without and with sag-free rest, or that nothing swings."""
    out = []
    for solver in sorted({k[0] for k in hz}):
        off, on = hz.get((solver, "0")), hz.get((solver, "1"))
        if off is None or on is None:
            continue
        if off != off or on != on:  # NaN: the swing detector found no strand that swings
            out.append(f"{solver}: no strand swings" + ("" if off != off and on != on else " in one of the two runs"))
        else:
            out.append(f"{solver}: the tip swings at {_g(off, 4)} Hz without it and {_g(on, 4)} Hz with it "
                       f"({on / off - 1:+.1%})")  # fmt: skip
    return out


def _sag_recommendation(rows):
    sag = {(r["solver"], str(r["shape_range"]), str(r["sag_free"])): _f(r, "rest_rms_L")
           for r in rows if r["study"] == "sagfree"}  # fmt: skip
    hz = {(r["solver"], str(r["sag_free"])): _f(r, "tip_hz") for r in rows if r["study"] == "sagfreq"}
    parts = []
    for (solver, rng, on), v in sorted(sag.items()):
        plain = sag.get((solver, rng, "0"))
        if on == "1" and solver == "xpbd" and plain:
            parts.append(
                f"shape range {rng}: it removes {1 - v / plain:.0%} of the sag (rest rms {_g(plain)} → {_g(v)}·L)"
            )
    if not parts:
        return []
    line = "- Sag-free rest (xpbd, the scene held still): " + "; ".join(parts)
    swings = _swing_words(hz)
    if swings:
        line += "; under the wind step " + "; ".join(swings)
    return [line + ". It holds only the points a shape constraint holds: use it with the shape range that covers "
            "the groom it should keep."]  # fmt: skip


def section(path):
    """The report's section from the study's CSV (or how to measure it)."""
    lines = ["## Modelling less: guides and followers, long-range attachments, sag-free rest, simulated-point LOD", ""]
    p = Path(path)
    if not p.exists():
        return lines + [
            f"Not measured here: this results directory has no `{display(p)}` (the study is newer than the run); "
            f"`python -m harness reduced --out {display(p)}` or `make bench` measures it."
        ]
    refs_path = p.with_name("references.csv")
    rows = read(p)
    if "guide_spacing_cm" not in (rows[0] if rows else {}):
        return lines + [
            f"`{display(p)}` was measured before the study compared rows with a converged reference at scale "
            "(no guide spacing, horizon or stretch columns): its verdicts are not shown. `python -m harness reduced` "
            "or `make bench` measures it again."
        ]
    refs = read(refs_path) if refs_path.exists() else []
    return lines + ["docs/model.md §3.14.", "", markdown(rows, refs).rstrip()]
