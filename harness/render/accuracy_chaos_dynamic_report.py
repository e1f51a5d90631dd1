"""The parts of the dynamic accuracy page that go beyond one reference trajectory (the page is
accuracy_dynamic_report.py's): the predictability of the scenes, the metrics that survive chaos
against the reference ensemble (ensemble.csv), the long runs (observables.csv) and the rest-jitter
budgets (the gates a mode must pass on them are studies/accuracy_verdicts_dynamic.py's). Every
number comes from those files; a table written before they existed reads as "not measured"."""

import math

import numpy as np

from harness.check import ensemble_dynamic as en
from harness.core import tolerances
from harness.studies.accuracy_verdicts_dynamic import ensemble_cells, jitter_budgets, long_metrics

CHAOS_COLUMNS = (
    ("tip_L", "tip distribution W1 / L"),
    ("curvature_rel", "curvature distribution W1, relative"),
    ("envelope_rel", "silhouette area, relative"),
    ("kinetic_pos", "KE of the motion (cm²/s²)"),
    ("stretch_max", "stretch max (ℓ_k), whole run"),
)
LONG_COLUMNS = (
    ("kinetic_pos", "KE from positions (cm²/s²)", "motion"),
    ("kinetic_stored", "KE of stored v (cm²/s²)", "motion"),
    ("energy_drift", "energy drift (cm²/s³)", "motion"),
    ("stretch_p99", "stretch p99 (ℓ_k)", "motion"),
    ("tip_L", "tip distribution W1 / L", "motion"),
    ("curvature_rel", "curvature W1, rel.", "motion"),
    ("envelope_rel", "silhouette area, rel.", "motion"),
    ("tip_spectrum", "tip spectrum TV", "motion"),
    ("tip_frequency_hz", "tip frequency (Hz)", "release"),
    ("tip_damping_ratio", "damping ratio ζ", "release"),
    ("jitter_rms_velocity", "rest jitter RMS v (cm/s)", "rest"),
    ("jitter_max_move", "largest rest move (cm)", "rest"),
)


def _fmt(v, digits=3):
    return "—" if v is None or not np.isfinite(v) else f"{v:.{digits}g}"


def _tp(v):
    """A predictability time: 'beyond the run' where the separation never grew."""
    return "beyond the run" if v is not None and math.isinf(v) else _fmt(v)


def _rate_sentence(p, tp):
    """How the twins separate (env.json's `predictability` p, T_p tp), as the page says it."""
    lam = p["lyapunov_per_s"]
    if p.get("lower_bound"):
        return (
            f"separate from it at the largest Lyapunov rate **λ ≥ {lam:.3g} /s** (the separation passed "
            f"{tolerances.DYN_LYAPUNOV_CEILING_L:g}·L by {p['fit_to_s']:.3g} s, faster than the frames resolve: the "
            "secant from the perturbation is a lower bound, and T_p below an upper bound). The **predictability "
            f"time** T_p ≤ **{tp:.3g} s**. "
        )
    if p["grew"]:
        return (
            f"separate from it at the largest Lyapunov rate **λ = {lam:.3g} /s** (e-folding {1e3 / lam:.3g} ms; ln "
            f"of the separation fitted from {p['fit_from_s']:.3g} to {p['fit_to_s']:.3g} s, {p['fit_frames']} "
            f"frames). The **predictability time** T_p = ln({tolerances.DYN_PREDICT_TOLERANCE_L:g}/2⁻²⁴)/λ = "
            f"**{tp:.3g} s**: the time a difference of fp32's rounding takes to grow to the games budget. "
        )
    return (
        f"do not separate: the separation never grew past {tolerances.DYN_LYAPUNOV_FLOOR:g}× the perturbation over "
        f"the run (its slope {_fmt(lam)} /s; it ended at {p['separation_end_L']:.3g}·L), so the scene is "
        "predictable beyond the run. "
    )


def predictability_lines(study, long):
    """The scenes' Lyapunov rates and predictability times, and what they mean for the page."""
    p = study.get("predictability")
    out = ["### Predictability", ""]
    if not p:
        return out + [
            "Measured before the study ran perturbed twins (env.json has no rate): pointwise errors are judged over "
            f"the whole {study['horizon']:g} s horizon, which may exceed the scene's predictability time.",
            "",
        ]
    tp = p["predictability_s"]
    asked = study.get("asked_horizon", study["horizon"])
    out += [
        f"{p['twins']} twins of the reference run (its first frame's positions perturbed by "
        f"{p['perturbation_L']:g}·L, RMS) "
        + _rate_sentence(p, tp)
        + f"Pointwise errors (RMS, p99, max, the Pareto front, the reference's convergence) are judged over "
        f"**{study['horizon']:.3g} s** = min(the asked {asked:g} s, T_p) ({study['horizon_frames']} frames); beyond "
        "it the page compares statistics against the reference ensemble "
        f"({'; '.join(study.get('ensemble', []))}).",
        "",
    ]
    _, ref = long_metrics(long)
    if ref:
        out += ["| long-run scene | λ (1/s) | T_p (s) |", "| --- | ---: | ---: |"]
        for scene, vals in ref.items():
            tp = vals.get("predictability_s")
            lam = "no growth" if tp is not None and math.isinf(tp) else _fmt(vals.get("lyapunov_per_s"))
            out.append(f"| {scene} | {lam} | {_tp(tp)} |")
        out.append("")
    return out


