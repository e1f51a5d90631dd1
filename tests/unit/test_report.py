"""`harness plot` / `harness report` from a small runs.csv: the report builds, says what
ran and what is absent, sets the paper's numbers beside ours, and every PNG is written."""

import json
import shutil

import numpy as np
import pytest

from conftest import ROOT
from harness.cli.main import main
from harness.io import results_data, runlog
from harness.io.results_data import FIGURE_STATE
from support.synthetic import radial_strands, write_state

STAGES = ["init", "collide", "wind", "collide"]


def case_rows(backend, variant, threads, block, strands, pair_ms, precision="fp32", fused=False):
    case_id = f"paper:{backend}:{variant}:t{threads}:b{block}:{precision}:N{strands}:P32"
    rows = []
    for i, st in enumerate(STAGES):
        ms = {"init": pair_ms / 2, "collide": pair_ms / 4, "wind": pair_ms * 3 / 4}[st]
        f = ""
        if fused and i == 2:
            f, ms = "wind+collide", pair_ms
        elif fused and i == 3:
            f, ms = "into-previous", 0.0
        rows.append(
            {
                "case_id": case_id,
                "stage_index": i,
                "n_stages": 4,
                "stage": st,
                "scene": "paper",
                "backend": backend,
                "build": "default" if backend == "cuda" else "",
                "variant": variant,
                "precision": precision,
                "block_size": block or "",
                "threads": threads,
                "strands": strands,
                "points": 32,
                "repeat": 9,
                "warmup": 1,
                "skipped": 0,
                "fused": f,
                "n_times": 9,
                "median_ms": ms,
                "min_ms": ms * 0.9,
                "max_ms": ms * 1.2,
                "q1_ms": ms * 0.95,
                "q3_ms": ms * 1.05,
                "iqr_ms": ms * 0.1,
                "bytes_moved": strands * 32 * 16,
                "achieved_gbps": strands * 32 * 16 / (ms or 1) / 1e6,
                "copy_gbps": 40.0,
                "bandwidth_fraction": 0.1,
                "device": "test",
                "binary": "x",
                "session": 0,
                "finished_at": "now",
            }
        )
    return rows


def write_results(d, gpu):
    d.mkdir(parents=True, exist_ok=True)
    rows = []
    for n in (1000, 10000, 100000, 1000000):
        t1 = n * 6e-4  # ref, 1 thread: 353 ms near N = 588,000
        rows += case_rows("cpu", "ref", "1", 0, n, t1)
        rows += case_rows("cpu", "simd", "all", 0, n, t1 / 8)
        rows += case_rows("cpu", "ref", "1", 0, n, t1 * 1.3, precision="fp64")
        if gpu:
            for b in (32, 64, 256):
                rows += case_rows("cuda", "paper", "", b, n, 0.05 + n * 1e-6 * (1 + (b == 32)))
            rows += case_rows("cuda", "fused", "", 256, n, 0.04 + n * 5e-7, fused=True)
    path = d / "runs.csv"
    path.write_text(runlog.HEADER + runlog.format_rows(rows))
    skipped = (
        []
        if gpu
        else [
            {
                "backends": ["cuda"],
                "builds": ["default"],
                "cases": 12,
                "reason": "no nvidia-smi on PATH: this machine has no NVIDIA GPU",
            }
        ]
    )
    (d / "env.json").write_text(
        json.dumps(
            {
                "sweep": "t",
                "scene": {"head_radius": 10.0, "hair_offset": 0.1, "hair_length": 30.0},
                "sessions": [
                    {
                        "started_at": "now",
                        "host": {"cpu_model": "Test CPU", "cpu_cores": 2},
                        "binaries": {"hairsim-cpu": {"flags": "-O2"}},
                        "bandwidth": {"hairsim-cpu": {"copy_gbps": 40.0}},
                        "skipped": skipped,
                    }
                ],
            }
        )
    )
    (d / FIGURE_STATE).parent.mkdir()
    write_state(d / FIGURE_STATE, radial_strands(60, 16, STAGES), STAGES)
    return d


@pytest.mark.parametrize("gpu", [False, True])
def test_report_builds_with_plots(tmp_path, gpu, capsys):
    results = write_results(tmp_path / "results", gpu)
    out = tmp_path / "report"
    assert main(["report", str(results), "--report-dir", str(out)]) == 0
    md = (out / "report.md").read_text()
    pngs = sorted(p.name for p in out.glob("*.png"))
    for name in (
        "speedup_fp32.png",
        "speedup_fp64.png",
        "block_size_fp32.png",
        "bandwidth_fp32.png",
        "fig1_initialized.png",
        "fig2_after_wind.png",
    ):
        assert name in pngs
        assert (out / name).stat().st_size > 5000
        assert f"]({name})" in md
    assert "no strand count" in md
    assert "353.107" in md and "309.174" in md and "255" in md and "4719.57" in md and "762.796" in md
    assert "stages `init,collide,wind,collide`" in md
    if gpu:
        assert "GPU rows are absent" not in md
        assert "fused: wind + collide ran as one kernel" in md
        assert "GPU paper b32" in md
    else:
        assert "GPU rows are absent**: no nvidia-smi on PATH" in md
        assert "no GPU rows" in md
    # the CPU single-thread curve crosses 353 ms between N = 1e5 and 1e6: interpolated, not extrapolated
    assert "588,512 (interpolated)" in md
    assert "| release, block 32 |" in md


