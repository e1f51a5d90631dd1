"""The timed figures of a run, for `harness compare`: one table, a row a figure, whatever file
held it. A figure is a median time (ms; lower is better) and its relative noise, the spread of
the samples behind it as a fraction of the median, taken from what the file recorded:

- `rsd`: the relative standard deviation (runs.csv rows timed under the stopping rule);
- `iqr`: the interquartile range over 1.349 (a normal distribution's IQR is 1.349 σ);
- `range`: half of max − min (headline rows, which keep no quartiles);
- none: the figure was measured once (a bench step's wall time); its noise is NaN.

A row the stopping rule marked as noise (its `noisy` column: a spread above the rule's, a
loaded host) keeps that mark.

Several rows of one case in one file (a sweep run twice into one folder) are one figure: the
median of their medians, with the larger of their own noise and the spread between them.

Sources, found in a run folder or given as files: every `runs.csv` (the folder's own and its
sub-folders': sweep/, dynamic/, dynamic-curly/), the headline JSONs (headline/*.json) and the
bench's step times (steps.json). A case is known by its case id without its repeat count, and
the stage, so a case timed with more repeats is still the same case."""

import math
import re
from pathlib import Path

import numpy as np
import pandas as pd

from harness import HarnessError
from harness.core import inputs
from harness.io import tables

COLUMNS = ["source", "key", "median_ms", "noise", "noise_from", "n", "noisy", "strands", "points"]
IQR_PER_SIGMA = 1.349  # a normal distribution's interquartile range in standard deviations
STEPS_FILE = "steps.json"
REPEATS = re.compile(r":r\d+w\d+(?=:|$)")  # a case id's repeat and warm-up counts


def _number(row, name):
    v = pd.to_numeric(row.get(name), errors="coerce") if name in row else float("nan")
    return float(v) if v == v else float("nan")


def _noise(row, median):
    """(relative noise, what it came from) of one row's figure."""
    rsd = _number(row, "rsd")
    if math.isfinite(rsd):
        return rsd, "rsd"
    iqr = _number(row, "iqr_ms")
    if not math.isfinite(iqr):
        iqr = _number(row, "q3_ms") - _number(row, "q1_ms")
    if math.isfinite(iqr):
        return iqr / IQR_PER_SIGMA / median, "iqr"
    lo, hi = _number(row, "min_ms"), _number(row, "max_ms")
    if math.isfinite(lo) and math.isfinite(hi):
        return (hi - lo) / 2 / median, "range"
    return float("nan"), ""


def _figure(source, key, row, median_name="median_ms", strands=None, points=None):
    median = _number(row, median_name)
    if not (math.isfinite(median) and median > 0):
        return None  # not timed (a skipped row, a stage fused into the one before)
    noise, why = _noise(row, median) if median_name == "median_ms" else (float("nan"), "")
    n = _number(row, "n_samples")
    if not math.isfinite(n):
        n = _number(row, "n_times")
    return {
        "source": source,
        "key": key,
        "median_ms": median,
        "noise": noise,
        "noise_from": why,
        "n": int(n) if math.isfinite(n) else 0,
        "noisy": row.get("noisy") if isinstance(row.get("noisy"), str) else "",
        "strands": strands if strands is not None else _number(row, "strands"),
        "points": points if points is not None else _number(row, "points"),
    }


def of_runs_csv(path, source):
    """The figures of a runs.csv: one per timed (case, stage) row."""
    try:
        rows = tables.read_csv(path, what="compare", dtype={"case_id": str, "stage": str})
    except (pd.errors.ParserError, pd.errors.EmptyDataError, UnicodeDecodeError) as e:
        raise HarnessError(f"compare {path}: not a runs.csv ({' '.join(str(e).split())})") from None
    missing = [c for c in ("case_id", "stage_index", "stage", "median_ms") if c not in rows]
    if missing:
        raise HarnessError(f"compare {path}: not a runs.csv of this harness (no column {', '.join(missing)})")
    out = []
    for row in rows.to_dict("records"):
        if str(row.get("skipped", "0")) in ("1", "1.0", "True"):
            continue
        key = f"{REPEATS.sub('', row['case_id'])} {int(row['stage_index'])}:{row['stage']}"
        fig = _figure(source, key, row)
        if fig:
            out.append(fig)
    return out


def _labelled(value):
    return isinstance(value, dict) and isinstance(value.get("label"), str)


