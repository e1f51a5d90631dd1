"""Render the dynamic model's speed-against-accuracy study (studies/accuracy_dynamic.py measures it,
studies/accuracy_verdicts_dynamic.py decides what its modes earn): read results/dynamic-accuracy/
(dynamic_accuracy.csv, env.json, analytic.json) and write report/dynamic_accuracy.md with its
pictures (the Pareto plot, the error growth over time, small steps against iterations). Every
number and sentence comes from those files.

`section(results_dir, report_dir)` gives the main report (report.py) a short section with
a link to the full page. A study on another scene than the default one (`--scene curly`)
has its own page and pictures, named with the scene (Names), so the two never overwrite
each other.
"""

from dataclasses import astuple, dataclass
from pathlib import Path

import numpy as np

from harness.core import timing, tolerances
from harness.core.paths import REPORT, RESULTS, display
from harness.io import files
from harness.render import accuracy_chaos_dynamic_report as chaos
from harness.render import analytic_dynamic_report
from harness.render.accuracy_chaos_dynamic_report import jitter_budget_lines
from harness.studies import accuracy_verdicts_dynamic as verdicts
from harness.studies.accuracy import CSV_NAME, DEFAULT_SCENE, NO_SIMULATION, RESULTS_NAME, results_name, scene_tag
from harness.studies.accuracy_results_dynamic import load, load_ensemble, load_long
from harness.studies.accuracy_rows_dynamic import (
    baseline,
    convergence_table,
    front_of,
    label,
    oracle,
    small_steps,
    summary,
    worst_verdict,
)

PAGE = "dynamic_accuracy.md"
PARETO_PNG = "dynamic_accuracy_pareto.png"
GROWTH_PNG = "dynamic_accuracy_growth.png"
STEPS_PNG = "dynamic_accuracy_steps.png"
DEFAULT_TITLE = "the dynamic model"
BACKEND_WORDS = {"cpu": "CPU", "cuda": "GPU"}


@dataclass(frozen=True)
class Names:
    """The page and picture names of one scene's study: the default scene's are PAGE and the
    *_PNG names; another scene's carry its name (dynamic_accuracy_curly.md, ...)."""

    page: str = PAGE
    pareto: str = PARETO_PNG
    growth: str = GROWTH_PNG
    steps: str = STEPS_PNG

    @classmethod
    def of(cls, scene):
        tag = scene_tag(scene)
        if not tag:
            return cls()
        return cls(*(n.replace("dynamic_accuracy", f"dynamic_accuracy_{tag}", 1) for n in astuple(cls())))


def title_of(scene):
    """The heading's subject: the dynamic model for the default scene, else the scene."""
    tag = scene_tag(scene)
    return f"the {tag} scene" if tag else DEFAULT_TITLE


# ---- what the rows say, in words ------------------------------------------------------


def reference_error_line(study):
    """The reference's own error, measured (two more doublings and the estimated tail)."""
    e = study["reference"].get("error")
    if not e:
        return "The reference's own error was not measured (`--ref-extra 0`)."
    q = e.get("ratio_per_doubling")
    return (
        f"The reference's own error (S = {study['reference']['substeps']} against S = {e['against_substeps']}, "
        f"worst over the horizon): RMS {_e(e['rms_horizon'])}, max {_e(e['max_horizon'])}; with the tail the "
        f"last doublings predict (change ratio {q:.3g} per doubling): RMS {_e(e['est_rms_horizon'])}, max "
        f"{_e(e['est_max_horizon'])}. A mode's error below these is not resolved."
        if verdicts.tail_estimated(e)
        else f"The reference's own error (S = {study['reference']['substeps']} against S = "
        f"{e['against_substeps']}, worst over the horizon): RMS {_e(e['rms_horizon'])}, max {_e(e['max_horizon'])}; "
        "the last doublings did not shrink the change, so no tail is estimated: read it as a lower bound."
    )


