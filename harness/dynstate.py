"""Reading the dynamic model's time series from a state file (docs/model.md §3; the file
layout is H5MD-shaped: /particles/hair/{position,velocity}/{value,step,time},
/observables/<name>/{value,step,time}). harness/states.py opens the positions; this adds
the velocities and the observables, by step."""
import numpy as np

from .states import StateError

VELOCITY = "particles/hair/velocity"
POSITION_STEP = "particles/hair/position/step"
OBSERVABLES = "observables"


def _open(path):
    import h5py  # imported here so `--help` works without h5py

    try:
        return h5py.File(str(path), "r")
    except OSError as e:
        raise StateError(f"{path}: cannot read: {e}") from None


def position_steps(path):
    """The step of every position frame, in file order."""
    with _open(path) as f:
        if POSITION_STEP not in f:
            raise StateError(f"{path}: no /{POSITION_STEP}")
        return [int(s) for s in f[POSITION_STEP][()]]


def velocity_steps(path):
    """The steps whose velocities the file stores."""
    with _open(path) as f:
        if VELOCITY not in f:
            raise StateError(f"{path}: no /{VELOCITY} (not a simulated state)")
        return [int(s) for s in f[VELOCITY + "/step"][()]]


def velocity(path, n_strands, points, step=None):
    """The velocities at `step` (default: the last stored) as an [N][P][3] array."""
    with _open(path) as f:
        if VELOCITY not in f:
            raise StateError(f"{path}: no /{VELOCITY} (not a simulated state)")
        steps = [int(s) for s in f[VELOCITY + "/step"][()]]
        i = len(steps) - 1 if step is None else (steps.index(step) if step in steps else None)
        if i is None:
            raise StateError(f"{path}: no velocities stored for step {step} (it has steps {steps})")
        return f[VELOCITY + "/value"][i].reshape(n_strands, points, 3)


def observables(path, step=None):
    """{name: value} of the observables at `step` (default: the last), as Python numbers."""
    with _open(path) as f:
        if OBSERVABLES not in f:
            raise StateError(f"{path}: no /{OBSERVABLES} (not a simulated state)")
        out = {}
        for name, g in f[OBSERVABLES].items():
            steps = [int(s) for s in g["step"][()]]
            if step is None:
                i = len(steps) - 1
            elif step in steps:
                i = steps.index(step)
            else:
                raise StateError(f"{path}: /{OBSERVABLES}/{name} has no step {step}")
            out[name] = np.asarray(g["value"][i]).item()
        return out
