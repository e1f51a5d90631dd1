"""The accuracy study's observables (harness/check/observables_dynamic.py) on runs of the C reference
with known answers: a pendulum's tip frequency against the exact period, a damped pendulum's
damping ratio against β/(2ω0), the energy of an undamped pendulum within the scheme's
measured drift, zero jitter for a strand resting on nothing, and the no-simulation solver
(`--solver rigid`) equal to the rest shape rotated by the head (an independent numpy
rotation). Tolerances: harness/core/tolerances.py (OBS_*). Small runs: one strand, ≤ 400 frames."""

import math

import numpy as np
import pytest

from harness.check import observables_dynamic as ob
from harness.core import tolerances as tol
from harness.io.trajectory import open_trajectory
from harness.studies import analytic_dynamic as an
from harness.studies.analytic_runs_dynamic import G0, pendulum_positions, simulate, write_paper_state
from support.statecheck import run

DT = 1 / 60
LENGTH = 30.0
THETA0 = 0.05


def read(path):
    """(times, positions, velocities) of the simulated frames, float64."""
    with open_trajectory(path) as t:
        sim = t.simulated
        x = np.stack([t.frame(f) for f in sim]).astype(np.float64)
        v = np.stack([t.velocity_at_step(s) for s in t.step[sim]]).astype(np.float64)
        return t.time[sim].copy(), x, v


def pendulum(cpu_bin, tmp_path, substeps, *extra, frames=400):
    inp = write_paper_state(tmp_path / "in.h5", pendulum_positions(LENGTH, THETA0), LENGTH)
    out = simulate(
        cpu_bin, inp, tmp_path / f"S{substeps}.h5", frames, substeps, "xpbd", extra=["--velocities", "all", *extra]
    )
    return read(out)


def test_tip_frequency_of_a_pendulum(cpu_bin, tmp_path):
    _, x, _ = pendulum(cpu_bin, tmp_path, 16)
    f = ob.dominant_frequency(ob.tip_displacement(x, axis=2), DT)
    expected = 1.0 / an.pendulum_period(LENGTH, G0, THETA0)
    assert abs(f / expected - 1) <= tol.OBS_TIP_FREQUENCY_REL, f"{f} Hz against {expected} Hz"


def test_damping_ratio_of_a_damped_pendulum(cpu_bin, tmp_path):
    beta = 0.5
    _, x, _ = pendulum(cpu_bin, tmp_path, 256, "--damping", beta)
    zeta = ob.damping_ratio(ob.tip_displacement(x, axis=2), DT)
    expected = beta / (2 * 2 * math.pi / an.pendulum_period(LENGTH, G0, THETA0))
    assert abs(zeta / expected - 1) <= tol.OBS_DAMPING_RATIO_REL, f"ζ = {zeta} against {expected}"


def test_energy_of_an_undamped_pendulum_within_its_drift(cpu_bin, tmp_path):
    """The swing's energy g·ℓ·(1 − cos θ0) is what the scheme may lose: at S = 64 it loses at
    most OBS_PENDULUM_ENERGY_LOSS_S64 of it over 6.7 s, and 4× the substeps lose about 4× less
    (first order); it never gains energy."""
    swing = G0 * LENGTH * (1 - math.cos(THETA0))
    loss = {}
    for S in (16, 64):
        t, x, v = pendulum(cpu_bin, tmp_path, S)
        _, _, e = ob.energy(x, v, G0)
        e0 = -G0 * LENGTH * math.cos(THETA0)  # at release: at rest, at height −ℓ cos θ0
        assert e.max() <= e0 + 1e-9 * swing, f"S = {S}: energy above the release's"
        loss[S] = (e0 - e[-1]) / swing
    assert 0 < loss[64] <= tol.OBS_PENDULUM_ENERGY_LOSS_S64, loss
    assert tol.OBS_FIRST_ORDER_RATIO[0] <= loss[16] / loss[64] <= tol.OBS_FIRST_ORDER_RATIO[1], loss


@pytest.mark.parametrize("solver", ["xpbd", "ftl", "rigid"])
def test_zero_jitter_for_a_strand_resting_on_nothing(cpu_bin, tmp_path, solver):
    """No gravity, no collider, still head: nothing acts, so no point moves (rigid: not a bit;
    the solvers: by the rounding of segments that init made ℓ to within an ulp or so)."""
    out = tmp_path / "rest.h5"
    run(
        cpu_bin,
        "--stages",
        "init,collide,simulate",
        "--strands",
        "8",
        "--points",
        "8",
        "--frames",
        "30",
        "--gravity",
        "0",
        "--no-collider",
        "--solver",
        solver,
        "--substeps",
        "4",
        "--precision",
        "fp64",
        "--output",
        out,
        "--quiet",
    )
    with open_trajectory(out) as t:
        x = np.stack([t.frame(f) for f in t.simulated]).astype(np.float64)
    rms_v, most = ob.jitter(x, DT)
    if solver == "rigid":
        assert (rms_v, most) == (0.0, 0.0)
    assert most <= tol.OBS_REST_MOVE_ABS_L * LENGTH and rms_v * DT <= tol.OBS_REST_MOVE_ABS_L * LENGTH, (rms_v, most)


