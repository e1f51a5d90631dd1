"""Head transform tracks (`--head-motion track --motion-track FILE`; docs/interfaces.md,
"Motion tracks"; docs/model.md §3.2): the CSV file the binaries read, written from samples,
from a USD xform's time samples (`python -m harness motion convert`, needs usd-core), or from
a documented motion (the stability map's recorded fast turn, configs/motions/fast-turn.csv).

The binaries read, interpolate (slerp) and store the track; this module only writes and reads
the file. Rotations are unit quaternions (w, x, y, z), the rotation from the rest pose about
the head centre, y up; translations in cm (read and stored, not yet modelled: the binaries
refuse a non-zero one)."""

import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from harness import HarnessError
from harness.io import files

HEADER = "time,qw,qx,qy,qz,tx,ty,tz"
AXIS_HEADER = "time,axis_x,axis_y,axis_z,angle,tx,ty,tz"


@dataclass(frozen=True)
class Track:
    times: np.ndarray  # [K] s, strictly increasing
    quats: np.ndarray  # [K][4] unit quaternions (w, x, y, z)
    trans: np.ndarray  # [K][3] cm


def about_axis(times, angles, axis):
    """The track of rotations by `angles` (radians) about the unit `axis`, no translation."""
    a = np.asarray(axis, dtype=np.float64)
    a = a / np.linalg.norm(a)
    th = np.asarray(angles, dtype=np.float64)
    quats = np.column_stack([np.cos(th / 2), np.outer(np.sin(th / 2), a)])
    t = np.asarray(times, dtype=np.float64)
    return Track(t, quats, np.zeros((len(t), 3)))


def write_csv(path, track, comment="", force=False):
    """Write the track as the binaries' CSV (repr floats, so it reads back bit for bit), whole
    or not at all; an existing file only with force."""
    path = Path(path)
    t, q, tr = track.times, track.quats, track.trans
    if len(t) < 1 or not (np.all(np.isfinite(t)) and np.all(np.diff(t) > 0)):
        raise HarnessError(f"motion track {path}: times must be finite and increasing")
    if path.exists() and not force:
        raise HarnessError(f"motion track {path} exists (give --force to replace it)")
    lines = [f"# {c}" for c in comment.splitlines()] + [HEADER]
    lines += [",".join(repr(float(v)) for v in (t[i], *q[i], *tr[i])) for i in range(len(t))]
    return files.write_text(path, "\n".join(lines) + "\n")


def read_csv(path):
    """A track file as the binaries read it (either header); quaternions normalised."""
    rows, header = [], None
    try:
        text = Path(path).read_text()
    except (OSError, UnicodeDecodeError) as e:
        raise HarnessError(f"motion track {path}: cannot read it ({e})") from None
    for n, line in enumerate(text.splitlines(), 1):
        s = line.strip()
        if not s or s.startswith("#"):
            continue
        fields = [f.strip() for f in s.split(",")]
        if header is None:
            header = ",".join(fields)
            if header not in (HEADER, AXIS_HEADER):
                raise HarnessError(f"motion track {path}: line {n}: the header must be {HEADER} or {AXIS_HEADER}")
            continue
        try:
            v = [float(f) for f in fields]
        except ValueError:
            raise HarnessError(f"motion track {path}: line {n}: not a number") from None
        if len(v) != 8 or not all(map(math.isfinite, v)):
            raise HarnessError(f"motion track {path}: line {n}: 8 finite numbers expected")
        rows.append(v)
    if header is None or not rows:
        raise HarnessError(f"motion track {path}: no header or no samples")
    a = np.array(rows)
    if header == AXIS_HEADER:
        axis = a[:, 1:4] / np.where(a[:, 4:5] == 0, 1.0, np.linalg.norm(a[:, 1:4], axis=1, keepdims=True))
        q = np.column_stack([np.cos(a[:, 4] / 2), axis * np.sin(a[:, 4:5] / 2)])
    else:
        q = a[:, 1:5] / np.linalg.norm(a[:, 1:5], axis=1, keepdims=True)
    return Track(a[:, 0], q, a[:, 5:8])


def minimum_jerk(fraction):
    """The minimum-jerk profile 10u³ − 15u⁴ + 6u⁵ of u in [0, 1] (0 → 0, 1 → 1, rest at both ends)."""
    u = np.clip(np.asarray(fraction, dtype=np.float64), 0.0, 1.0)
    return u**3 * (10 - 15 * u + 6 * u * u)


# The stability map's recorded fast motion (harness/studies/stability_slices_dynamic.py): a head turn
# about ŷ (shake's axis) to FAST_TURN_ANGLE and back, each way a minimum-jerk move of
# FAST_TURN_MOVE_S seconds, held FAST_TURN_HOLD_S between, sampled every FAST_TURN_DT. The move
# time gives a peak speed of 1.875·angle/time = 780 °/s, the group median of the largest head
# speed in vigorous voluntary yaw measured by Grossman et al. 1988 (docs/model.md §3.2).
FAST_TURN_ANGLE = math.radians(80.0)
FAST_TURN_MOVE_S = 1.875 * 80.0 / 780.0
FAST_TURN_HOLD_S = 0.2
FAST_TURN_DT = 1.0 / 240.0
FAST_TURN_FILE = "fast-turn.csv"


