"""The peer solver: chains in Bender's PositionBasedDynamics, through its Python bindings
(PyPI `pypbd`, an optional dependency). `run` builds N chains from our positions, steps
them frame by frame and returns every frame in our units with the time each frame took.

The mapping of our parameters onto pypbd's (docs/decisions.md, "The peer"):

- a strand of P points is P particles; the root gets mass 0 (pypbd's pinned particle), the
  others mass 1 (its default); the P−1 links are `addDistanceConstraint_XPBD(k−1, k)`
  added root first, with the rest length set to ℓ = L/(P−1);
- compliance α ↔ stiffness 1/α (pypbd forms α̃ = 1/(stiffness·h²)); α = 0 (rigid) ↔
  stiffness 0, which pypbd takes as α̃ = 0;
- substeps S ↔ `NUM_SUB_STEPS`, iterations I ↔ `MAX_ITERATIONS`, the frame Δt ↔ the
  TimeManager's step size (one `step` call is one frame of S substeps);
  `MAX_ITERATIONS_V` = 0: its velocity pass has nothing to do for distance constraints;
- gravity: pypbd's is (0, −9.81, 0) and the bindings do not expose it, so lengths are
  scaled by 9.81/g0 on the way in and back on the way out (g0 = 981 cm/s²: centimetres in,
  metres inside). A compliance is in s²/mass and does not change with the length unit.

pypbd keeps one global simulation, so one run at a time; a finished run frees its model.
"""

import ctypes
import os
import time

import numpy as np

from harness import HarnessError

PEER_GRAVITY = 9.81  # pypbd's fixed gravity, along −y (Simulation::m_gravitation)


def unavailable():
    """None when pypbd imports here, else the reason (one line) it does not."""
    try:
        import pypbd  # noqa: F401
    except ImportError as e:
        return f"pypbd is not installed ({e}); `pip install pypbd` adds the peer"
    return None


def version():
    from importlib import metadata

    try:
        return metadata.version("pypbd")
    except metadata.PackageNotFoundError:
        return "unknown"


def load(threads=None):
    """Import pypbd (HarnessError with the reason when absent) and set its OpenMP threads."""
    if threads and "pypbd" not in __import__("sys").modules:
        os.environ["OMP_NUM_THREADS"] = str(threads)  # read when libgomp loads
    reason = unavailable()
    if reason:
        raise HarnessError(f"peer: {reason}")
    import pypbd

    if threads:
        _omp("omp_set_num_threads", threads)
    return pypbd


def omp_threads():
    """The OpenMP threads pypbd's parallel loops use (None when its libgomp is not found)."""
    return _omp("omp_get_max_threads")


def _omp(name, *args):
    """Call an OpenMP runtime function of the libgomp loaded into this process."""
    try:
        with open("/proc/self/maps") as f:
            libs = {ln.split()[-1] for ln in f if "libgomp" in ln.rsplit("/", 1)[-1] and ln.split()[-1].startswith("/")}
    except OSError:
        return None
    for lib in sorted(libs):
        try:
            return getattr(ctypes.CDLL(lib), name)(*args)
        except (OSError, AttributeError):
            continue
    return None


def run(
    positions,
    hair_length,
    frames,
    *,
    substeps,
    iterations,
    compliance=0.0,
    frame_dt=1 / 60,
    gravity=981.0,
    record=True,
    threads=None,
):
    """Simulate chains from rest: positions [N][P][3] (cm, root first, links of length
    L/(P−1)). Returns (frames [F+1][N][P][3] in cm with the start first, or None when not
    `record`; milliseconds of each frame's `step` [F])."""
    if not gravity > 0:
        raise HarnessError("peer: pypbd's gravity is fixed; it maps only a gravity g0 > 0")
    if compliance < 0:
        raise HarnessError("peer: a compliance must be ≥ 0")
    pbd = load(threads)
    pos = np.asarray(positions, dtype=np.float64)
    n, p, _ = pos.shape
    scale = PEER_GRAVITY / gravity  # our length unit → pypbd's
    sim = pbd.Simulation.getCurrent()
    sim.initDefault()  # a fresh model (and its default collision detection, idle here)
    model = sim.getModel()
    try:
        ts = sim.getTimeStep()
        ts.setValueUInt(pbd.TimeStepController.NUM_SUB_STEPS, int(substeps))
        ts.setValueUInt(pbd.TimeStepController.MAX_ITERATIONS, int(iterations))
        ts.setValueUInt(pbd.TimeStepController.MAX_ITERATIONS_V, 0)
        ts.setValueInt(pbd.TimeStepController.VELOCITY_UPDATE_METHOD, 0)  # v = (x − x_old)/h, as ours
        pbd.TimeManager.getCurrent().setTimeStepSize(float(frame_dt))
        particles = model.getParticles()
        for row in (pos * scale).reshape(n * p, 3):
            particles.addVertex(row)
        stiffness = 0.0 if compliance == 0 else 1.0 / compliance
        rest = hair_length / (p - 1) * scale
        for i in range(n):
            particles.setMass(i * p, 0.0)
            for k in range(1, p):
                model.addDistanceConstraint_XPBD(i * p + k - 1, i * p + k, stiffness)
        for c in model.getConstraints():
            c.restLength = rest
        live = np.asarray(particles.getVertices())  # a view of pypbd's positions
        out = np.empty((frames + 1 if record else 1, n, p, 3))
        out[0] = pos
        ms = np.empty(frames)
        for f in range(frames):
            t0 = time.perf_counter()
            ts.step(model)
            ms[f] = (time.perf_counter() - t0) * 1e3
            if record:
                out[f + 1] = live.reshape(n, p, 3) / scale
        return (out if record else None), ms
    finally:
        model.cleanup()
