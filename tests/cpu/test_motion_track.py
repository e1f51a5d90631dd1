"""Recorded head motion (`--head-motion track --motion-track FILE`; docs/model.md §3.2,
docs/interfaces.md "Motion tracks") on the C reference: a constant track is `still` bit for
bit, a finely sampled sinusoid is `nod` within the interpolation bound (and the error shrinks as
the bound says), the track is stored so that a resumed run is bit for bit, and bad tracks are
refused in one line. Files are read through the harness (trajectory, diff)."""

import math

import numpy as np
import pytest

from harness.check import diff_dynamic
from harness.core import tolerances
from harness.io import motion_tracks
from harness.io.trajectory import open_trajectory
from support.statecheck import run

SIM = ["--stages", "init,collide,simulate", "--strands", "40", "--points", "16"]
# every feature but motion's own flags, so that the track drives roots and shape targets
FULL = ["--substeps", "4", "--iterations", "2", "--bend-compliance", "1e-6", "--shape-compliance", "1e-4"]
FULL += ["--wind-speed", "150", "--drag", "0.5", "--damping", "0.5", "--gust-amplitude", "0.5"]
A, F = 0.25, 1.0  # nod's default amplitude (rad) and frequency (Hz)


def nod_track(path, delta, seconds=0.6):
    t = np.arange(0, int(round(seconds / delta)) + 1) * delta
    return motion_tracks.write_csv(path, motion_tracks.about_axis(t, A * np.sin(2 * math.pi * F * t), (1, 0, 0)))


def positions(path):
    with open_trajectory(path) as t:
        return np.array([t.frame(f) for f in range(t.n_frames)])


def test_a_constant_track_is_still_bit_for_bit(cpu_bin, tmp_path):
    track = motion_tracks.about_axis([0.0, 0.1, 0.5], [0.0, 0.0, 0.0], (0, 1, 0))
    motion_tracks.write_csv(tmp_path / "c.csv", track)
    still, moved = tmp_path / "still.h5", tmp_path / "track.h5"
    run(cpu_bin, *SIM, *FULL, "--frames", "12", "--output", still, "--quiet")
    run(cpu_bin, *SIM, *FULL, "--frames", "12", "--head-motion", "track", "--motion-track", tmp_path / "c.csv",
        "--output", moved, "--quiet")  # fmt: skip
    assert np.array_equal(positions(still), positions(moved))
    with open_trajectory(moved) as t:
        assert "motion" in t.features and t.head_motion == "track"  # the track ran: the identity, applied


@pytest.mark.parametrize("solver", ["rigid", "xpbd"])
def test_a_finely_sampled_sinusoid_is_nod_within_the_interpolation_bound(cpu_bin, tmp_path, solver):
    """rigid carries every point with the head, so every point's error is bounded; xpbd's roots
    are kinematic, so theirs are. The bound is tolerances.track_sampling_bound (docs/model.md §3.2);
    doubling δ must multiply the error by about 4 (a nearest-sample track would be first order)."""
    nod = tmp_path / "nod.h5"
    flags = [*SIM, "--frames", "30", "--solver", solver, "--precision", "fp64", *FULL]
    run(cpu_bin, *flags, "--head-motion", "nod", "--output", nod, "--quiet")
    errors = {}
    for delta in (1e-3, 2e-3):
        csv, out = nod_track(tmp_path / f"nod{delta}.csv", delta), tmp_path / f"t{delta}.h5"
        run(cpu_bin, *flags, "--head-motion", "track", "--motion-track", csv, "--output", out, "--quiet")
        a, b = positions(nod), positions(out)
        with open_trajectory(nod) as t:
            r = np.linalg.norm(t.rest, axis=-1).reshape(-1, 16)
        pts = slice(None) if solver == "rigid" else slice(0, 1)
        gap = np.linalg.norm(a - b, axis=-1).reshape(len(a), -1, 16)[:, :, pts]
        bound = tolerances.track_sampling_bound(delta, A, F, r[:, pts], "fp64")
        assert np.all(gap <= bound), f"{solver}, δ = {delta}: {gap.max():.3g} over the bound"
        errors[delta] = gap.max()
    assert 3.0 <= errors[2e-3] / errors[1e-3] <= 5.0, errors


