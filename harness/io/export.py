"""`python -m harness export STATE`: sidecars that other tools open (docs/interfaces.md,
"Files other tools open").

- XDMF (`STATE.xdmf` + `STATE.topo.h5`): ParaView and VisIt open the state as polylines
  over time. The positions stay in STATE and are referenced frame by frame (hyperslabs);
  the polyline connectivity is an HDF5 dataset in the small sidecar, so the XML stays a
  few kilobytes at any strand count.
- USD (`STATE.usdc`, needs PyPI `usd-core`): one `BasisCurves` prim, linear, with one time
  sample per frame, for Blender, Houdini and usdview.
- HAIR (`STATE.hair`): one frame's strands (the last, or `frame`) as a groom, the format of
  Cem Yuksel's hair models that `--groom` reads (docs/model.md §3.15), in cm, float32.

A dynamic state's velocities go with the frames whose step has one (XDMF attribute
`velocity`, USD `velocities`), and its rest shape with every frame (XDMF `rest_position`,
USD primvar `rest`). Its observables are per-frame numbers, not geometry: they stay in the
state (harness.io.trajectory reads them). A dynamic state's frame times are in seconds
(frame_times); its USD frame rate is exact (time_codes_per_second).

Sidecars that exist are replaced only with --force; every refusal (no state, --usd
without usd-core, a symlinked target, an existing one) comes before anything is written.
"""

import errno
import math
import os
from pathlib import Path
from xml.sax.saxutils import escape

import numpy as np

from harness import HarnessError
from harness.io import files

POSITION = "particles/hair/position"
VELOCITY = "particles/hair/velocity"
REST = "particles/hair/rest_position"
BLOCK_ROWS = 1 << 20  # rows written or read at a time


def _writable(path):
    """Refuse, as the binaries do for --output, a target that is a symlink or exists and is
    not a regular file (harness/io/files.py then writes it whole or not at all)."""
    path = Path(path)
    if path.is_symlink() or (path.exists() and not path.is_file()):
        raise HarnessError(f"export: {path} is a symbolic link or not a regular file; refusing to replace it")
    return path


def _open_state(path):
    from harness.core import inputs

    f = inputs.open_h5(path, "export:")
    try:
        value = f[f"{POSITION}/value"]
        n = int(f["parameters"].attrs["n_strands"])
        p = int(f["parameters"].attrs["points_per_strand"])
    except (KeyError, TypeError, ValueError):
        f.close()
        raise HarnessError(
            f"export: {path} is not a hairbench state (no {POSITION}/value or /parameters n_strands, points_per_strand)"
        ) from None
    if value.ndim != 3 or value.shape[1] != n * p or value.shape[2] != 3:
        f.close()
        raise HarnessError(f"export: {path}: {POSITION}/value has shape {value.shape}, not [F][{n}·{p}][3]")
    return f, n, p


def _dynamic(f):
    """The dynamic model's (frame_dt, paper_frames), or None for a paper-model state."""
    from harness.io.states import as_text

    params = f["parameters"].attrs if "parameters" in f else {}
    if as_text(params.get("model", "paper")) != "dynamic":
        return None
    try:
        dt = float(params["frame_dt"])
        paper = int(params["paper_frames"])
    except (KeyError, TypeError, ValueError):
        raise HarnessError("export: a dynamic state's /parameters lacks frame_dt or paper_frames") from None
    if not (math.isfinite(dt) and dt > 0):
        raise HarnessError(f"export: frame_dt = {dt} is not a positive time")
    return dt, paper


def frame_times(f):
    """The time of each frame for viewers, increasing. A dynamic state: its times in
    seconds, and the paper stages before the simulation (all stored at t = 0) one frame
    interval apart, the last at 0 (e.g. init −Δt, collide 0, simulated frames Δt, 2Δt, …),
    so that each frame stays its own time step. A paper-model state (every frame at t = 0):
    the frame index."""
    frames = f[f"{POSITION}/value"].shape[0]
    dyn = _dynamic(f)
    if dyn and f"{POSITION}/time" in f:
        dt, paper = dyn
        t = np.asarray(f[f"{POSITION}/time"][:], dtype=np.float64)
        if t.shape == (frames,) and 1 <= paper <= frames:
            t = t.copy()
            t[:paper] = t[paper - 1] - dt * np.arange(paper - 1, -1, -1, dtype=np.float64)
            if frames < 2 or np.all(np.diff(t) > 0):
                return t
        raise HarnessError(f"export: the dynamic state's {POSITION}/time does not increase frame by frame")
    return np.arange(frames, dtype=np.float64)


