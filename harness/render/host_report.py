"""The host's load while a bench ran, at the top of its reports (docs/decisions/honest-timings.md):
from RUN/host.json (the load `harness bench` measured before it started) and the timing columns
of the run's tables (every sweep's runs.csv, the accuracy studies' and the feature costs' CSVs:
core/timing.py's `other_cores` and `noisy`). A run on a loaded host says so first; every run
says how many of its timed figures are noise."""

import json
from pathlib import Path

import numpy as np

from harness.core import tolerances
from harness.io import tables

HOST_JSON = "host.json"


def _figures(root):
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


def section(root):
    """Lines for the top of a report of the run in `root` (nothing where no figure carries a load)."""
    path = Path(root) / HOST_JSON
    start = json.loads(path.read_text()) if path.is_file() else {}
    total, noisy, others = _figures(root)
    if not start and not total:
        return []
    cores = start.get("cpu_cores")
    at_start = start.get("other_cores")
    typical = float(np.median(others)) if others else None
    limit = tolerances.TIMING_OTHER_CORES
    loaded = (at_start is not None and at_start > limit) or (typical is not None and typical > limit)
    facts = []
    if at_start is not None:
        facts.append(f"other processes used {at_start:.2g} of its {cores} cores when the bench started "
                     f"(1-minute load average {start.get('loadavg', float('nan')):.3g})")  # fmt: skip
    if typical is not None:
        facts.append(f"{typical:.2g} cores, the median over the timed figures while they ran")
    share = f"{noisy} of {total} timed figures are flagged as noise" if total else "no timed figure"
    if loaded:
        return [
            f"> **This host was loaded while the bench ran**: {'; '.join(facts)} (more than {limit:g} core marks a "
            f"figure as noise). {share}: their times are upper bounds, a ranking between them is a tie, and no "
            "recommendation rests on them. Run the bench again on a quiet host before trusting its times.",
            "",
        ]
    return [
        f"Host load: quiet ({'; '.join(facts) or 'not measured'}). {share} (a relative standard deviation above "
        f"{100 * tolerances.TIMING_MAX_RSD:g} % or a loaded host; core/timing.py).",
        "",
    ]
