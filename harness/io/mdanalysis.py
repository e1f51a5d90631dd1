"""MDAnalysis's H5MD reader on our states (docs/interfaces.md, "Files other tools open").

MDAnalysis 2.11 refuses them as it stands, for two reasons that are its own: its unit tables
have no centimetre (nor cm s-1), and it looks a `unit` up as text while h5py hands it the
fixed-length ASCII string that H5MD asks for as bytes. `teach_units()` adds our three units
to its tables, in both forms; `reader(path)` does that and opens the file with MDAnalysis's
H5MDReader (its defaults convert to Å and ps; `convert_units=False` keeps cm and s)."""

import numpy as np

from harness import HarnessError

# H5MD unit string → MDAnalysis unit name and its factor (units per Å, per ps, per Å/ps)
UNITS = (
    ("length", "cm", "cm", 1e-8),
    ("time", "s", "s", None),  # MDAnalysis knows seconds
    ("velocity", "cm s-1", "cm/s", 1e4),
)


def teach_units():
    """Add cm, s and cm s-1 (as text and as bytes) to MDAnalysis's H5MD unit tables."""
    try:
        from MDAnalysis import units
        from MDAnalysis.coordinates.H5MD import H5MDReader
    except ImportError:
        raise HarnessError(
            "MDAnalysis is not installed (python3 -m pip install -r requirements-readers.lock)"
        ) from None
    table = H5MDReader._unit_translation
    for kind, ours, theirs, factor in UNITS:
        table[kind].setdefault(ours, theirs)
        table[kind].setdefault(ours.encode("ascii"), theirs)
        if factor is not None:
            quantity = "length" if kind == "length" else "speed"
            units.conversion_factor[quantity].setdefault(theirs, factor)
            units.unit_types.setdefault(theirs, quantity)


def one_time_axis(path):
    """Why MDAnalysis would misread the state at `path`, or None. It takes every element's
    frame k to be position frame k; H5MD lets each element keep its own steps, and a dynamic
    state does: its velocities and observables exist for the simulated frames only."""
    from harness.io.trajectory import open_trajectory

    with open_trajectory(path) as t:
        if not t.is_dynamic:
            return None
        steps = {"velocities": t.velocity_steps, "observables": t.observables["step"].to_numpy()}
        for name, s in steps.items():
            if s is not None and len(s) and not np.array_equal(s, t.step[: len(s)]):
                return f"its {name} exist at steps {int(s[0])}…{int(s[-1])}, its positions at 0…{int(t.step[-1])}"
    return None


def reader(path, **kwargs):
    """MDAnalysis's H5MDReader on the state at `path` (kwargs go to it); a state whose
    elements do not share the positions' frames is refused in one line."""
    why = one_time_axis(path)
    if why:
        raise HarnessError(
            f"{path}: MDAnalysis reads every element at the positions' frames, but {why}: "
            "read it with harness.io.trajectory, or open `harness export` sidecars"
        )
    teach_units()
    from MDAnalysis.coordinates.H5MD import H5MDReader

    return H5MDReader(str(path), **kwargs)
