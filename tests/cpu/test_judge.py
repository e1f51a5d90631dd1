"""The one-frame judge (docs/judge.md): the scene's spread, and the judge's power on planted
defects and on honest CPU variants at the extremes (harness/studies/judge.py), on tiny scenes.

Needs build/hairsim-cpu-contract (make cpu) and build/planted/ (make planted; `make test`
builds both)."""

import json
import re

import pytest

from conftest import BUILD, ROOT
from harness.check import diff_dynamic
from harness.cli.main import main as harness_main
from harness.io.trajectory import open_trajectory
from harness.studies import judge

CONTRACT = BUILD / "hairsim-cpu-contract"


@pytest.fixture(scope="module")
def contract_bin():
    if not CONTRACT.exists():
        pytest.fail(f"{CONTRACT} is not built: run `make cpu`")
    return CONTRACT


def _reference(cpu_bin, tmp_path_factory, name, precision="fp64", strands=8):
    """The honest reference of one extreme scene, and its last frame to step from."""
    j = judge.Judge(judge.Plan.quick(strands=strands), tmp_path_factory.mktemp("judge_ref"), print)
    ref, frames = j.reference(judge.extreme_scene(name, j.plan), precision)
    return ref, frames[-1]


def test_planted_defects_declared_once():
    """The harness's list of planted defects and the C sources' `#if HB_PLANT == n` hunks name
    the same numbers (the Makefile builds one binary per number found in c_ref)."""
    text = "".join(p.read_text() for p in sorted((ROOT / "c_ref").rglob("*.[ch]")))
    in_c = {int(n) for n in re.findall(r"HB_PLANT == (\d+)", text)}
    assert in_c == set(judge.PLANTS)
    assert sum(p.model == "dynamic" for p in judge.PLANTS.values()) >= 10 and len(judge.EXTREME) >= 20
    assert sum(p.model == "paper" for p in judge.PLANTS.values()) >= 3


def test_spread_is_zero_for_a_bit_identical_build(cpu_bin, tmp_path_factory):
    ref, k = _reference(cpu_bin, tmp_path_factory, "gale")
    sp = diff_dynamic.measure_spread(ref, k, binary=cpu_bin)
    assert sp.position == 0.0 and sp.velocity == 0.0


def test_spread_is_positive_for_the_contraction_build(cpu_bin, contract_bin, tmp_path_factory):
    ref, k = _reference(cpu_bin, tmp_path_factory, "gale")
    sp = diff_dynamic.measure_spread(ref, k, binary=contract_bin)
    assert sp.position > 0.0 and sp.velocity > 0.0
    with open_trajectory(ref) as t:
        assert sp.step == int(t.step[k + 1])
    assert diff_dynamic.measure_spread(ref, k, binary=contract_bin) is sp  # measured once


def test_stepdiff_prints_the_spread_beside_the_error(cpu_bin, contract_bin, tmp_path_factory, capsys):
    ref, k = _reference(cpu_bin, tmp_path_factory, "fast-shake")
    args = ["stepdiff", "--reference", str(ref), "--binary", str(cpu_bin), "--frames", str(k), "--", "--variant"]
    assert harness_main([*args, "simd"]) == 0
    out = capsys.readouterr().out
    assert "spread" in out and "limit" in out and "DYN_SPREAD_K" in out
    row = next(ln for ln in out.splitlines() if ln.split()[:1] == [str(k)])
    spread, limit = (float(x) for x in row.split()[5:7])
    assert spread > 0 and limit >= spread
    assert harness_main([*args[:-2], "--no-spread"]) == 0
    assert "spread not" not in capsys.readouterr().out


@pytest.fixture(scope="module")
def planted_run(contract_bin, tmp_path_factory):
    missing = [n for n in judge.PLANTS if not judge.planted_binary(n).exists()]
    if missing:
        pytest.fail(f"planted builds {missing} missing: run `make planted`")
    plan = judge.Plan.quick(extreme=(), paper_extreme=(), gpu="no")
    return judge.run(plan, out_dir=tmp_path_factory.mktemp("judge_planted"), log=lambda m: None)


@pytest.mark.parametrize("n", sorted(judge.PLANTS))
def test_each_planted_defect_is_caught_on_a_standard_scene(planted_run, n):
    p = planted_run["plants"][str(n)]
    assert p["caught_on"], f"plant {n} ({p['what']}) not caught on any standard scene"


@pytest.fixture(scope="module")
def honest_run(contract_bin, tmp_path_factory):
    out = tmp_path_factory.mktemp("judge_honest")
    summary = judge.run(judge.Plan.quick(plants=(), standard=(), gpu="no"), out_dir=out, log=lambda m: None)
    return summary, out


def test_honest_cpu_variants_pass_the_extreme_scenes(honest_run):
    """Every CPU variant × precision, one frame from the reference on each dynamic extreme scene
    (stepdiff's judge) and whole runs of each paper extreme scene (diff's judge): no false alarm."""
    summary, out = honest_run
    by = summary["by_model"]  # ref and simd × scenes × precisions
    assert by["dynamic"]["honest_runs"] >= 2 * len(judge.EXTREME) * 2
    assert by["paper"]["honest_runs"] >= 2 * len(judge.PAPER_EXTREME) * 2
    assert summary["false_alarms"] == 0, summary["false_alarm_runs"]
    rows = (out / "judge.csv").read_text().splitlines()
    assert len(rows) > summary["honest_runs"] and rows[0].startswith("kind,who,scene")


def test_judge_command_counts_and_report_section(contract_bin, tmp_path, capsys):
    from harness.render import judge_report

    if not judge.planted_binary(1).exists():
        pytest.fail("build/planted is not built: run `make planted`")
    out = tmp_path / "judge"
    argv = ["judge", "--quick", "--gpu", "no", "--plant", "1", "--extreme", "two-points", "--out", str(out)]
    assert harness_main(argv) == 0
    text = capsys.readouterr().out
    assert "caught 1 / 1 planted" in text and "false alarms 0 / 4 honest runs" in text
    s = json.loads((out / "judge.json").read_text())
    assert (s["caught"], s["planted"], s["false_alarms"]) == (1, 1, 0)
    assert s["env"]["git_revision"] and s["env"]["cpu_cores"] >= 1  # where it was measured
    section = "\n".join(judge_report.section(out))
    assert "**1 / 1**" in section and "**0 / 4**" in section
    assert harness_main(["judge", "--extreme", "no-such-scene", "--out", str(tmp_path / "x")]) == 2
