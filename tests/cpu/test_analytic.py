"""Analytic checks of the dynamic model (docs/model.md §4) on the C reference, fp64.

Hand-made input states (harness/studies/analytic_runs_dynamic.py) run through
`hairsim-cpu --input IN --stages simulate --no-collider …`; the closed forms and the
measurements are in harness/studies/analytic_dynamic.py, the tolerances (with the measurements behind
them) in harness/core/tolerances.py (ANALYTIC_*). Only 2–3 substep counts S per check run here;
the full sweeps are in docs/analytic.md (`python -m harness analytic`).
"""

import math

import numpy as np
import pytest

from harness.check import observables_dynamic as ob
from harness.cli import main as cli
from harness.core import tolerances as tol
from harness.io import files
from harness.render import analytic_dynamic_report as analytic_report
from harness.studies import analytic_dynamic as an
from harness.studies import analytic_table_dynamic as analytic_table
from harness.studies.accuracy import ANALYTIC_MD, ANALYTIC_NAME
from harness.studies.accuracy_results_dynamic import load_analytic
from harness.studies.analytic_runs_dynamic import G0, run_chain, run_pendulum, run_wind

SOLVERS = ("xpbd", "ftl")


def assert_converges(s_values, errors, final_tol, what):
    """The error at the largest S is below `final_tol`, and never grows by more than the
    stated slack from one S to the next."""
    table = ", ".join(f"S={s}: {e:.3e}" for s, e in zip(s_values, errors))
    assert np.all(np.isfinite(errors)), f"{what}: no measurement ({table})"
    for a, b in zip(errors, errors[1:]):
        assert b <= (1.0 + tol.ANALYTIC_TREND_SLACK) * a, f"{what}: error grows with S ({table})"
    assert errors[-1] <= final_tol, f"{what}: error {errors[-1]:.3e} > {final_tol:.1e} at S={s_values[-1]} ({table})"


# ---------------------------------------------------------------- closed forms (no binary)


def test_elliptic_k_and_pendulum_period_closed_forms():
    assert an.ellipk(0.0) == pytest.approx(math.pi / 2, rel=1e-15)
    assert an.ellipk(0.5) == pytest.approx(1.854074677301372, rel=1e-14)  # DLMF §19.2
    assert an.ellipk(0.99) == pytest.approx(3.695637362989875, rel=1e-14)
    t0 = an.pendulum_period_small(30.0, G0)
    for theta in (1e-4, 0.1, 0.3):  # T ≈ T0·(1 + θ²/16 + 11θ⁴/3072), next term O(θ⁶)
        series = t0 * (1 + theta**2 / 16 + 11 * theta**4 / 3072)
        assert an.pendulum_period(30.0, G0, theta) == pytest.approx(series, rel=2e-3 * theta**6 + 1e-15)


def test_bessel_and_chain_closed_forms():
    assert abs(an.j0(an.J01)) < 1e-15
    assert an.j0(1.0) == pytest.approx(0.7651976865579666, rel=1e-15)
    assert abs(an.j0(5.520078110286311)) < 1e-14  # j0,2 (DLMF §10.21)
    # one mass on one link is the pendulum; the discrete chain tends to the continuum ≈ 0.25/P
    assert an.discrete_chain_omega1(2, 30.0, G0) == pytest.approx(math.sqrt(G0 / 30.0), rel=1e-14)
    w = an.chain_omega1(30.0, G0)
    gaps = [1 - an.discrete_chain_omega1(p, 30.0, G0) / w for p in (32, 64, 128)]
    assert 0 < gaps[2] < gaps[1] < gaps[0] < 0.01
    assert gaps[0] / gaps[2] == pytest.approx(4.0, rel=0.02)


def test_crossings_and_frequency_on_a_known_signal():
    t = np.arange(0, 5.0, 1 / 60)
    w = 6.8
    y = np.cos(w * t + 0.3) * np.exp(-0.1 * t)
    assert 2 * math.pi / an.period_from_crossings(t, y) == pytest.approx(w, rel=1e-5)
    assert 2 * math.pi * ob.dominant_frequency(y, t[1] - t[0]) == pytest.approx(w, rel=1e-3)


# ---------------------------------------------------------------- §4.1 pendulum

PENDULUM_S = (2, 8, 32)


@pytest.mark.parametrize("solver", SOLVERS)
@pytest.mark.parametrize(
    "theta0, final_tol", [(0.1, tol.ANALYTIC_PENDULUM_SMALL_REL), (2.0, tol.ANALYTIC_PENDULUM_LARGE_REL)]
)
def test_pendulum_period_converges_in_substeps(cpu_bin, tmp_path, solver, theta0, final_tol):
    runs = [run_pendulum(cpu_bin, tmp_path, solver, s, theta0) for s in PENDULUM_S]
    errors = [an.relative_error(r["measured"], r["expected"]) for r in runs]
    assert_converges(PENDULUM_S, errors, final_tol, f"pendulum θ0={theta0} {solver}")
    # position-based steps lose energy: the amplitude decays, less with more substeps
    amps = [r["amplitude_end"] for r in runs]
    assert all(a < theta0 for a in amps) and amps == sorted(amps)


def test_pendulum_ftl_is_xpbd_at_two_points(cpu_bin, tmp_path):
    for theta0 in (0.1, 2.0):
        a = run_pendulum(cpu_bin, tmp_path, "xpbd", 8, theta0)["measured"]
        b = run_pendulum(cpu_bin, tmp_path, "ftl", 8, theta0)["measured"]
        assert abs(a - b) / a <= tol.ANALYTIC_FTL_XPBD_P2_REL


