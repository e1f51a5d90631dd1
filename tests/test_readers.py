"""Files other tools open (docs/interfaces.md): the H5MD metadata of a state, MDAnalysis's
H5MD reader, and the `harness export` sidecars read back by VTK's XDMF reader (ParaView,
VisIt) and by pxr (USD: Blender, Houdini, usdview), compared bit for bit. The readers are
optional: each test skips, with the reason, where its package is absent."""

import subprocess
import sys
import warnings
from pathlib import Path

import h5py
import numpy as np
import pytest

ROOT_DIR = Path(__file__).resolve().parent.parent
SCENE = ["--strands", "40", "--points", "8", "--hair-length", "6", "--quiet"]


@pytest.fixture(scope="module", params=["fp32", "fp64"])
def state(request, cpu_bin, tmp_path_factory):
    path = tmp_path_factory.mktemp(request.param) / "s.h5"
    subprocess.run([str(cpu_bin), *SCENE, "--precision", request.param, "--output", str(path)], check=True)
    return path


def positions(path):
    with h5py.File(path, "r") as f:
        return f["particles/hair/position/value"][:]


def test_h5md_metadata(state):
    with h5py.File(state, "r") as f:
        for path in ("h5md/author", "h5md/creator"):
            for name in f[path].attrs:
                t = f[path].attrs.get_id(name).get_type()
                assert isinstance(t, h5py.h5t.TypeStringID) and not t.is_variable_str(), (path, name)
        b = f["particles/hair/box"].attrs.get_id("boundary").get_type()
        assert not b.is_variable_str()
        assert [s.decode() for s in f["particles/hair/box"].attrs["boundary"]] == ["none"] * 3
        assert list(f["h5md/modules/units"].attrs["version"]) == [1, 0]
        pos = f["particles/hair/position"]
        assert pos["value"].attrs["unit"] == "cm" and pos["time"].attrs["unit"] == "s"
        assert np.all(pos["time"][:] == 0.0)  # the paper model's frames: time 0
        n, p = int(f["parameters"].attrs["n_strands"]), int(f["parameters"].attrs["points_per_strand"])
        assert np.array_equal(f["particles/hair/strand"][:], np.repeat(np.arange(n), p))


def _mdanalysis_knows_cm():
    """MDAnalysis 2.x's H5MD reader has no 'cm' in its length table and refuses the file
    (with or without convert_units); teach it centimetres (1 cm = 1e8 Å)."""
    from MDAnalysis import units
    from MDAnalysis.coordinates.H5MD import H5MDReader

    H5MDReader._unit_translation["length"].setdefault("cm", "cm")
    units.lengthUnit_factor.setdefault("cm", 1e-8)


def test_mdanalysis_reads_every_frame(state):
    pytest.importorskip("MDAnalysis", reason="MDAnalysis not installed (pip install MDAnalysis)")
    from MDAnalysis.coordinates.H5MD import H5MDReader

    _mdanalysis_knows_cm()
    ref = positions(state)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        raw = H5MDReader(str(state), convert_units=False)
        assert raw.n_frames == len(ref) and raw.units["length"] == "cm" and raw.units["time"] == "s"
        for ts in raw:
            assert np.array_equal(ts.positions, ref[ts.frame].astype(np.float32)), ts.frame
            if ref.dtype == np.float32:
                assert ts.positions.tobytes() == ref[ts.frame].tobytes()  # bit for bit
        converted = H5MDReader(str(state))  # its defaults: convert to Å
        for ts in converted:
            np.testing.assert_allclose(ts.positions, ref[ts.frame] * 1e8, rtol=1e-6)


def test_mdanalysis_without_centimetres_names_the_unit(state):
    """Documents the upstream gap: until MDAnalysis knows 'cm', it names the unit and stops
    (a fresh interpreter: the test above taught this one)."""
    pytest.importorskip("MDAnalysis", reason="MDAnalysis not installed (pip install MDAnalysis)")
    code = (
        "import sys, warnings; warnings.simplefilter('ignore')\n"
        "from MDAnalysis.coordinates.H5MD import H5MDReader\n"
        "try:\n    H5MDReader(sys.argv[1])\nexcept RuntimeError as e:\n    print(e); sys.exit(3)\n"
    )
    p = subprocess.run([sys.executable, "-c", code, str(state)], capture_output=True, text=True)
    if p.returncode == 0:
        pytest.skip("this MDAnalysis reads 'cm' with its defaults: drop the shim in the test above")
    assert p.returncode == 3 and "'cm'" in p.stdout, p.stdout + p.stderr


