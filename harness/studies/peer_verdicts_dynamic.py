"""Where the peer wins, as data (render/peer_dynamic_report.py words it): from the peer study's
tables (peer_dynamic.py), the peer's time against our fastest fp64 run at each (S, I, N) and
against each of our runners, its trajectories against ours (one scheme's rounding drift,
tolerances.PEER_SAME_SCHEME_PER_SUBSTEP, or more), and its error against our fp32 runs beyond the
reference's own uncertainty."""

import math
from dataclasses import dataclass

from harness.core import tolerances

OURS = "hairsim-cpu"  # the solver column of our rows
PEER = "pypbd"
GROUP = ["substeps", "iterations", "strands"]


def label(r):
    """A timing row's runner: our binary, variant and precision, or the peer's."""
    return f"{r['solver']} {r['variant']} {r['precision']}" if r["solver"] == OURS else f"{PEER} {r['precision']}"


def time_ratio(g):
    """pypbd's time over our fastest fp64 time in one (S, I, N) group."""
    ours = g[(g["solver"] == OURS) & (g["precision"] == "fp64")]["median_ms"]
    theirs = g[g["solver"] == PEER]["median_ms"]
    return float(theirs.iloc[0]) / float(ours.min()) if len(ours) and len(theirs) else math.nan


def peer_faster_than_each(tim):
    """{our runner label: [((S, I, N), how many times faster the peer is)]} where the peer wins."""
    tim = tim.assign(label=tim.apply(label, axis=1))
    wins: dict[str, list] = {}
    for key, g in tim.groupby(GROUP):
        theirs = g[g["solver"] == PEER]["median_ms"]
        if not len(theirs):
            continue
        for _, r in g[g["solver"] == OURS].iterrows():
            if float(theirs.iloc[0]) < r["median_ms"]:
                wins.setdefault(r["label"], []).append((key, r["median_ms"] / float(theirs.iloc[0])))
    return wins


@dataclass(frozen=True)
class PeerVerdict:
    """`wins`: ((S, I, N), peer over our fastest fp64) where the peer is faster; `lose`: that ratio
    where ours is (of `cases` with a ratio); `worst`: the peer's largest departure from our fp64
    runs (·L; None: no peer row) and `same_scheme` whether it stays within one scheme's rounding
    drift; `faster_than_each` (peer_faster_than_each); `better_than_fp32`: ((S, I), the peer's
    error, our fp32's) where the peer's is smaller by more than the reference's uncertainty;
    `fp32`: whether any fp32 row of ours ran."""

    wins: list
    lose: list
    cases: int
    worst: float | None
    same_scheme: bool
    faster_than_each: dict
    better_than_fp32: list
    fp32: bool


def verdict(acc, tim, frames, ref_uncertainty):
    """The verdict from the accuracy and timing tables (`frames`: the accuracy horizon;
    `ref_uncertainty`: the reference's last change from S to 2S, ·L)."""
    groups = [(k, time_ratio(g)) for k, g in tim.groupby(GROUP)]
    wins = [(k, r) for k, r in groups if r < 1]
    lose = [r for _, r in groups if r >= 1]
    cases = sum(1 for _, r in groups if math.isfinite(r))
    mine = acc[acc["solver"] == PEER]
    worst, same = None, False
    if len(mine):
        worst = float(mine["vs_ours_fp64"].max())
        drift = mine["vs_ours_fp64"] / (mine["substeps"] * frames)  # ·L per substep taken
        same = float(drift.max()) <= tolerances.PEER_SAME_SCHEME_PER_SUBSTEP
    p = mine.set_index(["substeps", "iterations"])
    o32 = acc[(acc["solver"] == OURS) & (acc["precision"] == "fp32")].set_index(["substeps", "iterations"])
    better = [
        (k, p.loc[k, "err_max"], o32.loc[k, "err_max"])
        for k in p.index
        if k in o32.index and o32.loc[k, "err_max"] - p.loc[k, "err_max"] > ref_uncertainty
    ]
    return PeerVerdict(wins, lose, cases, worst, same, peer_faster_than_each(tim), better, bool(len(o32)))
