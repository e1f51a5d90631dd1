"""Hand-made input states for the analytic checks (docs/model.md §4), and the runs on them.

Self-contained on purpose (it needs only h5py, numpy, harness.studies.analytic_dynamic and
harness.check.observables_dynamic' dominant_frequency): it writes a
paper-model state file (the layout of docs/interfaces.md: /h5md,
/particles/hair/position/value [1][N·P][3], /parameters with the scene attributes and
/parameters/stage = ["init"]) with h5py, and runs the simulate stage of a hairsim binary
on it. With `--input` of a paper-model file the binary starts a new
simulation whose rest shape is that frame, with zero velocities (docs/model.md §3.1).

Geometry (docs/model.md §1.1: y up): every strand hangs from a root at the origin; the
horizontal displacement is along z. `--no-collider` is always passed, so the head sphere
plays no part and the root need not lie on it.
"""

import math
import os

import numpy as np

from harness.core import runner
from harness.core.runner import COMPLETED
from harness.io import files


def write_paper_state(path, positions, hair_length, precision="fp64", hair_offset=0.1, head_radius=10.0):
    """Write positions [N][P][3] as a one-frame paper-model state (stage "init")."""
    import h5py

    positions = np.asarray(positions, dtype=np.float64)
    n, p, _ = positions.shape
    dtype = np.float64 if precision == "fp64" else np.float32
    with files.writing(path) as tmp, h5py.File(tmp, "w") as f:
        h = f.create_group("h5md")
        h.attrs["version"] = np.array([1, 1], dtype=np.int32)
        h.create_group("author").attrs["name"] = "hairbench analytic tests"
        c = h.create_group("creator")
        c.attrs["name"] = "harness/studies/analytic_runs_dynamic.py"
        c.attrs["version"] = "1"
        pos = f.create_group("particles/hair/position")
        pos.create_dataset("value", data=positions.reshape(1, n * p, 3).astype(dtype))
        pos.create_dataset("step", data=np.zeros(1, dtype=np.int64))
        pos.create_dataset("time", data=np.zeros(1, dtype=np.float64))
        g = f.create_group("parameters")
        for key, value in (
            ("n_strands", n),
            ("points_per_strand", p),
            ("seed", 1),
            ("head_radius", float(head_radius)),
            ("hair_offset", float(hair_offset)),
            ("hair_length", float(hair_length)),
            ("face_margin", 1.0),
            ("wind_strength", 0.0),
            ("wind_angle", math.pi),
            ("precision", precision),
        ):
            g.attrs[key] = value
        g.create_dataset("stage", data=np.array(["init"], dtype=h5py.string_dtype()))
    return path


def pendulum_positions(length, theta0):
    """P = 2: the root at the origin, the particle at angle θ0 from the downward vertical,
    displaced toward +z."""
    return np.array([[[0.0, 0.0, 0.0], [0.0, -length * math.cos(theta0), length * math.sin(theta0)]]])


def straight_chain_positions(points, length, theta0, azimuth=0.0):
    """A straight chain of P points from the origin with links ℓ = L/(P−1), at angle θ0
    from the downward vertical (θ0 = π/2: horizontal), in the vertical plane turned by
    `azimuth` about +y from the (y, z) plane (azimuth 0 leans toward +z, π/2 toward +x).
    P = 2 is `pendulum_positions` turned by the azimuth."""
    r = (length / (points - 1)) * np.arange(points)
    pos = np.zeros((1, points, 3))
    pos[0, :, 0] = r * math.sin(theta0) * math.sin(azimuth)
    pos[0, :, 1] = -r * math.cos(theta0)
    pos[0, :, 2] = r * math.sin(theta0) * math.cos(azimuth)
    return pos