# ---------------------------------------------------------------- §4.2 wind


@pytest.mark.parametrize("solver", SOLVERS)
@pytest.mark.parametrize("substeps", (1, 8))
def test_steady_wind_angle(cpu_bin, tmp_path, solver, substeps):
    # horizontal wind toward +z at three speeds; toward −z (ψ = π); and tilted up (ψ = 0.5),
    # where the net acceleration (0, −g0 + c_d·U·sin ψ, c_d·U·cos ψ) sets the angle
    for speed, psi in ((250.0, 0.0), (981.0, 0.0), (3000.0, 0.0), (981.0, math.pi), (981.0, 0.5)):
        r = run_wind(cpu_bin, tmp_path, solver, substeps, speed, wind_angle=psi)
        assert abs(r["measured"] - r["expected"]) <= tol.ANALYTIC_WIND_ANGLE_ABS, (
            f"U={speed}, ψ={psi}: θ={r['measured']!r}, expected {r['expected']!r}"
        )
        assert r["change_last_second"] <= tol.ANALYTIC_WIND_ANGLE_ABS


# ---------------------------------------------------------------- §4.3 hanging chain

CHAIN_S = (64, 256)


@pytest.mark.parametrize("points", (32, 64))
@pytest.mark.parametrize("solver, ftl_damping", [("xpbd", None), ("ftl", 1.0)])
def test_hanging_chain_first_mode_converges_in_substeps(cpu_bin, tmp_path, points, solver, ftl_damping):
    runs = [run_chain(cpu_bin, tmp_path, solver, s, points, ftl_damping=ftl_damping) for s in CHAIN_S]
    errors = [an.relative_error(r["measured"], r["expected"]) for r in runs]
    assert_converges(CHAIN_S, errors, tol.ANALYTIC_CHAIN_REL, f"chain P={points} {solver}")
    # against the continuum: the discretisation gap into P−1 links plus the solver's error
    r = runs[-1]
    gap = an.relative_error(r["expected"], r["continuum"])
    assert an.relative_error(r["measured"], r["continuum"]) <= gap + tol.ANALYTIC_CHAIN_REL


# ---------------------------------------------------------------- fp32


@pytest.mark.parametrize("solver", SOLVERS)
def test_fp32_holds_the_analytic_answers_at_moderate_substeps(cpu_bin, tmp_path, solver):
    """fp32 stops converging once h²·|a| nears the ulp of a coordinate (docs/analytic.md);
    at S = 8 it still matches the closed forms."""
    r = run_pendulum(cpu_bin, tmp_path, solver, 8, 0.1, precision="fp32")
    assert an.relative_error(r["measured"], r["expected"]) <= tol.ANALYTIC_FP32_PENDULUM_REL
    for substeps in (1, 8):
        for speed, psi in ((250.0, 0.0), (981.0, 0.0), (3000.0, 0.0), (981.0, math.pi), (981.0, 0.5)):
            r = run_wind(cpu_bin, tmp_path, solver, substeps, speed, wind_angle=psi, precision="fp32")
            assert abs(r["measured"] - r["expected"]) <= tol.ANALYTIC_FP32_WIND_ANGLE_ABS, (
                f"fp32 S={substeps} U={speed} ψ={psi}: θ={r['measured']!r}, expected {r['expected']!r}"
            )


# ---------------------------------------------------------------- the sweeps' tables


def test_the_sweeps_print_as_tables_and_keep_as_json(cpu_bin, tmp_path, capsys, monkeypatch):
    """`harness analytic` prints render/analytic_dynamic_report.py's tables of
    studies/analytic_table_dynamic.measure's data, a row for each measurement; the accuracy study
    keeps that data as analytic.json and its page renders the same tables from it; a study from
    before #47 kept analytic.md, read as it is, and analytic.json wins where both are."""
    measured = []

    def recording(*args, **kwargs):
        measured.append(real(*args, **kwargs))
        return measured[-1]

    real = analytic_table.measure
    monkeypatch.setattr(analytic_table, "measure", recording)
    assert cli.main(["analytic", "--quick", "--binary", str(cpu_bin)]) == 0
    (sweeps,) = measured
    lines = analytic_report.lines(sweeps)
    assert capsys.readouterr().out == "\n".join(lines) + "\n"
    assert len([ln for ln in lines if ln.startswith("### ")]) == 6  # two pendulums, wind, two chains, fp32
    heads = ("| solver |", "| check |", "| --- |")
    rows = [ln for ln in lines if ln.startswith("| ") and not ln.startswith(heads)]
    cases = sweeps["pendulum"] + sweeps["chain"]
    assert len(rows) == sum(len(c["rows"]) for c in cases) + len(sweeps["wind"]) + len(sweeps["fp32"]) > 0
    files.write_json(tmp_path / ANALYTIC_NAME, sweeps)
    assert analytic_report.lines(load_analytic(tmp_path)) == lines
    (tmp_path / ANALYTIC_MD).write_text("### old tables\n")
    assert analytic_report.lines(load_analytic(tmp_path)) == lines
    (tmp_path / ANALYTIC_NAME).unlink()
    assert load_analytic(tmp_path) == ["### old tables"]
    assert load_analytic(tmp_path / "nothing") is None
