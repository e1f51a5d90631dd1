"""Read the dynamic parts of a state file (docs/model.md §3.4, §3.8): the one reader.

`open_trajectory(path)` opens any state file through `states.open_state` (same layout
checks, same `StateError` one-liners) and adds what a dynamic file (/parameters attribute
model = "dynamic") holds beyond the paper frames:

- `step`, `time`: per written position frame (int64, float64); paper frames have time 0,
  simulated frame f (counted from 1) has step paper_frames − 1 + f and time f·Δt;
- `paper_frames`: how many leading frames come from the paper stages;
- `rest`: the rest shape X̄ as [N][P][3] (None in a paper-model file);
- `velocity(i)`, `velocity_steps`, `velocity_times`: stored velocity frames;
- `observables`: a pandas DataFrame with one row per simulated frame (step, time,
  stretch_max, penetration_max, kinetic_energy, blown_up, blown_up_strands);
- `frame_at_step(step)`: the position frame index written at that step (None if the frame
  was not written, e.g. with --output-every);
- `dynamic_params`: the /parameters attributes of the dynamic model as a dict;
- `colliders`: the colliders of docs/model.md §3.17 (harness.io.colliders.Collider, each
  mesh with its stored SDF), [] without them.

A paper-model file opens too (`is_dynamic` False, no rest, no velocities, empty
observables), so callers can take either. Any departure from the layout (a missing
dataset, a shape or dtype that does not fit, steps that do not match) is a StateError.
"""

from dataclasses import dataclass, field, fields

import numpy as np

from harness.io.states import POSITION, State, StateError, as_text, open_state

HAIR = "particles/hair"
REST = f"{HAIR}/rest_position"
VELOCITY = f"{HAIR}/velocity"
TRACK = "parameters/motion_track"  # --head-motion track (docs/interfaces.md, "Motion tracks")
OBSERVABLES = ("stretch_max", "penetration_max", "kinetic_energy", "blown_up", "blown_up_strands")
DYNAMIC_ATTRS = (
    "paper_frames",
    "simulated_frames",
    "output_every",
    "solver",
    "head_motion",
    "features",
    "substeps",
    "iterations",
    "bend",
    "shape",
    "collider",
    "drag_declared",
    "frame_dt",
    "gravity",
    "drag",
    "damping",
    "stretch_compliance",
    "bend_compliance",
    "shape_compliance",
    "shape_range",
    "ftl_damping",
    "collision_margin",
    "wind_speed",
    "wind_angle",
    "gust_amplitude",
    "gust_frequency",
    "gust_wavelength",
    "motion_amplitude",
    "motion_frequency",
    "guided",
    "guides",
    "follow",
    "lra",
    "lra_scale",
    "sag_free",
    "per_segment",
    "render_points",
    "simulated_points",
    # §3.16 the grid, §3.17 colliders and friction (absent in older files: none)
    "grid",
    "grid_n",
    "grid_rebuild",
    "grid_box_given",
    "grid_box",
    "grid_padding",
    "grid_friction_declared",
    "grid_friction",
    "grid_volume_declared",
    "grid_volume",
    "friction_declared",
    "friction",
    "depenetration_declared",
    "depenetration_speed",
    "collider_sweeps",
    "planes_declared",
    "contact_margin",
    "collide_once",
    "body_motion",
    "body_amplitude",
    "body_frequency",
    "colliders",
    "colliders_file",
)
REQUIRED_DYNAMIC = (
    "paper_frames",
    "substeps",
    "frame_dt",
    "solver",
    "head_motion",
    "collider",
    "motion_amplitude",
    "motion_frequency",
    "collision_margin",
)


