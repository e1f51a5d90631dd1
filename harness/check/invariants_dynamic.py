"""Invariants of a dynamic state file (docs/model.md §3), checked on every written frame.

Paper frames of a dynamic file get the paper invariants (invariants.py). Each simulated
frame f (at step s, simulated frame number g = s − paper_frames + 1) is checked for:

  finite       no NaN or Inf in the positions, nor in the velocities stored for f
  roots        the root is at Q(t)·X̄_0 (§3.2), t = (g·S)·h with h = Δt/S in double as
               the binary computes it; Q in double with the formula of
               c_ref/dynamic/dynamics_host.c hb_head_rotation, each entry rounded once to the working
               precision, and the product row by row, left to right, in the working
               precision (c_ref/dynamic/dynamics_impl.h rotate). With head motion `still` the root
               is X̄_0 itself. Bit-exact for the reference (`exact=True`, the default);
               otherwise each coordinate within DYN_ROOT_K·ε·R.
  collider     (collider on) no non-root point inside the sphere R_c = R + c_m by more than
               DYN_PENETRATION_K·ε·R_c
  ftl_segments (solver ftl) every segment (k−1, k) whose end k the collider did not move
               (|x_k| above R_c by more than that tolerance, or the collider off) has length
               ℓ (a groom: its ℓ_k, §3.15) within DYN_FTL_SEGMENT_K·ε·E, E = R + h + L
  follower_segments  (a guided xpbd file, §3.14) the same of every follower's segments: a
               follower is placed segment by segment at its own ℓ_k (ftl files check their
               followers under ftl_segments)
  observables  the frame's observables (§3.8) agree with its positions: stretch_max and
               penetration_max recomputed in double from the stored positions (bit for bit
               with `exact`, the reference: a maximum does not depend on order; otherwise
               within DYN_OBSERVABLE_K·ε64 of 1 + stretch and of R_c), blown_up_strands recomputed from
               positions and velocities (equal where velocities are stored; where they are
               not, the count from positions alone may not exceed it), kinetic energy
               within DYN_KINETIC_REL (a sum, whose order the binary may choose); and one
               observables row for every simulated step.

`check(traj)` returns a DynamicReport (same interface as invariants.InvariantReport).
"""

import math
from dataclasses import dataclass, field, fields, replace

import numpy as np

from harness.check import invariants
from harness.check.head_motion_dynamic import head_rotation, track_rotation  # noqa: F401 (read from here by other modules)
from harness.check.invariants import Violation
from harness.core import tolerances
from harness.core.guides import guide_count, guide_strands
from harness.io.states import State, as_text
from harness.io.trajectory import SimulatedView


def collider_depths(traj, points, t):
    """Each point's depth in each collider of §3.17 (harness.check.colliders_dynamic), [ncol][M]."""
    from harness.check.colliders_dynamic import depths

    return depths(traj, points, t)


@dataclass
class DynamicReport:
    path: str
    kind: str
    exact_roots: bool = True
    violations: list = field(default_factory=list)
    worst_root: float = 0.0
    worst_penetration_k: float = float("-inf")  # (R_c − |x|)/(ε·R_c), positive = inside
    worst_ftl_segment_k: float = 0.0  # |len − ℓ|/(ε·E)
    worst_kinetic_rel: float = 0.0
    worst_observable_k: float = 0.0  # stretch, penetration: |Δ|/(ε64·scale)
    paper: object = None  # InvariantReport of the paper frames

    @property
    def ok(self):
        return not self.violations and (self.paper is None or self.paper.ok)

    def all_violations(self):
        return (self.paper.violations if self.paper else []) + self.violations

    def as_dict(self):
        return {
            "path": self.path,
            "kind": self.kind,
            "ok": self.ok,
            "exact_roots": self.exact_roots,
            "worst_root": self.worst_root,
            "worst_penetration_k": None if self.worst_penetration_k == float("-inf") else self.worst_penetration_k,
            "worst_ftl_segment_k": self.worst_ftl_segment_k,
            "worst_kinetic_rel": self.worst_kinetic_rel,
            "worst_observable_k": self.worst_observable_k,
            "violations": [v.as_dict() for v in self.all_violations()],
        }


def frame_end_time(traj, f):
    """t at the end of written frame f, as the binary computes Q's time: (g·S)·(Δt/S)."""
    S = int(traj.dynamic_params["substeps"])
    h = float(traj.dynamic_params["frame_dt"]) / S
    return float(traj.simulated_index(f) * S) * h


