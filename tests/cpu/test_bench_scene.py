"""`make bench SCENE=my.toml` (harness bench --scene, harness/bench/scene.py) end to end on the CPU,
its sizes made tiny: a user's scene is validated, swept, studied for accuracy, its budget curves
timed and its stability mapped, into its own folder and report; `harness budget` then answers
from that folder; and what the bench cannot run is refused in one line."""

import json

import pytest

from conftest import ROOT
from harness.bench import dynamic as bench_dynamic
from harness.cli.main import main as harness_main
from harness.core import timing
from harness.studies import accuracy_dynamic
from harness.studies import budget_curves_dynamic as budget_curves
from harness.studies import stability_dynamic as stability
from support.accuracy_plans import TINY

SCENE = """description = "a user's groom: curls, a fine fibre"
model = "dynamic"
stages = ["init", "simulate"]
groom = "curly"
[hair]
points = 32
length = 20.0
[fibre]
preset = "fine"
[dynamics]
substeps = 4
iterations = 1
damping = 0.5
[constraints]
shape_compliance = 1e-4
"""
SWEEP = """name = "tiny"
scene = "dynamic"
frames = 1
repeat = 9
[axes]
strands = [20, 40]
points = [32]
solver = ["xpbd", "ftl"]
[cpu]
variant = ["ref"]
threads = ["all"]
"""


@pytest.fixture
def tiny(tmp_path, monkeypatch):
    """The bench's sizes cut to seconds: validation at 20 strands, a two-size sweep, the tiny
    accuracy plan, curves at 20 and 40 strands with one timed round, a 2-strand stability map."""
    monkeypatch.setenv("HAIRBENCH_NO_GPU", "1")
    (tmp_path / "sweep.toml").write_text(SWEEP)
    monkeypatch.setattr(bench_dynamic, "SWEEP", str(tmp_path / "sweep.toml"))
    monkeypatch.setattr(bench_dynamic, "VALIDATION_STRANDS", 20)
    plan = {k: v for k, v in TINY.items() if k != "analytic"}
    monkeypatch.setattr(accuracy_dynamic.Plan, "quick", classmethod(lambda cls, **c: cls(**{**plan, **c})))
    monkeypatch.setattr(budget_curves, "LADDER", (20, 40))
    monkeypatch.setattr(timing, "RULE", timing.fixed(3))
    real = stability.run_study
    monkeypatch.setattr(stability, "run_study", lambda **k: real(**k, strands=2, frames=3, slices=()))
    scene = tmp_path / "my groom.toml"
    scene.write_text(SCENE)
    return scene


def test_the_studies_run_on_the_users_scene_into_its_own_folder_and_report(cpu_bin, tiny, tmp_path, capsys):
    out = tmp_path / "run"
    assert harness_main(["bench", "--scene", str(tiny), "--out", str(out), "--gpu", "no"]) == 0
    page = (out / "report" / "scene.md").read_text()
    for head in ("# hairbench: my groom", "## Validation", "## Throughput over strand counts",
                 "## Speed against accuracy: my groom", "## Frame budget → settings", "Stability"):  # fmt: skip
        assert head in page, head
    assert "Host load" in page or "This host was loaded" in page
    assert json.loads((out / "host.json").read_text())["cpu_cores"] >= 1
    assert "12 comparisons, 12 equivalent" in page  # 2 precisions × 3 solvers... of this scene
    curves = (out / "budget-curves-my-groom" / "curves.csv").read_text().splitlines()
    assert len(curves) > 2 and all(",20," in ln or ",40," in ln for ln in curves[1:])
    capsys.readouterr()
    args = ["budget", "--scene", str(tiny), "--run", str(out), "--strands", "30", "--frame-ms", "1000"]
    assert harness_main(args) == 0
    said = capsys.readouterr().out
    assert "interpolated between 20 and 40" in said and "RMS error" in said and "- CPU (" in said


@pytest.mark.parametrize(
    "extra,says",
    [
        (["--model", "paper"], "drop --model"),
        (["--shard", "1/2"], "drop --shard"),
    ],
)
def test_options_of_the_default_bench_are_refused_with_a_scene(tiny, tmp_path, capsys, extra, says):
    assert harness_main(["bench", "--scene", str(tiny), "--out", str(tmp_path / "r"), *extra]) == 2
    assert says in capsys.readouterr().err and not (tmp_path / "r").exists()


def test_a_paper_scene_is_refused(tmp_path, capsys):
    assert harness_main(["bench", "--scene", "paper", "--out", str(tmp_path / "r")]) == 2
    assert "a paper-model scene" in capsys.readouterr().err and not (tmp_path / "r").exists()


def test_a_groom_file_times_its_modes_at_its_own_strand_count(tmp_path):
    """A HAIR groom holds its strands and no more (docs/model.md §3.15): the accuracy study asked
    to time 1,000 strands of the 256-strand example groom times them at 256 and says so (found
    by the GPU node's `bench --scene` on the example groom, which stopped with exit 2)."""
    scene = tmp_path / "mine.toml"
    example = ROOT / "configs" / "grooms" / "example.hair"
    scene.write_text(SCENE.replace('groom = "curly"', f'groom = "{example}"').replace("points = 32", "points = 24"))
    said = []
    plan = accuracy_dynamic.Plan(**{**TINY, "time_strands": 1000, "scene": str(scene)})
    study = accuracy_dynamic.Study(plan, tmp_path / "acc", said.append)
    assert study.plan.time_strands == 256
    assert any("the groom holds 256 strands" in s for s in said), said
    small = accuracy_dynamic.Study(accuracy_dynamic.Plan(**{**TINY, "scene": str(scene)}), tmp_path / "b", said.append)
    assert small.plan.time_strands == TINY["time_strands"]