def small_steps_verdict(solver, pairs, ladder=None):
    """Sentences on what the pairs show (accuracy_verdicts_dynamic.small_steps_findings); `ladder`:
    the solver's I = 1 modes by S (the trend of the error with S alone)."""
    if not pairs:
        return [f"- {solver}: no pair S = n × I = 1 / S = 1 × I = n in this grid."]
    found = verdicts.small_steps_findings(pairs, ladder)
    wins, losses = found["wins"], found["losses"]
    last = pairs[-1]
    a, b = last["steps"], last["iters"]
    line = (
        f"- **{solver}**: S substeps × 1 iteration had the smaller RMS error in {len(wins)} of "
        f"{len(pairs)} pairs" + (f" (n = {_list(wins)})" if wins else "") + "."
    )
    if losses:
        line += f" 1 substep × n iterations had it for n = {_list(losses)}."
    if a["usable"] and b["usable"]:
        line += (
            f" At n = {last['n']}: {_e(a['rms'])} against {_e(b['rms'])} "
            f"({max(a['rms'], b['rms']) / min(a['rms'], b['rms']):.3g}× "
            f"{'smaller' if a['rms'] < b['rms'] else 'larger'} with substeps), "
            f"stretch {_pct(a['stretch'])} against {_pct(b['stretch'])}, "
            f"{a['time_per_frame_ms']:.3g} against {b['time_per_frame_ms']:.3g} ms per frame."
        )
    if found["blown_iters"]:
        line += f" 1 substep × n iterations blew up for n = {_list(found['blown_iters'])}."
    if found["blown_steps"]:
        line += f" n substeps × 1 iteration blew up for n = {_list(found['blown_steps'])}."
    best, top = found["best"], found["top"]
    if best is not None:
        line += (
            f" With I = 1 alone its error falls with every doubling of S, to {_e(top['rms'])} at "
            f"S = {int(top['substeps'])}."
            if found["falls"]
            else f" With I = 1 alone its error is smallest at S = {int(best['substeps'])} ({_e(best['rms'])}) "
            f"and is {_e(top['rms'])} at S = {int(top['substeps'])}: more substeps do not bring it closer "
            "to the reference."
        )
    line += (
        " This agrees with Macklin et al. 2019."
        if not losses
        else " Where iterations won, that is against Macklin et al. 2019's finding, measured here."
        if wins
        else " This is the opposite of Macklin et al. 2019's finding, measured here."
    )
    return [line]


def _list(ns):
    return ", ".join(str(n) for n in ns)


def _pick_words(what, pick):
    """One backend's pick (accuracy_verdicts_dynamic.recommendations) in words."""
    best = pick["best"]
    if best is None:
        near = pick["near"]
        return f"{what}: no mode of this grid meets it" + (
            f" (the most accurate, {near['mode']}, has RMS error {_e(near['rms'])} and stretch "
            f"{_pct(near['stretch'])}; it fails " + ", ".join(pick["near_fails"]) + ")"
            if near is not None
            else ""
        )
    long_note = "" if pick["long_measured"] else "; no long runs at these settings"
    return (
        f"{what}: **{best['mode']}** (solver {best['solver']}"
        + (f", s = {best['ftl_damping']:g}" if best["solver"] == "ftl" else "")
        + f", S = {int(best['substeps'])}, I = {int(best['iterations'])}, {best['precision']}, build "
        f"{label(best)}; {best['time_per_frame_ms']:.3g} ms per frame at {int(best['time_strands']):,} "
        f"strands; RMS error {_e(best['rms'])}, stretch {_pct(best['stretch'])}{long_note}; "
        + (
            f"decided by {pick['decided']}, which rejected {pick['rejected']} of the {pick['faster']} faster modes"
            if pick["decided"]
            else "the fastest mode of all"
        )
        + ")"
        + tie_note(best, pick["tied"])
    )


def _gates_words(use, rec, horizon):
    """A use's budgets and gates, as the recommendation's bullet states them."""
    rms_budget, stretch_budget, why = tolerances.DYN_ACC_USES[use]
    lb = tolerances.DYN_ACC_USES_LONG[use]
    allow = tolerances.DYN_ACC_USES_CHAOS[use]
    over = f" up to {horizon:.3g} s" if horizon is not None else " over the horizon"
    chaos_txt = (
        f"; over the whole run, within the reference ensemble's spread plus {allow['tip_L']:g}·L (tip "
        f"distribution), {100 * allow['curvature_rel']:g} % (curvature) and {100 * allow['envelope_rel']:g} % "
        f"(silhouette area), kinetic energy of the motion within ×{allow['kinetic_factor']:g} of the members' "
        "range, stretch against ℓ_k within the use's budget"
        if rec["ensemble"]
        else ""
    )
    long_txt = (
        f"; in the long runs tip frequency within {100 * lb['freq_rel']:g} % and damping ratio within "
        f"{100 * lb['damping_rel']:g} % of the reference ensemble's range, kinetic energy from positions within "
        f"×{lb['kinetic_factor']:g}, and no point of a still head moving more than {lb['jitter_px']:g} px from "
        f"frame to frame at {lb['lines']} lines ({_jit(use)}; noise allowed)"
        if rec["long"]
        else ""
    )
    base_note = ""
    if rec["base_rms"] is not None:
        base_note = (
            f"; the RMS budget is {rec['base_rms'] / rms_budget:.3g}× tighter than not simulating at all "
            f"({_e(rec['base_rms'])})"
            if rec["tighter"]
            else f"; **the RMS budget is not tighter than not simulating at all** ({_e(rec['base_rms'])})"
        )
    return (
        f"RMS error ≤ {rms_budget:g}·L and stretch ≤ {_pct(stretch_budget)}{over}{chaos_txt}"
        f"{long_txt}, never blown up; {why}{base_note}"
    )


