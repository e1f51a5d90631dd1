"""Files other tools open (docs/interfaces.md): the H5MD metadata of a state, MDAnalysis's
H5MD reader, and the `harness export` sidecars read back by VTK's XDMF reader (ParaView,
VisIt) and by pxr (USD: Blender, Houdini, usdview), compared bit for bit. The readers are
optional: each test skips, with the reason, where its package is absent."""

import os
import shutil
import subprocess
import sys
import warnings
from pathlib import Path

import numpy as np
import pytest

from harness import HarnessError
from harness.io import export as export_mod
from harness.io import h5md, mdanalysis
from harness.io.states import open_state
from harness.io.trajectory import OBSERVABLES, open_trajectory
from support.synthetic import H5MD_BREAKS, break_h5md

ROOT_DIR = Path(__file__).resolve().parents[2]
SCENE = ["--strands", "40", "--points", "8", "--hair-length", "6", "--quiet"]
# the dynamic model: init and collide (no velocities, no observables), then 3 simulated frames
DYNAMIC = [
    *("--strands", "12", "--points", "6", "--hair-length", "6", "--stages", "init,collide,simulate"),
    *("--frames", "3", "--velocities", "all", "--wind-speed", "150", "--head-motion", "nod", "--quiet"),
]


def _write(cpu_bin, directory, args, precision):
    path = directory / "s.h5"
    subprocess.run([str(cpu_bin), *args, "--precision", precision, "--output", str(path)], check=True)
    return path


@pytest.fixture(scope="module", params=["fp32", "fp64"])
def state(request, cpu_bin, tmp_path_factory):
    return _write(cpu_bin, tmp_path_factory.mktemp(request.param), SCENE, request.param)


@pytest.fixture(scope="module", params=["fp32", "fp64"])
def dynamic_state(request, cpu_bin, tmp_path_factory):
    return _write(cpu_bin, tmp_path_factory.mktemp(f"dyn-{request.param}"), DYNAMIC, request.param)


def positions(path):
    """Every frame as [F][N·P][3], in the file's dtype, through the harness's reader."""
    with open_state(path) as s:
        return s.frames().reshape(s.n_frames, s.n_strands * s.points, 3)


PAPER_UNITS = {"particles/hair/position/value": "cm", "particles/hair/position/time": "s"}
DYNAMIC_UNITS = {
    **PAPER_UNITS,
    "particles/hair/velocity/value": "cm s-1",
    "particles/hair/velocity/time": "s",
    "particles/hair/rest_position": "cm",
    "observables/penetration_max/value": "cm",
    "observables/kinetic_energy/value": "cm+2 s-2",
    **{f"observables/{name}/time": "s" for name in OBSERVABLES},
}


def test_paper_state_conforms_to_h5md(state):
    assert h5md.problems(state) == []
    assert h5md.units(state) == PAPER_UNITS
    with open_trajectory(state) as t:
        assert np.all(t.time == 0.0)  # the paper model's frames: time 0, ordered by step
        assert np.array_equal(t.step, np.arange(t.n_frames))


def test_dynamic_state_conforms_to_h5md(dynamic_state):
    assert h5md.problems(dynamic_state) == []
    assert h5md.units(dynamic_state) == DYNAMIC_UNITS
    with open_trajectory(dynamic_state) as t:
        dt = float(t.dynamic_params["frame_dt"])
        sim = t.simulated
        assert np.all(t.time[: t.paper_frames] == 0.0)
        np.testing.assert_allclose(t.time[sim], (t.step[sim] - t.paper_frames + 1) * dt, rtol=1e-12)  # seconds
        np.testing.assert_allclose(t.velocity_times, t.time[sim], rtol=0)


@pytest.mark.parametrize("how", sorted(H5MD_BREAKS))
def test_h5md_check_names_each_departure(state, tmp_path, how):
    broken = tmp_path / "broken.h5"
    shutil.copy(state, broken)
    break_h5md(broken, how)
    found = h5md.problems(broken)
    assert any(H5MD_BREAKS[how] in p for p in found), found


def test_unit_strings_follow_the_units_module():
    for ok in ("cm", "s", "cm s-1", "cm+2 s-2", "nm+3", "um+2 s-1", "60 s", "10+3 m", "kg m+2 s-2"):
        assert h5md.unit_string_problem(ok) is None, ok
    for bad in ("", "cm  s", "cm/s", "s 60", "cm cm", "furlong", "cm+0", "cm^2"):
        assert h5md.unit_string_problem(bad) is not None, bad