def chaos_lines(summ, ens, shown):
    """The metrics that survive chaos for the modes `shown` (mode names), beside the ensemble's
    spread; every mode's are in ensemble.csv."""
    out = ["### What survives chaos: statistics against the reference ensemble", ""]
    cells = ensemble_cells(ens)
    if not cells:
        return out + ["Measured before the study had a reference ensemble (no ensemble.csv beside its table).", ""]
    members = ens[ens["study"] == "member"]
    first = next(iter(cells.values()))
    spread = " · ".join(
        f"{label} {_fmt(first[m][1]) if m not in en.SCALARS else _fmt(first[m][2]) + ' … ' + _fmt(first[m][3])}"
        for m, label in CHAOS_COLUMNS
        if m in first
    )
    out += [
        f"Over the whole run ({len(members['mode'].unique())} ensemble members), every mode's statistics against "
        "the reference ensemble (harness/check/ensemble_dynamic.py): a distance is the mean over the members, a "
        f"scalar the mode's own. The ensemble itself: {spread} (spread, or the members' range). A mode passes a use "
        "when each distance is within the spread plus the use's allowance and the kinetic energy within the members' "
        "range times the use's factor (tolerances.DYN_ACC_USES_CHAOS).",
        "",
        "| mode | " + " | ".join(label for _, label in CHAOS_COLUMNS) + " |",
        "| --- |" + " ---: |" * len(CHAOS_COLUMNS),
    ]
    for name in shown:
        c = cells.get(name)
        if c:
            out.append(f"| {name} | " + " | ".join(_fmt(c.get(m, (np.nan,))[0]) for m, _ in CHAOS_COLUMNS) + " |")
    out.append("")
    return out


def _pm(v, n):
    if v is None or not np.isfinite(v):
        return "—"
    return f"{v:.3g} ± {n:.2g}" if n is not None and np.isfinite(n) else f"{v:.3g}"


def long_lines(long, worst_verdict):
    """The long runs' section: the reference ensemble's row (its own values, ranges and spreads),
    then every mode (± its noise)."""
    head = ["### What a user sees over seconds", ""]
    if long is None or long.empty:
        return head + ["Not measured with these results (`--long-seconds 0`).", ""]
    if "ref_lo" not in long.columns:
        return head + ["Measured before the reference ensemble (observables.csv has no ranges): not shown.", ""]
    first = long.iloc[0]
    rest = long[long["scene"] == "rest"]
    rest_s = f"{rest['seconds'].iloc[0]:g} s" if len(rest) else "its time"
    out = head + [
        f"Long runs ({first['seconds']:g} s, {int(first['strands'])} strands × {int(first['points'])} points, "
        "harness/studies/observables_long_dynamic.py), each made from the study's own scene: "
        "**motion** the scene itself; "
        "**release** the scene with the head still, no wind and no collider, let go from its rest shape (the median "
        "over the strands whose tip swings, at least two periods, of each strand's swing frequency over the first "
        "half and of its damping ratio over the whole run; — where no strand swings); **rest** the scene still, "
        f"windless, with a strong damping for {rest_s} (RMS frame-to-frame velocity and the largest move over its "
        "last fifth: what flickers). The kinetic energy is the motion's, from positions (the stored velocities' "
        "beside it: ftl's carry its correction); distances (W1 of the tip's and the curvature's distributions, "
        "silhouette area, total variation of the tip's spectrum) are means over the reference ensemble's members. "
        "The reference row gives its own value and, after a /, the ensemble's spread (a distance) or range (a "
        "scalar); a mode's ± is its noise (half the difference between the even and the odd strands).",
        "",
        "| mode | " + " | ".join(c[1] for c in LONG_COLUMNS) + " | verdict |",
        "|" + " --- |" * (len(LONG_COLUMNS) + 2),
    ]
    ref = long[long["study"] == "reference"]
    cells = []
    for metric, _, _ in LONG_COLUMNS:
        r = ref[ref["metric"] == metric]
        if r.empty or not np.isfinite(r["reference"].iloc[0]):
            cells.append("—")
            continue
        r = r.iloc[0]
        band = f"{_fmt(r['ref_lo'])} … {_fmt(r['ref_hi'])}" if np.isfinite(r["ref_lo"]) else _fmt(r["ref_uncertainty"])
        cells.append(f"{_fmt(r['reference'])} / {band}")
    out.append(f"| reference: {ref['mode'].iloc[0] if len(ref) else '?'} | " + " | ".join(cells) + " | ok |")
    for mode, g in long[long["study"] == "mode"].groupby("mode", sort=False):
        cell = {r["metric"]: (r["value"], r["noise"]) for _, r in g.iterrows()}
        out.append(
            f"| {mode} | "
            + " | ".join(_pm(*cell.get(m, (None, None))) for m, _, _ in LONG_COLUMNS)
            + f" | {worst_verdict(g['verdict'])} |"
        )
    out.append("")
    return out


def jitter_budget_lines(long):
    """Each use's rest-jitter budget in pixels and cm, against the reference's own largest
    move and the no-simulation mode's (nothing moves)."""
    budgets = jitter_budgets(long)
    if not budgets:
        return []
    out = [
        "Rest jitter budgets: the largest frame-to-frame move of any point of the settled **rest** scene, in "
        f"pixels of a picture {tolerances.DYN_ACC_VIEW_CM:g} cm high (a head-and-shoulders shot; "
        "harness/core/tolerances.py, DYN_ACC_USES_LONG). Not simulating moves nothing (0 px), so every move is "
        "flicker the simulation adds; the reference's own largest move is its settling, and each budget must be "
        "looser than it.",
        "",
        "| use | lines | budget (px) | budget (cm) | reference's largest move (px) | looser than the reference |",
        "| --- | ---: | ---: | ---: | ---: | --- |",
    ]
    for b in budgets:
        looser = "yes" if b["looser"] else "**no**"
        out.append(f"| {b['use']} | {b['lines']} | {b['px']:g} | {b['cm']:.3g} | {b['ref_px']:.2g} | {looser} |")
    out.append("")
    return out
