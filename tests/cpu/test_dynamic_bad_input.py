"""Bad input to the dynamic model (docs/model.md §3): every new flag, scene key and damaged
dynamic file is refused before any work with one line on stderr, exit status 2, and no
output file (nor a temporary one) left behind; the harness reader refuses the same files in
one line."""

import h5py
import numpy as np
import pytest

from harness.cli.main import main as harness_main
from support.statecheck import run, tmp_leftovers

SMALL = ["--strands", "20", "--points", "8", "--hair-length", "5"]
SIM = ["--stages", "init,collide,simulate"]

# (name, args (with SIM unless they give --stages), text of the one-line message)
FLAG_CASES = [
    ("frames_zero", ["--frames", "0"], "--frames must be at least 1"),
    ("frames_negative", ["--frames", "-1"], "--frames must be at least 1"),
    ("substeps_zero", ["--substeps", "0"], "--substeps must be at least 1"),
    ("iterations_zero", ["--iterations", "0"], "--iterations must be at least 1"),
    ("frame_dt_zero", ["--frame-dt", "0"], "--frame-dt must be a finite number > 0"),
    ("frame_dt_inf", ["--frame-dt", "inf"], "--frame-dt must be finite"),
    ("substep_too_short", ["--frame-dt", "1e-14"], "outside the substep lengths"),
    ("unknown_solver", ["--solver", "rk4"], "--solver must be xpbd, ftl or rigid"),
    ("gravity_inf", ["--gravity", "inf"], "--gravity must be finite"),
    ("gravity_negative", ["--gravity", "-1"], "--gravity must be a finite number >= 0"),
    ("drag_negative", ["--drag", "-1"], "--drag must be a finite number >= 0"),
    ("damping_nan", ["--damping", "nan"], "--damping must be finite"),
    ("stretch_negative", ["--stretch-compliance", "-1"], "--stretch-compliance must be a finite number >= 0"),
    ("bend_inf", ["--bend-compliance", "inf"], "--bend-compliance must be finite"),
    ("shape_nan", ["--shape-compliance", "nan"], "--shape-compliance must be finite"),
    ("shape_range_zero", ["--shape-compliance", "1", "--shape-range", "0"], "--shape-range must be in (0, 1]"),
    ("shape_range_above_one", ["--shape-compliance", "1", "--shape-range", "1.5"], "--shape-range must be in (0, 1]"),
    ("shape_range_alone", ["--shape-range", "0.5"], "--shape-range needs --shape-compliance"),
    ("ftl_damping_above_one", ["--ftl-damping", "2"], "--ftl-damping must be in [0, 1]"),
    ("margin_negative", ["--collision-margin", "-1"], "--collision-margin must be a finite number >= 0"),
    ("wind_speed_negative", ["--wind-speed", "-1"], "--wind-speed must be a finite number >= 0"),
    ("gust_amplitude_negative", ["--gust-amplitude", "-1"], "--gust-amplitude must be a finite number >= 0"),
    ("gust_frequency_negative", ["--gust-frequency", "-2"], "--gust-frequency must be a finite number >= 0"),
    ("gust_wavelength_zero", ["--gust-wavelength", "0"], "--gust-wavelength must be a finite number > 0"),
    ("unknown_motion", ["--head-motion", "spin"], "--head-motion must be still, nod, shake, tilt or track"),
    ("motion_amplitude_nan", ["--motion-amplitude", "nan"], "--motion-amplitude must be finite"),
    ("motion_frequency_negative", ["--motion-frequency", "-1"], "--motion-frequency must be a finite number >= 0"),
    ("output_every_zero", ["--output-every", "0"], "--output-every must be at least 1"),
    ("velocities_unknown", ["--velocities", "some"], "--velocities must be last or all"),
    (
        "flag_without_simulate",
        ["--stages", "init,collide", "--substeps", "2"],
        "--substeps belongs to the simulate stage",
    ),
    ("frames_without_simulate", ["--stages", "init", "--frames", "3"], "belong to the simulate stage"),
    ("motion_without_simulate", ["--stages", "init", "--head-motion", "nod"], "belongs to the simulate stage"),
    ("simulate_not_last", ["--stages", "init,simulate,collide"], "simulate may appear once, as the last stage"),
    ("draw_on_the_cpu", ["--draw", "64x64"], "--draw draws on the GPU: the cuda backend only"),
    ("draw_too_small", ["--draw", "8x64"], "--draw needs WIDTHxHEIGHT in pixels, each 16..16384"),
    ("draw_not_a_size", ["--draw", "64"], "--draw needs WIDTHxHEIGHT in pixels"),
    ("draw_without_simulate", ["--stages", "init", "--draw", "64x64"], "belong to the simulate stage"),
    ("draw_image_without_draw", ["--draw-image", "x"], "--draw-image needs --draw"),
]


