"""The hair–hair grid and the body in the studies (docs/model.md §3.16, §3.17): the stability
map's grid and body slices are built and judged, the world study's table has its axes and its
verdict follows its numbers, the sweep's body groups and the refusals. Small: a few strands,
a few frames."""

import math
from dataclasses import replace

import pytest

from harness import HarnessError
from harness.cli.main import main as harness_main
from harness.core import tolerances, variants
from harness.io.sweepfile import SweepError, load_sweep
from harness.render import accuracy_world_dynamic_report as accuracy_world_report
from harness.render import report_dynamic
from harness.studies import accuracy_world_dynamic as accuracy_world
from harness.studies import accuracy_world_verdicts_dynamic as world_verdicts
from harness.studies import stability_dynamic as stability
from harness.studies import stability_slices_dynamic as stability_slices
from harness.studies.stability_slices_dynamic import OFF

CPU = stability.Backend("cpu", "default", variants.declared("cpu").default_variant if variants.names("cpu") else "")


def slice_named(name):
    return next(s for s in stability_slices.SLICES if s.name == name)


def test_the_grid_slices_declare_the_grid_and_off_removes_every_grid_flag():
    on = stability.cell_scene(slice_named("grid-nod"), 32, 4, "xpbd", "fp32", 16, 2)
    assert on.dynamic["--grid"] == 32 and "--grid-friction" in on.dynamic and "--grid-volume" in on.dynamic
    assert on.strands == 64  # the slice's own strands, not the map's
    off = stability.cell_scene(slice_named("grid-nod"), OFF, 4, "xpbd", "fp32", 16, 2)
    assert not any(f.startswith("--grid") for f in off.dynamic)
    dense = stability.cell_scene(slice_named("grid-dense"), 256, OFF, "ftl", "fp64", 16, 2)
    assert dense.strands == 256 and "--grid-volume" not in dense.dynamic and dense.dynamic["--grid"] == 32


def test_the_body_slices_run_the_body_without_its_grid():
    nod = stability.cell_scene(slice_named("body-nod"), 0.3, 8, "xpbd", "fp32", 16, 2)
    assert "--colliders" in nod.dynamic and not any(f.startswith("--grid") for f in nod.dynamic)
    inside = stability.cell_scene(slice_named("body-inside"), 200, 4, "xpbd", "fp32", 16, 2)
    assert not any(f.startswith("--body-") for f in inside.dynamic)  # still from the start
    assert inside.dynamic["--depenetration-speed"] == 200
    assert slice_named("body-inside").settles and not slice_named("body-nod").settles


def test_a_settling_cell_is_judged_by_its_last_frame_against_its_start():
    bound = tolerances.STABILITY_PENETRATION_REL
    assert stability.verdict(0.0, 1.0, 0, settling=(1.0, 0.0)) == "ok"  # deep at the start, out at the end
    assert stability.verdict(0.0, 1.0, 0, settling=(1.0, 2 * bound)) == "penetrating"  # still inside
    assert stability.verdict(0.0, 0.0, 0, settling=(bound / 4, bound / 2)) == "penetrating"  # sinking in
    assert stability.verdict(0.0, 1.0, 0) == "penetrating"  # the worst frame decides elsewhere


# measured on the CPU oracle (16 strands, 60 frames); margins in the comments
KNOWN_CELLS = [
    # a groom started 10.4 cm inside the chest: ftl at S = 64 with the bounded depenetration gets out
    # (last frame 2.9e-4 cm, 34× under the bound); unbounded, xpbd at S = 4 throws points past 2L
    ("body-inside", 200, 64, "ftl", "fp32", "ok"),
    ("body-inside", OFF, 4, "xpbd", "fp32", "escaped"),
    # the 32³ grid in a gale: ftl holds (stretch 0.002), xpbd at I = 2 stretches 1.80 at 16000 cm/s
    ("grid-gale", 32, 2000, "ftl", "fp32", "ok"),
    ("grid-gale", 32, 16000, "xpbd", "fp32", "over-stretched"),
]


@pytest.mark.parametrize("name,row,col,solver,precision,want", KNOWN_CELLS)
def test_world_cells_with_known_verdicts(cpu_bin, name, row, col, solver, precision, want):
    cell = stability.run_cell(slice_named(name), row, col, solver, precision, CPU, stability.STRANDS, stability.FRAMES)
    assert cell["verdict"] == want, cell
    if name == "body-inside":
        assert cell["penetration_start"] > 5.0, cell  # it did start inside the body


TINY = accuracy_world.Plan(strands=4, seconds=0.05, ref_substeps=16, grid_sizes=(8,), sdf_sizes=(16,),
                           contact_margins=(5.0,), time_strands=8, time_frames=1, repeat=1, jobs=2)  # fmt: skip