def chain_positions(points, length, amplitude, shape="continuum"):
    """A chain of P points hanging from the origin with rigid links ℓ = L/(P−1), displaced
    along z by amplitude × the first-mode shape with the tip at `amplitude`.

    shape "continuum": J0(j01·√(s/L)), s the arc length from the free end (docs/model.md
    §4.3); a numpy array of P values: that shape (root value ignored). The y coordinates are
    chosen so that every link has exactly length ℓ (in double)."""
    ell = length / (points - 1)
    if isinstance(shape, str):
        s = length - ell * np.arange(points)
        u = _analytic().chain_mode_shape(np.maximum(s, 0.0), length)
    else:
        u = np.asarray(shape, dtype=np.float64)
    u = amplitude * u / u[-1]
    u[0] = 0.0
    pos = np.zeros((1, points, 3))
    for k in range(1, points):
        du = u[k] - u[k - 1]
        pos[0, k, 1] = pos[0, k - 1, 1] - math.sqrt(ell * ell - du * du)
        pos[0, k, 2] = u[k]
    return pos


def simulate(
    binary,
    input_path,
    output_path,
    frames,
    substeps,
    solver,
    *,
    gravity=981.0,
    iterations=1,
    precision="fp64",
    extra=(),
    timeout=600,
):
    """Run `binary --input IN --stages simulate --no-collider … --output OUT` and return OUT."""
    cmd = [
        str(binary),
        "--input",
        str(input_path),
        "--stages",
        "simulate",
        "--no-collider",
        "--frames",
        str(frames),
        "--substeps",
        str(substeps),
        "--iterations",
        str(iterations),
        "--solver",
        solver,
        "--gravity",
        repr(float(gravity)),
        "--precision",
        precision,
        "--threads",
        "1",
        "--velocities",
        "last",
        "--output",
        str(output_path),
        "--force",
        "--quiet",
    ]
    cmd += [str(a) for a in extra]
    r = runner.run_command(cmd, timeout=timeout)
    if r.returncode not in COMPLETED:
        raise RuntimeError(f"{' '.join(cmd)} exited {r.returncode}: {r.stderr.strip()}")
    return output_path


# ---------------------------------------------------------------- the checks' runs
# Each returns a dict with the measured value, the expected value(s) and extras. They import
# harness.studies.analytic_dynamic for the analysis (the closed forms live there, once).

FRAME_DT = 1.0 / 60.0
G0 = 981.0


def _analytic():
    from harness.studies import analytic_dynamic as analytic

    return analytic


def run_series(binary, workdir, tag, positions, length, frames, substeps, solver, precision="fp64", **options):
    """Write `positions` as WORKDIR/TAG_in.h5, simulate it into WORKDIR/TAG.h5 (`options`: those of
    simulate()) and return the output's (times, positions [F][N][P][3])."""
    inp = write_paper_state(os.path.join(workdir, f"{tag}_in.h5"), positions, length, precision=precision)
    out = simulate(
        binary, inp, os.path.join(workdir, f"{tag}.h5"), frames, substeps, solver, precision=precision, **options
    )
    return _analytic().read_series(out)


def run_pendulum(binary, workdir, solver, substeps, theta0, length=30.0, periods=3, precision="fp64"):
    """§4.1: P = 2, rigid, released from rest at θ0; the period from the zero crossings of z
    over the first `periods` full periods (frames enough for periods + 1)."""
    an = _analytic()
    expected = an.pendulum_period(length, G0, theta0)
    frames = int(math.ceil((periods + 1) * expected / FRAME_DT))
    tag = f"pend_{solver}_{substeps}_{theta0:g}_{precision}"
    positions = pendulum_positions(length, theta0)
    t, x = run_series(binary, workdir, tag, positions, length, frames, substeps, solver, precision)
    z = x[:, 0, 1, 2]
    measured = an.period_from_crossings(t, z, periods=periods)
    # amplitude decay: the largest |θ| in the last full period against θ0 (energy loss)
    theta = an.segment_angle(x[:, 0, 0], x[:, 0, 1])
    last = t >= t[-1] - expected
    return {
        "measured": measured,
        "expected": expected,
        "small_angle": an.pendulum_period_small(length, G0),
        "amplitude_end": float(np.max(np.abs(theta[last]))),
        "frames": frames,
    }