def of_headline(path, source):
    """The figures of a headline JSON: each `*_ms` of each labelled row (the paper headline's
    init and wind + collide, the dynamic headline's median and frame loop), by section."""
    data = inputs.read_json(path, "compare")
    if not isinstance(data, dict):
        raise HarnessError(f"compare {path}: not a headline JSON (no object at the top)")
    out = []
    for section, value in data.items():
        rows = value if isinstance(value, list) else [value]
        for row in filter(_labelled, rows):
            for name, v in row.items():
                if name.endswith("_ms") and name not in ("min_ms", "max_ms") and isinstance(v, (int, float)):
                    size = (row.get("strands", data.get("strands")), row.get("points", data.get("points")))
                    fig = _figure(source, f"{section} {row['label']} {name}", row, name, *size)
                    if fig and name == "median_ms":
                        fig["noise"], fig["noise_from"] = _noise(row, fig["median_ms"])
                    if fig:
                        out.append(fig)
    return out


def of_steps(path, source):
    """The bench's step times (steps.json, harness/bench/steps.py): a figure a step, measured once."""
    data = inputs.read_json(path, "compare")
    steps = data.get("steps") if isinstance(data, dict) else None
    if not isinstance(steps, list):
        raise HarnessError(f"compare {path}: not a bench's steps.json (no list 'steps')")
    out = []
    for s in steps:
        if isinstance(s, dict) and isinstance(s.get("seconds"), (int, float)):
            fig = _figure(source, f"step {s.get('name')}", {"wall_ms": 1e3 * s["seconds"]}, "wall_ms", "", "")
            if fig:
                out.append(fig)
    return out


def _sources(path):
    """(source name, reader, file) of every file of figures under a run folder, or of one file."""
    p = Path(path)
    if p.is_dir():
        found = [(f.relative_to(p).as_posix(), of_runs_csv, f) for f in sorted(p.glob("runs.csv"))]
        found += [(f.relative_to(p).as_posix(), of_runs_csv, f) for f in sorted(p.glob("*/runs.csv"))]
        found += [(f.relative_to(p).as_posix(), of_headline, f) for f in sorted(p.glob("headline/*.json"))]
        found += [(STEPS_FILE, of_steps, p / STEPS_FILE)] if (p / STEPS_FILE).is_file() else []
        if not found:
            raise HarnessError(f"compare {path}: no runs.csv, headline/*.json or {STEPS_FILE} in this folder")
        return found
    inputs.regular(p, "compare")
    if p.suffix == ".csv":
        return [("runs.csv", of_runs_csv, p)]
    if p.name == STEPS_FILE:
        return [(STEPS_FILE, of_steps, p)]
    if p.suffix == ".json":
        return [("headline.json" if "dynamic" not in p.name else "headline_dynamic.json", of_headline, p)]
    raise HarnessError(f"compare {path}: give a run folder, a runs.csv, a headline JSON or a {STEPS_FILE}")


def _pooled(group):
    """One figure of several rows of one case: the median of their medians, the larger of their
    own noise and their spread about it."""
    if len(group) == 1:
        return group.iloc[0]
    first = group.iloc[0].copy()
    medians = group["median_ms"].to_numpy(dtype=float)
    first["median_ms"] = float(np.median(medians))
    between = float(np.std(medians, ddof=1) / first["median_ms"])
    own = group["noise"].max()
    first["noise"] = max(between, own) if own == own else between
    first["noise_from"] = "rows" if not own == own or between > own else first["noise_from"]
    first["n"] = int(group["n"].sum())
    return first


def read(path):
    """Every figure of a run folder or file, one row per (source, key) (COLUMNS)."""
    rows = []
    for source, reader, f in _sources(path):
        rows += reader(f, source)
    table = pd.DataFrame(rows, columns=COLUMNS)
    if table.duplicated(["source", "key"]).any():
        table = pd.DataFrame(
            [_pooled(g) for _, g in table.groupby(["source", "key"], sort=False)], columns=COLUMNS
        ).reset_index(drop=True)
    return table


def _host(data):
    """The host record inside a headline JSON (env), a sweep's env.json (its last session's
    host) or an env record itself."""
    if not isinstance(data, dict):
        return {}
    sessions = data.get("sessions")
    if isinstance(sessions, list) and sessions and isinstance(sessions[-1], dict):
        return sessions[-1].get("host") or {}
    env = data.get("env", data)
    return env if isinstance(env, dict) else {}


def provenance(path):
    """The device and revision a run folder or file records (env.json, a headline's env), or ''."""
    p = Path(path)
    if p.is_dir():
        candidates = [p / "env.json", *sorted(p.glob("*/env.json")), *sorted(p.glob("headline/*.json"))]
    else:
        candidates = [p.parent / "env.json"] if p.suffix == ".csv" else [p]
    for c in candidates:
        if not c.is_file() or c.suffix != ".json":
            continue
        try:
            host = _host(inputs.read_json(c, "compare"))
        except HarnessError:
            continue
        if host.get("device") or host.get("git_revision"):
            return {"device": str(host.get("device") or ""), "revision": str(host.get("git_revision") or "")}
    return {"device": "", "revision": ""}