@pytest.fixture(scope="module")
def world_rows(cpu_bin):
    return accuracy_world.measure(TINY, log=lambda *_: None)


def test_the_world_table_has_every_variant_of_both_axes(world_rows):
    grid = [r for r in world_rows if r["group"] == "grid"]
    body = [r for r in world_rows if r["group"] == "body"]
    assert {(r["grid"], r["rebuild"], r["friction"], r["volume"]) for r in grid if r["variant"] != "off"} == {
        (8, rb, f, v) for rb in ("frame", "substep", "held") for f in ("on", "off") for v in ("on", "off")
    }
    assert {(r["sdf"], r["friction"], r["planes"], r["once"]) for r in body if r["variant"] != "off"} == {
        (16, "on", "off", "off"),
        (16, "off", "off", "off"),
        (16, "on", "5", "off"),
        (16, "on", "off", "on"),
    }
    for r in world_rows:
        assert r["ms_frame"] > 0 and math.isfinite(r["rms_err_L"]) and r["rms_err_L"] > 0, r
        assert r["substeps"] == 8 and r["ref_substeps"] == 16
    assert all(r["cost_ratio"] == 1.0 for r in world_rows if r["variant"] == "off")


@pytest.mark.parametrize("flag,column", [("--contact-planes", "planes"), ("--collide-once", "once")])
def test_a_planes_or_once_row_is_judged_against_the_exact_colliders_reference(tmp_path, monkeypatch, flag, column):
    """the planes (or once) variant runs its own scene in fp32 and its exact twin's at S = ref_substeps in
    fp64"""
    todo = accuracy_world.body_variants(TINY, tmp_path)
    exact = next(v for v in todo if v.columns == dict(sdf=16, friction="on", planes="off", once="off"))
    planes = next(v for v in todo if v.columns.get(column) in ("5", "on"))
    assert planes.scene.dynamic == {**exact.scene.dynamic, flag: 5.0 if column == "planes" else True}
    ran = []

    def fake_run(scene, path, plan, precision, substeps):
        ran.append((scene.dynamic, precision, substeps))
        if len(ran) == 2:
            raise StopIteration
        return path

    monkeypatch.setattr(accuracy_world, "_run", fake_run)
    with pytest.raises(StopIteration):
        accuracy_world.measure_variant(planes, TINY, tmp_path)
    assert ran == [(planes.scene.dynamic, "fp32", 8), (exact.scene.dynamic, "fp64", TINY.ref_substeps)]


def test_a_grid_that_applies_nothing_moves_no_point(world_rows):
    """The grid built with neither friction nor volume changes no bit: its error is the scene's own."""
    off = next(r for r in world_rows if r["group"] == "grid" and r["variant"] == "off")
    idle = [r for r in world_rows if r["group"] == "grid" and r["friction"] == "off" and r["volume"] == "off"]
    idle = [r for r in idle if r["variant"] != "off"]
    assert idle and all(r["rms_err_L"] == off["rms_err_L"] for r in idle)
    active = [r for r in world_rows if r["group"] == "grid" and r["volume"] == "on"]
    assert any(r["rms_err_L"] != off["rms_err_L"] for r in active)


def _row(group, variant, ms, err, **cols):
    base = dict(group=group, variant=variant, grid="", rebuild="", friction="", volume="", sdf="")
    return {**base, **cols, "ms_frame": str(ms), "rms_err_L": str(err), "cost_ratio": str(ms / 1.0)}