def expected_roots(traj, f, rest_roots):
    """The roots [N][3] the model puts at frame f, in the working precision."""
    if traj.head_motion == "still":
        return rest_roots.copy()
    dt = rest_roots.dtype.type
    q = [
        dt(v)
        for v in head_rotation(
            traj.head_motion,
            float(traj.dynamic_params["motion_amplitude"]),
            float(traj.dynamic_params["motion_frequency"]),
            frame_end_time(traj, f),
            traj.motion_track,
        )
    ]
    a0, a1, a2 = rest_roots[:, 0], rest_roots[:, 1], rest_roots[:, 2]
    out = np.empty_like(rest_roots)
    for row in range(3):
        out[:, row] = q[3 * row] * a0 + q[3 * row + 1] * a1 + q[3 * row + 2] * a2
    return out


def observe(traj, x, v=None, t=None):
    """§3.8 recomputed in double from stored positions x [N][P][3] (and velocities v) at time t
    (the colliders' poses, §3.17): (stretch_max, penetration_max, kinetic_energy or None,
    blown-up count)."""
    N, P = traj.n_strands, traj.points
    ell = traj.segment_rest()
    xd = x.astype(np.float64)
    with np.errstate(invalid="ignore", over="ignore"):
        e = xd[:, 1:, :] - xd[:, :-1, :]
        l2 = (e[..., 0] * e[..., 0] + e[..., 1] * e[..., 1]) + e[..., 2] * e[..., 2]
        st = np.abs(np.sqrt(l2) / ell - 1.0)
        stretch = float(np.max(st, initial=0.0, where=~np.isnan(st)))
        pen = 0.0
        if traj.collider:
            n2 = (xd[:, 1:, 0] * xd[:, 1:, 0] + xd[:, 1:, 1] * xd[:, 1:, 1]) + xd[:, 1:, 2] * xd[:, 1:, 2]
            depth = traj.collide_radius - np.sqrt(n2)
            pen = float(np.max(depth, initial=0.0, where=~np.isnan(depth)))
        if traj.colliders and t is not None:  # §3.17: each collider's depth
            d = collider_depths(traj, xd[:, 1:, :], t)
            pen = max(pen, float(np.max(d, initial=0.0, where=~np.isnan(d))))
        r = xd[:, 1:, :] - xd[:, :1, :]
        r2 = (r[..., 0] * r[..., 0] + r[..., 1] * r[..., 1]) + r[..., 2] * r[..., 2]
        far = np.any(r2 > 4.0 * traj.hair_length * traj.hair_length, axis=1)
        bad = ~np.all(np.isfinite(x), axis=(1, 2))
        ke = None
        if v is not None:
            bad |= ~np.all(np.isfinite(v), axis=(1, 2))
            vd = v[:, 1:, :].astype(np.float64)
            w2 = (vd[..., 0] * vd[..., 0] + vd[..., 1] * vd[..., 1]) + vd[..., 2] * vd[..., 2]
            ke = 0.5 * float(np.cumsum(np.cumsum(w2, axis=1)[:, -1])[-1]) / (N * (P - 1))
    return stretch, pen, ke, int(np.sum(bad | far))


def _paper_view(traj):
    """The paper frames of a dynamic file as a plain State (for invariants.check)."""
    cut = dict(
        n_frames=traj.paper_frames,
        stages=traj.stages[: traj.paper_frames],
        skipped=traj.skipped[: traj.paper_frames],
        fused=traj.fused[: traj.paper_frames],
    )
    if isinstance(traj, SimulatedView):  # a LOD file's simulated rows (its frames read through them)
        return replace(traj, **cut)
    return State(**{**{f.name: getattr(traj, f.name) for f in fields(State)}, **cut})


def _strands_holding_rest(traj):
    """The strands whose every segment the model puts at ℓ (ℓ_k) before the collider: all of an
    ftl run, the followers of a guided xpbd run (§3.14, placed segment by segment), else None."""
    if traj.solver == "ftl":
        return np.arange(traj.n_strands)
    if traj.guided:
        g = guide_count(traj.n_strands, float(traj.dynamic_params["guides"]))
        return np.setdiff1d(np.arange(traj.n_strands), guide_strands(traj.n_strands, g))
    return None


def is_reference_build(traj):
    """The C reference built as the oracle (no FMA contraction): its roots must be bit-exact."""
    return as_text(traj.params.get("backend", "")) == "cpu" and "-ffp-contract=off" in traj.flags