def test_a_track_run_resumes_bit_for_bit_and_stores_its_samples(cpu_bin, tmp_path):
    csv = motion_tracks.write_csv(tmp_path / "turn.csv", motion_tracks.fast_turn())
    whole, first, second = tmp_path / "whole.h5", tmp_path / "a.h5", tmp_path / "b.h5"
    flags = [*SIM, *FULL, "--head-motion", "track", "--motion-track", csv, "--velocities", "all"]
    run(cpu_bin, *flags, "--frames", "20", "--output", whole, "--quiet")
    run(cpu_bin, *flags, "--frames", "9", "--output", first, "--quiet")
    run(cpu_bin, "--input", first, "--stages", "simulate", "--frames", "11", "--output", second, "--quiet")
    assert diff_dynamic.compare(whole, second, exact=True).equivalent
    with open_trajectory(second) as t:
        stored = t.motion_track
    want = motion_tracks.read_csv(csv)
    assert np.array_equal(stored[:, 0], want.times) and np.allclose(stored[:, 1:5], want.quats, rtol=0, atol=1e-15)
    # the same file again is accepted; another track is refused
    again = run(cpu_bin, "--input", first, "--stages", "simulate", "--head-motion", "track", "--motion-track", csv)
    assert again.returncode == 0
    other = nod_track(tmp_path / "other.csv", 1e-2)
    p = run(cpu_bin, "--input", first, "--stages", "simulate", "--head-motion", "track", "--motion-track", other,
            check=False)  # fmt: skip
    assert p.returncode == 2 and "does not match the input file's track" in p.stderr


def test_axis_angle_rows_are_the_same_rotations(cpu_bin, tmp_path):
    quat, axis = tmp_path / "q.csv", tmp_path / "a.csv"
    t = np.linspace(0, 0.5, 11)
    th = 0.8 * np.sin(2 * math.pi * t)
    motion_tracks.write_csv(quat, motion_tracks.about_axis(t, th, (0, 0, 1)))
    rows = "".join(f"{float(a)!r},0,0,2.5,{float(b)!r},0,0,0\n" for a, b in zip(t, th))
    axis.write_text(motion_tracks.AXIS_HEADER + "\n" + rows)
    outs = []
    for name, csv in (("q", quat), ("a", axis)):
        outs.append(tmp_path / f"{name}.h5")
        run(cpu_bin, *SIM, *FULL, "--frames", "20", "--precision", "fp64", "--head-motion", "track",
            "--motion-track", csv, "--output", outs[-1], "--quiet")  # fmt: skip
    assert np.max(np.abs(positions(outs[0]) - positions(outs[1]))) < 1e-11


BAD = [
    ("time,qw,qx,qy,qz,tx,ty,tz\n0,1,0,0,0,0,0,0\n0.1,1,0,0,0,0,2,0\n", "head translation is not modelled yet"),
    ("time,qw,qx,qy,qz\n0,1,0,0,0\n", "the header must be"),
    ("time,qw,qx,qy,qz,tx,ty,tz\n0,1,0,0,0,0,0,0\n0,1,0,0,0,0,0,0\n", "times must increase"),
    ("time,qw,qx,qy,qz,tx,ty,tz\n0,0,0,0,0,0,0,0\n", "the quaternion is zero"),
    ("time,qw,qx,qy,qz,tx,ty,tz\n0,1,0,nan,0,0,0,0\n", "not a finite decimal number"),
    ("time,qw,qx,qy,qz,tx,ty,tz\n0,1,0,0,0,0,0\n", "7 fields"),
    ("time,qw,qx,qy,qz,tx,ty,tz\n", "no samples"),
]


@pytest.mark.parametrize("text,message", BAD)
def test_a_bad_track_is_refused_in_one_line(cpu_bin, tmp_path, text, message):
    csv = tmp_path / "bad.csv"
    csv.write_text(text)
    out = tmp_path / "out.h5"
    p = run(cpu_bin, *SIM, "--frames", "2", "--head-motion", "track", "--motion-track", csv, "--output", out,
            check=False)  # fmt: skip
    assert p.returncode == 2 and message in p.stderr and len(p.stderr.strip().splitlines()) == 1
    assert not out.exists()


@pytest.mark.parametrize(
    "flags,message",
    [
        (["--head-motion", "track"], "--head-motion track needs --motion-track FILE"),
        (["--motion-track", "x.csv"], "--motion-track needs --head-motion track"),
        (["--head-motion", "track", "--motion-track", "x.csv", "--motion-frequency", "2"], "not --head-motion track"),
    ],
)
def test_track_flags_go_together(cpu_bin, flags, message):
    p = run(cpu_bin, *SIM, "--frames", "2", *flags, check=False)
    assert p.returncode == 2 and message in p.stderr
    p = run(cpu_bin, "--strands", "10", "--motion-track", "x.csv", check=False)
    assert p.returncode == 2 and "belongs to the simulate stage" in p.stderr
