"""Grooms from other tools (docs/model.md §3.15): USD BasisCurves converted to the HAIR file the
binaries read (`python -m harness groom convert IN.usda OUT.hair`).

The binaries are C and cannot link usd-core (Python); so a USD groom passes through here: every
BasisCurves prim at the stage's earliest time (its default value, else the first time sample:
the first frame of an animation, such as `harness export --usd` writes), its points taken to
world space, scaled by the
stage's metersPerUnit to cm, turned Y-up when the stage is Z-up, and written as a HAIR file
(segments and points arrays). usd-core is optional: without it a USD groom is refused in one line.
"""

import contextlib
import dataclasses
import math
import os
import struct
import tempfile
from pathlib import Path

import numpy as np

from harness import HarnessError
from harness.core import inputs
from harness.io import files

USD_SUFFIXES = (".usd", ".usda", ".usdc", ".usdz")
HAIR_SEGMENTS, HAIR_POINTS = 1, 2


def is_usd(path):
    return Path(path).suffix.lower() in USD_SUFFIXES


def _pxr():
    try:
        from pxr import Usd, UsdGeom
    except ImportError:
        raise HarnessError("a USD groom needs the USD Python bindings: python3 -m pip install usd-core") from None
    return Usd, UsdGeom


def read_usd_curves(path):
    """The strands of every BasisCurves prim in a USD file, as float64 [n][3] arrays in cm, Y up."""
    Usd, UsdGeom = _pxr()
    inputs.regular(path, "groom")
    try:  # USD raises its own error type (pxr.Tf.ErrorException) for a file it cannot parse
        return _curves(Usd, UsdGeom, path)
    except HarnessError:
        raise
    except Exception as e:
        why = (str(e).strip().splitlines() or [type(e).__name__])[-1].strip()
        raise HarnessError(f"groom {path}: USD could not read it ({why[:160]})") from None


def _curves(Usd, UsdGeom, path):  # noqa: N803 (pxr's module names)
    stage = Usd.Stage.Open(str(path))
    if stage is None:
        raise HarnessError(f"groom {path}: USD could not open it")
    meters = UsdGeom.GetStageMetersPerUnit(stage)
    if not (math.isfinite(meters) and meters > 0):
        raise HarnessError(f"groom {path}: metersPerUnit is {meters}; it must be a finite number > 0")
    to_cm = meters / 0.01
    z_up = UsdGeom.GetStageUpAxis(stage) == UsdGeom.Tokens.z
    strands = []
    for prim in stage.Traverse():
        if not prim.IsA(UsdGeom.BasisCurves):
            continue
        curves = UsdGeom.BasisCurves(prim)
        at = Usd.TimeCode.EarliestTime()  # the default value, else the first time sample (an animation)
        pts = np.asarray(curves.GetPointsAttr().Get(at) or [], dtype=np.float64).reshape(-1, 3)
        counts = list(curves.GetCurveVertexCountsAttr().Get(at) or [])
        if sum(counts) != len(pts):
            raise HarnessError(
                f"groom {path}: {prim.GetPath()} has {len(pts)} points but its counts sum to {sum(counts)}"
            )
        m = np.asarray(UsdGeom.XformCache(at).GetLocalToWorldTransform(prim), dtype=np.float64)  # p·M
        world = np.hstack([pts, np.ones((len(pts), 1))]) @ m
        world = world[:, :3] * to_cm
        if z_up:
            world = np.stack([world[:, 0], world[:, 2], -world[:, 1]], axis=1)
        start = 0
        for n in counts:
            strands.append(world[start : start + n])
            start += n
    if not strands:
        raise HarnessError(f"groom {path}: no BasisCurves with points")
    return strands


def hair_strand_count(path):
    """The strand count a HAIR file's header gives (docs/model.md §3.15), or None where it is not one."""
    try:
        with open(path, "rb") as f:
            head = f.read(8)
    except OSError:
        return None
    if len(head) < 8 or head[:4] != b"HAIR":
        return None
    return struct.unpack("<I", head[4:8])[0]