def recommend(summ, long=None, ens=None, horizon=None):
    """Per use and per backend, the pick of accuracy_verdicts_dynamic.recommendations in words:
    the cheapest mode that meets every budget measured for it, naming its solver, s, S, I,
    precision and build, and the metric that decided it (the one that rejected most of the faster
    modes); `horizon`: the pointwise horizon (s) the RMS budget is judged over. Lines of Markdown."""
    lines = []
    for rec in verdicts.recommendations(summ, long, ens):
        picks = [_pick_words(BACKEND_WORDS[b], pick) for b, pick in rec["picks"].items()]
        jit_note = (
            f" Rest jitter rejects {rec['jitter']} of the {rec['modes']} modes, {rec['jitter_alone']} of them on that "
            "alone."
            if rec["long"]
            else ""
        )
        lines.append(
            f"- **{rec['use']}** ({_gates_words(rec['use'], rec, horizon)}): " + "; ".join(picks) + "." + jit_note
        )
    return lines


def tie_note(best, tied):
    """Words for a pick that tied with others within noise, or whose own time is noise."""
    note = ""
    if len(tied):
        others = ", ".join(f"{r['mode']} ({r['time_per_frame_ms']:.3g} ms)" for _, r in tied.iterrows())
        note += (
            f"; **a tie within timing noise** with {others}: named the most accurate, not the one whose median "
            "happened to be lowest"
        )
    noisy = [r["time_noisy"] for r in [best, *(r for _, r in tied.iterrows())] if r["time_noisy"]]
    if noisy:
        note += f"; timings flagged as noise ({noisy[0]}): re-measure on a quiet host before trusting the order"
    return note


def _jit(use):
    return f"{tolerances.jitter_budget_cm(use):.2g} cm"


def baseline_lines(summ, study):
    """The no-simulation baseline: its errors, and each use's budget against it."""
    base = baseline(summ)
    if base is None:
        return [
            "### The no-simulation baseline",
            "",
            f"Not measured: no build here declares the `{NO_SIMULATION}` solver (--list-variants).",
            "",
        ]
    out = [
        "### The no-simulation baseline",
        "",
        f"`{base['mode']}`: the hair carried rigidly with the head, nothing simulated (docs/model.md §3.13). "
        f"Over the horizon its RMS error is {_e(base['rms'])}, p99 {_e(base['p99'])}, max {_e(base['max'])}, "
        f"silhouette IoU at worst {base['iou']:.3f}. A mode is worth its time only where it is well below "
        "this; the tables give every mode's RMS error as a multiple of it.",
        "",
        "| use | RMS budget / L | budget ÷ no-sim RMS | tighter than no simulation |",
        "| --- | ---: | ---: | --- |",
    ]
    for b in verdicts.budgets_against_baseline(base):
        out.append(f"| {b['use']} | {b['budget']:g} | {b['ratio']:.3g} | {'yes' if b['tighter'] else '**no**'} |")
    out.append("")
    return out


def _e(x):
    return "blown up" if x is None or not np.isfinite(x) else f"{x:.2e}·L"


def _pct(x):
    return "n/a" if x is None or not np.isfinite(x) else f"{100 * x:.3g} %"


# ---- pictures -------------------------------------------------------------------------


def _plt():
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def _save(fig, path):
    return files.save_figure(fig, path, dpi=110, bbox_inches="tight")


