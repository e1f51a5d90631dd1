"""Where the peer wins (harness/studies/peer_verdicts_dynamic.py) on known tables: time against
our fastest fp64 run and each of our runners, its trajectories within one scheme's rounding drift
(tolerances.PEER_SAME_SCHEME_PER_SUBSTEP) or beyond, its error against our fp32 beyond the
reference's uncertainty. The peer study itself needs pypbd (tests/cpu/test_peer.py)."""

import pandas as pd

from harness.core import tolerances
from harness.studies import peer_verdicts_dynamic as verdicts
from harness.studies.peer_verdicts_dynamic import OURS, PEER


def timing(ours_fp64, ours_fp32, theirs):
    rows = []
    for n, (a, b, c) in enumerate(zip(ours_fp64, ours_fp32, theirs)):
        for solver, prec, ms in ((OURS, "fp64", a), (OURS, "fp32", b), (PEER, "fp64", c)):
            rows.append(dict(substeps=8, iterations=1, strands=10**n, solver=solver, variant="ref", precision=prec,
                             median_ms=ms))  # fmt: skip
    return pd.DataFrame(rows)


def accuracy(departure, peer_err, ours32_err):
    return pd.DataFrame([
        dict(substeps=8, iterations=1, solver=PEER, precision="fp64", err_max=peer_err, vs_ours_fp64=departure),
        dict(substeps=8, iterations=1, solver=OURS, precision="fp32", err_max=ours32_err, vs_ours_fp64=1e-6),
    ])  # fmt: skip


def test_the_peer_wins_time_where_it_is_faster_and_loses_elsewhere():
    v = verdicts.verdict(accuracy(0.0, 0.1, 0.1), timing((1.0, 2.0), (0.5, 3.0), (0.5, 4.0)), 10, 0.01)
    assert v.wins == [((8, 1, 1), 0.5)] and v.lose == [2.0] and v.cases == 2
    assert v.faster_than_each == {f"{OURS} ref fp64": [((8, 1, 1), 2.0)]}


def test_a_departure_beyond_one_schemes_drift_is_no_longer_the_same_scheme():
    drift = tolerances.PEER_SAME_SCHEME_PER_SUBSTEP * 8 * 10  # per substep at the limit
    tim = timing((1.0,), (1.0,), (2.0,))
    assert verdicts.verdict(accuracy(drift, 0.1, 0.1), tim, 10, 0.01).same_scheme
    assert not verdicts.verdict(accuracy(2 * drift, 0.1, 0.1), tim, 10, 0.01).same_scheme


def test_the_peer_beats_our_fp32_only_beyond_the_references_uncertainty():
    tim = timing((1.0,), (1.0,), (2.0,))
    assert verdicts.verdict(accuracy(0.0, 0.1, 0.2), tim, 10, 0.01).better_than_fp32 == [((8, 1), 0.1, 0.2)]
    within = verdicts.verdict(accuracy(0.0, 0.1, 0.105), tim, 10, 0.01)
    assert within.better_than_fp32 == [] and within.fp32