def _refused(p, out, tmp_path, text):
    assert p.returncode == 2, p.stderr
    lines = p.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("hairsim-cpu: error: "), p.stderr
    assert text in lines[0], lines[0]
    assert not out.exists()
    assert tmp_leftovers(tmp_path) == []


@pytest.mark.parametrize("name,args,text", FLAG_CASES, ids=[c[0] for c in FLAG_CASES])
def test_bad_dynamic_flags_are_refused(cpu_bin, tmp_path, name, args, text):
    out = tmp_path / "out.h5"
    stages = [] if "--stages" in args else SIM
    p = run(cpu_bin, *SMALL, *stages, *args, "--output", out, check=False)
    _refused(p, out, tmp_path, text)


@pytest.fixture
def dynamic_file(cpu_bin, tmp_path):
    path = tmp_path / "good.h5"
    run(cpu_bin, *SMALL, *SIM, "--frames", "4", "--output", path, "--quiet")
    return path


def _damaged(good, tmp_path, kind):
    path = tmp_path / f"{kind}.h5"
    path.write_bytes(good.read_bytes())
    with h5py.File(path, "r+") as f:
        if kind == "no_rest":
            del f["particles/hair/rest_position"]
        elif kind == "no_velocity":
            del f["particles/hair/velocity"]
        elif kind == "velocity_wrong_shape":
            del f["particles/hair/velocity/value"]
            f["particles/hair/velocity/value"] = np.zeros((1, 7, 3), np.float32)
        elif kind == "no_observables":
            del f["observables"]
    return path


INPUT_CASES = [
    ("no_rest", "rest_position"),
    ("no_velocity", "no stored velocities"),
    ("velocity_wrong_shape", "velocity/value must be"),
    ("no_observables", "/observables must hold"),
]