class _FrameChecks:
    """The checks of one simulated frame of a trajectory, each adding its violations to `rep`."""

    def __init__(self, traj, rep, exact, kind):
        self.traj, self.rep, self.exact = traj, rep, exact
        self.eps = tolerances.EPS[kind]
        R, h, L = float(traj.params["head_radius"]), float(traj.params["hair_offset"]), traj.hair_length
        self.E = tolerances.extent(R, h, L)
        self.rc = traj.collide_radius
        self.ell = traj.segment_rest()
        self.pen_allow = tolerances.DYN_PENETRATION_K * self.eps * self.rc
        self.rest_roots = np.ascontiguousarray(traj.rest[:, 0, :])

    def add(self, f, name, count, worst, message):
        if count:
            self.rep.violations.append(
                Violation(
                    f,
                    "simulate",
                    name,
                    int(count),
                    float(worst),
                    f"frame {f} (simulate, step {int(self.traj.step[f])}): {message}",
                )
            )

    def bound(self, f, name, values, k, worst_field, message, nan_over=True):
        """Values (in units of ε·scale) over k, NaN included with nan_over: `name`'s violation,
        `message` formatted with n (how many), k and worst; rep.<worst_field> the largest seen."""
        worst = float(np.nanmax(values)) if values.size else 0.0
        setattr(self.rep, worst_field, max(getattr(self.rep, worst_field), worst))
        over = ~(values <= k) if nan_over else values > k
        self.add(f, name, over.sum(), worst, message.format(n=int(over.sum()), k=k, worst=worst))

    def roots(self, f, x):
        """The roots at Q(t)·X̄0: bit-identical, or within DYN_ROOT_K·ε·R."""
        want = expected_roots(self.traj, f, self.rest_roots)
        got = np.ascontiguousarray(x[:, 0, :])
        if self.exact:
            bits = invariants._bits
            moved = np.any(bits(got) != bits(want), axis=1)
            if moved.any():
                from harness.core.ulp import ulp_distance

                self.rep.worst_root = max(self.rep.worst_root, float(ulp_distance(got, want, got.dtype).max()))
            self.add(
                f,
                "roots",
                moved.sum(),
                self.rep.worst_root,
                f"{int(moved.sum())} root(s) not bit-identical to Q(t)·X̄0 (worst {self.rep.worst_root:g} ULP)",
            )
        else:
            R = float(self.traj.params["head_radius"])
            with np.errstate(invalid="ignore"):
                d = np.max(np.abs(got.astype(np.float64) - want.astype(np.float64)), axis=1) / (self.eps * R)
            self.bound(
                f,
                "roots",
                d,
                tolerances.DYN_ROOT_K,
                "worst_root",
                "{n} root(s) farther than {k:g}·ε·R from Q(t)·X̄0 (worst {worst:.3g}·ε·R)",
            )

    def geometry(self, f, x):
        """No point inside the collider; the segments a solver holds at rest length."""
        xd = x.astype(np.float64)
        with np.errstate(invalid="ignore", over="ignore"):
            r = np.sqrt((xd[:, :, 0] * xd[:, :, 0] + xd[:, :, 1] * xd[:, :, 1]) + xd[:, :, 2] * xd[:, :, 2])
            # with §3.17's colliders a later collider may push a point back into the head, and a
            # bounded depenetration leaves it inside on purpose: the bound holds without them
            bounded = int(self.traj.dynamic_params.get("depenetration_declared", 0))
            if self.traj.collider and not self.traj.colliders and not bounded:
                self.bound(
                    f,
                    "collider",
                    (self.rc - r[:, 1:]) / (self.eps * self.rc),
                    tolerances.DYN_PENETRATION_K,
                    "worst_penetration_k",
                    f"{{n}} point(s) inside the collider R_c = {self.rc:g} by more than {{k:g}}·ε·R_c "
                    "(worst {worst:.3g}·ε·R_c)",
                    nan_over=False,
                )
            held = _strands_holding_rest(self.traj)
            if held is not None:
                seg = np.sqrt(np.sum(np.diff(xd, axis=1) ** 2, axis=2))
                err = np.abs(seg - self.ell) / (self.eps * self.E)
                free = np.ones_like(err, dtype=bool)
                # §3.17: friction moves a point in contact along the surface, which lifts it off a
                # curved one: with friction a point within a segment's length of a surface counts as moved
                near = self.pen_allow
                if int(self.traj.dynamic_params.get("friction_declared", 0)) or any(
                    c.mu_s > 0 for c in self.traj.colliders
                ):
                    near = float(np.max(self.ell)) if np.ndim(self.ell) else float(self.ell)
                if self.traj.collider:
                    free = r[:, 1:] > self.rc + near  # the collider did not move point k
                if self.traj.colliders:  # nor any other collider
                    d = collider_depths(self.traj, xd[:, 1:, :], frame_end_time(self.traj, f))
                    free &= ~np.any(np.nan_to_num(d, nan=-np.inf) > -near, axis=0).reshape(free.shape)
                    if int(self.traj.dynamic_params.get("planes_declared", 0)) and f >= 1:
                        # --contact-planes: a point within M of a collider at the frame's start met its
                        # plane all frame, and a plane reaches far beyond a curved surface (hair slides
                        # along it): such a point counts as moved (M + near: the poses of the first substep)
                        m = float(self.traj.dynamic_params["contact_margin"]) + near
                        x0 = self.traj.frame(f - 1).astype(np.float64)[:, 1:, :]
                        d0 = collider_depths(self.traj, x0, frame_end_time(self.traj, f - 1))
                        free &= ~np.any(np.nan_to_num(d0, nan=-np.inf) > -m, axis=0).reshape(free.shape)
                err = np.where(free, err, 0.0)[held]
                self.bound(
                    f,
                    "ftl_segments" if self.traj.solver == "ftl" else "follower_segments",
                    err,
                    tolerances.DYN_FTL_SEGMENT_K,
                    "worst_ftl_segment_k",
                    "{n} segment(s) not moved by the collider differ from ℓ by more than {k:g}·ε·E "
                    "(worst {worst:.3g}·ε·self.E)",
                )

    def observables(self, f, x, v, row):
        """The frame's observables row against what its positions and velocities give."""
        stretch, pen, ke, blown = observe(self.traj, x, v, frame_end_time(self.traj, f))
        msgs = []
        # the reference computes both exactly as observe() does; another build may contract
        # or reorder the double sums: DYN_OBSERVABLE_K·ε64 of the quantity's scale
        e64 = tolerances.EPS["fp64"]
        s_file, p_file = float(row["stretch_max"]), float(row["penetration_max"])
        ds, dp = abs(stretch - s_file), abs(pen - p_file)
        self.rep.worst_observable_k = max(
            self.rep.worst_observable_k, ds / (e64 * (1 + abs(stretch))), dp / (e64 * self.rc)
        )
        if not (stretch == s_file if self.exact else ds <= tolerances.DYN_OBSERVABLE_K * e64 * (1 + abs(stretch))):
            msgs.append(f"stretch_max {s_file:.17g} but the positions give {stretch:.17g}")
        if not (pen == p_file if self.exact else dp <= tolerances.DYN_OBSERVABLE_K * e64 * self.rc):
            msgs.append(f"penetration_max {p_file:.17g} but the positions give {pen:.17g}")
        if ke is not None:
            k = float(row["kinetic_energy"])
            rel = abs(ke - k) / max(abs(ke), np.finfo(float).tiny) if math.isfinite(ke) else float("nan")
            if math.isfinite(rel):
                self.rep.worst_kinetic_rel = max(self.rep.worst_kinetic_rel, rel)
            if math.isfinite(ke) and not rel <= tolerances.DYN_KINETIC_REL:
                msgs.append(f"kinetic_energy {k:.17g} but the velocities give {ke:.17g}")
        stored = int(row["blown_up_strands"])
        if (v is not None and blown != stored) or (v is None and blown > stored):
            msgs.append(
                f"blown_up_strands {stored} but positions{' and velocities' if v is not None else ''} give {blown}"
            )
        if bool(row["blown_up"]) != (stored > 0):
            msgs.append(f"blown_up {bool(row['blown_up'])} disagrees with blown_up_strands {stored}")
        self.add(f, "observables", len(msgs), 0, "; ".join(msgs))


