"""The invariants of docs/model.md §2.7 asserted on a state (a LoadedState of support/statecheck.py).

Every per-frame invariant (finite, roots fixed, x constant, segment lengths, shell after
collide, skipped stages unchanged) is checked by harness/check/invariants.py with the tolerances
of harness/core/tolerances.py. The tests add two facts of the root draw (docs/model.md §2.2): roots
lie on the head sphere, and none sits on the lower face.
"""

import numpy as np

from harness.check import invariants
from harness.core import tolerances
from harness.io.states import open_state
from support.statecheck import State, run


def assert_invariants(s, tol=None):
    """`tol`: an InvariantTolerance tighter than the precision's (tolerances.py), or None."""
    eps = float(np.finfo(s.dtype).eps)
    R = float(s.params["head_radius"])
    root0 = s.frames[0, :, 0, :]
    assert np.isfinite(root0).all(), "NaN or Inf in a root"
    r3 = np.linalg.norm(root0.astype(np.float64), axis=1)
    assert np.abs(r3 - R).max() <= tolerances.ROOT_ON_SPHERE_K * eps * R, "a root off the head sphere"
    assert not np.any((root0[:, 2] > 0) & (root0[:, 1] < 0)), "a root on the lower face"
    assert_frames_invariants(s.path, tol)


def assert_frames_invariants(path, tol=None):
    """The per-frame invariants only (for hand-made inputs whose roots are not drawn)."""
    with open_state(path) as st:
        report = invariants.check(st, tol)
    assert report.ok, "; ".join(v.message for v in report.violations)
    return report


WINDY_STAGES = "init,collide,wind,collide,wind,collide"


def assert_windy_runs_keep_invariants(binary, tmp_path, angles, *flags, tag=""):
    """Run `binary FLAGS` at wind strength 1 from each of `angles` (two wind+collide rounds);
    assert the invariants on every output."""
    for angle in angles:
        out = tmp_path / f"w{tag}_{angle}.h5"
        run(
            binary,
            *flags,
            "--wind-strength",
            1,
            "--wind-angle",
            angle,
            "--stages",
            WINDY_STAGES,
            "--output",
            out,
            "--quiet",
        )
        assert_invariants(State(out))
