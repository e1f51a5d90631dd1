"""Read a results directory (runs.csv + env.json) into the tables the plots and the report
use. One job: turn tidy rows into per-case numbers.

`pair_ms` is what the paper timed as "applying wind": the median of the first wind stage
plus the median of the collide right after it (for the fused variant the wind row carries
the pair and the collide row is 0). `total_ms` is the sum of every stage's median.
Medians are added, not the medians of sums: each stage is timed on its own."""

import json
import math
from pathlib import Path

import numpy as np
import pandas as pd

from harness import HarnessError
from harness.io import runlog

# the small paper-scene state of Fig. 1/2, inside a sweep's results directory
FIGURE_STATE = "states/figure-cpu-fp32.h5"

CASE_KEYS = ["case_id", *runlog.CASE]


def load(results_dir):
    """(rows DataFrame, env dict) of a results directory; HarnessError if it has none."""
    d = Path(results_dir)
    csv_path = d / "runs.csv"
    if not csv_path.exists():
        raise HarnessError(f"{csv_path}: no such file (run `python -m harness sweep …` first)")
    try:
        rows = runlog.read_rows(csv_path)
    except (pd.errors.ParserError, pd.errors.EmptyDataError, KeyError) as e:
        raise HarnessError(f"{csv_path}: not a runs.csv of this harness ({e})") from None
    env = {}
    if (d / "env.json").exists():
        try:
            env = json.loads((d / "env.json").read_text())
        except json.JSONDecodeError:
            env = {}
    for col in ("build", "fused", "threads"):
        if col in rows:
            rows[col] = rows[col].fillna("").astype(str)
    if "block_size" in rows:
        rows["block_size"] = pd.to_numeric(rows["block_size"], errors="coerce").fillna(0).astype(int)
    return rows, env


def per_case(rows):
    """One row per case: pair_ms (wind + collide after it), total_ms, and the case keys."""
    out = []
    for case_id, g in rows.groupby("case_id", sort=False):
        g = g.sort_values("stage_index")
        stages = list(g["stage"])
        med = list(g["median_ms"].astype(float))
        iqr = list(pd.to_numeric(g["iqr_ms"], errors="coerce").fillna(0.0))
        pair = pair_iqr = None
        if "wind" in stages:
            i = stages.index("wind")
            pair, pair_iqr = med[i], iqr[i]
            if i + 1 < len(stages) and stages[i + 1] == "collide":
                pair += med[i + 1]
                pair_iqr += iqr[i + 1]
        first = g.iloc[0]
        rec = {k: first[k] for k in CASE_KEYS}
        noisy = [x for x in g["noisy"] if isinstance(x, str) and x] if "noisy" in g else []  # core/timing.py
        rec.update(
            noisy=noisy[0] if noisy else "",
            pair_ms=pair,
            pair_iqr_ms=pair_iqr,
            total_ms=float(np.sum(med)),
            stages=",".join(stages),
            skipped_stages=",".join(s for s, k in zip(stages, g["skipped"]) if int(k)),
            fused=",".join(f for f in g["fused"] if f),
            end_to_end_ms=first.get("end_to_end_ms"),
        )
        out.append(rec)
    cases = pd.DataFrame(out)
    if not cases.empty:
        cases["label"] = cases.apply(case_label, axis=1)
    return cases


def case_label(c):
    if c["backend"] == "cpu":
        t = str(c["threads"])
        where = "1 thread" if t == "1" else ("all cores" if t == "all" else f"{t} threads")
        return f"CPU {c['variant']} {where}"
    build = "" if c["build"] in ("", "default") else f" {c['build']}"
    return f"GPU {c['variant']}{build} b{int(c['block_size'])}"


# The two baselines every speedup names: the plain single-threaded C code (what the paper
# ran on its CPU), and the fastest CPU variant on all cores of the same node (the fair one).
BASELINES = {"single": "CPU ref, 1 thread", "all": "CPU all cores (fastest variant)"}


def cpu_baseline(cases, which):
    """pair_ms of a baseline ('single' or 'all'), indexed by (precision, points, strands)."""
    cpu = cases[cases["backend"] == "cpu"].dropna(subset=["pair_ms"])
    if which == "single":
        c = cpu[(cpu["variant"] == "ref") & (cpu["threads"].astype(str) == "1")]
        return c.set_index(["precision", "points", "strands"])["pair_ms"]
    c = cpu[cpu["threads"].astype(str) == "all"]
    return c.groupby(["precision", "points", "strands"])["pair_ms"].min()


def main_points(cases):
    """The points per strand most cases ran with (the axis the speedup plots fix)."""
    return int(cases["points"].mode().iloc[0]) if not cases.empty else None


def gpu_absent_reason(env):
    """Why a results directory has no GPU rows, from env.json's skip records."""
    reasons = []
    for s in env.get("sessions", []):
        for k in s.get("skipped", []):
            if "cuda" in k.get("backends", []) or k.get("backend") == "cuda":
                reasons.append(k.get("reason"))
    if reasons:
        return reasons[-1]
    return "the sweep has no cuda cases"


def strands_at_time(curve, target_ms):
    """Strand count at which a (strands → ms) curve reaches target_ms.

    Log-log interpolation between measured points; beyond the largest, linear in N from
    it (the work is linear in N), marked extrapolated. (None, note) if it cannot."""
    pts = sorted((int(n), float(t)) for n, t in curve.items() if t and t > 0)
    if not pts:
        return None, "no data"
    for (n0, t0), (n1, t1) in zip(pts, pts[1:]):
        if t0 <= target_ms <= t1 and t1 > t0:
            f = (math.log(target_ms) - math.log(t0)) / (math.log(t1) - math.log(t0))
            return math.exp(math.log(n0) + f * (math.log(n1) - math.log(n0))), "interpolated"
    n_max, t_max = pts[-1]
    if target_ms > t_max:
        return n_max * target_ms / t_max, f"extrapolated linearly from N = {n_max:,}"
    n_min, t_min = pts[0]
    return n_min * target_ms / t_min, f"below our smallest N = {n_min:,}: extrapolated"


def interp_time(curve, n):
    """Our time at strand count n (log-log interpolation, linear extrapolation)."""
    pts = sorted((int(k), float(t)) for k, t in curve.items() if t and t > 0)
    if not pts or n is None:
        return None
    for (n0, t0), (n1, t1) in zip(pts, pts[1:]):
        if n0 <= n <= n1:
            f = (math.log(n) - math.log(n0)) / (math.log(n1) - math.log(n0))
            return math.exp(math.log(t0) + f * (math.log(t1) - math.log(t0)))
    n_edge, t_edge = pts[-1] if n > pts[-1][0] else pts[0]
    return t_edge * n / n_edge


def curve_of(cases, mask):
    c = cases[mask].dropna(subset=["pair_ms"])
    return dict(zip(c["strands"], c["pair_ms"]))
