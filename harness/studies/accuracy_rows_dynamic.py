"""What the dynamic accuracy study's rows say, as numbers (studies/accuracy_dynamic.py measures
them; render/accuracy_dynamic_report.py words and draws them): each mode's summary over the
horizon, the reference ladder's convergence, the Pareto front, the oracle's small-steps pairs."""

import math

import numpy as np

from harness.core import tolerances
from harness.studies.accuracy import NO_SIMULATION, holds_until, scheme_name, smallest

KEYS = ("backend", "build", "variant", "solver", "ftl_damping", "substeps", "iterations", "precision")


def summary(rows, horizon_frames):
    """One row per mode: worst RMS and max error, stretch and penetration over the frames up
    to the horizon; blown = strands blown up in any frame of the run; time per frame."""
    m = rows[rows["study"] == "mode"]
    inside = m[m["frame"] <= horizon_frames]
    g = inside.groupby("mode", sort=False)
    out = g[list(KEYS) + ["time_per_frame_ms", "time_strands", "device"]].first()
    # honest timings (core/timing.py): the time's spread and why it is noise; a table measured
    # before them has neither (its times then decide as before, without a noise flag)
    first = g.first()
    out["time_rsd"] = first["time_rsd"].astype(float) if "time_rsd" in first else np.nan
    out["time_noisy"] = [x if isinstance(x, str) else "" for x in first["time_noisy"]] if "time_noisy" in first else ""
    out["scheme"] = [scheme_name(s, d) for s, d in zip(out["solver"], out["ftl_damping"])]
    out["rms"] = g["rms_err_L"].apply(lambda s: s.max(skipna=False))
    out["max"] = g["max_err_L"].apply(lambda s: s.max(skipna=False))
    out["p99"] = g["err_p99_L"].apply(lambda s: s.max(skipna=False))
    out["stretch"] = g["stretch_max"].max()
    out["stretch_p99"] = g["stretch_p99"].max()
    out["iou"] = g[["iou_front", "iou_side"]].min().min(axis=1)
    out["penetration"] = g["penetration_max"].max()
    out["blown"] = m.groupby("mode", sort=False)["blown_up_strands"].max()
    verdicts = m.groupby("mode", sort=False)["verdict"]
    out["verdict"] = verdicts.apply(worst_verdict)
    out["usable"] = (out["blown"] == 0) & np.isfinite(out["rms"])
    return out.reset_index()


def worst_verdict(s):
    """diverged before escaped before ok, over a mode's frames ("blown up": a table written
    before the split by cause)."""
    v = set(s.dropna().astype(str))
    for worst in ("diverged", "escaped", "blown up"):
        if worst in v:
            return worst
    return "ok"


def baseline(summ):
    """The no-simulation mode's row (the oracle build's fp64 if present, else any), or None."""
    b = summ[summ["solver"] == NO_SIMULATION]
    if b.empty:
        return None
    fp64 = b[b["precision"] == "fp64"]
    return (fp64 if len(fp64) else b).iloc[0]


def smallest_errors(rows):
    """Per frame, the smallest RMS and max error of the modes never blown up (as the study
    decided convergence): two Series indexed by frame."""
    m = rows[rows["study"] == "mode"]
    blown = m.groupby("mode")["blown_up_strands"].max()
    ok = m[m["mode"].isin(blown[blown == 0].index)]
    out = []
    for col in ("rms_err_L", "max_err_L"):
        wide = ok.pivot(index="frame", columns="mode", values=col)
        out.append(
            (wide.index.to_numpy(), smallest({c: wide[c].to_numpy() for c in wide.columns}))
            if not wide.empty
            else (np.array([]), np.array([]))
        )
    return out


