"""DESIGN §3 invariants asserted on a State (tests/statecheck.py).

Tolerances (measured, docs/decisions.md): with ε the precision's machine epsilon and
S = R + L the largest coordinate scale, segment lengths stay within 16·ε·S of ℓ
(measured ≤ 3.1·ε·S in fp32 over 200,000 strands); after collide no point is inside
rc·(1 − 32ε) (the collide test itself allows 16ε·rc of rounding).
"""
import numpy as np


def assert_invariants(s):
    eps = float(np.finfo(s.dtype).eps)
    R = float(s.params["head_radius"])
    h = float(s.params["hair_offset"])
    L = float(s.params["hair_length"])
    fr = s.frames
    assert np.isfinite(fr).all(), "NaN or Inf in a frame"
    root0 = fr[0, :, 0, :]
    # roots on the head sphere, none on the lower face
    r3 = np.linalg.norm(root0.astype(np.float64), axis=1)
    assert np.abs(r3 - R).max() <= 8 * eps * R
    assert not np.any((root0[:, 2] > 0) & (root0[:, 1] < 0)), "a root on the lower face"
    rc = np.hypot(root0[:, 1].astype(np.float64), root0[:, 2].astype(np.float64)) + h
    for f in range(fr.shape[0]):
        st = fr[f].astype(np.float64)
        assert np.array_equal(fr[f, :, 0, :], root0), f"frame {f}: a root moved"
        assert np.array_equal(fr[f, :, :, 0], np.repeat(fr[f, :, :1, 0], s.p, axis=1)), f"frame {f}: x changed"
        seg = np.linalg.norm(np.diff(st, axis=1), axis=2)
        worst = np.abs(seg - s.ell).max() if s.p > 1 else 0.0
        assert worst <= 16 * eps * (R + L), f"frame {f}: segment length off by {worst}"
        if s.stages[f] == "collide":
            r = np.hypot(st[:, 1:, 1], st[:, 1:, 2])
            inside = (rc[:, None] * (1 - 32 * eps) - r).max()
            assert inside <= 0, f"frame {f}: a point is {inside} inside its shell"
