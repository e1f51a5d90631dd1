"""Which paper mode for which use, as data (render/accuracy_paper_report.py words it): from
accuracy.csv's end-to-end errors and times (studies/accuracy_paper.py measures them), the fastest
mode, and per use the fastest within the use's error bound unless others tie with it within
timing noise (core/timing.py `tie`), when the most accurate of the tie; and the fewest points
per strand within RESOLUTION_BOUND of the finest strand."""

from dataclasses import dataclass

import numpy as np

from harness.core import timing, tolerances
from harness.studies.accuracy import PAPER_REFERENCE

# (end-to-end max error / L, the use that needs it); of L: what a point count may leave
USE_BOUNDS = tolerances.PAPER_ACC_USES
RESOLUTION_BOUND = tolerances.PAPER_ACC_RESOLUTION_L


def end_to_end(rows):
    """One row per mode: its last frame (the end-to-end error)."""
    last = {}
    for r in rows:
        if r["study"] == "mode":
            if r["mode"] not in last or r["frame"] > last[r["mode"]]["frame"]:
                last[r["mode"]] = r
    return list(last.values())


def _tied(modes):
    """The modes that tie with the fastest within timing noise (these tables keep no spread, so
    within core/timing.py's floor), fastest first."""
    return [modes[i] for i in timing.tie([(r["time_ms"], float("nan")) for r in modes])]


def pick(modes):
    """The mode to recommend among `modes` (rows that meet a use's bound): the fastest, unless
    others tie with it within timing noise: then the most accurate of the tie. (mode, the others
    it tied with)."""
    tied = _tied(sorted(modes, key=lambda r: r["time_ms"]))
    best = min(tied, key=lambda r: r["max_err_L"])
    return best, [r["mode"] for r in tied if r is not best]


@dataclass(frozen=True)
class UsePick:
    """A use, its error bound, the mode picked (None: none meets it) and those it tied with."""

    limit: float
    use: str
    best: dict | None
    tied_with: list


@dataclass(frozen=True)
class Recommendation:
    """The fastest mode and those it tied with, each use's pick, and the resolution row with the
    fewest points within RESOLUTION_BOUND (None: none) beside the finest strand's points. `fastest`
    None: no mode but the reference ran."""

    fastest: dict | None
    fastest_tied_with: list
    uses: list
    enough: dict | None
    finest_points: int | None


def recommendation(rows):
    """Which mode for which use, from the measured end-to-end errors and times; modes whose times
    tie within noise are a tie, decided by their errors (noise never decides)."""
    e2e = [r for r in end_to_end(rows) if r["mode"] != PAPER_REFERENCE and np.isfinite(r["max_err_L"])]
    if not e2e:
        return Recommendation(None, [], [], None, None)
    fastest = min(e2e, key=lambda r: r["time_ms"])
    tied = [r["mode"] for r in _tied(e2e) if r["mode"] != fastest["mode"]]
    uses = []
    for limit, use in USE_BOUNDS:
        ok = [r for r in e2e if r["max_err_L"] <= limit]
        best, others = pick(ok) if ok else (None, [])
        uses.append(UsePick(limit, use, best, others))
    res = sorted(
        (r for r in rows if r["study"] == "resolution" and np.isfinite(r["max_err_L"])), key=lambda r: r["points"]
    )
    enough = [r for r in res if r["max_err_L"] <= RESOLUTION_BOUND and r["max_err_L"] > 0]
    finest = max(r["points"] for r in res) if res else None
    return Recommendation(fastest, tied, uses, enough[0] if enough else None, finest)
