"""The dynamic model's extra datasets of a state file (docs/interfaces.md): velocities and
per-frame observables, read through an open `harness.states.State` (whose file handle it
uses), so tests and tools never open the HDF5 file by hand.

    with open_state(path) as s:
        steps, v = velocities(s)      # [Fv] steps, [Fv][N][P][3] in the file's dtype
        obs = observables(s)          # {"kinetic_energy": array [F], ...}
"""
import numpy as np

from .states import StateError

VELOCITY = "particles/hair/velocity"
OBSERVABLES = "observables"


def velocities(state):
    """(steps [Fv], values [Fv][N][P][3]) of the stored velocities."""
    f = state._file
    if f is None or VELOCITY + "/value" not in f:
        raise StateError(f"{state.path}: no /{VELOCITY}/value (not a dynamic state)")
    value = f[VELOCITY + "/value"][()]
    steps = f[VELOCITY + "/step"][()] if VELOCITY + "/step" in f else np.arange(len(value))
    return np.asarray(steps), value.reshape(value.shape[0], state.n_strands, state.points, 3)


def observables(state):
    """{name: values [F]} of /observables/*/value (one value per simulated frame)."""
    f = state._file
    if f is None or OBSERVABLES not in f:
        raise StateError(f"{state.path}: no /{OBSERVABLES} group (not a dynamic state)")
    return {name: np.asarray(f[OBSERVABLES][name]["value"][()]) for name in f[OBSERVABLES]}