def pareto_plot(summ, study, path):
    plt = _plt()
    ok = summ[summ["usable"]].reset_index(drop=True)
    fig, ax = plt.subplots(figsize=(8.5, 5.5))
    labels = list(dict.fromkeys(ok.apply(label, axis=1)))
    solvers = list(dict.fromkeys(ok["scheme"]))
    colors = {lab: f"C{i % 10}" for i, lab in enumerate(labels)}
    markers = {s: "osD^v<>"[i % 7] for i, s in enumerate(solvers)}
    base = baseline(summ)
    if base is not None and np.isfinite(base["rms"]):
        ax.axhline(
            base["rms"], color="0.3", lw=0.9, ls="--", label=f"no simulation ({NO_SIMULATION}): {_e(base['rms'])}"
        )
    for _, r in ok.iterrows():
        c = colors[label(r)]
        filled = r["precision"] == "fp64"
        ax.scatter(
            r["time_per_frame_ms"],
            r["rms"],
            s=28,
            marker=markers[r["scheme"]],
            facecolors=c if filled else "none",
            edgecolors=c,
            linewidths=1,
            alpha=0.8,
        )
    front = front_of(summ)
    ax.step(
        front["time_per_frame_ms"],
        front["rms"],
        where="post",
        color="k",
        lw=0.9,
        label="Pareto front (# as in the table)",
    )
    for k, (_, r) in enumerate(front.iterrows(), 1):
        ax.annotate(str(k), (r["time_per_frame_ms"], r["rms"]), textcoords="offset points", xytext=(3, 3), fontsize=8)
    for lab in labels:
        ax.scatter([], [], color=colors[lab], marker="s", label=lab)
    for s in solvers:
        ax.scatter([], [], color="0.4", marker=markers[s], label=f"{s} (filled fp64, hollow fp32)")
    blown = int((~summ["usable"]).sum())
    if len(ok):
        ax.set_xscale("log")
        ax.set_yscale("log")
    ax.set_xlabel(f"time per frame (ms), {int(ok['time_strands'].iloc[0]) if len(ok) else 0:,} strands")
    ax.set_ylabel(f"RMS position error / L, worst frame up to {study['horizon']:g} s")
    ax.set_title(
        f"Dynamic model: error against time per frame ({len(ok)} modes"
        + (f"; {blown} blown up, not shown)" if blown else ")")
    )
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=7, loc="upper left", bbox_to_anchor=(1.01, 1.0), frameon=False)  # beside the data, not on it
    fig.tight_layout()
    out = _save(fig, path)
    plt.close(fig)
    return out


GROWTH_COLUMNS = 2  # panels a row: readable at a page's width


def growth_plot(rows, summ, study, path):
    """RMS error against time for the oracle build's fp64, I = 1 modes, one panel per solver,
    with the reference's own S-vs-2S difference and the horizon."""
    plt = _plt()
    o = oracle(summ, study)
    base = o[o["solver"] == NO_SIMULATION]
    o = o[(o["iterations"] == 1) & (o["solver"] != NO_SIMULATION)]
    solvers = list(dict.fromkeys(o["scheme"])) or ["none"]
    ncols = min(GROWTH_COLUMNS, len(solvers))
    nrows = -(-len(solvers) // ncols)
    fig, grid = plt.subplots(nrows, ncols, figsize=(5.2 * ncols, 3.8 * nrows), sharey=True, squeeze=False)
    axes = [list(grid.flat)]
    for spare in axes[0][len(solvers) :]:
        spare.set_visible(False)
    ref = rows[rows["study"] == "reference"]
    finest = ref[ref["substeps"] == ref["substeps"].max()] if len(ref) else ref
    m = rows[rows["study"] == "mode"]
    for ax, solver in zip(axes[0], solvers):
        for k, (_, r) in enumerate(o[o["scheme"] == solver].sort_values("substeps").iterrows()):
            d = m[m["mode"] == r["mode"]].sort_values("frame")
            ax.plot(d["time_s"], d["rms_err_L"], color=f"C{k % 10}", lw=1.2, label=f"S = {int(r['substeps'])}")
        if len(base):
            d = m[m["mode"] == base["mode"].iloc[0]].sort_values("frame")
            ax.plot(d["time_s"], d["rms_err_L"], color="0.3", lw=1.4, ls="-.", label="no simulation")
        if len(finest):
            f = finest.sort_values("frame")
            S = int(f["substeps"].iloc[0])
            ax.plot(f["time_s"], f["rms_err_L"], "k--", lw=1, label=f"reference S = {S} vs {2 * S}")
        ax.axvline(study["horizon"], color="0.5", lw=0.8, ls=":")
        ax.text(study["horizon"], 0.02, " horizon", fontsize=7, color="0.4", transform=ax.get_xaxis_transform())
        if any(np.nanmax(np.asarray(ln.get_ydata(), float), initial=0) > 0 for ln in ax.get_lines()[:-1]):
            ax.set_yscale("log")
        ax.set_xlabel("simulated time (s)")
        ax.set_title(f"{solver}, fp64, I = 1 ({study['builds'][0] if study.get('builds') else ''})", fontsize=9)
        ax.grid(True, which="both", alpha=0.3)
    for row in grid:
        row[0].set_ylabel("RMS error / L vs the reference")
    handles, names = axes[0][len(solvers) - 1].get_legend_handles_labels()
    fig.legend(handles, names, loc="lower center", ncol=min(len(names), 5), fontsize=7, frameon=False)
    fig.tight_layout(rect=(0, 0.1 / nrows, 1, 1))
    out = _save(fig, path)
    plt.close(fig)
    return out


def steps_plot(pairs_by_solver, path):
    plt = _plt()
    fig, ax = plt.subplots(figsize=(6.5, 4.2))
    for k, (solver, pairs) in enumerate(pairs_by_solver.items()):
        n = [p["n"] for p in pairs]
        ax.plot(n, [p["steps"]["rms"] for p in pairs], "-o", color=f"C{k}", label=f"{solver}: S = n, I = 1")
        ax.plot(
            n, [p["iters"]["rms"] for p in pairs], "--s", color=f"C{k}", mfc="none", label=f"{solver}: S = 1, I = n"
        )
    if any(pairs_by_solver.values()):
        ax.set_xscale("log", base=2)
        ax.set_yscale("log")
    else:
        ax.text(0.5, 0.5, "no n > 1 in this grid", ha="center", transform=ax.transAxes)
    ax.set_xlabel("n")
    ax.set_ylabel("RMS position error / L (worst frame up to the horizon)")
    ax.set_title("Small steps against iterations (blown-up runs leave gaps)", fontsize=10)
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=7)
    fig.tight_layout()
    out = _save(fig, path)
    plt.close(fig)
    return out


