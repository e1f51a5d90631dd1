"""`harness compare A B` on synthetic runs whose answer is known: runs.csv files written with the
harness's own row writer from samples drawn with a known spread (1 % relative standard
deviation), two runs of the same distribution (noise alone: nothing flagged, exit 0), a 10 %
slowdown of some cases (exactly those slower, exit 1), a speed-up, a noisy figure, the old
columns (quartiles, no rsd), headline JSON and the bench's steps.json, and the refusals."""

import json
import shutil

import numpy as np
import pytest

from conftest import ROOT
from harness import HarnessError
from harness.check import compare_runs
from harness.cli.main import main
from harness.core import timing
from harness.io import figures, runlog

CASES = 60
STAGES = ("init", "collide", "wind", "collide")
RSD = 0.01  # the synthetic samples' relative spread


def row(case, stage_index, samples, noisy="", with_rsd=True):
    s = timing.stats(samples)
    q1, q3 = np.percentile(samples, [25, 75])
    strands = 1000 * (1 + case)
    out = {
        "case_id": f"paper:cpu:ref:t1:fp32:N{strands}:P32:r9w1",
        "stage_index": stage_index,
        "n_stages": len(STAGES),
        "stage": STAGES[stage_index],
        "scene": "paper",
        "backend": "cpu",
        "variant": "ref",
        "precision": "fp32",
        "threads": 1,
        "strands": strands,
        "points": 32,
        "repeat": 9,
        "warmup": 1,
        "skipped": 0,
        "n_times": s["n"],
        "median_ms": s["median_ms"],
        "min_ms": s["min_ms"],
        "max_ms": s["max_ms"],
        "q1_ms": float(q1),
        "q3_ms": float(q3),
        "iqr_ms": float(q3 - q1),
    }
    if with_rsd:
        out.update(n_samples=s["n"], rsd=s["rsd"], std_ms=s["std_ms"], noisy=noisy)
    return out


def write_run(folder, seed, factor=None, noisy=None, with_rsd=True, samples=10):
    """A run folder whose sweep/runs.csv holds CASES cases × 4 stages; `factor` {case: ×} scales
    a case's true time, `noisy` {case: mark} marks its figures as noise."""
    rng = np.random.default_rng(seed)
    rows = []
    for case in range(CASES):
        for i in range(len(STAGES)):
            true_ms = 0.1 * (1 + case) * (1 + i) * (factor or {}).get(case, 1.0)
            draws = true_ms * np.exp(rng.normal(0.0, RSD, samples))
            rows.append(row(case, i, draws, (noisy or {}).get(case, ""), with_rsd))
    (folder / "sweep").mkdir(parents=True)
    (folder / "sweep" / "runs.csv").write_text(runlog.HEADER + runlog.format_rows(rows))
    return folder