@dataclass
class Trajectory(State):
    """A State plus the dynamic model's time series (see the module docstring)."""

    is_dynamic: bool = False
    paper_frames: int = 0
    step: np.ndarray = None
    time: np.ndarray = None
    velocity_steps: np.ndarray = None
    velocity_times: np.ndarray = None
    observables: object = None
    dynamic_params: dict = field(default_factory=dict)
    _rest: object = field(repr=False, default=None)
    _vel: object = field(repr=False, default=None)
    simulated_rows: np.ndarray = None  # --render-points: which rows of a strand are simulated points (§3.14)
    colliders: list = field(default_factory=list)  # §3.17
    # --head-motion track: /parameters/motion_track [K][8] (time, qw, qx, qy, qz, tx, ty, tz), else None
    motion_track: np.ndarray = None

    @property
    def rest(self):
        """X̄ as [N][P][3] in the file's dtype, or None (paper-model file)."""
        if self._rest is None:
            return None
        try:
            return self._rest[()].reshape(self.n_strands, self.points, 3)
        except Exception as e:
            raise StateError(f"{self.path}: cannot read /{REST}: {e}") from None

    @property
    def simulated(self):
        """Indices of the written position frames that are simulated frames."""
        return [f for f in range(self.n_frames) if self.stages[f] == "simulate"]

    def velocity(self, i):
        """Stored velocity frame i (negative from the end) as [N][P][3]."""
        n = 0 if self._vel is None else self._vel.shape[0]
        if not -n <= i < n:
            raise StateError(f"{self.path}: has no velocity frame {i} (it has {n})")
        try:
            return self._vel[i % n].reshape(self.n_strands, self.points, 3)
        except Exception as e:
            raise StateError(f"{self.path}: cannot read velocity frame {i}: {e}") from None

    def velocity_at_step(self, step):
        """The velocities stored for `step`, or None."""
        hits = np.nonzero(self.velocity_steps == step)[0]
        return self.velocity(int(hits[0])) if hits.size else None

    def frame_at_step(self, step):
        """The index of the position frame written at `step`, or None."""
        hits = np.nonzero(self.step == step)[0]
        return int(hits[0]) if hits.size else None

    def simulated_index(self, f):
        """Simulated frame number (1, 2, …, counted over the whole simulation) of frame f."""
        return int(self.step[f]) - self.paper_frames + 1

    @property
    def solver(self):
        return as_text(self.dynamic_params.get("solver", ""))

    @property
    def head_motion(self):
        return as_text(self.dynamic_params.get("head_motion", "still"))

    @property
    def features(self):
        return as_text(self.dynamic_params.get("features", ""))

    @property
    def guided(self):
        """Whether only guides were simulated and the other strands placed from them (§3.14)."""
        return bool(int(self.dynamic_params.get("guided", 0)))

    @property
    def follow(self):
        return as_text(self.dynamic_params.get("follow", "blend3"))

    @property
    def render_points(self):
        """P_r of a file written with --render-points (its `points`), else 0 (§3.14)."""
        return int(self.dynamic_params.get("render_points", 0))

    @property
    def simulated_points(self):
        """P_s: the points a strand simulated (= `points` without --render-points)."""
        return int(self.dynamic_params.get("simulated_points", self.points))

    @property
    def collider(self):
        return bool(int(self.dynamic_params.get("collider", 1)))

    @property
    def per_segment(self):
        """Whether the stretch rest lengths are the rest shape's own segments (a groom, §3.15)."""
        return bool(int(self.dynamic_params.get("per_segment", 0)))

    def segment_rest(self):
        """The stretch rest lengths in double: ℓ = L/(P−1), or [N][P−1] from the rest shape
        for a groom (§3.15, summed as c_ref/dynamic/dynamics_host.c hb_dyn_seg_rest does)."""
        if not self.per_segment:
            return self.hair_length / (self.points - 1)
        e = np.diff(self.rest.astype(np.float64), axis=1)
        return np.sqrt((e[..., 0] * e[..., 0] + e[..., 1] * e[..., 1]) + e[..., 2] * e[..., 2])

    @property
    def collide_radius(self):
        """R_c = R + c_m in double (§3.5)."""
        return float(self.params["head_radius"]) + float(self.dynamic_params.get("collision_margin", 0.0))


def _series(f, name, path, length=None, dtype_kind="if"):
    if name not in f:
        raise StateError(f"{path}: no /{name} dataset (a dynamic file has one)")
    ds = f[name]
    if not hasattr(ds, "shape") or ds.ndim != 1:
        raise StateError(f"{path}: /{name} is not a one-dimensional dataset")
    if length is not None and ds.shape[0] != length:
        raise StateError(f"{path}: /{name} has {ds.shape[0]} entries, expected {length}")
    if ds.dtype.kind not in dtype_kind:
        raise StateError(f"{path}: /{name} has dtype {ds.dtype}, expected a number")
    return ds[()]