def test_the_verdict_follows_the_numbers():
    rows = [
        _row("grid", "off", 1.0, 0.01, grid="off", friction="off", volume="off"),
        _row("grid", "a", 2.0, 0.010, grid="16", rebuild="frame", friction="on", volume="on"),
        _row("grid", "b", 6.0, 0.006, grid="16", rebuild="substep", friction="on", volume="on"),
    ]
    v = world_verdicts.verdict(rows, "grid")
    assert (v.change.cost, v.change.err, v.change.pairs) == (3.0, pytest.approx(0.6), 1)
    assert v.pick["variant"] == "a"  # within 2× of the smallest error, and cheaper
    assert v.held.pairs == 0 and "held" not in accuracy_world_report.verdict(rows, "grid")  # no held rows, no clause
    text = accuracy_world_report.verdict(rows, "grid")
    assert "costs 3.00× the once-a-frame build" in text and "by 0.60×" in text and "is a (2 ms a frame" in text
    held = _row("grid", "h", 1.5, 0.012, grid="16", rebuild="held", friction="on", volume="on")
    v = world_verdicts.verdict([*rows, held], "grid")
    assert (v.held.cost, v.held.err, v.held.pairs) == (0.75, pytest.approx(1.2), 1)
    text = accuracy_world_report.verdict([*rows, held], "grid")
    assert "(held) costs 0.75× the once-a-frame build sampled every substep and moves the error by 1.20×" in text
    rows[1]["rms_err_L"] = str(0.006 * tolerances.WORLD_ACC_ERROR_FACTOR * 1.5)  # now too far from the best
    assert world_verdicts.verdict(rows, "grid").pick["variant"] == "b"
    body = [
        _row("body", "off", 1.0, 0.01, sdf="off", friction="off", planes="off"),
        _row("body", "s on", 3.0, 0.02, sdf="32", friction="on", planes="off"),
        _row("body", "s off", 2.0, 0.04, sdf="32", friction="off", planes="off"),
    ]
    v = world_verdicts.verdict(body, "body")
    assert (v.change.cost, v.change.err, v.pick["variant"], v.sdf) == (1.5, 0.5, "s off", None)
    text = accuracy_world_report.verdict(body, "body")
    assert "friction costs 1.50×" in text and "by 0.50×" in text and "is s off" in text
    assert world_verdicts.verdict([body[0]], "body").pick is None
    planes = _row("body", "s planes", 1.5, 0.03, sdf="32", friction="on", planes="5")
    v = world_verdicts.verdict([*body, planes], "body")
    assert (v.change.cost, v.change.err) == (1.5, 0.5)  # friction's pair is still the exact one
    assert [(m, c.cost, c.err, c.pairs) for m, c in v.planes] == [("5", 0.5, pytest.approx(1.5), 1)]
    text = accuracy_world_report.verdict([*body, planes], "body")
    assert "As contact planes within 5 cm the colliders cost 0.50× the exact ones" in text and "by 1.50×" in text
    assert v.once.pairs == 0 and "Colliding once" not in text  # no once rows, no clause
    once = _row("body", "s once", 2.4, 0.025, sdf="32", friction="on", planes="off", once="on")
    for r in (*body, planes):
        r["once"] = "off"
    v = world_verdicts.verdict([*body, planes, once], "body")
    assert (v.change.cost, v.change.err) == (1.5, 0.5)  # friction's pair is still the every-iteration one
    assert [(m, c.pairs) for m, c in v.planes] == [("5", 1)]
    assert (v.once.cost, v.once.err, v.once.pairs) == (pytest.approx(0.8), pytest.approx(1.25), 1)
    text = accuracy_world_report.verdict([*body, planes, once], "body")
    assert "Colliding once a substep (in the last iteration alone) costs 0.80× colliding in every iteration" in text


def test_the_world_section_renders_from_its_csv(world_rows, tmp_path):
    from harness.io import files

    files.write_csv(tmp_path / accuracy_world.CSV_NAME, accuracy_world.COLUMNS, world_rows)
    text = "\n".join(accuracy_world_report.section(tmp_path))
    assert "8³ substep, friction on, volume on" in text and "SDF 16³, friction off" in text
    assert text.count("| --- |") == 2 and "Rebuilding the grid every substep costs" in text
    missing = "\n".join(accuracy_world_report.section(tmp_path / "none"))
    assert "Not measured" in missing


@pytest.mark.parametrize(
    "changes,words",
    [
        (dict(ref_substeps=8), "--ref-substeps 8 must exceed"),
        (dict(grid_sizes=(1,)), "--grid-sizes"),
        (dict(sdf_sizes=(4,)), "--sdf-sizes"),
        (dict(contact_margins=(0.0,)), "contact planes' margins"),
        (dict(seconds=0.0), "--seconds"),
        (dict(rebuilds=("never",)), "rebuilds"),
    ],
)
def test_a_world_plan_that_measures_nothing_is_refused(changes, words):
    with pytest.raises(HarnessError, match=words) as e:
        accuracy_world.check_plan(accuracy_world.Plan(**changes))
    assert e.value.code == 2