def test_strand_count_at_a_time():
    curve = {1000: 1.0, 10000: 10.0, 100000: 100.0}
    n, how = results_data.strands_at_time(curve, 50.0)
    assert n == pytest.approx(50000, rel=1e-9) and how == "interpolated"
    n, how = results_data.strands_at_time(curve, 400.0)
    assert n == pytest.approx(400000) and how.startswith("extrapolated")
    assert results_data.strands_at_time({}, 5.0) == (None, "no data")
    assert results_data.interp_time(curve, 30000) == pytest.approx(30.0)


def test_report_without_results_is_one_clear_error(tmp_path, capsys):
    assert main(["report", str(tmp_path / "nothing")]) == 2
    err = capsys.readouterr().err
    assert err.startswith("harness: error:") and "runs.csv: no such file" in err


def test_plot_command_writes_only_pngs(tmp_path, capsys):
    results = write_results(tmp_path / "results", gpu=False)
    out = tmp_path / "plots"
    assert main(["plot", str(results), "--report-dir", str(out)]) == 0
    written = sorted(p.name for p in out.iterdir())
    assert written and all(n.endswith(".png") for n in written)
    assert all(np.fromfile(out / n, dtype=np.uint8)[:4].tobytes() == b"\x89PNG" for n in written)


def test_report_of_the_reference_run_with_its_accuracy_study(tmp_path, capsys):
    """`python -m harness report results/reference-h200/sweep` (a copy of it): the accuracy/ beside
    the sweep is rendered into the page, the committed hair state draws Fig. 1/2, and nothing is
    written into the results it reads."""
    results = tmp_path / "reference-h200"
    shutil.copytree(ROOT / "results" / "reference-h200", results)
    before = {p: p.stat().st_mtime_ns for p in results.rglob("*")}
    rep = tmp_path / "rep"
    assert main(["report", str(results / "sweep"), "--report-dir", str(rep)]) == 0
    md = (rep / "report.md").read_text()
    assert "Which mode for which use" in md and "Not measured with these results" not in md
    assert "## Headline: bandwidth fractions and speedups" in md
    assert (rep / "accuracy_pareto.png").stat().st_size > 5000
    assert (rep / "fig1_initialized.png").exists() and (rep / "fig2_after_wind.png").exists()
    assert {p: p.stat().st_mtime_ns for p in results.rglob("*")} == before
    assert capsys.readouterr().out.strip() == f"wrote {rep / 'report.md'}"


def test_both_reports_say_what_a_time_budget_left_out(tmp_path):
    """RUN/budget.json (harness bench --budget) becomes a "Time budget" section in report.md
    and dynamic.md; a run without one has no such section."""
    import json

    from harness.render import report_dynamic, report_paper

    run = tmp_path / "run"
    results = write_results(run / "sweep", False)
    report_paper.build(results, tmp_path / "plain")
    assert "## Time budget" not in (tmp_path / "plain" / "report.md").read_text()
    left = {"step": "sweep default", "what": "8 case(s) at sizes 96000000 (strands × points)", "reason": "over"}
    (run / "budget.json").write_text(json.dumps({"budget_s": 600.0, "used_s": 590.2, "left_out": [left]}))
    for path in (report_paper.build(results, tmp_path / "r"), report_dynamic.build(run, tmp_path / "r")):
        text = path.read_text()
        assert "## Time budget" in text and "budget of 600 s" in text and "used 590 s" in text
        assert "- sweep default: 8 case(s) at sizes 96000000 (strands × points) (over)" in text


def test_a_merged_validation_names_each_checks_shard_and_the_worst_of_each_kind(tmp_path):
    from harness.render.report_paper import validation_section

    def check(what, k, shard):
        return {"what": what, "pair": "fp32↔fp32", "equivalent": True, "max_abs": k * 1e-6, "max_k": k, "over": 0}

    checks = []
    for shard in (1, 2):
        part = [check("cpu fp32 vs cpu fp64", 0.1, shard)]
        for b in range(16):
            part.append(check(f"cuda default fused b{b} fp32 vs cpu", 0.1 + b / 100 + shard / 1000, shard))
        part.append(check("cuda default fused b64 fp32: stage 3 (collide) from the cpu state", 0.05, shard))
        checks += [dict(c, shard=shard) for c in part]
    (tmp_path / "validation.json").write_text(json.dumps({"strands": 2000, "points": 32, "checks": checks}))
    text = "\n".join(validation_section(tmp_path))
    assert "2 shards, each validated on its own node" in text
    rows = [ln for ln in text.splitlines() if ln.startswith("| cpu") or ln.startswith("| cuda")]
    assert rows == [  # in validation.json's order; of equal worst ones, the first
        "| cpu fp32 vs cpu fp64 (shard 1) | fp32↔fp32 | 1e-07 | 0.1 | 0 | ok |",
        "| cuda default fused b64 fp32: stage 3 (collide) from the cpu state (shard 1) "
        "| fp32↔fp32 | 5e-08 | 0.05 | 0 | ok |",
        "| cpu fp32 vs cpu fp64 (shard 2) | fp32↔fp32 | 1e-07 | 0.1 | 0 | ok |",
        "| cuda default fused b15 fp32 vs cpu (shard 2) | fp32↔fp32 | 2.52e-07 | 0.252 | 0 | ok |",
    ]