def _observables(f, path):
    import pandas as pd

    cols = {}
    step = time = None
    for name in OBSERVABLES:
        base = f"observables/{name}"
        value = _series(f, f"{base}/value", path)
        s = _series(f, f"{base}/step", path, len(value), "iu")
        t = _series(f, f"{base}/time", path, len(value), "f")
        if step is None:
            step, time = s, t
        elif not (np.array_equal(s, step) and np.array_equal(t, time)):
            raise StateError(f"{path}: /{base} has other steps or times than /observables/{OBSERVABLES[0]}")
        cols[name] = value
    frame = pd.DataFrame({"step": step.astype(np.int64), "time": time.astype(np.float64), **cols})
    frame["blown_up"] = frame["blown_up"].astype(bool)
    return frame


def _check_dynamic(t, f):
    path = t.path
    params = t.params
    missing = [a for a in REQUIRED_DYNAMIC if a not in params]
    if missing:
        raise StateError(f"{path}: a dynamic file's /parameters lacks attribute(s) {', '.join(missing)}")
    t.dynamic_params = {k: params[k] for k in DYNAMIC_ATTRS if k in params}
    try:
        t.paper_frames = int(params["paper_frames"])
    except (TypeError, ValueError):
        raise StateError(f"{path}: paper_frames attribute is not a whole number") from None
    if not 1 <= t.paper_frames <= t.n_frames:
        raise StateError(f"{path}: paper_frames = {t.paper_frames} but the file has {t.n_frames} frame(s)")
    for fr in range(t.n_frames):
        want = "simulate" if fr >= t.paper_frames else None
        if want and t.stages[fr] != want:
            raise StateError(
                f"{path}: frame {fr} is '{t.stages[fr]}', expected 'simulate' after {t.paper_frames} paper frame(s)"
            )
        if not want and t.stages[fr] == "simulate":
            raise StateError(f"{path}: frame {fr} is 'simulate' but lies among the paper frames")
    if not np.all(np.diff(t.step) > 0):
        raise StateError(f"{path}: /{HAIR}/position/step is not increasing")
    if not np.array_equal(t.step[: t.paper_frames], np.arange(t.paper_frames)):
        raise StateError(f"{path}: the paper frames' steps are not 0 … {t.paper_frames - 1}")
    if REST not in f:
        raise StateError(f"{path}: no /{REST} dataset (a dynamic file has its rest shape)")
    rest = f[REST]
    if not hasattr(rest, "shape") or rest.shape != (t.n_strands * t.points, 3):
        raise StateError(
            f"{path}: /{REST} has shape {getattr(rest, 'shape', None)}, expected ({t.n_strands * t.points}, 3)"
        )
    if rest.dtype != t.dtype:
        raise StateError(f"{path}: /{REST} is {rest.dtype} but positions are {t.dtype}")
    t._rest = rest
    if f"{VELOCITY}/value" not in f:
        raise StateError(f"{path}: no /{VELOCITY}/value dataset (a dynamic file stores velocities)")
    vel = f[f"{VELOCITY}/value"]
    if not hasattr(vel, "shape") or vel.ndim != 3 or vel.shape[1:] != (t.n_strands * t.points, 3):
        raise StateError(
            f"{path}: /{VELOCITY}/value has shape {getattr(vel, 'shape', None)}, "
            f"expected [Fv][{t.n_strands * t.points}][3]"
        )
    if vel.dtype != t.dtype:
        raise StateError(f"{path}: /{VELOCITY}/value is {vel.dtype} but positions are {t.dtype}")
    t._vel = vel
    t.velocity_steps = _series(f, f"{VELOCITY}/step", path, vel.shape[0], "iu").astype(np.int64)
    t.velocity_times = _series(f, f"{VELOCITY}/time", path, vel.shape[0], "f").astype(np.float64)
    written = set(t.step.tolist())
    stray = [int(s) for s in t.velocity_steps if s not in written]
    if stray:
        raise StateError(f"{path}: velocities stored for step(s) {stray[:3]} that have no position frame")
    t.observables = _observables(f, path)
    if t.head_motion == "track":
        track = f.get(TRACK)
        if track is None or track.ndim != 2 or track.shape[1] != 8 or track.shape[0] < 1:
            raise StateError(f"{path}: head_motion is 'track' but /{TRACK} [K][8] is missing")
        t.motion_track = track[()]
    if t.render_points:
        _check_lod(t, f)
    if int(params.get("colliders", 0)) > 0:
        from harness.io.colliders import read_colliders

        t.colliders = read_colliders(f, path, int(params["colliders"]))