def convergence_table(rows, horizon_frames):
    """Per reference rung S: the worst over the horizon of its difference to 2S and of that
    difference over the smallest mode error at the same frame, both measures; and the last
    time up to which the RMS rule holds over the whole run."""
    ref = rows[rows["study"] == "reference"]
    (frames, min_rms), (_, min_max) = smallest_errors(rows)
    factor = tolerances.DYN_ACC_REF_FACTOR
    table = []
    for S, r in ref.groupby("substeps"):
        r = r.set_index("frame").reindex(frames)
        with np.errstate(invalid="ignore", divide="ignore"):
            q_rms = r["rms_err_L"].to_numpy() / min_rms
            q_max = r["max_err_L"].to_numpy() / min_max
        inside = frames <= horizon_frames
        table.append(
            dict(
                S=int(S),
                S2=int(r["ref_substeps"].dropna().iloc[0]),
                rms=float(np.nanmax(r["rms_err_L"].to_numpy()[inside])),
                q_rms=float(np.nanmax(q_rms[inside])),
                max=float(np.nanmax(r["max_err_L"].to_numpy()[inside])),
                q_max=float(np.nanmax(q_max[inside])),
                holds=bool((q_rms[inside] < factor).all()),
                max_holds=bool((q_max[inside] < factor).all()),
                until=holds_until(q_rms < factor, r["time_s"].to_numpy()),
                stretch=float(r["stretch_max"].to_numpy()[inside].max()),
            )
        )
    return table


def pareto_front(times, errors, tie=0.0):
    """Boolean mask of the points no other point beats: sorted by time, a point is on the
    front when its error is below (1 − tie) × the smallest error of every faster point (ties
    in time go to the smaller error). With tie > 0, errors that differ only by rounding
    (fp32 against fp64, one build against another) do not make a slower mode a front point.
    NaN points are never on the front."""
    t = np.asarray(times, dtype=np.float64)
    e = np.asarray(errors, dtype=np.float64)
    good = np.isfinite(t) & np.isfinite(e)
    front = np.zeros(len(t), dtype=bool)
    best = math.inf
    for i in sorted(np.flatnonzero(good), key=lambda i: (t[i], e[i])):
        if e[i] < best * (1.0 - tie):
            front[i] = True
            best = e[i]
    return front


def front_of(summ):
    """The usable modes on the front (tolerances.DYN_ACC_FRONT_TIE), fastest first."""
    ok = summ[summ["usable"]]
    mask = pareto_front(ok["time_per_frame_ms"], ok["rms"], tolerances.DYN_ACC_FRONT_TIE)
    return ok[mask].sort_values("time_per_frame_ms")


def oracle(summ, study):
    """The rows of the study's first cpu build (the C reference's default variant) in fp64."""
    first = study["builds"][0] if study.get("builds") else None
    labels = summ.apply(label, axis=1)
    return summ[(labels == first) & (summ["precision"] == "fp64")] if first else summ.iloc[0:0]


def label(r):
    if r["backend"] == "cpu":
        return f"cpu {r['variant']}"
    return f"gpu {'normal' if r['build'] == 'default' else r['build']} {r['variant']}"


def small_steps(summ, study):
    """Per solver: for each n > 1 of the grid, S = n × I = 1 against S = 1 × I = n (oracle
    build, fp64). {solver: [dict(n, steps=row, iters=row)]}."""
    o = oracle(summ, study)
    o = o[o["solver"] != NO_SIMULATION]
    out = {}
    for solver, s in o.groupby("scheme", sort=False):
        pairs = []
        for n in sorted(set(s["substeps"]) | set(s["iterations"])):
            a = s[(s["substeps"] == n) & (s["iterations"] == 1)]
            b = s[(s["substeps"] == 1) & (s["iterations"] == n)]
            if n > 1 and len(a) and len(b):
                pairs.append(dict(n=int(n), steps=a.iloc[0], iters=b.iloc[0]))
        out[solver] = pairs
    return out


def better(a, b):
    """Mode a beats mode b: b blown up and a not, or both usable and a's RMS error smaller."""
    if a["blown"] == 0 and b["blown"] > 0:
        return True
    return bool(a["usable"] and b["usable"] and a["rms"] < b["rms"])