# ---- Markdown -------------------------------------------------------------------------


def _header(study, env):
    ref = study["reference"]
    dev = env.get("device") or "no GPU"
    command = study.get("command") or "python -m harness accuracy --model dynamic"
    return [
        f"Scene `{study['scene_file']}` ({study.get('scene_description') or 'no description'}) at "
        f"{study['strands']:,} strands × "
        f"{study['points']} points (strands are independent and keep their roots at any count: same seed), "
        f"{study['frames']} frames of Δt = {study['frame_dt']:.4g} s ({study['seconds']:g} s). Pointwise errors "
        f"are compared over the **horizon of {study['horizon']:.3g} s** ({study['horizon_frames']} frames"
        + (
            f"; the asked {study['asked_horizon']:g} s cut to the scene's predictability time, below"
            if verdicts.horizon_cut(study)
            else ""
        )
        + f"): the worst frame of RMS and of max |x − x_ref| over all points, over L = {study['hair_length']:g} cm; "
        "statistics that survive chaos are compared over the whole run against a reference ensemble. "
        f"Time per frame: a separate run of the same mode at {study['time_strands']:,} strands, "
        f"{study['time_frames']} frame(s) × `--repeat {study['repeat']}`, no output file, the simulate stage's "
        f"median (never a run that also checks). Reference: {ref['label']} {ref['solver']} {ref['precision']}, "
        f"I = {ref['iterations']}, S = {ref['substeps']}.",
        "",
        f"Machine: {env.get('cpu_model')} ({env.get('cpu_cores')} cores), GPU: {dev}; revision "
        f"{env.get('git_revision')}; {env.get('date')}. Measured by `{command}` "
        f"(the whole study took {study.get('wall_s', float('nan')):.0f} s); this page is rendered from the "
        "results that command wrote.",
        "",
    ]