def run_wind(
    binary,
    workdir,
    solver,
    substeps,
    speed,
    drag=1.0,
    damping=10.0,
    seconds=8.0,
    length=30.0,
    wind_angle=0.0,
    precision="fp64",
):
    """§4.2: P = 2 hanging straight down, steady wind along ψ (0: toward +z), no gusts; the
    angle of the segment at the last frame against the net acceleration's,
    atan(c_d·U/g0) for ψ = 0."""
    an = _analytic()
    frames = int(math.ceil(seconds / FRAME_DT))
    tag = f"wind_{solver}_{substeps}_{speed:g}_{wind_angle:g}_{precision}"
    t, x = run_series(
        binary,
        workdir,
        tag,
        pendulum_positions(length, 0.0),
        length,
        frames,
        substeps,
        solver,
        precision,
        extra=(
            "--wind-speed",
            repr(float(speed)),
            "--drag",
            repr(float(drag)),
            "--damping",
            repr(float(damping)),
            "--wind-angle",
            repr(float(wind_angle)),
            "--gust-amplitude",
            "0",
        ),
    )
    theta = an.segment_angle(x[:, 0, 0], x[:, 0, 1])
    return {
        "measured": float(theta[-1]),
        "expected": an.wind_angle(drag, speed, G0, wind_angle),
        "change_last_second": float(np.max(np.abs(theta[t >= t[-1] - 1.0] - theta[-1]))),
        "frames": frames,
    }


def run_chain(
    binary,
    workdir,
    solver,
    substeps,
    points,
    length=30.0,
    amplitude=0.3,
    periods=4,
    iterations=1,
    ftl_damping=None,
    precision="fp64",
):
    """§4.3: P points hanging from a fixed root, rigid links, no bend, displaced along z by
    amplitude × the continuum first mode J0(j01·√(s/L)) (tip at `amplitude`).

    The frequency is measured from the zero crossings of the first-mode coordinate
    q1(t) = φ1·u(t) (u the points' z, φ1 the discrete chain's first mode shape): by
    orthogonality of the modes this removes the small higher-mode content that the continuum
    shape starts with, which shifts the tip's own zero crossings. The tip's dominant
    frequency (FFT) is returned too, as a cross-check. Expected: the discrete chain's ω1
    (the solver's target); the continuum ω1 is returned for the discretisation error."""
    from harness.check.observables_dynamic import dominant_frequency

    an = _analytic()
    w_cont = an.chain_omega1(length, G0)
    omegas, shapes = an.discrete_chain_modes(points, length, G0)
    w_disc = float(omegas[0])
    frames = int(math.ceil((periods + 1) * 2 * math.pi / w_disc / FRAME_DT))
    tag = f"chain_{solver}_{substeps}_{points}_{iterations}_{ftl_damping}_{precision}"
    positions = chain_positions(points, length, amplitude)
    extra = ("--ftl-damping", repr(float(ftl_damping))) if ftl_damping is not None else ()
    t, x = run_series(
        binary, workdir, tag, positions, length, frames, substeps, solver, precision, iterations=iterations, extra=extra
    )
    q1 = x[:, 0, :, 2] @ shapes[:, 0]
    period = an.period_from_crossings(t, q1, periods=periods)
    tip = x[:, 0, -1, 2]
    last = t >= t[-1] - 2 * math.pi / w_disc
    stretch = np.linalg.norm(np.diff(x[:, 0], axis=1), axis=-1).sum(axis=1) / length - 1.0
    return {
        "measured": 2 * math.pi / period,
        "expected": w_disc,
        "continuum": w_cont,
        "tip_fft": 2 * math.pi * dominant_frequency(tip, float(np.mean(np.diff(t)))),
        "amplitude_end": float(np.max(np.abs(tip[last]))) / amplitude,
        "stretch_max": float(np.max(np.abs(stretch))),
        "frames": frames,
    }
