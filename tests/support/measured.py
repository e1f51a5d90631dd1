"""The worst errors a GPU test file measured, written to build/ for recalibrating
harness/core/tolerances.py. Under pytest-xdist each worker measures a share of the tests, so the
workers of one run merge their maxima into the one file (under a lock); a new run starts the
file afresh. The file stays a flat {key: worst value} JSON object."""

import fcntl
import json
import os
from pathlib import Path


def _run_id():
    """The xdist run this process belongs to (None outside xdist)."""
    return os.environ.get("PYTEST_XDIST_TESTRUNUID")


def write_worst(path, errors):
    """Write {key: worst value} to `path`, merged with the values the same run's other
    workers wrote (the largest per key); nothing when `errors` is empty or build/ is not
    writable."""
    if not errors:
        return
    path = Path(path)
    try:
        with open(path.with_name(path.name + ".lock"), "a+") as lock:
            fcntl.flock(lock, fcntl.LOCK_EX)
            lock.seek(0)
            run = _run_id()
            merged = {}
            if run is not None and lock.read().strip() == run:
                try:
                    merged = {k: float(v) for k, v in json.loads(path.read_text()).items()}
                except (OSError, ValueError, AttributeError):
                    merged = {}
            for k, v in errors.items():
                merged[k] = max(float(v), merged.get(k, 0.0))
            tmp = path.with_name(f"{path.name}.tmp.{os.getpid()}")
            tmp.write_text(json.dumps(merged, indent=1, sort_keys=True) + "\n")
            os.replace(tmp, path)
            lock.seek(0)
            lock.truncate()
            lock.write(run or "")
    except OSError:
        pass
