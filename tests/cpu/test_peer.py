"""Beside a peer (harness/studies/peer_dynamic.py, harness/studies/peer_pypbd_dynamic.py): the parameter mapping onto
Bender's PositionBasedDynamics (pypbd) checked on cases with a known answer, the `peer`
command end to end at a tiny size, and its refusals. pypbd is optional: the tests that run
it are skipped, with the reason, where it is not installed; the skip path itself is tested
everywhere by hiding the module."""

import sys

import numpy as np
import pytest

from harness.cli.main import main as harness_main
from harness.core import tolerances as tol
from harness.io import tables
from harness.studies import analytic_dynamic as an
from harness.studies import analytic_runs_dynamic as ar
from harness.studies import peer_dynamic as peer
from harness.studies import peer_pypbd_dynamic as peer_pypbd

PYPBD_REASON = peer_pypbd.unavailable()
needs_pypbd = pytest.mark.skipif(PYPBD_REASON is not None, reason=f"peer tests skipped: {PYPBD_REASON}")
L = 30.0


def _ours(cpu_bin, tmp_path, pos, frames, substeps, iterations=1, compliance=0.0, tag="c"):
    inp = ar.write_paper_state(tmp_path / f"{tag}_in.h5", pos, L)
    out = ar.simulate(
        cpu_bin,
        inp,
        tmp_path / f"{tag}.h5",
        frames,
        substeps,
        "xpbd",
        iterations=iterations,
        extra=("--stretch-compliance", repr(compliance)),
    )
    return an.read_series(out)[1]


def _gap(a, b):
    return float(np.max(np.linalg.norm(a - b, axis=-1))) / L


@needs_pypbd
def test_pendulum_period_peer_against_closed_form_and_ours(cpu_bin, tmp_path):
    """§4.1 at θ0 = 0.1, S = 32: gravity (981 cm/s² ↔ pypbd's 9.81 m/s² through the length
    unit), Δt and substeps mapped right give the closed-form period, and ours to rounding."""
    theta0, substeps = 0.1, 32
    ours = ar.run_pendulum(cpu_bin, tmp_path, "xpbd", substeps, theta0)
    x, _ = peer_pypbd.run(ar.pendulum_positions(L, theta0), L, ours["frames"], substeps=substeps, iterations=1)
    t = np.arange(ours["frames"] + 1) * ar.FRAME_DT
    period = an.period_from_crossings(t, x[:, 0, 1, 2], periods=3)
    assert an.relative_error(period, ours["expected"]) <= tol.ANALYTIC_PENDULUM_SMALL_REL
    assert abs(period - ours["measured"]) / ours["expected"] <= tol.PEER_PERIOD_REL


@needs_pypbd
def test_both_hold_a_rigid_chain_at_many_substeps_and_agree(cpu_bin, tmp_path):
    """A rigid 32-point chain tilted 60° and 90°, released from rest, 30 frames of S = 256:
    both stretch less than the measured bound, and the trajectories are one scheme's."""
    frames, substeps = 30, 256
    pos = peer.chain_positions(2, 32, L, (60.0, 90.0))
    theirs, ms = peer_pypbd.run(pos, L, frames, substeps=substeps, iterations=1)
    ours = _ours(cpu_bin, tmp_path, pos, frames, substeps)
    assert ms.shape == (frames,) and np.all(ms > 0)
    for x in (theirs, ours):
        stretch, blown = peer._observed(x, L)
        assert blown == 0 and stretch <= tol.PEER_RIGID_STRETCH_S256
    assert _gap(theirs, ours) <= tol.PEER_SAME_SCHEME_PER_SUBSTEP * substeps * frames


@needs_pypbd
def test_compliance_maps_to_inverse_stiffness(cpu_bin, tmp_path):
    """Soft links (α = 1e-6, S = 8, I = 2): stiffness 1/α reproduces ours to rounding, and the
    rule tells a wrong mapping (stiffness 2/α) from that by orders of magnitude."""
    frames, substeps, alpha = 30, 8, 1e-6
    pos = peer.chain_positions(2, 32, L, (30.0, 60.0))
    ours = _ours(cpu_bin, tmp_path, pos, frames, substeps, iterations=2, compliance=alpha)
    bound = tol.PEER_SAME_SCHEME_PER_SUBSTEP * substeps * frames
    right = peer_pypbd.run(pos, L, frames, substeps=substeps, iterations=2, compliance=alpha)[0]
    wrong = peer_pypbd.run(pos, L, frames, substeps=substeps, iterations=2, compliance=alpha / 2)[0]
    assert _gap(right, ours) <= bound
    assert _gap(wrong, ours) > 1e6 * bound
    assert np.max(np.abs(right[-1] - right[0])) > 1.0  # the chains did swing (cm)


