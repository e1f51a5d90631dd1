"""Test helpers: run a hairsim binary, read its state, and judge two states.

States are read by harness.io.states (the one reader), compared by harness.check.diff and checked
by harness.check.invariants, with the tolerances of harness/core/tolerances.py.
"""

import json
import subprocess
from pathlib import Path

import numpy as np

from harness.check import diff
from harness.io.states import LoadedState, load_state
from harness.io.trajectory import open_trajectory


def run(binary, *args, check=True, timeout=600, ok=(0,)):
    """Runs a hairsim binary; returns the CompletedProcess (text mode). With `check`, an exit
    status not in `ok` fails (runner.COMPLETED: a run that may blow up, exit 5, is fine too)."""
    cmd = [str(binary), *[str(a) for a in args]]
    p = subprocess.run(cmd, capture_output=True, text=True, timeout=timeout)
    if check and p.returncode not in ok:
        raise AssertionError(f"{' '.join(cmd)} exited {p.returncode}: {p.stderr.strip()}")
    return p


def run_json(binary, *args):
    p = run(binary, *args, "--json", "--quiet")
    return json.loads(p.stdout)


def trajectory(path):
    """A dynamic file's every frame's positions [F][N·P][3], its stored velocities, its observables (an
    array) and its /parameters (a dict), read by harness.io.trajectory."""
    with open_trajectory(path) as t:
        pos = np.stack([t.frame(f) for f in range(t.n_frames)])
        vel = np.stack([t.velocity(i) for i in range(len(t.velocity_steps))])
        return pos, vel, t.observables.to_numpy(), dict(t.dynamic_params)


def same_trajectory_bits(a, b):
    """Whether two dynamic files hold the same bits in every position, velocity and observable."""
    pa, va, oa, _ = trajectory(a)
    pb, vb, ob, _ = trajectory(b)
    bits = pa.view(np.uint8).tobytes() == pb.view(np.uint8).tobytes()
    return bits and np.array_equal(va.view(np.uint8), vb.view(np.uint8)) and np.array_equal(oa, ob)


def State(path) -> LoadedState:  # noqa: N802 (reads like the type it returns)
    """The whole state at `path`, read by harness.io.states."""
    return load_state(path)


def assert_equivalent(path_a, path_b, frames="all", tolerance=None, what=""):
    """harness diff's verdict on two files (docs/harness.md, "Equivalence"): every compared frame within the
    tolerance and every invariant held in both; returns the DiffResult."""
    result = diff.compare(str(path_a), str(path_b), frames=frames, tolerance=tolerance)
    assert result.equivalent, f"{what}: " + diff.format_result(result)
    return result


def assert_threads_change_no_bit(binary, tmp_path, *flags, threads=(1, 2, 3)):
    """Run `binary FLAGS` at each thread count: every frame and every moved count bit-identical."""
    states = []
    for n in threads:
        out = tmp_path / f"t{n}.h5"
        run(binary, *flags, "--threads", n, "--output", out, "--quiet")
        states.append(State(out))
    for s in states[1:]:
        assert np.array_equal(s.frames, states[0].frames)
        assert list(s.moved) == list(states[0].moved)


def tmp_leftovers(directory: Path):
    """Temporary files a writer could have left behind."""
    return sorted(p.name for p in Path(directory).iterdir() if ".tmp." in p.name)