def test_world_refuses_an_out_that_is_a_file_before_measuring(tmp_path, capsys):
    f = tmp_path / "taken"
    f.write_text("mine\n")
    assert harness_main(["world", "--quick", "--out", str(f)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "is not a directory" in err[0]
    assert f.read_text() == "mine\n"


def test_the_dynamic_sweep_runs_the_body_scene_in_its_own_groups():
    sweep = load_sweep("dynamic")
    body = [c for c in sweep.cases() if c.scene == "body"]
    assert body and {c.variant for c in body} == {"ref", "lanes"}
    assert all("--grid" in sweep.scene_of(c).dynamic and "--colliders" in sweep.scene_of(c).dynamic for c in body)
    assert all(sweep.scene_of(c).name == "dynamic" for c in sweep.cases() if c.scene != "body")


@pytest.mark.parametrize(
    "group,words",
    [('scene = "paper"', "is the paper model"), ("scene = 3", "must be a scene name"), ('scene = "nope"', "nope")],
)
def test_a_bad_group_scene_is_refused(tmp_path, group, words):
    p = tmp_path / "s.toml"
    p.write_text(f'scene = "dynamic"\nframes = 1\n[axes]\nstrands = [10]\n[[cpu]]\n{group}\nvariant = ["ref"]\n')
    with pytest.raises((SweepError, HarnessError), match=words):
        load_sweep(str(p))


def test_the_report_keeps_the_body_rows_apart():
    import pandas as pd

    rows = pd.DataFrame({"scene": ["dynamic", "body", "dynamic"], "x": [1, 2, 3]})
    main, world = report_dynamic.split_world(rows)
    assert list(main["x"]) == [1, 3] and list(world["x"]) == [2]
    only = pd.DataFrame({"scene": ["body"], "x": [1]})
    main, world = report_dynamic.split_world(only)
    assert list(main["x"]) == [1] and world.empty


def test_the_default_body_holds_no_root_of_the_default_scene(cpu_bin, tmp_path):
    """The neck clear of the scalp (configs/bodies/default.colliders): no root of the default scene lies
    in a collider of the body at rest (a root inside one holds its strand's first point in it)."""
    from harness.check import colliders_dynamic as colliders
    from harness.core import runner, scenes
    from harness.io.trajectory import open_trajectory

    s = scenes.load_scene("body").with_overrides(strands=1000)
    s = s.__class__(**{**s.__dict__, "dynamic": {**s.dynamic, "--frames": 1}})
    out = tmp_path / "b.h5"
    runner.run_binary(cpu_bin, runner.run_flags(s, "cpu", output=out), timeout=120)
    with open_trajectory(out) as t:
        roots = t.frame(0).astype(float).reshape(t.n_strands, t.points, 3)[:, 0]
        body = [k for k, c in enumerate(t.colliders) if c.frame == "body"]
        # the body in place (its rise over): t large enough that b(t) = 0
        d = colliders.depths(t, roots, 10.0)[body]
    assert (d < 0).all(), float(d.max())


def test_the_sdf_clause_says_when_the_size_changed_nothing():
    rows = [
        _row("body", "a", 2.0, 0.02, sdf="32", friction="on"),
        _row("body", "b", 3.0, 0.02, sdf="64", friction="on"),
    ]
    assert world_verdicts.sdf_change(rows).unchanged
    assert "changed no error" in accuracy_world_report.sdf_clause(world_verdicts.sdf_change(rows))
    rows[1]["rms_err_L"] = "0.01"
    sdf = world_verdicts.sdf_change(rows)
    assert (sdf.lo, sdf.hi, sdf.ratio, sdf.pairs, sdf.unchanged) == ("32", "64", 0.5, 1, False)
    assert "moves the error by 0.50× over the 32³" in accuracy_world_report.sdf_clause(sdf)


def test_without_a_gpu_the_world_study_says_so_and_times_the_cpu_alone(monkeypatch):
    todo = accuracy_world.grid_variants(TINY)[:2]
    assert accuracy_world.gpu_variants(todo, replace(TINY, gpu="no"), log=pytest.fail) == [None, None]
    monkeypatch.setattr(accuracy_world.env, "gpu_status", lambda: (False, "no NVIDIA driver"))
    said = []
    assert accuracy_world.gpu_variants(todo, TINY, log=said.append) == [None, None]
    assert said == ["accuracy-world: no GPU rows: no NVIDIA driver"]


def test_gpu_times_get_their_own_columns():
    rows = [
        {**_row("grid", "off", 1.0, 0.01), "gpu_ms_frame": "0.5", "gpu_cost_ratio": "1.0", "gpu_variant": "lanes",
         "gpu_strands": "1000000"},
        {**_row("grid", "a", 2.0, 0.01), "gpu_ms_frame": "", "gpu_cost_ratio": "", "gpu_variant": ""},
    ]  # fmt: skip
    lines = accuracy_world_report.table(rows, "grid")
    assert lines[0].endswith("GPU ms / frame (1000000 strands) | GPU × off |")
    assert lines[2].endswith("| 0.5 (lanes) | 1.00 |") and lines[3].endswith("| nan (—) | nan |")
    assert "GPU" not in accuracy_world_report.table([_row("grid", "off", 1.0, 0.01)], "grid")[0]