def convergence_lines(rows, study):
    ref = study["reference"]
    table = convergence_table(rows, study["horizon_frames"])
    factor = tolerances.DYN_ACC_REF_FACTOR
    out = [
        "### The converged reference",
        "",
        f"S doubled from {study['ref_start'] or table[0]['S'] if table else '?'}: each row compares S with 2S "
        f"({ref['label']}, xpbd, fp64, I = {ref['iterations']}). The rule: at every frame up to the horizon the "
        f"RMS difference is under {factor:g} × the smallest RMS error any mode (never blown up) has at that "
        "frame. The max measure is shown against the same rule; it does not decide S.",
        "",
        "| S | 2S | RMS(S − 2S)/L, worst | ÷ smallest RMS error, worst | RMS rule over the horizon "
        "| RMS rule holds until (s) | max(S − 2S)/L, worst | ÷ smallest max error, worst | max rule | "
        "stretch_max of S |",
        "| ---: | ---: | ---: | ---: | --- | ---: | ---: | ---: | --- | ---: |",
    ]
    for t in table:
        out.append(
            f"| {t['S']} | {t['S2']} | {t['rms']:.2e} | {t['q_rms']:.3f} | {'holds' if t['holds'] else 'fails'} "
            f"| {t['until']:.3f} | {t['max']:.2e} | {t['q_max']:.3f} | {'holds' if t['max_holds'] else 'fails'} "
            f"| {t['stretch']:.2e} |"
        )
    out.append("")
    if ref["converged"]:
        out.append(
            f"**Converged**: the rule holds over the whole horizon at S = {ref['substeps'] // 2} against "
            f"{ref['substeps']}; the modes are compared with S = {ref['substeps']}. Over the whole run it holds "
            f"until t = {ref['converged_until_s']:.3f} s"
            + (
                ": beyond that the reference is no longer ten times better than the best mode, and the "
                "errors after it are not a measurement of the modes (they are drawn, not tabulated)."
                if not verdicts.converged_to_the_end(study)
                else "."
            )
        )
    else:
        out.append(
            f"**NOT converged**: by S = {ref['substeps']} (`--ref-max {study['ref_max']}`) the rule still fails "
            "over the horizon; the errors below are bounded by the reference's own difference in the table, not "
            "measured to a tenth. Raise `--ref-max` or shorten `--horizon`."
        )
    if table and not table[-1]["max_holds"]:
        out.append(
            f"The max measure does not meet the rule (worst ratio {table[-1]['q_max']:.2f} at the last rung): single "
            "points near a contact or in a nearly straight bend triple converge far more slowly than the RMS "
            '(docs/decisions.md, "The dynamic accuracy study"). Read the max errors below as uncertain by about '
            f"{table[-1]['max']:.1e}·L."
        )
    check = rows[rows["study"] == "gpu_check"]
    if len(check):
        H = study["horizon_frames"]
        c = check[check["frame"] <= H]
        out.append(
            f"GPU fp64 reference ({check['mode'].iloc[0]}): RMS difference from the CPU's at S = "
            f"{int(check['substeps'].iloc[0])} up to {c['rms_err_L'].max():.2e}·L over the horizon "
            f"(max {c['max_err_L'].max():.2e}·L), allowed {tolerances.DYN_ACC_GPU_REF_SHARE:g} × the margin; "
            f"{ref.get('gpu_check')}."
        )
    else:
        out.append(f"No GPU reference: {ref.get('gpu_check')}.")
    out.append("")
    return out


def _mode_table(df, numbered=False, base=None):
    """Markdown rows of modes; `base`: the no-simulation row, against which the RMS is also
    given as a ratio (below 1: closer to the reference than not simulating at all)."""
    out = [
        ("| # " if numbered else "")
        + "| mode | time/frame (ms) | RMS err / L | ÷ no-sim RMS | p99 err / L | max err / L | stretch_max | "
        "stretch p99 | IoU min | penetration_max (cm) | verdict (blown-up strands) |",
        ("| ---: " if numbered else "")
        + "| --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | --- |",
    ]
    b = base["rms"] if base is not None and np.isfinite(base["rms"]) and base["rms"] > 0 else None
    for k, (_, r) in enumerate(df.iterrows(), 1):
        ok = r["blown"] == 0
        out.append(
            (f"| {k} " if numbered else "") + f"| {r['mode']} | {_time(r)} | {_e(r['rms']) if ok else '—'} | "
            f"{f'{r.rms / b:.3g}' if ok and b else '—'} | {_e(r['p99']) if ok else '—'} | "
            f"{_e(r['max']) if ok else '—'} | {r['stretch']:.3g} | {r['stretch_p99']:.3g} | "
            f"{f'{r.iou:.3f}' if ok and np.isfinite(r['iou']) else '—'} | {r['penetration']:.2g} | "
            f"{r['verdict']} ({int(r['blown'])}) |"
        )
    return out


def _time(r):
    """A mode's time per frame, with its spread where measured and a mark where it is noise."""
    rsd = r.get("time_rsd", np.nan)
    spread = f" ± {100 * rsd:.2g} %" if rsd == rsd else ""
    return f"{r['time_per_frame_ms']:.3g}{spread}" + (" (noise)" if r.get("time_noisy") else "")


def noise_lines(summ):
    """How many timed modes are noise, and why (nothing for a table measured before the rule)."""
    if "time_noisy" not in summ or summ["time_rsd"].isna().all():
        return []
    noisy = summ[summ["time_noisy"].astype(bool)]
    if noisy.empty:
        return [
            f"Every mode's time met the stopping rule on a quiet host (spread ≤ {100 * timing.RULE.max_rsd:g} %).",
            "",
        ]
    why = noisy["time_noisy"].value_counts().index[0]
    return [
        f"**{len(noisy)} of {len(summ)} modes' times are flagged as noise** (the commonest reason: {why}); they "
        'are marked "(noise)" below, and a pick that rests on them says so: modes whose times overlap within '
        "their spread are reported as a tie.",
        "",
    ]


