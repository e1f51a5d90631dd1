"""What the dynamic accuracy study's modes earn, as data (render/accuracy_dynamic_report.py and
accuracy_chaos_dynamic_report.py word it): the gates a mode must pass for a use (`checks`: the
pointwise budgets, the statistics against the reference ensemble, the long runs), the pick of
each use and backend (`recommendations`, `recommended`, `recommended_modes`), what the small-steps
pairs show, and each use's budgets against the no-simulation baseline and the reference's rest
jitter. Every threshold is harness/core/tolerances.py's."""

import math

import numpy as np

from harness.check import ensemble_dynamic as en
from harness.core import timing, tolerances
from harness.studies.accuracy import scheme_name
from harness.studies.accuracy_results_dynamic import load, load_ensemble, load_long
from harness.studies.accuracy_rows_dynamic import baseline, better, summary

BACKENDS = ("cpu", "cuda")

# ---- the gates of a use ----------------------------------------------------------------


def setting(r):
    """What a mode's physics is, whatever build ran it: (scheme, S, I, precision)."""
    return (r["scheme"], int(r["substeps"]), int(r["iterations"]), r["precision"])


def ensemble_cells(ens):
    """{mode: {metric: (value, spread, lo, hi)}} of ensemble.csv's modes."""
    out = {}
    if ens is None or ens.empty:
        return out
    for _, r in ens[ens["study"] == "mode"].iterrows():
        out.setdefault(r["mode"], {})[r["metric"]] = (r["value"], r["spread"], r["lo"], r["hi"])
    return out


def long_metrics(long):
    """{(scheme, S, I, precision): {metric: (value, noise, lo, hi, spread)}} of the long runs'
    modes (one build ran them; the same settings of another build are the same model), and the
    reference's {scene: {metric: value}}."""
    out, ref = {}, {}
    if long is None or long.empty or "ref_lo" not in long.columns:
        return out, ref
    for _, r in long.iterrows():
        if r["study"] == "reference":
            ref.setdefault(r["scene"], {})[r["metric"]] = r["value"]
            continue
        key = (scheme_name(r["solver"], r["ftl_damping"]), int(r["substeps"]), int(r["iterations"]), r["precision"])
        out.setdefault(key, {})[r["metric"]] = (r["value"], r["noise"], r["ref_lo"], r["ref_hi"], r["ref_uncertainty"])
    return out, ref


def _noise(x):
    return x if np.isfinite(x) else 0.0


def _range_gate(cell, rel=0.0, factor=1.0):
    """A scalar within the members' range widened by the use (and the mode's noise); None where
    the reference has no value (e.g. no strand of it swings)."""
    if cell is None:
        return None
    v, noise, lo, hi, _ = cell
    if not (np.isfinite(lo) and np.isfinite(hi)):
        return None
    if not np.isfinite(v):
        return False
    slack = _noise(noise)
    return en.within_range(v, lo - slack, hi + slack, rel=rel, factor=factor)


def _distance_gate(cell, allow):
    if cell is None:
        return None
    v, noise, _, _, spread = cell
    return bool(np.isfinite(v) and v <= _noise(spread) + allow + _noise(noise))


def checks(r, use, longm, ensm):
    """{gate: passes} of mode row r (studies/accuracy_rows_dynamic.summary) for a use (None: not
    measured): the pointwise RMS error over the horizon (min(horizon, T_p)) and stretch, the
    metrics that survive chaos against the ensemble over the whole run, and the long runs'
    motion (kinetic energy from positions), release (tip frequency, damping ratio) and rest
    (jitter) where they measured its settings."""
    rms_budget, stretch_budget, _ = tolerances.DYN_ACC_USES[use]
    out = {"RMS error": bool(r["usable"] and r["rms"] <= rms_budget), "stretch": bool(r["stretch"] <= stretch_budget)}
    cells = ensm.get(r["mode"])
    if cells:
        row = {m: (c[0], (c[2], c[3]) if m in en.SCALARS else c[1]) for m, c in cells.items()}
        for m, ok in en.passes(row, use).items():
            out[f"ensemble {m}"] = ok
    lb = tolerances.DYN_ACC_USES_LONG[use]
    allow = tolerances.DYN_ACC_USES_CHAOS[use]
    m = longm.get(setting(r))
    if m is not None:
        out["kinetic energy (motion)"] = _range_gate(m.get("kinetic_pos"), factor=lb["kinetic_factor"])
        out["tip frequency"] = _range_gate(m.get("tip_frequency_hz"), rel=lb["freq_rel"])
        out["damping ratio"] = _range_gate(m.get("tip_damping_ratio"), rel=lb["damping_rel"])
        for metric in ("tip_L", "curvature_rel", "envelope_rel"):
            out[f"long {metric}"] = _distance_gate(m.get(metric), allow[metric])
        j = m.get("jitter_max_move")
        if j is not None:
            v, noise = j[0], j[1]
            out["rest jitter"] = bool(np.isfinite(v) and v <= tolerances.jitter_budget_cm(use) + _noise(noise))
    return out


