"""Writing a results file whole or not at all: to a temporary name beside it, then renamed
over it, so a killed run never leaves half a file."""

import csv
import json
import os
from pathlib import Path


def write_json(path, data):
    """`data` as indented JSON (what JSON cannot hold, as text) at `path`."""
    tmp = f"{path}.tmp.{os.getpid()}"
    with open(tmp, "w") as f:
        json.dump(data, f, indent=1, default=str)
        f.write("\n")
    os.replace(tmp, path)


def write_csv(path, fields, rows, extrasaction="raise"):
    """`rows` (dicts) as CSV with the header `fields` at `path` (its folder made if absent); a
    missing key is an empty cell, an extra one an error (or dropped: extrasaction="ignore")."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_name(f"{path.name}.tmp.{os.getpid()}")
    with open(tmp, "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=fields, restval="", extrasaction=extrasaction)
        w.writeheader()
        w.writerows(rows)
    os.replace(tmp, path)
    return path


def write_text(path, text):
    """`text` at `path`, whole or not at all; returns the path."""
    path = Path(path)
    tmp = path.with_name(f"{path.name}.tmp.{os.getpid()}")
    try:
        tmp.write_text(text)
        os.replace(tmp, path)
    finally:
        tmp.unlink(missing_ok=True)
    return path