def export(state, *args):
    p = subprocess.run(
        [sys.executable, "-m", "harness", "export", str(state), *args], cwd=ROOT_DIR, capture_output=True, text=True
    )
    assert p.returncode == 0, p.stderr
    return p


def test_xdmf_opens_in_vtk_as_polylines_over_time(state):
    vtk_xdmf = pytest.importorskip("vtkmodules.vtkIOXdmf2", reason="VTK not installed (pip install vtk)")
    from vtkmodules.util.numpy_support import vtk_to_numpy
    from vtkmodules.vtkCommonCore import vtkLogger
    from vtkmodules.vtkCommonExecutionModel import vtkStreamingDemandDrivenPipeline as SDDP

    export(state)
    xdmf = Path(f"{state}.xdmf")
    assert xdmf.stat().st_size < 4096 * len(positions(state))  # no inline heavy data
    ref = positions(state)
    n_rows = ref.shape[1]
    with h5py.File(f"{state}.topo.h5", "r") as t:
        p = t["connectivity"].shape[1]
        assert np.array_equal(t["connectivity"][:].ravel(), np.arange(n_rows))
    vtkLogger.SetStderrVerbosity(vtkLogger.VERBOSITY_OFF)  # "no caching possible" per frame
    r = vtk_xdmf.vtkXdmfReader()
    r.SetFileName(str(xdmf))
    r.UpdateInformation()
    times = r.GetOutputInformation(0).Get(SDDP.TIME_STEPS())
    assert len(times) == len(ref)
    for k, t in enumerate(times):
        r.UpdateTimeStep(t)
        grid = r.GetOutputDataObject(0)
        assert grid.GetNumberOfCells() == n_rows // p
        assert all(
            grid.GetCellType(c) == 4 and grid.GetCell(c).GetNumberOfPoints() == p  # VTK_POLY_LINE
            for c in range(grid.GetNumberOfCells())
        )
        pts = vtk_to_numpy(grid.GetPoints().GetData())
        assert pts.dtype == ref.dtype and pts.tobytes() == ref[k].tobytes(), k
        strand = vtk_to_numpy(grid.GetPointData().GetArray("strand"))
        assert np.array_equal(strand, np.repeat(np.arange(n_rows // p), p))


def test_usd_basis_curves_one_sample_per_frame(state):
    pytest.importorskip("pxr", reason="usd-core not installed (pip install usd-core)")
    from pxr import Usd, UsdGeom

    export(state, "--usd-only")
    ref = positions(state)
    stage = Usd.Stage.Open(f"{state}.usdc")
    assert UsdGeom.GetStageUpAxis(stage) == UsdGeom.Tokens.y and UsdGeom.GetStageMetersPerUnit(stage) == 0.01
    curves = UsdGeom.BasisCurves(stage.GetPrimAtPath("/hair/strands"))
    assert curves.GetTypeAttr().Get() == UsdGeom.Tokens.linear
    counts = list(curves.GetCurveVertexCountsAttr().Get())
    assert sum(counts) == ref.shape[1] and len(set(counts)) == 1
    attr = curves.GetPointsAttr()
    assert attr.GetTimeSamples() == [float(k) for k in range(len(ref))]
    for k in range(len(ref)):
        got = np.array(attr.Get(k), dtype=np.float32)
        assert got.tobytes() == ref[k].astype(np.float32).tobytes(), k  # fp64 states: rounded to fp32


def test_export_refuses_what_is_not_a_state(tmp_path):
    bad = tmp_path / "x.h5"
    bad.write_text("not hdf5")
    p = subprocess.run(
        [sys.executable, "-m", "harness", "export", str(bad)], cwd=ROOT_DIR, capture_output=True, text=True
    )
    assert p.returncode == 2 and p.stderr.count("\n") == 1 and p.stderr.startswith("harness: error: export:")


def test_export_refuses_a_symlinked_target(state, tmp_path):
    target = tmp_path / "elsewhere.txt"
    target.write_text("keep")
    link = Path(f"{state}.xdmf")
    link.unlink(missing_ok=True)
    link.symlink_to(target)
    try:
        p = subprocess.run(
            [sys.executable, "-m", "harness", "export", str(state)], cwd=ROOT_DIR, capture_output=True, text=True
        )
        assert p.returncode == 2 and "symbolic link" in p.stderr and target.read_text() == "keep"
        assert not [q for q in Path(state).parent.iterdir() if ".tmp" in q.name]
    finally:
        link.unlink()