def _check_lod(t, f):
    """--render-points: P_r = points, (P_r − 1) a multiple of (P_s − 1), and the marks of the
    simulated rows (row k·m of every strand) as docs/interfaces.md states them."""
    path, pr, ps = t.path, t.render_points, t.simulated_points
    if pr != t.points or not 2 <= ps < pr or (pr - 1) % (ps - 1):
        raise StateError(f"{path}: render_points = {pr}, simulated_points = {ps} do not fit {t.points} points a strand")
    name = f"{HAIR}/simulated"
    marks = f[name][()] if name in f else None
    if marks is None or marks.shape != (t.n_strands * pr,):
        raise StateError(f"{path}: a --render-points file needs /{name} [{t.n_strands * pr}]")
    rows = np.flatnonzero(marks.reshape(t.n_strands, pr)[0])
    want = np.arange(ps) * ((pr - 1) // (ps - 1))
    if not np.array_equal(rows, want) or not np.all(marks.reshape(t.n_strands, pr) == marks[:pr]):
        raise StateError(f"{path}: /{name} does not mark rows k·(P_r − 1)/(P_s − 1) of every strand")
    t.simulated_rows = want


@dataclass
class SimulatedView(Trajectory):
    """A --render-points file seen through its simulated rows only (docs/model.md §3.14): P_s
    points a strand, as the run simulated them, its rest shape and velocities likewise, no
    render_points. What the paper model's and the dynamic model's checks apply to; the rendered
    rows are checked by recomputation (harness/check/lod_dynamic.py)."""

    rows_of: np.ndarray = None
    rendered_points: int = 0

    def _sim(self, flat):
        return flat.reshape(self.n_strands, self.rendered_points, 3)[:, self.rows_of]

    def frame(self, f):
        if not -self.n_frames <= f < self.n_frames:
            raise StateError(f"{self.path}: has no frame {f} (it has {self.n_frames})")
        try:
            return self._sim(self._dset[f % self.n_frames])
        except StateError:
            raise
        except Exception as e:
            raise StateError(f"{self.path}: cannot read frame {f}: {e}") from None

    def frames(self):
        return np.stack([self.frame(f) for f in range(self.n_frames)])

    def strands(self, f, i0, i1):
        rows = self._dset[f, i0 * self.rendered_points : i1 * self.rendered_points]
        return rows.reshape(i1 - i0, self.rendered_points, 3)[:, self.rows_of]

    @property
    def rest(self):
        return None if self._rest is None else self._sim(self._rest[()])

    def velocity(self, i):
        n = 0 if self._vel is None else self._vel.shape[0]
        if not -n <= i < n:
            raise StateError(f"{self.path}: has no velocity frame {i} (it has {n})")
        return self._sim(self._vel[i % n])


def simulated_view(t):
    """The SimulatedView of a --render-points Trajectory (t itself otherwise); it shares t's file."""
    if not t.render_points:
        return t
    kw = {f.name: getattr(t, f.name) for f in fields(Trajectory)}
    params = {k: v for k, v in t.dynamic_params.items() if k not in ("render_points", "simulated_points")}
    kw.update(points=t.simulated_points, dynamic_params=params, simulated_rows=None)
    return SimulatedView(**kw, rows_of=t.simulated_rows, rendered_points=t.points)


def open_trajectory(path):
    """Open and check a state file (paper or dynamic); StateError with one line if it is not one."""
    import pandas as pd

    state = open_state(path)
    f = state._file
    try:
        t = Trajectory(**{k: getattr(state, k) for k in State.__dataclass_fields__})
        F = t.n_frames
        base = f"{HAIR}/position"
        t.step = (
            _series(f, f"{base}/step", t.path, F, "iu").astype(np.int64)
            if f"{base}/step" in f
            else np.arange(F, dtype=np.int64)
        )
        t.time = _series(f, f"{base}/time", t.path, F, "f").astype(np.float64) if f"{base}/time" in f else np.zeros(F)
        t.is_dynamic = as_text(t.params.get("model", "paper")) == "dynamic"
        if t.is_dynamic:
            _check_dynamic(t, f)
        else:
            if "simulate" in t.stages:
                raise StateError(f"{t.path}: has simulate frames but its model attribute is not 'dynamic'")
            t.paper_frames = F
            t.velocity_steps = np.zeros(0, np.int64)
            t.velocity_times = np.zeros(0)
            t.observables = pd.DataFrame({c: [] for c in ("step", "time", *OBSERVABLES)})
        return t
    except Exception:
        state.close()
        raise


__all__ = ["Trajectory", "SimulatedView", "open_trajectory", "simulated_view", "StateError", "POSITION"]