def passing(summ, use, longm, ensm):
    """({mode: {gate: passes}}, the usable modes that pass every gate measured for them)."""
    verdicts = {r["mode"]: checks(r, use, longm, ensm) for _, r in summ.iterrows()}
    passes = summ[[all(v is not False for v in verdicts[m].values()) for m in summ["mode"]]]
    return verdicts, passes[passes["usable"]]


# ---- the pick of each use --------------------------------------------------------------


def with_noise(summ):
    """summ with its timing-noise columns (a summary measured before them: no spread, no noise)."""
    return summ.assign(
        time_rsd=summ["time_rsd"] if "time_rsd" in summ else np.nan,
        time_noisy=summ["time_noisy"] if "time_noisy" in summ else "",
    )


def recommended(summ, long=None, ens=None):
    """The pick of each use and backend (the cheapest passing mode, a tie within timing noise to
    the most accurate: fastest_or_tie, as the page picks), in order, once each."""
    longm, _ = long_metrics(long)
    ensm = ensemble_cells(ens)
    summ = with_noise(summ)
    out = []
    for use in tolerances.DYN_ACC_USES:
        _, passes = passing(summ, use, longm, ensm)
        for _, f in passes.groupby("backend", sort=False):
            out.append(fastest_or_tie(f)[0]["mode"])
    return list(dict.fromkeys(out))


def recommended_modes(results_dir):
    """The modes the page recommends, as data: [{use, backend, meets, mode, solver, ftl_damping,
    substeps, iterations, precision}], the pick of each use and backend (fastest_or_tie; where
    none passes, meets False and the most accurate usable one, as the page names it), and the
    study's record (env.json's "study": its scene, horizon and reference)."""
    rows, study, _, _ = load(results_dir)
    summ = with_noise(summary(rows, study["horizon_frames"]))
    longm, _ = long_metrics(load_long(results_dir))
    ensm = ensemble_cells(load_ensemble(results_dir))
    out = []
    for use in tolerances.DYN_ACC_USES:
        _, passes = passing(summ, use, longm, ensm)
        for backend in BACKENDS:
            f = passes[passes["backend"] == backend]
            usable = summ[(summ["backend"] == backend) & summ["usable"]]
            if f.empty and usable.empty:
                continue
            best = usable.loc[usable["rms"].idxmin()] if f.empty else fastest_or_tie(f)[0]
            damping = best["ftl_damping"] if best["solver"] == "ftl" else None
            out.append(
                {"use": use, "backend": backend, "meets": not f.empty, "mode": str(best["mode"])}
                | {"solver": str(best["solver"])}
                | {"ftl_damping": None if damping is None else float(damping), "precision": str(best["precision"])}
                | {"substeps": int(best["substeps"]), "iterations": int(best["iterations"])}
            )
    return out, study


def fastest_or_tie(f):
    """The pick among passing modes `f` by time, and the modes tied with the fastest within their
    noise (core/timing.tie: bands of ±2 standard deviations, at least ±0.5 %): a tie goes to the
    most accurate of them (its RMS error, a number the timing noise does not touch)."""
    figs = [(float(t), float(r)) for t, r in zip(f["time_per_frame_ms"], f["time_rsd"])]
    tied = f.iloc[timing.tie(figs)]
    if len(tied) <= 1:
        return f.loc[f["time_per_frame_ms"].idxmin()], tied.iloc[0:0]
    best = tied.loc[tied["rms"].idxmin()]
    return best, tied[tied["mode"] != best["mode"]]


def _pick(mine, passes, verdicts, longm):
    """One backend's pick for a use: {best, tied, faster, decided, rejected, long_measured}, or
    where no mode passes {best: None, near: the most accurate usable mode or None, near_fails}."""
    if passes.empty:
        ok = mine[mine["usable"]]
        near = ok.loc[ok["rms"].idxmin()] if len(ok) else None
        fails = [] if near is None else [k for k, v in verdicts[near["mode"]].items() if v is False]
        return dict(best=None, near=near, near_fails=fails)
    best, tied = fastest_or_tie(passes)
    faster = mine[mine["time_per_frame_ms"] < best["time_per_frame_ms"]]
    failed = {}
    for m in faster["mode"]:
        for k, v in verdicts[m].items():
            if v is False:
                failed[k] = failed.get(k, 0) + 1
    decided = max(failed, key=failed.get) if failed else None
    return dict(
        best=best,
        tied=tied,
        faster=len(faster),
        decided=decided,  # the gate that rejected most of the faster modes (None: it is the fastest)
        rejected=failed.get(decided, 0),
        long_measured=setting(best) in longm,
    )