def test_mdanalysis_reads_every_frame(state):
    pytest.importorskip("MDAnalysis", reason="MDAnalysis not installed (pip install -r requirements-readers.lock)")
    ref = positions(state)
    ref32 = ref.astype(np.float32)  # MDAnalysis keeps coordinates as float32
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        raw = mdanalysis.reader(state, convert_units=False)
        assert raw.n_frames == len(ref) and raw.units["length"] == "cm" and raw.units["time"] == "s"
        seen = [ts.frame for ts in raw if np.array_equal(ts.positions, ref32[ts.frame])]
        assert seen == list(range(len(ref)))  # every frame, bit for bit (fp64: rounded to float32 once)
        converted = mdanalysis.reader(state)  # its defaults: Å and ps
        seen = [ts.frame for ts in converted if np.array_equal(ts.positions, ref32[ts.frame] * np.float32(1e8))]
        assert seen == list(range(len(ref)))  # cm × 1e8 = Å, bit for bit in float32
        raw.close()
        converted.close()


def test_mdanalysis_as_it_stands_names_the_unit(state):
    """The upstream gaps harness.io.mdanalysis works around: MDAnalysis, untaught, stops at the
    first unit it does not know (the fixed-length `s` comes back from h5py as bytes, b's';
    `cm` is not in its tables either). A fresh interpreter: the test above taught this one."""
    pytest.importorskip("MDAnalysis", reason="MDAnalysis not installed (pip install -r requirements-readers.lock)")
    code = (
        "import sys, warnings; warnings.simplefilter('ignore')\n"
        "from MDAnalysis.coordinates.H5MD import H5MDReader\n"
        "try:\n    H5MDReader(sys.argv[1])\nexcept RuntimeError as e:\n    print(e); sys.exit(3)\n"
    )
    p = subprocess.run([sys.executable, "-c", code, str(state)], capture_output=True, text=True)
    if p.returncode == 0:
        pytest.skip("this MDAnalysis reads our units as they are: harness.io.mdanalysis.teach_units can go")
    assert p.returncode == 3 and "is not recognized by H5MDReader" in p.stdout, p.stdout + p.stderr


def test_mdanalysis_refuses_a_dynamic_state_in_one_line(dynamic_state):
    """MDAnalysis pairs every element's k-th entry with position frame k; the dynamic files'
    velocities and observables start at the first simulated frame, so harness.io.mdanalysis
    refuses them instead of handing back velocities of the wrong frames."""
    pytest.importorskip("MDAnalysis", reason="MDAnalysis not installed (pip install -r requirements-readers.lock)")
    with pytest.raises(HarnessError, match="MDAnalysis reads every element at the positions' frames") as e:
        mdanalysis.reader(dynamic_state)
    assert "\n" not in str(e.value)
    mdanalysis.teach_units()  # untaught it stops at the units; taught, it reads frame 0 wrongly or fails
    from MDAnalysis.coordinates.H5MD import H5MDReader

    with open_trajectory(dynamic_state) as t:
        first_velocity = t.velocity(0).reshape(-1, 3).astype(np.float32)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        r = H5MDReader(str(dynamic_state), convert_units=False)
        assert np.array_equal(r.ts.velocities, first_velocity) and r.ts.frame == 0  # frame 0 has no velocity
        r.close()


def export_cmd(state, *args, env=None):
    return subprocess.run(
        [sys.executable, "-m", "harness", "export", str(state), *args],
        cwd=ROOT_DIR,
        capture_output=True,
        text=True,
        env=env,
    )


def export(state, *args):
    """Export beside the state (the module's states are exported by several tests: --force)."""
    p = export_cmd(state, "--force", *args)
    assert p.returncode == 0, p.stderr
    return p


def vtk_frames(xdmf):
    """VTK's XDMF reader (as ParaView and VisIt use it) on `xdmf`: each time step's grid."""
    vtk_xdmf = pytest.importorskip("vtkmodules.vtkIOXdmf2", reason="VTK not installed (pip install vtk)")
    from vtkmodules.vtkCommonCore import vtkLogger
    from vtkmodules.vtkCommonExecutionModel import vtkStreamingDemandDrivenPipeline as SDDP

    vtkLogger.SetStderrVerbosity(vtkLogger.VERBOSITY_OFF)  # "no caching possible" per frame
    r = vtk_xdmf.vtkXdmfReader()
    r.SetFileName(str(xdmf))
    r.UpdateInformation()
    for t in r.GetOutputInformation(0).Get(SDDP.TIME_STEPS()):
        r.UpdateTimeStep(t)
        yield r.GetOutputDataObject(0)