def fast_turn():
    """The recorded fast head turn (its constants above) as a Track, starting and ending at rest."""
    move, hold = FAST_TURN_MOVE_S, FAST_TURN_HOLD_S
    total = 2 * move + hold
    t = np.append(np.arange(0, int(total / FAST_TURN_DT) + 1) * FAST_TURN_DT, total)  # the last sample at rest
    there = minimum_jerk(t / move)
    back = minimum_jerk((t - move - hold) / move)
    return about_axis(t, FAST_TURN_ANGLE * (there - back), (0.0, 1.0, 0.0))


def fast_turn_comment():
    return (
        f"A fast head turn about y (docs/model.md §3.2): {math.degrees(FAST_TURN_ANGLE):g} degrees and back, "
        f"each way a minimum-jerk move of {FAST_TURN_MOVE_S:.6g} s (peak 780 deg/s, Grossman et al. 1988), held "
        f"{FAST_TURN_HOLD_S:g} s between.\nWritten by harness.io.motion_tracks.fast_turn(); tests/unit/"
        "test_motion_tracks.py checks that it still is."
    )


# ---- USD xform time samples -------------------------------------------------------------


def _pxr():
    try:
        from pxr import Gf, Usd, UsdGeom
    except ImportError:
        raise HarnessError(
            "a USD motion track needs the USD Python bindings: python3 -m pip install usd-core"
        ) from None
    return Gf, Usd, UsdGeom


def _animated_prim(stage, UsdGeom, prim_path, path):
    if prim_path:
        prim = stage.GetPrimAtPath(prim_path)
        if not prim or not prim.IsA(UsdGeom.Xformable):
            raise HarnessError(f"motion track {path}: no xformable prim {prim_path}")
        return prim
    for prim in stage.Traverse():
        if prim.IsA(UsdGeom.Xformable) and UsdGeom.Xformable(prim).GetTimeSamples():
            return prim
    raise HarnessError(f"motion track {path}: no xformable prim with time samples (name one with --prim)")


def from_usd(path, prim_path=None, relative=False, rotation_only=False):
    """The world transform of a USD prim at each of its xform's time samples, as a Track: times
    in seconds (time code / timeCodesPerSecond), rotations as unit quaternions turned Y-up where
    the stage is Z-up, translations scaled by metersPerUnit to cm. `relative`: each rotation
    relative to the first sample's (the groom was made in that pose); `rotation_only`: the
    translation dropped (zeros), since the binaries do not model it yet."""
    Gf, Usd, UsdGeom = _pxr()
    if not Path(path).is_file():
        raise HarnessError(f"motion track {path}: no such file")
    try:
        stage = Usd.Stage.Open(str(path))
    except Exception as e:  # pxr raises Tf.ErrorException for a file it cannot read
        why = (str(e).strip().splitlines() or [type(e).__name__])[-1].strip()
        raise HarnessError(f"motion track {path}: USD could not read it ({why[:160]})") from None
    if stage is None:
        raise HarnessError(f"motion track {path}: USD could not open it")
    prim = _animated_prim(stage, UsdGeom, prim_path, path)
    codes = sorted(UsdGeom.Xformable(prim).GetTimeSamples()) or [Usd.TimeCode.Default()]
    to_cm = UsdGeom.GetStageMetersPerUnit(stage) / 0.01
    z_up = UsdGeom.GetStageUpAxis(stage) == UsdGeom.Tokens.z
    tps = stage.GetTimeCodesPerSecond()
    times, quats, trans = [], [], []
    for code in codes:
        m = UsdGeom.XformCache(code).GetLocalToWorldTransform(prim)
        rot = m.RemoveScaleShear().ExtractRotationQuat()
        q = np.array([rot.GetReal(), *rot.GetImaginary()], dtype=np.float64)
        tr = np.array(m.ExtractTranslation(), dtype=np.float64) * to_cm
        if z_up:  # (x, y, z) Z-up is (x, z, −y) Y-up, for a rotation's axis as for a point
            q = np.array([q[0], q[1], q[3], -q[2]])
            tr = np.array([tr[0], tr[2], -tr[1]])
        times.append(0.0 if code == Usd.TimeCode.Default() else float(code) / tps)
        quats.append(q / np.linalg.norm(q))
        trans.append(tr)
    q = np.array(quats)
    if relative:  # q_j ⊗ conj(q_0): the rotation from the first pose
        q = np.array([_qmul(qj, q[0] * np.array([1, -1, -1, -1])) for qj in q])
    tr = np.zeros((len(times), 3)) if rotation_only else np.array(trans)
    return Track(np.array(times), q, tr)


def _qmul(a, b):
    w1, x1, y1, z1 = a
    w2, x2, y2, z2 = b
    return np.array(
        [
            w1 * w2 - x1 * x2 - y1 * y2 - z1 * z2,
            w1 * x2 + x1 * w2 + y1 * z2 - z1 * y2,
            w1 * y2 - x1 * z2 + y1 * w2 + z1 * x2,
            w1 * z2 + x1 * y2 - y1 * x2 + z1 * w2,
        ]
    )


def convert(src, dst, prim_path=None, relative=False, rotation_only=False, force=False):
    """A USD xform's time samples as the binaries' CSV track; the number of samples written."""
    track = from_usd(src, prim_path=prim_path, relative=relative, rotation_only=rotation_only)
    write_csv(dst, track, comment=f"from {src}" + (f" {prim_path}" if prim_path else ""), force=force)
    return len(track.times)