@needs_pypbd
def test_peer_command_end_to_end_tiny(tmp_path, capsys):
    out, rep = tmp_path / "peer", tmp_path / "report"
    argv = ["peer", "--points", "8", "--tilts", "45", "--frames", "4", "--settings", "4x1", "2x2"]
    argv += ["--strands", "1", "3", "--time-frames", "1", "--repeat", "1", "--ref-start", "8", "--ref-max", "256"]
    assert harness_main([*argv, "--out", str(out), "--report-dir", str(rep)]) == 0
    acc = tables.read_csv(out / "accuracy.csv")
    tim = tables.read_csv(out / "timing.csv")
    assert sorted(acc["solver"].unique()) == ["hairsim-cpu", "pypbd"] and len(acc) == 2 * 3
    assert set(tim["strands"]) == {1, 3} and (tim["median_ms"] > 0).all()
    mine = acc[acc["solver"] == "pypbd"]
    assert (mine["vs_ours_fp64"] <= tol.PEER_SAME_SCHEME_PER_SUBSTEP * mine["substeps"] * 4).all()
    md = (rep / "peer.md").read_text()
    assert "### Where the peer wins" in md and (rep / "peer_time.png").exists()


def test_peer_skipped_with_reason_without_pypbd(tmp_path, monkeypatch, capsys):
    """Where pypbd cannot be imported: one line says why, exit 0, no results written."""
    monkeypatch.setitem(sys.modules, "pypbd", None)  # import pypbd now raises ImportError
    reason = peer_pypbd.unavailable()
    assert reason and "pypbd" in reason
    with pytest.raises(peer_pypbd.HarnessError, match="pypbd"):
        peer_pypbd.load()
    out = tmp_path / "peer"
    assert harness_main(["peer", "--out", str(out), "--report-dir", str(tmp_path)]) == 0
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("harness: peer: skipped: pypbd is not installed")
    assert not out.exists() and not (tmp_path / "peer.md").exists()
    from harness.render import peer_dynamic_report as peer_report

    note = peer_report.section(out, tmp_path, missing_ok=True)
    assert any(line.startswith("Not measured here: pypbd is not installed") for line in note)


@pytest.mark.parametrize(
    "args,words",
    [
        (["--gravity", "0"], "--gravity must be > 0"),
        (["--compliance", "-1"], "--compliance must be a finite number"),
        (["--tilts", "200"], "--tilts are degrees"),
        (["--settings", "0x1"], "S and I must be at least 1"),
        (["--settings", "8"], "needs SxI"),
        (["--ref-start", "64", "--ref-max", "100"], "--ref-max"),
        (["--length", "nan"], "needs a finite number"),
    ],
)
def test_peer_refuses_bad_input_in_one_line(tmp_path, capsys, args, words):
    out = tmp_path / "peer"
    try:
        code = harness_main(["peer", *args, "--out", str(out), "--report-dir", str(tmp_path)])
    except SystemExit as e:  # argparse's refusals
        code = e.code
    assert code == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("harness: error: ") and words in err[0], err
    assert not out.exists()


def test_report_only_without_results_is_one_line(tmp_path, capsys):
    assert harness_main(["peer", "--report-only", "--out", str(tmp_path / "none"), "--report-dir", str(tmp_path)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "missing" in err[0] and "python -m harness peer" in err[0]


def test_chain_positions_have_links_of_length_l_and_the_tilts_asked():
    pos = peer.chain_positions(4, 9, L, (30.0, 90.0))
    links = np.linalg.norm(np.diff(pos, axis=1), axis=-1)
    np.testing.assert_allclose(links, L / 8, rtol=1e-14)
    tip = pos[:, -1] - pos[:, 0]
    angles = np.degrees(np.arccos(-tip[:, 1] / np.linalg.norm(tip, axis=-1)))
    np.testing.assert_allclose(angles, [30.0, 90.0, 30.0, 90.0], atol=1e-12)
    assert not np.allclose(pos[0], pos[2])  # turned about +y
    assert peer._observed(pos[None].repeat(2, axis=0), L) == (pytest.approx(0.0, abs=1e-14), 0)