def read_hair(path):
    """The strands of a HAIR file (docs/model.md §3.15's layout) as float64 [n][3] arrays in the
    file's units: its segments (or the header's count) and points arrays; the rest is skipped.
    A file that is not one, or is shorter than its header says, is refused in one line."""
    data = inputs.read_bytes(path, "groom")
    if len(data) < 128 or data[:4] != b"HAIR":
        raise HarnessError(f"groom {path}: not a HAIR file (no 'HAIR' header)")
    strands, points, arrays, default_segments = struct.unpack("<IIII", data[4:20])
    at = 128
    if arrays & HAIR_SEGMENTS:
        counts = np.frombuffer(data, "<u2", strands, at).astype(np.int64) + 1 if len(data) >= at + 2 * strands else None
        at += 2 * strands
    else:
        counts = np.full(strands, default_segments + 1, dtype=np.int64)
    if counts is None or not arrays & HAIR_POINTS or len(data) < at + 12 * points or int(counts.sum()) != points:
        raise HarnessError(f"groom {path}: shorter than its header says, or its counts disagree with its points")
    xyz = np.frombuffer(data, "<f4", 3 * points, at).reshape(points, 3).astype(np.float64)
    return np.split(xyz, np.cumsum(counts)[:-1])


def hair_bytes(strands):
    """A HAIR file (docs/model.md §3.15's layout) holding the strands: segments and points arrays."""
    counts = [len(s) for s in strands]
    if any(n < 1 or n > 65536 for n in counts):
        raise HarnessError("groom: a HAIR strand holds 1 to 65536 points")
    head = struct.pack("<4sIIII", b"HAIR", len(strands), sum(counts), HAIR_SEGMENTS | HAIR_POINTS, 0)
    head += struct.pack("<ff3f", 0.0, 0.0, 0.0, 0.0, 0.0) + b"hairbench groom".ljust(88, b"\0")
    segments = struct.pack(f"<{len(strands)}H", *[n - 1 for n in counts])
    return head + segments + np.concatenate(strands).astype("<f4").tobytes()


def write_hair(path, strands, force=False):
    """Write the strands as a HAIR file at path, whole or not at all (an existing file only with force)."""
    path = Path(path)
    if path.is_symlink() or (path.exists() and not path.is_file()):
        raise HarnessError(f"groom: {path} is a symbolic link or not a regular file; refusing to replace it")
    if path.exists() and not force:
        raise HarnessError(f"groom: {path} exists (give --force to replace it)")
    return files.write_bytes(path, hair_bytes(strands))


@contextlib.contextmanager
def hair_for(scene):
    """The scene as the binaries take it, and a function that names things as the user did: a
    USD groom converted to a HAIR file in a temporary folder (removed after the block), whose path
    the function turns back into the user's USD path in a record or message; an error raised in the
    block names the user's file too. Other scenes pass through unchanged."""
    src = scene.groom_file
    if not (src and is_usd(src)):
        yield scene, lambda x: x
        return
    with tempfile.TemporaryDirectory(prefix="hairbench-groom-") as folder:
        hair = os.path.join(folder, "groom.hair")
        convert(src, hair)

        def named(x):
            if isinstance(x, str):
                return x.replace(hair, str(src))
            if isinstance(x, dict):
                return {k: named(v) for k, v in x.items()}
            if isinstance(x, list):
                return [named(v) for v in x]
            return x

        try:
            yield dataclasses.replace(scene, groom=hair), named
        except HarnessError as e:
            e.args = (named(str(e)), *e.args[1:])
            raise


def convert(src, dst, force=False):
    """A USD groom as a HAIR file; returns the number of strands written."""
    strands = read_usd_curves(src)
    write_hair(dst, strands, force=force)
    return len(strands)
