"""The accuracy study on curly hair (configs/scenes/curly.toml) through the dynamic bench and
report/dynamic.md: the bench's step (the studies stubbed: no real run), its own results folder
and page, and the report's section from a tiny real study whose reference does not converge
(the known case on curls, docs/decisions/grooms.md) and without one."""

import pytest

from harness.bench import dynamic as bench_dynamic
from harness.core import variants
from harness.core.budget import Budget
from harness.core.shards import Shard
from harness.render import accuracy_dynamic_report, report_dynamic
from harness.studies import accuracy_dynamic
from harness.studies.accuracy import results_name
from support.accuracy_plans import TINY
from support.bench_stubs import Clock  # the fixture `stubbed` comes from there too (tests/conftest.py)

CURLY = report_dynamic.CURLY_SCENE
HEAD = f"## Speed against accuracy: {report_dynamic.CURLY_TITLE}"


def test_each_scene_has_its_own_folder_and_page():
    assert results_name("dynamic") == accuracy_dynamic_report.RESULTS_NAME == "dynamic-accuracy"
    assert results_name("configs/scenes/dynamic.toml") == "dynamic-accuracy"
    assert results_name(CURLY) == "dynamic-accuracy-curly"
    assert results_name("/tmp/my groom.toml") == "dynamic-accuracy-my-groom"
    straight, curly = accuracy_dynamic_report.Names.of("dynamic"), accuracy_dynamic_report.Names.of(CURLY)
    assert straight.page == accuracy_dynamic_report.PAGE and straight.pareto == accuracy_dynamic_report.PARETO_PNG
    assert curly.page == "dynamic_accuracy_curly.md"
    assert {curly.pareto, curly.growth, curly.steps} == {
        "dynamic_accuracy_curly_pareto.png",
        "dynamic_accuracy_curly_growth.png",
        "dynamic_accuracy_curly_steps.png",
    }


def test_the_bench_runs_the_quick_accuracy_study_on_curly_hair_beside_the_straight_one(stubbed, tmp_path):
    calls, _ = stubbed
    log = []
    bench_dynamic.studies(tmp_path, [], log.append, quick=True)
    assert [p.scene for p, _ in calls] == ["dynamic", CURLY]
    (straight, straight_dir), (curly, curly_dir) = calls
    assert straight_dir == tmp_path / "dynamic-accuracy" and curly_dir == tmp_path / "dynamic-accuracy-curly"
    assert curly == accuracy_dynamic.Plan.quick(gpu="no", scene=CURLY, analytic="none")
    assert straight == accuracy_dynamic.Plan.quick(gpu="no")
    assert "harness: accuracy --model dynamic --scene curly --analytic none --quick --gpu no" in log
    calls.clear()
    bench_dynamic.studies(tmp_path, [], log.append, quick=True, shard=Shard(2, 2))
    assert [p.scene for p, _ in calls] == [CURLY]  # the straight study is shard 1's


@pytest.mark.parametrize("n", [1, 2, 3, 4, 6])
def test_every_study_measured_once_runs_on_exactly_one_of_n_shards(stubbed, tmp_path, n):
    started = {  # the line each study says when it starts
        "featurecost": "harness: featurecost --backend cpu",
        "reduced": "harness: reduced --quick",
        "accuracy": "harness: accuracy --model dynamic --quick",
        f"accuracy {CURLY}": f"harness: accuracy --model dynamic --scene {CURLY}",
        "peer": "harness: peer",
        "world": "harness: world --quick",
    }
    assert set(started) == set(bench_dynamic.ONE_MEASUREMENT_STUDIES)
    ran = {}
    for k in range(1, n + 1):
        log = []
        bench_dynamic.studies(tmp_path / f"s{k}", [], log.append, quick=True, shard=Shard(k, n))
        for study, line in started.items():
            if any(m.startswith(line) for m in log):
                ran.setdefault(study, []).append(k)
        assert any(m.startswith("harness: stability") for m in log)  # every shard runs its cells
    assert ran == {s: [i % n + 1] for i, s in enumerate(bench_dynamic.ONE_MEASUREMENT_STUDIES)}


def test_the_curly_study_is_left_out_with_a_line_when_the_budget_is_spent(stubbed, tmp_path):
    calls, hooks = stubbed
    clock = Clock()
    budget = Budget(100.0, clock=clock, stop_studies=False)  # the fake clock times no child: studies in-process

    def spend(plan):  # the straight study uses the whole budget
        if plan.scene == "dynamic":
            clock.t = 200.0

    hooks.append(spend)
    log = []
    bench_dynamic.studies(tmp_path, [], log.append, quick=True, budget=budget)
    assert [p.scene for p, _ in calls] == ["dynamic"]
    assert f"harness: accuracy {CURLY}: left out to fit the budget (no time left)" in log
    left_out = {e["step"]: e["what"] for e in budget.record()["left_out"]}
    assert left_out.get(f"accuracy {CURLY}") == "the whole study" and "accuracy" not in left_out


