"""harness.io.motion_tracks: the CSV tracks the binaries read (docs/interfaces.md, "Motion
tracks"), the shipped fast head turn, a scene's track keys, and a USD xform's time samples
converted (usd-core optional: those tests skip without it)."""

import math

import numpy as np
import pytest

from harness import HarnessError
from harness.cli.main import main as harness_main
from harness.core import scenes
from harness.core.paths import MOTIONS
from harness.io import motion_tracks


def test_the_shipped_fast_turn_is_what_its_generator_writes(tmp_path):
    again = motion_tracks.write_csv(tmp_path / "t.csv", motion_tracks.fast_turn(), motion_tracks.fast_turn_comment())
    assert (MOTIONS / motion_tracks.FAST_TURN_FILE).read_text() == again.read_text()


def test_the_fast_turn_peaks_at_the_measured_head_speed_and_ends_at_rest():
    k = motion_tracks.fast_turn()
    angle = 2 * np.arctan2(k.quats[:, 2], k.quats[:, 0])  # about y
    speed = np.abs(np.diff(angle) / np.diff(k.times))
    assert math.degrees(speed.max()) == pytest.approx(780.0, rel=0.01)
    assert math.degrees(angle.max()) == pytest.approx(80.0, abs=1e-9)
    assert angle[0] == 0.0 and abs(angle[-1]) < 1e-12 and not k.trans.any()


def test_a_track_reads_back_as_written(tmp_path):
    t = np.array([0.0, 0.25, 1.0])
    k = motion_tracks.about_axis(t, [0.0, 0.5, -1.0], (1.0, 2.0, 2.0))
    back = motion_tracks.read_csv(motion_tracks.write_csv(tmp_path / "k.csv", k))
    assert np.array_equal(back.times, t)
    assert np.allclose(back.quats, k.quats, rtol=0, atol=4e-16)  # normalised again on reading
    with pytest.raises(HarnessError, match="exists"):
        motion_tracks.write_csv(tmp_path / "k.csv", k)
    with pytest.raises(HarnessError, match="increasing"):
        motion_tracks.write_csv(tmp_path / "bad.csv", motion_tracks.about_axis([0.0, 0.0], [0, 0], (1, 0, 0)))


def scene_file(tmp_path, head):
    path = tmp_path / "s.toml"
    path.write_text(f'model = "dynamic"\n[head]\n{head}\n')
    return path


def test_a_scene_names_its_track_relative_to_itself(tmp_path):
    motion_tracks.write_csv(tmp_path / "turn.csv", motion_tracks.fast_turn())
    s = scenes.load_scene(str(scene_file(tmp_path, 'motion = "track"\nmotion_track = "turn.csv"')))
    flags = s.flags()
    assert flags[flags.index("--motion-track") + 1] == str(tmp_path / "turn.csv")
    assert flags[flags.index("--head-motion") + 1] == "track"


@pytest.mark.parametrize(
    "head,message",
    [
        ('motion = "track"', "go together"),
        ('motion = "nod"\nmotion_track = "turn.csv"', "go together"),
        ('motion = "track"\nmotion_track = "none.csv"', "no such file"),
        ('motion = "track"\nmotion_track = "turn.usda"', "convert it first"),
        ('motion = "track"\nmotion_track = "turn.csv"\nmotion_frequency = 2.0', 'not "track"'),
    ],
)
def test_a_bad_track_in_a_scene_is_refused_naming_the_key(tmp_path, head, message):
    motion_tracks.write_csv(tmp_path / "turn.csv", motion_tracks.fast_turn())
    with pytest.raises(scenes.SceneError, match=message):
        scenes.load_scene(str(scene_file(tmp_path, head)))


# ---- USD ------------------------------------------------------------------------------------


def pxr():
    pytest.importorskip("pxr", reason="usd-core is optional (requirements-readers.lock)")
    from pxr import Usd, UsdGeom

    return Usd, UsdGeom


def usd_stage(path, up="Y", meters=0.01):
    Usd, UsdGeom = pxr()
    stage = Usd.Stage.CreateNew(str(path))
    UsdGeom.SetStageUpAxis(stage, UsdGeom.Tokens.y if up == "Y" else UsdGeom.Tokens.z)
    UsdGeom.SetStageMetersPerUnit(stage, meters)
    stage.SetTimeCodesPerSecond(24)
    head = UsdGeom.Xform.Define(stage, "/char/head")
    head.AddTranslateOp().Set((1.0, 2.0, 3.0))
    op = head.AddRotateXOp()
    for frame, deg in ((0, 0.0), (12, 30.0), (24, -10.0)):
        op.Set(deg, frame)
    stage.GetRootLayer().Save()
    return path


def test_a_usd_rotation_becomes_the_same_quaternions(tmp_path):
    src = usd_stage(tmp_path / "nod.usda")
    dst = tmp_path / "nod.csv"
    assert harness_main(["motion", "convert", str(src), str(dst)]) == 0
    k = motion_tracks.read_csv(dst)
    assert np.allclose(k.times, [0.0, 0.5, 1.0])
    want = motion_tracks.about_axis(k.times, np.radians([0.0, 30.0, -10.0]), (1, 0, 0)).quats
    assert np.allclose(k.quats, want, atol=1e-12)  # USD's rotateX turns y toward z, as nod does
    assert np.allclose(k.trans, [[1.0, 2.0, 3.0]] * 3)  # cm already (metersPerUnit 0.01)


def test_a_z_up_stage_turns_y_up_in_cm(tmp_path):
    src = usd_stage(tmp_path / "z.usda", up="Z", meters=1.0)
    k = motion_tracks.from_usd(src)
    want = motion_tracks.about_axis(k.times, np.radians([0.0, 30.0, -10.0]), (1, 0, 0)).quats
    assert np.allclose(k.quats, want, atol=1e-12)  # the x axis is x in both frames
    assert np.allclose(k.trans, [[100.0, 300.0, -200.0]] * 3)  # metres to cm, (x, y, z) Z-up = (x, z, −y) Y-up
    assert not motion_tracks.from_usd(src, rotation_only=True).trans.any()
    rel = motion_tracks.from_usd(src, relative=True)
    assert np.allclose(rel.quats[0], [1, 0, 0, 0])


def test_a_usd_track_without_samples_or_usd_is_refused(tmp_path):
    Usd, UsdGeom = pxr()
    stage = Usd.Stage.CreateNew(str(tmp_path / "still.usda"))
    UsdGeom.Xform.Define(stage, "/head")
    stage.GetRootLayer().Save()
    with pytest.raises(HarnessError, match="no xformable prim with time samples"):
        motion_tracks.from_usd(tmp_path / "still.usda")
