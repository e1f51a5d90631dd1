"""Test helpers: run a hairsim binary and read its HDF5 state.

The DESIGN §3 invariants themselves live in harness/invariants.py (one place); the tests
call them through `check_invariants` below.
"""
import json
import subprocess
from pathlib import Path

import h5py
import numpy as np


def run(binary, *args, check=True, timeout=600):
    """Runs a hairsim binary; returns the CompletedProcess (text mode)."""
    cmd = [str(binary), *[str(a) for a in args]]
    p = subprocess.run(cmd, capture_output=True, text=True, timeout=timeout)
    if check and p.returncode != 0:
        raise AssertionError(f"{' '.join(cmd)} exited {p.returncode}: {p.stderr.strip()}")
    return p


def run_json(binary, *args):
    p = run(binary, *args, "--json", "--quiet")
    return json.loads(p.stdout)


class State:
    """An HDF5 state: frames [F][N][P][3], the /parameters attributes and per-frame data."""

    def __init__(self, path):
        self.path = str(path)
        with h5py.File(path, "r") as f:
            self.params = dict(f["parameters"].attrs)
            self.n = int(self.params["n_strands"])
            self.p = int(self.params["points_per_strand"])
            value = f["particles/hair/position/value"]
            self.dtype = value.dtype
            self.frames = value[:].reshape(value.shape[0], self.n, self.p, 3)
            self.stages = [s.decode() if isinstance(s, bytes) else s for s in f["parameters/stage"][:]]
            self.skipped = f["parameters/skipped"][:]
            self.moved = f["parameters/moved_points"][:]

    @property
    def ell(self):
        return float(self.params["hair_length"]) / (self.p - 1)


def tmp_leftovers(directory: Path):
    """Temporary files a writer could have left behind."""
    return sorted(p.name for p in Path(directory).iterdir() if ".tmp." in p.name)