@pytest.mark.parametrize("kind,text", INPUT_CASES, ids=[c[0] for c in INPUT_CASES])
def test_damaged_dynamic_files_are_refused(cpu_bin, tmp_path, dynamic_file, kind, text, capsys):
    bad = _damaged(dynamic_file, tmp_path, kind)
    out = tmp_path / "out.h5"
    p = run(cpu_bin, "--input", bad, "--stages", "simulate", "--frames", "1", "--output", out, check=False)
    _refused(p, out, tmp_path, text)
    # the harness's reader refuses the same file in one line (exit 2, "could not compare")
    assert harness_main(["diff", str(dynamic_file), str(bad)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("harness: error: cannot compare: ") and "Traceback" not in err[0]


@pytest.mark.parametrize(
    "args,text",
    [
        (["--input-frame", "9"], "--input-frame 9"),
        (["--input-frame", "-3"], "--input-frame must be at least 0"),
        (["--input-frame", "3"], "has no stored velocities"),  # only the last frame has velocities
        (["--gravity", "500"], "--gravity does not match the input file's simulation"),
        (["--solver", "ftl"], "--solver does not match the input file's simulation"),
    ],
    ids=["out_of_range", "negative", "no_velocities", "other_gravity", "other_solver"],
)
def test_bad_resume_is_refused(cpu_bin, tmp_path, dynamic_file, args, text):
    out = tmp_path / "out.h5"
    p = run(cpu_bin, "--input", dynamic_file, "--stages", "simulate", *args, "--output", out, check=False)
    _refused(p, out, tmp_path, text)


def test_a_simulated_frame_only_continues_with_simulate(cpu_bin, tmp_path, dynamic_file):
    out = tmp_path / "out.h5"
    p = run(cpu_bin, "--input", dynamic_file, "--stages", "collide", "--output", out, check=False)
    _refused(p, out, tmp_path, "only simulate can follow it")


# ---- scene files -----------------------------------------------------------------------------

SCENE_CASES = [
    ("frames_zero", "[dynamics]\nframes = 0", "dynamics.frames must be a whole number ≥ 1"),
    ("frames_float", "[dynamics]\nframes = 2.5", "dynamics.frames must be a whole number ≥ 1"),
    ("substeps_zero", "[dynamics]\nsubsteps = 0", "dynamics.substeps must be a whole number ≥ 1"),
    ("iterations_huge", "[dynamics]\niterations = 10000000", "dynamics.iterations must lie in 1 …"),
    ("frame_dt_negative", "[dynamics]\nframe_dt = -0.1", "dynamics.frame_dt must be > 0"),
    ("frame_dt_inf", "[dynamics]\nframe_dt = inf", "dynamics.frame_dt is infinite"),
    ("substep_too_short", "[dynamics]\nframe_dt = 1e-13\nsubsteps = 10", "outside [1e-12, 1000] s"),
    ("solver_unknown", '[dynamics]\nsolver = "rk4"', "dynamics.solver must be one of xpbd, ftl, rigid"),
    ("solver_not_text", "[dynamics]\nsolver = 1", "dynamics.solver must be one of"),
    ("gravity_nan", "[dynamics]\ngravity = nan", "dynamics.gravity is NaN"),
    ("drag_negative", "[dynamics]\ndrag = -1.0", "dynamics.drag must be ≥ 0"),
    ("damping_text", '[dynamics]\ndamping = "lots"', "dynamics.damping must be a number"),
    ("ftl_damping_above_one", "[dynamics]\nftl_damping = 1.5", "dynamics.ftl_damping must be in [0, 1]"),
    ("output_every_zero", "[dynamics]\noutput_every = 0", "dynamics.output_every must be a whole number"),
    ("dynamics_unknown", "[dynamics]\ntimestep = 1", "unknown key 'dynamics.timestep'"),
    ("bend_negative", "[constraints]\nbend_compliance = -1e-6", "constraints.bend_compliance must be ≥ 0"),
    (
        "shape_range_zero",
        "[constraints]\nshape_compliance = 1e-4\nshape_range = 0.0",
        "constraints.shape_range must be in (0, 1]",
    ),
    ("shape_range_alone", "[constraints]\nshape_range = 0.5", "constraints.shape_range needs"),
    ("collider_text", '[constraints]\ncollider = "yes"', "constraints.collider must be true or false"),
    ("constraints_unknown", "[constraints]\nfriction = 0.1", "unknown key 'constraints.friction'"),
    ("wind_speed_negative", "[wind]\nspeed = -1.0", "wind.speed must be ≥ 0"),
    ("gust_wavelength_zero", "[wind]\ngust_wavelength = 0.0", "wind.gust_wavelength must be > 0"),
    ("gust_amplitude_inf", "[wind]\ngust_amplitude = inf", "wind.gust_amplitude is infinite"),
    ("wind_unknown", "[wind]\ngusts = 1.0", "unknown key 'wind.gusts'"),
    ("motion_unknown", '[head]\nmotion = "spin"', "head.motion must be one of still, nod, shake, tilt"),
    ("motion_amplitude_negative", "[head]\nmotion_amplitude = -0.1", "head.motion_amplitude must be ≥ 0"),
    ("dynamics_not_a_table", "dynamics = 3", "'dynamics' must be a table"),
    ("simulate_not_last", 'stages = ["init", "simulate", "collide"]', "must end with simulate"),
    (
        "paper_with_dynamics",
        'model = "paper"\nstages = ["init"]\n[dynamics]\nframes = 3',
        'table [dynamics] belongs to model = "dynamic"',
    ),
    (
        "paper_with_wind_speed",
        'model = "paper"\nstages = ["init"]\n[wind]\nspeed = 1.0',
        "'wind.speed' belongs to model",
    ),
    (
        "paper_with_simulate",
        'model = "paper"\nstages = ["init", "simulate"]',
        "stage 'simulate' needs model = \"dynamic\"",
    ),
]


@pytest.mark.parametrize("name,text,words", SCENE_CASES, ids=[c[0] for c in SCENE_CASES])
def test_bad_dynamic_scene_keys_are_refused(tmp_path, capsys, name, text, words):
    head = "" if "model =" in text else 'model = "dynamic"\n'
    # top-level keys first, then tables (TOML puts keys after a table header inside it)
    scene = tmp_path / "s.toml"
    scene.write_text(head + text + "\n")
    out = tmp_path / "out.h5"
    assert harness_main(["run", str(scene), "--output", str(out)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("harness: error: scene "), err
    assert words in err[0], err[0]
    assert not out.exists()