def _all_modes_lines(summ):
    order = summ.assign(label=summ.apply(label, axis=1)).sort_values(
        ["label", "scheme", "precision", "substeps", "iterations"]
    )
    return [
        "### Every mode",
        "",
        "Errors, stretch, silhouette overlap (IoU, front and side, the smaller) and penetration: the worst "
        "frame up to the horizon; verdict: the worst frame of the run, split by cause (diverged: a NaN or "
        "Inf; escaped: a point farther than 2L from its root), with the most strands blown up in any frame "
        "(its errors are then not shown).",
        "",
        *_mode_table(order, base=baseline(summ)),
        "",
    ]


def markdown(rows, study, env, analytic, long=None, names=Names(), title=DEFAULT_TITLE, ens=None):
    summ = summary(rows, study["horizon_frames"])
    front = front_of(summ)
    pairs = small_steps(summ, study)
    base = baseline(summ)
    out = [f"## Speed against accuracy: {title}", "", *_header(study, env), *noise_lines(summ)]
    out += chaos.predictability_lines(study, long)
    out += convergence_lines(rows, study)
    out += [reference_error_line(study), ""]
    out += baseline_lines(summ, study)
    out += [
        "### Error against time per frame",
        "",
        f"{len(summ)} modes ({', '.join(study.get('builds', []))} × solver × S × I × precision); "
        f"{int((~summ['usable']).sum())} blew up. The Pareto front (no other mode is both faster and more "
        "accurate):",
        "",
        *_mode_table(front, numbered=True, base=base),
        "",
        reference_error_line(study),
        "",
        f"![error against time per frame]({names.pareto})",
        "",
        "### Error growth over time",
        "",
        "Trajectories of different modes part over time, and the reference's own S-against-2S difference "
        "(dashed) grows too: a mode's error means something only while it is well above that line. The "
        f"comparison is made over the horizon ({study['horizon']:g} s, dotted); "
        f"the rule holds until t = {study['reference']['converged_until_s']:.3f} s.",
        "",
        f"![error growth over time]({names.growth})",
        "",
        "### Small steps against iterations",
        "",
        "Macklin et al. 2019 found n substeps × 1 iteration more accurate than 1 substep × n iterations "
        f"for the same cost. Here, {study['builds'][0] if study.get('builds') else ''}, fp64:",
        "",
    ]
    for solver, ps in pairs.items():
        out += [
            f"| {solver}: n | S = n, I = 1: RMS err / L | stretch | ms/frame | S = 1, I = n: RMS err / L | stretch "
            "| ms/frame |",
            "| ---: | ---: | ---: | ---: | ---: | ---: | ---: |",
        ]
        for p in ps:
            a, b = p["steps"], p["iters"]
            out.append(
                f"| {p['n']} | {_e(a['rms']) if a['blown'] == 0 else 'blown up'} | {_pct(a['stretch'])} | "
                f"{a['time_per_frame_ms']:.3g} | {_e(b['rms']) if b['blown'] == 0 else 'blown up'} | "
                f"{_pct(b['stretch'])} | {b['time_per_frame_ms']:.3g} |"
            )
        out.append("")
    o = oracle(summ, study)
    for solver, ps in pairs.items():
        ladder = o[(o["scheme"] == solver) & (o["iterations"] == 1)].sort_values("substeps")
        out += small_steps_verdict(solver, ps, ladder)
    out += ["", reference_error_line(study), "", f"![small steps against iterations]({names.steps})", ""]
    shown = list(dict.fromkeys([*front["mode"], *verdicts.recommended(summ, long, ens)]))
    out += chaos.chaos_lines(summ, ens, shown)
    out += chaos.long_lines(long, worst_verdict)
    out += [
        "### Which settings for which use",
        "",
        "Rule: for each use, the mode with the least time per frame among those never blown up whose RMS error "
        f"and stretch_max up to the pointwise horizon ({study['horizon']:.3g} s) are within the use's budget "
        "(harness/core/tolerances.py, DYN_ACC_USES); whose statistics over the whole run are within the reference "
        "ensemble's spread plus the use's allowance (DYN_ACC_USES_CHAOS); and, where the long runs measured its "
        "settings, whose kinetic energy from positions, tip frequency and damping ratio are within the use's "
        "allowance of the ensemble's range and whose rest jitter is within the use's pixel budget "
        "(DYN_ACC_USES_LONG, each widened by the measured noise), on the CPU and on the GPU apart. ftl's s is "
        "part of the setting: s < 1 converges to another motion and adds energy (docs/model.md §3.7).",
        "",
        *jitter_budget_lines(long),
        *recommend(summ, long, ens, study["horizon"]),
        "",
    ]
    if analytic:
        out += [
            "### Analytic checks against S",
            "",
            "docs/model.md §4 against the C reference (fp64 unless a table says fp32, `--threads 1`, no collider; "
            "`harness/studies/analytic_table_dynamic.py`, run by this study):",
            "",
            *[ln.replace("### ", "#### ", 1) if ln.startswith("### ") else ln for ln in _analytic_lines(analytic)],
            "",
        ]
    out += _all_modes_lines(summ)
    out += [reference_error_line(study), ""]
    return out, summ, front, pairs