def time_codes_per_second(f):
    """USD timeCodesPerSecond (time code = frame index): a dynamic state's frame rate 1/Δt,
    exactly n when Δt is the double nearest 1/n (60, not 59.999999999999815, for 1/60);
    24 for the paper model's timeless frames."""
    dyn = _dynamic(f)
    return time_codes_per_second_of(dyn[0]) if dyn else 24.0


def time_codes_per_second_of(dt):
    """1/dt, exactly n where dt is the double nearest 1/n."""
    n = round(1.0 / dt)
    return float(n) if n >= 1 and 1.0 / n == dt else 1.0 / dt


def velocity_frames(f):
    """{position frame index: velocity frame index} for the frames whose step has velocities."""
    if f"{VELOCITY}/value" not in f:
        return {}
    at = {int(s): j for j, s in enumerate(f[f"{VELOCITY}/step"][()])}
    return {k: at[int(s)] for k, s in enumerate(f[f"{POSITION}/step"][()]) if int(s) in at}


def write_connectivity(path, n, p):
    """[N][P] point indices of each strand's polyline, compressed, written in blocks."""
    import h5py

    dtype = np.int32 if n * p < 2**31 else np.int64
    strands_per_block = max(1, BLOCK_ROWS // p)
    with h5py.File(path, "w") as f:
        d = f.create_dataset(
            "connectivity",
            shape=(n, p),
            dtype=dtype,
            chunks=(min(n, strands_per_block), p),
            compression="gzip",
            compression_opts=1,
            shuffle=True,
        )
        d.attrs["description"] = "row i: the point indices i*P … i*P + P-1 of strand i"
        for start in range(0, n, strands_per_block):
            stop = min(n, start + strands_per_block)
            d[start:stop] = np.arange(start * p, stop * p, dtype=dtype).reshape(stop - start, p)
    return dtype


def _vector(name, state_ref, dataset, rows, float_bytes, index=None, count=None):
    """An XDMF node attribute of 3-vectors: DATASET [rows][3], or its frame INDEX of COUNT."""
    heavy = f'<DataItem Dimensions="{{dims}}" NumberType="Float" Precision="{float_bytes}" Format="HDF">{state_ref}:/{dataset}</DataItem>'
    if index is None:
        item = heavy.format(dims=f"{rows} 3")
    else:
        item = (
            f'<DataItem ItemType="HyperSlab" Dimensions="{rows} 3" Type="HyperSlab">\n'
            f'       <DataItem Dimensions="3 3" Format="XML">{index} 0 0 1 1 1 1 {rows} 3</DataItem>\n'
            f"       {heavy.format(dims=f'{count} {rows} 3')}\n"
            f"      </DataItem>"
        )
    return f'\n     <Attribute Name="{name}" AttributeType="Vector" Center="Node">\n      {item}\n     </Attribute>'


def _xdmf(state_ref, topo_ref, n, p, frames, times, float_bytes, int_bytes, has_strand, dyn):
    rows = n * p
    grids = []
    for k in range(frames):
        extra = ""
        if k in dyn["velocity"]:
            extra += _vector(
                "velocity", state_ref, f"{VELOCITY}/value", rows, float_bytes, dyn["velocity"][k], dyn["n_velocity"]
            )
        if dyn["rest"]:
            extra += _vector("rest_position", state_ref, REST, rows, float_bytes)
        strand = (
            (
                f'\n     <Attribute Name="strand" AttributeType="Scalar" Center="Node">\n'
                f'      <DataItem Dimensions="{rows}" NumberType="Int" Precision="4" Format="HDF">'
                f"{state_ref}:/particles/hair/strand</DataItem>\n     </Attribute>"
            )
            if has_strand
            else ""
        )
        grids.append(f"""    <Grid Name="frame {k}" GridType="Uniform">
     <Time Value="{float(times[k])!r}"/>
     <Topology TopologyType="Polyline" NumberOfElements="{n}" NodesPerElement="{p}">
      <DataItem Dimensions="{n} {p}" NumberType="Int" Precision="{int_bytes}" Format="HDF">{topo_ref}:/connectivity</DataItem>
     </Topology>
     <Geometry GeometryType="XYZ">
      <DataItem ItemType="HyperSlab" Dimensions="{rows} 3" Type="HyperSlab">
       <DataItem Dimensions="3 3" Format="XML">{k} 0 0 1 1 1 1 {rows} 3</DataItem>
       <DataItem Dimensions="{frames} {rows} 3" NumberType="Float" Precision="{float_bytes}" Format="HDF">{state_ref}:/{POSITION}/value</DataItem>
      </DataItem>
     </Geometry>{strand}{extra}
    </Grid>""")
    body = "\n".join(grids)
    return f"""<?xml version="1.0" ?>
<!DOCTYPE Xdmf SYSTEM "Xdmf.dtd" []>
<Xdmf Version="2.0">
 <Domain>
  <Grid Name="hair" GridType="Collection" CollectionType="Temporal">
{body}
  </Grid>
 </Domain>
</Xdmf>
"""


def export_xdmf(state, out_prefix=None):
    """Write OUT.xdmf and OUT.topo.h5 beside the state (or at out_prefix); return both paths."""
    state = Path(state)
    xdmf_path, topo_path = targets(state, out_prefix, xdmf=True)
    f, n, p = _open_state(state)
    with f:
        value = f[f"{POSITION}/value"]
        frames, float_bytes = value.shape[0], value.dtype.itemsize
        times = frame_times(f)
        has_strand = "particles/hair/strand" in f
        dyn = {
            "velocity": velocity_frames(f),
            "n_velocity": f[f"{VELOCITY}/value"].shape[0] if f"{VELOCITY}/value" in f else 0,
            "rest": REST in f,
        }
    here = xdmf_path.parent.resolve()
    state_ref = escape(os.path.relpath(state.resolve(), here))
    topo_ref = escape(os.path.relpath(topo_path.resolve(), here))
    with files.writing(_writable(topo_path)) as tmp_topo, files.writing(_writable(xdmf_path)) as tmp_xdmf:
        int_bytes = np.dtype(write_connectivity(tmp_topo, n, p)).itemsize
        text = _xdmf(state_ref, topo_ref, n, p, frames, times, float_bytes, int_bytes, has_strand, dyn)
        tmp_xdmf.write_bytes(text.encode("utf-8"))
    return xdmf_path, topo_path


def export_usd(state, out_prefix=None):
    """Write OUT.usdc: /hair/strands, a linear BasisCurves with one time sample per frame
    (points are float3 in USD: an fp64 state is rounded to fp32)."""
    Sdf, Usd, UsdGeom, Vt = _pxr()
    state = Path(state)
    (usd_path,) = targets(state, out_prefix, usd=True)
    f, n, p = _open_state(state)
    with f:
        value = f[f"{POSITION}/value"]
        frames = value.shape[0]
        times = frame_times(f)
        with files.writing(_writable(usd_path), create=False) as tmp:  # USD creates it, by its suffix
            _write_usd(Sdf, Usd, UsdGeom, Vt, tmp, f, value, frames, times, n, p)
    return usd_path


def _write_usd(Sdf, Usd, UsdGeom, Vt, tmp, f, value, frames, times, n, p):  # noqa: N803 (pxr's names)
    """The stage at tmp, saved; a save USD refuses (a full disk) as an OSError naming tmp."""
    stage = Usd.Stage.CreateNew(str(tmp))
    UsdGeom.SetStageUpAxis(stage, UsdGeom.Tokens.y)  # column 1 is up
    UsdGeom.SetStageMetersPerUnit(stage, 0.01)  # positions are in cm
    stage.SetStartTimeCode(0)
    stage.SetEndTimeCode(frames - 1)
    # time code = frame index; a dynamic state's frame rate makes its velocities (per second) agree
    stage.SetTimeCodesPerSecond(time_codes_per_second(f))
    root = UsdGeom.Xform.Define(stage, "/hair")
    stage.SetDefaultPrim(root.GetPrim())
    curves = UsdGeom.BasisCurves.Define(stage, "/hair/strands")
    curves.CreateTypeAttr(UsdGeom.Tokens.linear)
    curves.CreateCurveVertexCountsAttr(Vt.IntArray.FromNumpy(np.full(n, p, dtype=np.int32)))
    curves.CreateWidthsAttr(Vt.FloatArray([0.01]))
    curves.SetWidthsInterpolation(UsdGeom.Tokens.constant)
    points = curves.CreatePointsAttr()
    for k in range(frames):
        frame = np.ascontiguousarray(value[k], dtype=np.float32)
        points.Set(Vt.Vec3fArray.FromNumpy(frame), Usd.TimeCode(k))
    vel = velocity_frames(f)
    if vel:
        velocities = curves.CreateVelocitiesAttr()
        for k, j in vel.items():
            frame = np.ascontiguousarray(f[f"{VELOCITY}/value"][j], dtype=np.float32)
            velocities.Set(Vt.Vec3fArray.FromNumpy(frame), Usd.TimeCode(k))
    if REST in f:
        rest = UsdGeom.PrimvarsAPI(curves).CreatePrimvar("rest", Sdf.ValueTypeNames.Point3fArray, UsdGeom.Tokens.vertex)
        rest.Set(Vt.Vec3fArray.FromNumpy(np.ascontiguousarray(f[REST][()], dtype=np.float32)))
    prim = curves.GetPrim()
    prim.CreateAttribute("hairbench:frameTime", Sdf.ValueTypeNames.DoubleArray).Set(Vt.DoubleArray.FromNumpy(times))
    try:
        saved = stage.GetRootLayer().Save()
    except Exception as e:  # USD's own error type (pxr.Tf.ErrorException)
        why = (str(e).strip().splitlines() or [type(e).__name__])[-1].strip()
        raise OSError(errno.EIO, f"USD could not save it ({why[:120]})") from None
    if not saved:
        raise OSError(errno.EIO, "USD could not save it")
    del stage


def _pxr():
    try:
        from pxr import Sdf, Usd, UsdGeom, Vt
    except ImportError:
        raise HarnessError("export --usd needs the USD Python bindings: python3 -m pip install usd-core") from None
    return Sdf, Usd, UsdGeom, Vt


def _frame_index(state, frame):
    """`frame` (negative from the end) as an index of the state's frames, or refused in one line."""
    f, _, _ = _open_state(state)
    with f:
        count = f[f"{POSITION}/value"].shape[0]
    k = frame if frame >= 0 else count + frame
    if not 0 <= k < count:
        raise HarnessError(f"export: --frame {frame}: {state} holds frames 0 … {count - 1}")
    return k


def export_hair(state, out_prefix=None, frame=-1):
    """Write OUT.hair: frame `frame` (negative from the end) of the state, a strand a polyline."""
    from harness.io import grooms

    state = Path(state)
    (hair_path,) = targets(state, out_prefix, hair=True)
    k = _frame_index(state, frame)
    f, n, p = _open_state(state)
    with f:
        strands = np.asarray(f[f"{POSITION}/value"][k], dtype=np.float64).reshape(n, p, 3)
    files.write_bytes(_writable(hair_path), grooms.hair_bytes(list(strands)))
    return hair_path


def targets(state, out_prefix=None, xdmf=False, usd=False, hair=False):
    """The files an export writes: OUT.xdmf and OUT.topo.h5, OUT.usdc, OUT.hair (OUT: out_prefix,
    else the state)."""
    prefix = Path(out_prefix) if out_prefix else Path(state)
    names = ([".xdmf", ".topo.h5"] if xdmf else []) + ([".usdc"] if usd else []) + ([".hair"] if hair else [])
    return [prefix.with_name(prefix.name + suffix) for suffix in names]


def run(state, xdmf=True, usd=False, out=None, force=False, hair=False, frame=-1):
    """Write the sidecars; return their paths. Everything that can refuse does so before
    anything is written: no such state, USD asked for without usd-core, a target that is a
    symbolic link or not a regular file, or one that exists without `force`."""
    from harness.core import inputs

    inputs.regular(state, "export:")
    if usd:
        _pxr()
    if hair:
        _frame_index(state, frame)
    paths = targets(state, out, xdmf, usd, hair)
    for path in paths:
        _writable(path)
    if not force:
        there = [str(p) for p in paths if p.exists()]
        if there:
            raise HarnessError(f"export: {', '.join(there)} exist(s); use --force to replace")
    written = []
    if xdmf:
        written += export_xdmf(state, out)
    if usd:
        written.append(export_usd(state, out))
    if hair:
        written.append(export_hair(state, out, frame))
    return written