# the tiny plan on the curls: one rung pair of the reference, which does not converge there
TINY_CURLY = {
    **TINY,
    **dict(scene=CURLY, strands=3, substeps=(1, 16), time_strands=6, ref_start=32, ref_max=64),
    **dict(ftl_damping=(1.0,), long_seconds=0, ref_extra=0),
}


def test_the_report_renders_curly_hair_from_a_study_whose_reference_did_not_converge(cpu_bin, tmp_path, monkeypatch):
    monkeypatch.setenv("HAIRBENCH_NO_GPU", "1")
    root, rep = tmp_path / "root", tmp_path / "report"
    missing = report_dynamic.build(root, rep).read_text()
    head = missing.index(HEAD)
    section = missing[head:].split("\n## ")[0].strip().splitlines()
    assert section[2].startswith("Not measured with these results (no `") and len(section) == 3
    assert "dynamic-accuracy-curly" in section[2] and "--scene curly" in section[2]

    plan = accuracy_dynamic.Plan(**TINY_CURLY)
    assert accuracy_dynamic.run_study(plan, root / results_name(CURLY), log=lambda *_: None) == 1
    text = report_dynamic.build(root, rep).read_text()
    section = text[text.index(HEAD) :].split("\n## ")[0]
    assert "Not measured" not in section and "**The reference did NOT converge**" in section
    names = accuracy_dynamic_report.Names.of(CURLY)
    assert f"]({names.page})" in section and f"]({names.pareto})" in section
    page = (rep / names.page).read_text()
    assert page.startswith(HEAD) and "**NOT converged**" in page and "Scene `configs/scenes/curly.toml`" in page
    assert "### Analytic checks" not in page  # the default scene's page carries them
    for png in (names.pareto, names.growth, names.steps):
        assert (rep / png).stat().st_size > 5000
    # the straight study's page and pictures are not written, and its section says so
    assert not (rep / accuracy_dynamic_report.PAGE).exists() and not (rep / accuracy_dynamic_report.PARETO_PNG).exists()
    assert "## Speed against accuracy\n\nNot measured with these results" in text


def test_a_groom_study_leaves_out_the_variants_without_per_segment_rest_lengths(monkeypatch):
    def declared(backend, build="default"):
        return variants.Declared(
            backend=backend,
            build=build,
            default_variant="a",
            precisions=("fp32",),
            variants=("a", "b", "c"),
            stages={"a": ("simulate",), "b": ("simulate",), "c": ("init",)},
            max_points={},
            per_segment=("a",),
        )

    monkeypatch.setattr(accuracy_dynamic.variants, "declared", declared)
    straight, none_left = accuracy_dynamic.study_builds(False)
    assert [r.variant for r in straight] == ["a", "b"] and none_left == []
    groom, left = accuracy_dynamic.study_builds(False, groom=True)
    assert [r.variant for r in groom] == ["a"] and left == ["cpu b"]


def test_the_bench_runs_the_curly_sweep_into_its_own_folder_within_its_share(monkeypatch, tmp_path):
    seen = []

    def run_sweep(name, out=None, gpu=None, log=None, announce_skips=None, shard=None, gate=None):
        seen.append((name, out, gpu, shard, gate))
        return [], 0

    monkeypatch.setattr(bench_dynamic, "run_sweep", run_sweep)
    clock = Clock()
    plan = Budget(1000.0, clock=clock)
    assert not bench_dynamic.curly_sweep(tmp_path, "no", lambda m: None, shard=Shard(1, 2), budget=plan)
    name, out, gpu, shard, gate = seen[0]
    assert (name, out, gpu, shard) == ("dynamic-curly", tmp_path / "dynamic-curly", "no", Shard(1, 2))
    assert gate.allowance == pytest.approx(1000.0 * 0.15)


def test_the_report_shows_the_curly_sweep_beside_the_straight_one(cpu_bin, tmp_path):
    sweep = tmp_path / "tiny-curly.toml"
    sweep.write_text(
        'name = "tiny-curly"\nscene = "curly"\nframes = 1\nrepeat = 9\nwarmup = 0\n'
        '[axes]\nstrands = [60]\npoints = [32]\nprecision = ["fp32"]\nsolver = ["xpbd"]\n'
        '[[cpu]]\nvariant = ["ref"]\nthreads = [1]\n'
    )
    root = tmp_path / "run"
    missing = report_dynamic.curly_throughput_lines(root / report_dynamic.CURLY_SWEEP)
    assert any(line.startswith("Not measured") for line in missing)
    bench_dynamic.run_sweep(str(sweep), out=root / report_dynamic.CURLY_SWEEP, gpu="no", log=lambda m: None)
    lines = report_dynamic.curly_throughput_lines(root / report_dynamic.CURLY_SWEEP)
    row = next(line for line in lines if line.startswith("| xpbd | 60 |"))
    assert "cpu ref 1 thread" in row and not any(line.startswith("Not measured") for line in lines)