def check(traj, exact=True, frames=None, paper=True):
    """Check a Trajectory's simulated frames (all, or the frame indices `frames`), and with
    `paper` its paper frames with invariants.check. Returns a DynamicReport."""
    kind = tolerances.kind_of(traj.precision, traj.fast_math)
    rep = DynamicReport(path=traj.path, kind=kind, exact_roots=exact)
    # a groom's init frame (§3.15) is no paper state: its strands leave their slice planes
    if paper and traj.paper_frames and not traj.per_segment:
        rep.paper = invariants.check(_paper_view(traj))
    if not traj.is_dynamic:
        return rep
    checks = _FrameChecks(traj, rep, exact, kind)
    obs = traj.observables.set_index("step")
    sim = traj.simulated if frames is None else [f for f in frames if traj.stages[f] == "simulate"]

    want_steps = np.arange(traj.paper_frames, int(traj.step[-1]) + 1) if traj.simulated else np.zeros(0)
    if frames is None and not np.array_equal(np.asarray(obs.index), want_steps):
        rep.violations.append(
            Violation(
                -1,
                "simulate",
                "observables",
                1,
                0.0,
                f"the observables do not have one row per simulated step {traj.paper_frames} … {int(traj.step[-1])}",
            )
        )
    for f in sim:
        x = traj.frame(f)
        step = int(traj.step[f])
        v = traj.velocity_at_step(step)
        nonfinite = int((~np.isfinite(x)).sum()) + (0 if v is None else int((~np.isfinite(v)).sum()))
        checks.add(f, "finite", nonfinite, 1, f"{nonfinite} coordinate(s) of positions or velocities are NaN or Inf")
        checks.roots(f, x)
        checks.geometry(f, x)
        if step not in obs.index:
            checks.add(f, "observables", 1, 0, "no observables row for this step")
            continue
        checks.observables(f, x, v, obs.loc[step])
    return rep