def point_array(grid, name):
    from vtkmodules.util.numpy_support import vtk_to_numpy

    a = grid.GetPointData().GetArray(name)
    return None if a is None else vtk_to_numpy(a)


def test_xdmf_opens_in_vtk_as_polylines_over_time(state):
    pytest.importorskip("vtkmodules.vtkIOXdmf2", reason="VTK not installed (pip install vtk)")
    from vtkmodules.util.numpy_support import vtk_to_numpy

    export(state)
    xdmf = Path(f"{state}.xdmf")
    ref = positions(state)
    assert xdmf.stat().st_size < 4096 * len(ref)  # no inline heavy data
    with open_state(state) as s:
        n, p = s.n_strands, s.points
    grids = 0
    for k, grid in enumerate(vtk_frames(xdmf)):
        grids += 1
        assert grid.GetNumberOfCells() == n
        for c in range(n):
            cell = grid.GetCell(c)
            assert grid.GetCellType(c) == 4  # VTK_POLY_LINE
            assert [cell.GetPointId(i) for i in range(cell.GetNumberOfPoints())] == list(range(c * p, c * p + p))
        pts = vtk_to_numpy(grid.GetPoints().GetData())
        assert pts.dtype == ref.dtype and pts.tobytes() == ref[k].tobytes(), k
        assert np.array_equal(point_array(grid, "strand"), np.repeat(np.arange(n), p))
    assert grids == len(ref)


def test_xdmf_of_a_dynamic_state_carries_velocities_and_rest_shape(dynamic_state):
    pytest.importorskip("vtkmodules.vtkIOXdmf2", reason="VTK not installed (pip install vtk)")
    from vtkmodules.util.numpy_support import vtk_to_numpy

    export(dynamic_state)
    with open_trajectory(dynamic_state) as t:
        ref, rest = positions(dynamic_state), t.rest.reshape(-1, 3)
        velocity = {k: t.velocity_at_step(int(t.step[k])) for k in range(t.n_frames)}
    with_velocity = []
    for k, grid in enumerate(vtk_frames(f"{dynamic_state}.xdmf")):
        assert vtk_to_numpy(grid.GetPoints().GetData()).tobytes() == ref[k].tobytes(), k
        assert point_array(grid, "rest_position").tobytes() == rest.tobytes()
        v = point_array(grid, "velocity")
        assert (v is None) == (velocity[k] is None), k
        if v is not None:
            assert v.dtype == ref.dtype and v.tobytes() == velocity[k].reshape(-1, 3).tobytes(), k
            with_velocity.append(k)
    assert with_velocity == [k for k in velocity if velocity[k] is not None] and with_velocity


def usd_curves(path):
    pytest.importorskip("pxr", reason="usd-core not installed (pip install usd-core)")
    from pxr import Usd, UsdGeom

    stage = Usd.Stage.Open(str(path))
    return stage, UsdGeom.BasisCurves(stage.GetPrimAtPath("/hair/strands"))


def test_usd_basis_curves_one_sample_per_frame(state):
    pytest.importorskip("pxr", reason="usd-core not installed (pip install usd-core)")
    from pxr import UsdGeom

    export(state, "--usd-only")
    ref = positions(state)
    stage, curves = usd_curves(f"{state}.usdc")
    assert UsdGeom.GetStageUpAxis(stage) == UsdGeom.Tokens.y and UsdGeom.GetStageMetersPerUnit(stage) == 0.01
    assert curves.GetTypeAttr().Get() == UsdGeom.Tokens.linear
    counts = list(curves.GetCurveVertexCountsAttr().Get())
    assert sum(counts) == ref.shape[1] and len(set(counts)) == 1
    attr = curves.GetPointsAttr()
    assert attr.GetTimeSamples() == [float(k) for k in range(len(ref))]
    for k in range(len(ref)):
        got = np.array(attr.Get(k), dtype=np.float32)
        assert got.tobytes() == ref[k].astype(np.float32).tobytes(), k  # fp64 states: rounded to fp32
    assert not curves.GetVelocitiesAttr().HasAuthoredValue()