def test_energy_from_positions_of_a_still_ftl_chain_is_zero(cpu_bin, tmp_path):
    """A chain hanging straight down under gravity, ftl, collider off: its positions stay put (to
    rounding), so the kinetic energy of its motion, from positions, is zero, while the velocities
    ftl stores (its correction −s·d/h, docs/model.md §3.7) read g·h·Σ s^j along the chain."""
    from harness.studies.analytic_runs_dynamic import straight_chain_positions

    inp = write_paper_state(tmp_path / "in.h5", straight_chain_positions(32, LENGTH, 0.0), LENGTH)
    out = simulate(cpu_bin, inp, tmp_path / "still.h5", 60, 8, "ftl", extra=["--velocities", "all"])
    _, x, v = read(out)
    stored, _, _ = ob.energy(x, v, G0)
    moved = ob.kinetic_from_positions(x, DT)
    h, s, P = DT / 8, 0.9, 32
    carried = [G0 * h * sum(s**j for j in range(1, P - k)) for k in range(1, P)]  # docs/analytic.md
    assert stored[-1] == pytest.approx(0.5 * np.mean(np.square(carried)), rel=1e-9)
    assert moved.max() <= (tol.OBS_REST_MOVE_ABS_L * LENGTH / DT) ** 2, moved.max()


@pytest.mark.parametrize("motion,axis", [("nod", 0), ("shake", 1), ("tilt", 2)])
def test_rigid_solver_is_the_rest_shape_rotated_by_the_head(cpu_bin, tmp_path, motion, axis):
    amp, freq = 0.4, 1.5
    out = tmp_path / "rigid.h5"
    run(
        cpu_bin,
        "--stages",
        "init,collide,simulate",
        "--strands",
        "16",
        "--points",
        "8",
        "--frames",
        "12",
        "--solver",
        "rigid",
        "--substeps",
        "3",
        "--head-motion",
        motion,
        "--motion-amplitude",
        amp,
        "--motion-frequency",
        freq,
        "--precision",
        "fp64",
        "--velocities",
        "all",
        "--output",
        out,
        "--quiet",
    )
    with open_trajectory(out) as t:
        rest = t.rest.astype(np.float64)
        for f in t.simulated:
            time = float(t.time[f])
            th = amp * math.sin(2 * math.pi * freq * time)
            c, s = math.cos(th), math.sin(th)
            i, j = [k for k in range(3) if k != axis]
            q = np.eye(3)
            q[i, i], q[j, j] = c, c
            # nod and tilt turn i toward j; shake (axis y) turns z toward x
            q[j, i], q[i, j] = (s, -s) if motion != "shake" else (-s, s)
            want = rest @ q.T
            got = t.frame(f).astype(np.float64)
            assert np.max(np.abs(got - want)) <= tol.OBS_RIGID_ROTATION_ABS_L * LENGTH, f"frame {f}"
            # every point moves with the head: the velocity is the last substep's displacement over h
            th0 = amp * math.sin(2 * math.pi * freq * (time - DT / 3))
            c0, s0 = math.cos(th0), math.sin(th0)
            q0 = np.eye(3)
            q0[i, i], q0[j, j] = c0, c0
            q0[j, i], q0[i, j] = (s0, -s0) if motion != "shake" else (-s0, s0)
            v = t.velocity_at_step(t.step[f]).astype(np.float64)
            np.testing.assert_allclose(v[:, 1:], ((rest @ q.T) - (rest @ q0.T))[:, 1:] / (DT / 3), atol=1e-6)


def test_gpu_and_simd_refuse_rigid_with_one_line(cpu_bin, tmp_path):
    p = run(
        cpu_bin,
        "--stages",
        "init,collide,simulate",
        "--strands",
        "2",
        "--frames",
        "1",
        "--solver",
        "rigid",
        "--variant",
        "simd",
        "--quiet",
        check=False,
    )
    assert p.returncode == 2
    assert p.stderr.strip().count("\n") == 0 and "does not run it" in p.stderr


def test_swing_frequency_of_a_hanging_chain(cpu_bin, tmp_path):
    """A chain of 32 points displaced along its first mode swings at the linearised discrete
    chain's ω1 (docs/model.md §4.3)."""
    from harness.studies.analytic_runs_dynamic import chain_positions

    inp = write_paper_state(tmp_path / "chain.h5", chain_positions(32, LENGTH, 0.3), LENGTH)
    out = simulate(cpu_bin, inp, tmp_path / "chain_out.h5", 300, 256, "xpbd", extra=["--velocities", "all"])
    _, x, _ = read(out)
    f, _, _ = ob.swing(x, DT)
    expected = an.discrete_chain_omega1(32, LENGTH, G0) / (2 * math.pi)
    assert abs(f / expected - 1) <= tol.OBS_CHAIN_SWING_FREQUENCY_REL, f"{f} Hz against {expected} Hz"