def _analytic_lines(analytic):
    """The analytic tables: rendered from the sweeps' data, or a study's Markdown from before #47."""
    return analytic if isinstance(analytic, list) else analytic_dynamic_report.lines(analytic)


def write(results_dir=None, report_dir=None, csv_path=None, title=None):
    """Write report/dynamic_accuracy.md (another scene's: Names.of its scene) and its
    pictures from a results directory (its table or csv_path); return the paths written.
    Nothing is created when the input is refused."""
    results_dir = Path(results_dir or RESULTS / RESULTS_NAME)
    report_dir = Path(report_dir or REPORT)
    rows, study, env, analytic = load(results_dir, csv_path)
    where = Path(csv_path).parent if csv_path else results_dir
    long, ens = load_long(where), load_ensemble(where)
    scene = study.get("scene", DEFAULT_SCENE)
    names = Names.of(scene)
    report_dir.mkdir(parents=True, exist_ok=True)
    lines, summ, _, pairs = markdown(rows, study, env, analytic, long, names, title or title_of(scene), ens)
    pics = [
        pareto_plot(summ, study, report_dir / names.pareto),
        growth_plot(rows, summ, study, report_dir / names.growth),
        steps_plot(pairs, report_dir / names.steps),
    ]
    page = report_dir / names.page
    files.write_text(page, "\n".join(lines) + "\n")
    return [page, *pics]


def not_converged_line(rows, study):
    """What a reference that did not converge over the horizon means for the rows beside it."""
    ref = study["reference"]
    table = convergence_table(rows, study["horizon_frames"])
    last = f"; S = {table[-1]['S']} and {table[-1]['S2']} still differ by RMS {_e(table[-1]['rms'])}" if table else ""
    return (
        f"**The reference did NOT converge**: S doubled up to {ref['substeps']} (`--ref-max {study['ref_max']}`) "
        f"and the RMS rule still fails over the {study['horizon']:g} s horizon{last}. The errors and the "
        "recommendation below are against that unconverged reference: read them as bounded by its own change, "
        "not measured."
    )


def section(results_dir=None, report_dir=None, write_page=True, scene=DEFAULT_SCENE, title=None):
    """Markdown lines for the main report: the front, the recommendation and a link to the
    full page (written again into report_dir unless write_page=False), or how to measure it
    when no results exist. `scene`: the scene the folder is for (its command when missing);
    `title`: the heading's subject (title_of the study's scene when None)."""
    results_dir = Path(results_dir or RESULTS / results_name(scene))
    report_dir = Path(report_dir or REPORT)
    if not (results_dir / CSV_NAME).exists():
        where = f" --scene {scene}" if scene_tag(scene) else ""
        return [f"## Speed against accuracy: {title or title_of(scene)}", ""] + [
            f"Not measured with these results (no `{display(results_dir / CSV_NAME)}`): run "
            f"`python3 -m harness accuracy --model dynamic{where}` on this machine.",
            "",
        ]
    if write_page:
        write(results_dir, report_dir, title=title)
    rows, study, env, analytic = load(results_dir)
    names = Names.of(study.get("scene", DEFAULT_SCENE))
    summ = summary(rows, study["horizon_frames"])
    front = front_of(summ)
    ref = study["reference"]
    head = [f"## Speed against accuracy: {title or title_of(study.get('scene', DEFAULT_SCENE))}", ""]
    if not ref["converged"]:
        head += [not_converged_line(rows, study), ""]
    return head + [
        f"{len(summ)} modes against {ref['label']} xpbd fp64 at S = {ref['substeps']} "
        f"({'converged' if ref['converged'] else 'NOT converged'} over the {study['horizon']:g} s horizon); "
        f"the full study, its convergence table, small steps against iterations"
        f"{' and the analytic checks' if analytic else ''}: [{names.page}]({names.page}).",
        "",
        *_mode_table(front, numbered=True, base=baseline(summ)),
        "",
        reference_error_line(study),
        "",
        *baseline_lines(summ, study)[2:3],
        *recommend(summ, load_long(results_dir), load_ensemble(results_dir), study["horizon"]),
        "",
        f"![error against time per frame]({names.pareto})",
        "",
    ]
