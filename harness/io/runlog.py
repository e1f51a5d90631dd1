"""results/<name>/runs.csv: one tidy row per (case, stage), appended case by case.

Each case's rows are written with one write, then flushed and fsynced, so after a kill
the file holds whole cases plus at most one partial case at its end. `resume` reads the
file, keeps every complete case, and cuts off the trailing partial line or partial case
(the only bytes ever removed); the sweep then runs only the cases not yet complete, so no
row is lost or duplicated. The file is never truncated otherwise, and a file with other
columns is refused rather than mixed.
"""

import csv
import io
import os

from harness import HarnessError
from harness.io import tables

# what makes a case (its rows, one a stage, share these)
CASE = ["scene", "backend", "build", "variant", "precision", "block_size", "threads", "strands", "points"]
COLUMNS = [
    "case_id",
    "stage_index",
    "n_stages",
    "stage",
    *CASE,
    "repeat",
    "warmup",
    "skipped",
    "fused",
    "n_times",
    "median_ms",
    "min_ms",
    "max_ms",
    "q1_ms",
    "q3_ms",
    "iqr_ms",
    "moved_points",
    "bytes_moved",
    "achieved_gbps",
    "copy_gbps",
    "bandwidth_fraction",
    "end_to_end_ms",
    "h2d_ms",
    "d2h_ms",
    "state_bytes",
    "device",
    "binary",
    "session",
    "finished_at",
    # the simulate stage (dynamic scenes); empty for the paper stages
    "solver",
    "substeps",
    "iterations",
    "features",
    "point_substeps_per_s",
    # the GPU (nvidia-smi -L's index) that measured a cuda row
    "gpu",
    # honest timings (harness/core/timing.py Figure.columns): the samples' count, relative and
    # absolute standard deviation, why the rule stopped, its rounds, the load they ran under
    # (others' CPU cores, the 1-minute load average, the GPU's busy % before), and why the
    # figure is noise ("" when it is not)
    "n_samples",
    "rsd",
    "std_ms",
    "stop",
    "rounds",
    "other_cores",
    "loadavg",
    "gpu_busy_pct",
    "noisy",
]
HEADER = ",".join(COLUMNS) + "\n"


def _clean(value):
    if value is None:
        return ""
    if isinstance(value, float):
        return repr(value)
    return str(value).replace("\n", " ").replace("\r", " ")


def format_rows(rows):
    buf = io.StringIO()
    w = csv.writer(buf, lineterminator="\n")
    for row in rows:
        w.writerow([_clean(row.get(c)) for c in COLUMNS])
    return buf.getvalue()


def resume(path):
    """Prepare runs.csv for appending; return (complete case ids, bytes dropped).

    Creates the file with its header if absent. Cuts a trailing partial line and the rows
    of a trailing incomplete case (what a kill mid-write leaves); a damaged line anywhere
    else is refused, never cut."""
    header = HEADER.encode()
    data = open(path, "rb").read() if os.path.exists(path) else b""
    if not data.startswith(header):
        if header.startswith(data):  # absent, empty, or a header cut by a kill
            _truncate(path, 0, header)
            return set(), len(data)
        first = data.split(b"\n", 1)[0].decode("utf-8", "replace")
        raise HarnessError(
            f"{path}: has other columns than this harness writes (first line '{first[:60]}…'); use another --out"
        )
    lines = data[len(header) :].splitlines(keepends=True)
    complete = set()
    keep = len(header)  # end of the last complete case
    offset = keep
    group_id, group_seen, group_n = None, set(), 0
    for i, raw in enumerate(lines):
        offset += len(raw)
        last = i == len(lines) - 1
        fields = _fields(raw) if raw.endswith(b"\n") else None
        if fields is None:
            if last:
                break  # a partial trailing line: cut below
            raise HarnessError(
                f"{path}: line {i + 2} is damaged (not {len(COLUMNS)} fields); "
                f"fix or move the file, the harness will not cut it"
            )
        row = dict(zip(COLUMNS, fields))
        if row["case_id"] != group_id:
            group_id, group_seen, group_n = row["case_id"], set(), int(row["n_stages"])
        group_seen.add(int(row["stage_index"]))
        if len(group_seen) == group_n:
            complete.add(group_id)
            keep = offset
            group_id = None
    dropped = len(data) - keep
    if dropped:
        _truncate(path, keep)
    return complete, dropped


def _fields(raw):
    try:
        fields = next(csv.reader([raw.decode("utf-8")]))
        int(fields[COLUMNS.index("n_stages")]), int(fields[COLUMNS.index("stage_index")])
    except (UnicodeDecodeError, csv.Error, StopIteration, ValueError, IndexError):
        return None
    return fields if len(fields) == len(COLUMNS) else None


def _truncate(path, size, then_write=b""):
    with open(path, "ab") as f:  # never truncates on open
        f.truncate(size)
        f.write(then_write)
        f.flush()
        os.fsync(f.fileno())


def append_case(path, rows):
    """Append one case's rows in one write, then flush and fsync."""
    text = format_rows(rows)
    with open(path, "a") as f:
        f.write(text)
        f.flush()
        os.fsync(f.fileno())


def read_rows(path):
    """Every complete case's rows, as a pandas DataFrame (duplicates of a case keep the last)."""
    df = tables.read_csv(path, dtype={"threads": str, "build": str, "fused": str})
    if df.empty:
        return df
    counts = df.groupby("case_id")["stage_index"].transform("nunique")
    df = df[counts == df["n_stages"]]
    return df.drop_duplicates(subset=["case_id", "stage_index"], keep="last").reset_index(drop=True)