def test_usd_of_a_dynamic_state_carries_velocities_and_rest_shape(dynamic_state):
    pytest.importorskip("pxr", reason="usd-core not installed (pip install usd-core)")
    from pxr import UsdGeom

    export(dynamic_state, "--usd-only")
    stage, curves = usd_curves(f"{dynamic_state}.usdc")
    with open_trajectory(dynamic_state) as t:
        ref, rest = positions(dynamic_state), t.rest.reshape(-1, 3)
        velocity = {k: t.velocity_at_step(int(t.step[k])) for k in range(t.n_frames)}
        frame_dt = float(t.dynamic_params["frame_dt"])
    # time code = frame index, at the simulation's frame rate: velocities (cm/s) agree with it
    assert stage.GetTimeCodesPerSecond() == export_mod.time_codes_per_second_of(frame_dt)
    points = curves.GetPointsAttr()
    for k in range(len(ref)):
        assert np.array(points.Get(k), dtype=np.float32).tobytes() == ref[k].astype(np.float32).tobytes(), k
    vel = curves.GetVelocitiesAttr()
    samples = [k for k in velocity if velocity[k] is not None]
    assert vel.GetTimeSamples() == [float(k) for k in samples] and samples
    for k in samples:
        want = velocity[k].reshape(-1, 3).astype(np.float32)
        assert np.array(vel.Get(k), dtype=np.float32).tobytes() == want.tobytes(), k
    primvar = UsdGeom.PrimvarsAPI(curves).GetPrimvar("rest")
    assert primvar.GetInterpolation() == UsdGeom.Tokens.vertex
    assert np.array(primvar.Get(), dtype=np.float32).tobytes() == rest.astype(np.float32).tobytes()


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


def test_export_refuses_to_replace_sidecars_without_force(state, tmp_path):
    out = tmp_path / "x"
    assert export_cmd(state, "--out", str(out)).returncode == 0
    sidecars = [tmp_path / "x.xdmf", tmp_path / "x.topo.h5"]
    for q in sidecars:
        q.write_text("keep")
    p = export_cmd(state, "--out", str(out))
    assert p.returncode == 2 and p.stderr.count("\n") == 1 and "--force" in p.stderr, p.stderr
    assert "Traceback" not in p.stderr and all(q.read_text() == "keep" for q in sidecars)
    assert sorted(q.name for q in tmp_path.iterdir()) == ["x.topo.h5", "x.xdmf"]
    assert export_cmd(state, "--out", str(out), "--force").returncode == 0
    assert "<Xdmf" in sidecars[0].read_text()


def test_export_usd_without_usd_core_writes_nothing(state, tmp_path):
    """Refused before anything is written (a pxr that cannot be imported stands in for none)."""
    fake = tmp_path / "nopxr" / "pxr"
    fake.mkdir(parents=True)
    (fake / "__init__.py").write_text("raise ImportError('no usd-core here')\n")
    env = dict(os.environ, PYTHONPATH=os.pathsep.join(filter(None, [str(fake.parent), os.environ.get("PYTHONPATH")])))
    out = tmp_path / "out" / "x"
    out.parent.mkdir()
    p = export_cmd(state, "--usd", "--out", str(out), env=env)
    assert p.returncode == 2 and p.stderr.count("\n") == 1 and "usd-core" in p.stderr, p.stderr
    assert list(out.parent.iterdir()) == []


def test_xdmf_times_of_a_dynamic_state_are_seconds(dynamic_state, tmp_path):
    import re

    out = tmp_path / "d"
    assert export_cmd(dynamic_state, "--out", str(out)).returncode == 0
    times = [float(t) for t in re.findall(r'<Time Value="([^"]+)"/>', (tmp_path / "d.xdmf").read_text())]
    with open_trajectory(dynamic_state) as t:
        stored, paper, dt = t.time, t.paper_frames, float(t.dynamic_params["frame_dt"])
    assert len(times) == len(stored) and np.all(np.diff(times) > 0)
    assert times[paper:] == [float(v) for v in stored[paper:]]  # seconds, as stored
    assert times[paper - 1] == 0.0 and times[0] == pytest.approx(-(paper - 1) * dt)
    assert times[paper] == pytest.approx(dt)


def test_usd_frame_rate_is_exact():
    """1/Δt exactly where Δt is the double nearest 1/n (1/(1/60) = 60, not 59.999999999999815)."""
    for n in (24, 30, 60, 120, 240, 1000):
        assert export_mod.time_codes_per_second_of(1.0 / n) == float(n)
    assert export_mod.time_codes_per_second_of(0.0125) == 80.0
    assert export_mod.time_codes_per_second_of(0.3) == 1.0 / 0.3