def recommendations(summ, long=None, ens=None):
    """Per use (tolerances.DYN_ACC_USES, DYN_ACC_USES_LONG, DYN_ACC_USES_CHAOS): the cheapest mode
    of each backend that meets every gate measured for it (`checks`; a tie within timing noise to
    the most accurate), the gate that rejected most of the faster modes, the RMS budget against
    not simulating at all, and how many modes rest jitter rejects. [{use, picks: {backend: pick},
    base_rms, tighter, modes, jitter, jitter_alone, long, ensemble}]; long and ensemble: whether
    those were measured."""
    longm, _ = long_metrics(long)
    ensm = ensemble_cells(ens)
    base = baseline(summ)
    base_rms = float(base["rms"]) if base is not None and np.isfinite(base["rms"]) else None
    summ = with_noise(summ)
    out = []
    for use, (rms_budget, _, _) in tolerances.DYN_ACC_USES.items():
        verdicts, passes = passing(summ, use, longm, ensm)
        picks = {
            backend: _pick(summ[summ["backend"] == backend], passes[passes["backend"] == backend], verdicts, longm)
            for backend in BACKENDS
            if (summ["backend"] == backend).any()
        }
        jit = [c for c in verdicts.values() if c.get("rest jitter") is False]
        alone = [c for c in jit if all(v is not False for k, v in c.items() if k != "rest jitter")]
        out.append(
            dict(use=use, picks=picks, base_rms=base_rms, tighter=base_rms is not None and rms_budget < base_rms)
            | dict(modes=len(verdicts), jitter=len(jit), jitter_alone=len(alone), long=bool(longm), ensemble=bool(ensm))
        )
    return out


# ---- what the small-steps pairs show ----------------------------------------------------


def small_steps_findings(pairs, ladder=None):
    """What one solver's pairs S = n × I = 1 against S = 1 × I = n show: the n where substeps won
    (`wins`, studies/accuracy_rows_dynamic.better) and lost, where either side blew up, and on
    `ladder` (the solver's I = 1 modes by S) the most accurate usable rung (`best`), the last
    (`top`) and whether the error fell with every doubling (`falls`); best None without a ladder."""
    wins = [p["n"] for p in pairs if better(p["steps"], p["iters"])]
    out = dict(wins=wins, losses=[p["n"] for p in pairs if p["n"] not in wins], best=None, top=None, falls=False)
    out["blown_iters"] = [p["n"] for p in pairs if p["iters"]["blown"] > 0]
    out["blown_steps"] = [p["n"] for p in pairs if p["steps"]["blown"] > 0]
    if ladder is not None and len(ladder) > 1:
        ok = ladder[ladder["usable"]]
        if len(ok):
            out["best"] = ok.loc[ok["rms"].idxmin()]
            out["top"] = ladder.iloc[-1]
            out["falls"] = bool(np.all(np.diff(ladder["rms"].to_numpy()) < 0))
    return out


# ---- budgets against what they are judged by ---------------------------------------------


def budgets_against_baseline(base):
    """[{use, budget, ratio, tighter}]: each use's RMS budget over the no-simulation mode's RMS
    error (NaN where that is 0) and whether the budget is tighter than not simulating at all."""
    out = []
    for use, (rms_budget, _, _) in tolerances.DYN_ACC_USES.items():
        ratio = rms_budget / base["rms"] if base["rms"] > 0 else float("nan")
        out.append(dict(use=use, budget=rms_budget, ratio=ratio, tighter=bool(ratio < 1)))
    return out


def jitter_budgets(long):
    """[{use, lines, px, cm, ref_px, looser}]: each use's rest-jitter budget in pixels and cm, the
    reference's own largest rest move in that use's pixels, and whether the budget is looser than
    it ([] without long runs)."""
    if long is None or long.empty:
        return []
    ref = long[(long["study"] == "reference") & (long["metric"] == "jitter_max_move")]
    ref_move = float(ref["value"].iloc[0]) if len(ref) else math.nan
    out = []
    for use, lb in tolerances.DYN_ACC_USES_LONG.items():
        cm = tolerances.jitter_budget_cm(use)
        px = ref_move * lb["lines"] / tolerances.DYN_ACC_VIEW_CM
        out.append(dict(use=use, lines=lb["lines"], px=lb["jitter_px"], cm=cm, ref_px=px))
        out[-1]["looser"] = bool(np.isfinite(ref_move) and cm > ref_move)
    return out


# ---- what the study's record says ---------------------------------------------------------


def tail_estimated(error):
    """Whether the reference's own error has a tail estimate: its change shrank with the last
    doublings (ratio per doubling below 1)."""
    q = error.get("ratio_per_doubling")
    return q == q and q < 1


def horizon_cut(study):
    """Whether the asked horizon was cut to the scene's predictability time."""
    return study.get("asked_horizon", study["horizon"]) > study["horizon"] + 1e-9


def converged_to_the_end(study):
    """Whether the reference's rule holds over the whole run, not only up to the horizon."""
    return not study["reference"]["converged_until_s"] < study["frames"] * study["frame_dt"] - 1e-9
