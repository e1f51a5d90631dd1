"""Whether the host was loaded while a bench ran, as data (render/host_report.py words it): from
RUN/host.json (the load `harness bench` measured before it started) and the timing columns of the
run's tables (every sweep's runs.csv, the accuracy studies' and the feature costs' CSVs:
core/timing.py's `other_cores` and `noisy`), judged against tolerances.TIMING_OTHER_CORES
(docs/decisions/honest-timings.md)."""

import json
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from harness.core import tolerances
from harness.io import tables

HOST_JSON = "host.json"


def figures(root):
    """(figures, noisy, others' cores of each figure) over the run's timing tables."""
    total, noisy, others = 0, 0, []
    for path in sorted(Path(root).glob("*/*.csv")):
        try:
            df = tables.read_csv(path)
        except (OSError, ValueError):
            continue
        if "noisy" in df and "n_samples" in df:  # a sweep's or the feature costs' rows
            df = df[df["n_samples"].fillna(0).astype(float) > 0]
            flags, load = df["noisy"], df["other_cores"]
        elif "time_noisy" in df and "mode" in df:  # an accuracy study: one time a mode
            df = df[df["study"] == "mode"].drop_duplicates("mode")
            flags, load = df["time_noisy"], df["time_other_cores"]
        else:
            continue
        total += len(df)
        noisy += sum(1 for x in flags if isinstance(x, str) and x)
        others += [float(x) for x in load.dropna()]
    return total, noisy, others


@dataclass(frozen=True)
class HostLoad:
    """The run's host load: host.json's record at the start ({} where absent), the timed figures
    and how many are noise, the median of others' cores over them (None: none carries one), the
    limit and whether either load passed it."""

    start: dict
    total: int
    noisy: int
    typical: float | None
    limit: float
    loaded: bool


def host_load(root):
    """The host load of the run in `root`."""
    path = Path(root) / HOST_JSON
    start = json.loads(path.read_text()) if path.is_file() else {}
    total, noisy, others = figures(root)
    at_start = start.get("other_cores")
    typical = float(np.median(others)) if others else None
    limit = tolerances.TIMING_OTHER_CORES
    loaded = (at_start is not None and at_start > limit) or (typical is not None and typical > limit)
    return HostLoad(start, total, noisy, typical, limit, loaded)