def verdicts(comp):
    t = comp.table
    return {
        v: sorted({int(k.split(":N")[1].split(":")[0]) // 1000 - 1 for k in t.key[t.verdict == v]})
        for v in compare_runs.VERDICTS
    }


def test_noise_alone_is_not_flagged(tmp_path):
    comp = compare_runs.compare(write_run(tmp_path / "a", 1), write_run(tmp_path / "b", 2))
    assert len(comp.table) == CASES * len(STAGES) and not comp.only_a and not comp.only_b
    assert comp.counts() == {"slower": 0, "faster": 0, "within noise": CASES * len(STAGES)}
    assert not comp.failed
    assert set(comp.table.noise_from_a) == {"rsd"} and comp.table.noise_a.between(0.3 * RSD, 3 * RSD).all()


def test_a_ten_percent_slowdown_is_detected_and_fails(tmp_path):
    slow = {3: 1.10, 17: 1.10, 42: 1.10}
    comp = compare_runs.compare(write_run(tmp_path / "a", 1), write_run(tmp_path / "b", 2, factor=slow))
    v = verdicts(comp)
    assert v["slower"] == sorted(slow) and v["faster"] == []
    assert comp.table[comp.table.verdict == "slower"].ratio.between(1.06, 1.14).all()
    assert comp.failed and comp.table.fails.sum() == 3 * len(STAGES)
    # above the threshold only: a 10 % slowdown passes --fail-above 1.2, still said slower
    lenient = compare_runs.compare(tmp_path / "a", tmp_path / "b", fail_above=1.2)
    assert not lenient.failed and lenient.counts()["slower"] == 3 * len(STAGES)


def test_a_speedup_is_faster_and_passes(tmp_path):
    comp = compare_runs.compare(write_run(tmp_path / "a", 1), write_run(tmp_path / "b", 2, factor={5: 0.9}))
    assert verdicts(comp)["faster"] == [5] and verdicts(comp)["slower"] == [] and not comp.failed


def test_a_slowdown_marked_as_noise_is_said_but_does_not_fail(tmp_path):
    b = write_run(tmp_path / "b", 2, factor={8: 1.10}, noisy={8: "others used 1.2 cores"})
    comp = compare_runs.compare(write_run(tmp_path / "a", 1), b)
    assert verdicts(comp)["slower"] == [8] and not comp.failed and comp.noisy_slower() == len(STAGES)
    assert (comp.table[comp.table.verdict == "slower"].noisy == "others used 1.2 cores").all()


def test_old_columns_give_the_noise_from_the_quartiles(tmp_path):
    """A runs.csv from before the stopping rule (no rsd column): σ ≈ IQR/1.349, same verdicts."""
    a = write_run(tmp_path / "a", 1, with_rsd=False, samples=40)
    comp = compare_runs.compare(a, write_run(tmp_path / "b", 2, factor={11: 1.10}, with_rsd=False, samples=40))
    assert set(comp.table.noise_from_a) == {"iqr"} and comp.table.noise_a.between(0.3 * RSD, 3 * RSD).all()
    assert verdicts(comp)["slower"] == [11] and comp.failed


def test_rows_of_one_case_run_twice_are_one_figure_with_their_spread(tmp_path):
    a = write_run(tmp_path / "a", 1)
    csv = a / "sweep" / "runs.csv"
    lines = csv.read_text().splitlines(keepends=True)
    first_case = lines[1 : 1 + len(STAGES)]
    csv.write_text("".join(lines + [x.replace(",0.", ",0.5") for x in first_case[:1]]))
    f = figures.read(a)
    assert len(f) == CASES * len(STAGES)
    pooled = f[f.key.str.startswith("paper:cpu:ref:t1:fp32:N1000:P32 0:")].iloc[0]
    assert pooled.noise_from == "rows" and pooled.noise > 0.1


def test_headline_and_steps_are_figures_too(tmp_path):
    for side, scale in (("a", 1.0), ("b", 1.10)):
        (tmp_path / side / "headline").mkdir(parents=True)
        data = json.loads((ROOT / "results/reference-h200/headline/headline_dynamic.json").read_text())
        data["default"][0]["median_ms"] *= scale
        (tmp_path / side / "headline" / "headline_dynamic.json").write_text(json.dumps(data))
        steps = {"steps": [{"name": "validation", "seconds": 60.0 * scale}, {"name": "sweep default", "seconds": 300}]}
        (tmp_path / side / "steps.json").write_text(json.dumps(steps))
    comp = compare_runs.compare(tmp_path / "a", tmp_path / "b")
    slower = set(comp.table.key[comp.table.verdict == "slower"])
    assert slower == {"default gpu strand median_ms", "step validation"}, slower
    row = comp.table.set_index("key").loc["default gpu strand median_ms"]
    assert row.noise_from_a == "range" and row.ratio == pytest.approx(1.10)


def test_the_committed_reference_against_itself(tmp_path):
    comp = compare_runs.compare(ROOT / "results/reference-h200", ROOT / "results/reference-h200")
    assert len(comp.table) > 2000 and comp.counts()["within noise"] == len(comp.table) and not comp.failed
    assert {"sweep/runs.csv", "dynamic/runs.csv", "headline/headline.json"} <= set(comp.table.source)
    assert comp.a["device"] == "NVIDIA H200"


def test_the_command_exit_codes_and_outputs(tmp_path, capsys):
    a, b = write_run(tmp_path / "a", 1), write_run(tmp_path / "b", 2, factor={3: 1.10})
    assert main(["compare", str(a), str(a)]) == 0
    assert main(["compare", str(a), str(b), "--out", str(tmp_path / "cmp")]) == 1
    out = capsys.readouterr().out
    assert "**4 slower**" in out and "N4000:P32 0:init" in out
    assert sorted(p.name for p in (tmp_path / "cmp").glob("compare.*")) == [
        "compare.csv",
        "compare.json",
        "compare.md",
        "compare.png",
    ]
    record = json.loads((tmp_path / "cmp" / "compare.json").read_text())
    assert record["failed"] and record["counts"]["slower"] == 4 and len(record["figures"]) == CASES * len(STAGES)
    assert main(["compare", str(a / "sweep" / "runs.csv"), str(b / "sweep" / "runs.csv"), "--json"]) == 1
    assert json.loads(capsys.readouterr().out)["counts"]["slower"] == 4


@pytest.mark.parametrize(
    "setup, message",
    [
        (lambda t: (t / "a", t / "a" / "sweep" / "runs.csv"), "two run folders or two files"),
        (lambda t: (t / "a", t / "empty"), "no runs.csv"),
        (lambda t: (t / "a" / "sweep" / "runs.csv", t / "bad.csv"), "not a runs.csv"),
        (lambda t: (t / "a" / "sweep" / "runs.csv", t / "missing.csv"), "no such file"),
    ],
)
def test_refusals_are_one_line_and_write_nothing(tmp_path, capsys, setup, message):
    write_run(tmp_path / "a", 1)
    (tmp_path / "empty").mkdir()
    (tmp_path / "bad.csv").write_text("x,y\n1,2\n")
    a, b = setup(tmp_path)
    assert main(["compare", str(a), str(b), "--out", str(tmp_path / "out")]) == 2
    err = capsys.readouterr().err
    assert message in err and err.count("\n") == 1 and not (tmp_path / "out").exists()


def test_nothing_in_common_and_a_bad_threshold_are_refused(tmp_path, capsys):
    a = write_run(tmp_path / "a", 1)
    other = tmp_path / "o"
    shutil.copytree(a, other)
    csv = other / "sweep" / "runs.csv"
    csv.write_text(csv.read_text().replace("paper:cpu", "dynamic:cpu"))
    with pytest.raises(HarnessError, match="no case in common"):
        compare_runs.compare(a, other)
    with pytest.raises(SystemExit):
        main(["compare", str(a), str(a), "--fail-above", "0.9"])
    assert "must be a finite ratio" in capsys.readouterr().err
