"""`python -m harness accuracy --model dynamic` (harness/studies/accuracy_dynamic.py measures,
accuracy_dynamic_report.py renders): the machinery at a tiny size. The study itself (its numbers)
belongs to `make bench`, not here."""

import csv
import json
import os
import signal
import subprocess
import sys
import time

import numpy as np
import pytest

from harness.cli import main as cli
from harness.core import env, tolerances, variants
from harness.core.paths import ROOT
from harness.render import accuracy_dynamic_report
from harness.studies import accuracy_dynamic
from harness.studies import accuracy_rows_dynamic as accuracy_rows
from harness.studies import observables_long_dynamic as observables_long
from support.accuracy_plans import TINY
from support.cuda_standin import install


def test_frame_errors_of_a_known_difference():
    ref = np.zeros((3, 2, 3, 3))  # 3 frames, 2 strands × 3 points
    x = ref.copy()
    x[1, 0, 2] = (3.0, 4.0, 0.0)  # one point 5 away in frame 1
    x[2, 1, 1, 0] = np.nan  # frame 2 not finite
    rms, mx = accuracy_dynamic.frame_errors(x, ref, L=10.0)
    assert rms[0] == 0 and mx[0] == 0
    assert mx[1] == pytest.approx(0.5) and rms[1] == pytest.approx(np.sqrt(25 / 6) / 10)
    assert np.isnan(rms[2]) and np.isnan(mx[2])


def test_the_grid_holds_both_sides_of_small_steps_against_iterations():
    assert accuracy_dynamic.grid((1, 4), (1, 2)) == [(1, 1), (1, 2), (1, 4), (4, 1), (4, 2)]
    assert (1, 8) in accuracy_dynamic.grid((2, 8), (2,)) and (8, 1) in accuracy_dynamic.grid((2, 8), (2,))


def test_convergence_is_detected_frame_by_frame():
    errors = {
        "a": np.array([1e-2, 2e-2, 4e-2, 8e-2]),
        "b": np.array([2e-3, np.nan, 5e-2, 1e-2]),
        "c": np.full(4, np.nan),
    }
    low = accuracy_dynamic.smallest(errors)
    assert np.allclose(low, [2e-3, 2e-2, 4e-2, 1e-2])
    diff = np.array([1e-4, 1e-3, 5e-3, 1e-3])  # the reference's S against 2S
    ok = accuracy_dynamic.reference_ok(diff, low, 0.1)
    assert ok.tolist() == [True, True, False, False]  # 1e-3 < 2e-3 holds; 5e-3 < 4e-3 does not; 1e-3 < 1e-3 does not
    times = np.array([0.1, 0.2, 0.3, 0.4])
    assert accuracy_dynamic.holds_until(ok, times) == 0.2
    assert accuracy_dynamic.holds_until(np.ones(4, bool), times) == 0.4
    assert accuracy_dynamic.holds_until(np.array([False, True, True, True]), times) == 0.0
    assert not accuracy_dynamic.reference_ok(np.array([np.nan]), np.array([1.0]), 0.1)[0]


def test_pareto_front_selection():
    t = [1.0, 2.0, 3.0, 4.0, 4.0, 5.0, 6.0, np.nan]
    e = [10.0, 5.0, 6.0, 1.0, 0.5, 0.499, np.nan, 0.1]
    # (3, 6) is beaten by (2, 5); (4, 1) by (4, 0.5); NaNs are never on the front
    assert accuracy_rows.pareto_front(t, e).tolist() == [True, True, False, False, True, True, False, False]
    # with a tie of 1 %, 0.499 is no better than 0.5: the slower mode leaves the front
    assert accuracy_rows.pareto_front(t, e, tie=0.01).tolist()[5] is False


@pytest.mark.parametrize(
    "argv, says",
    [
        (["--model", "dynamic", "--resolution", "4", "8"], "--resolution is an option of the paper"),
        (["--quick"], "--quick is an option of the dynamic"),
        (["--model", "paper", "--scene", "dynamic"], "dynamic-model scene"),
        (["--model", "dynamic", "--scene", "paper"], "paper-model scene"),
        (["--model", "dynamic", "--horizon", "2", "--seconds", "1"], "--horizon 2 must be > 0 and at most"),
        (["--model", "dynamic", "--ref-start", "16"], "--ref-start 16 must exceed the largest --substeps (32)"),
        (["--model", "dynamic", "--ref-start", "64", "--ref-max", "100"], "--ref-max 100 must be at least twice"),
        (["--model", "dynamic", "--substeps", "0"], "must be at least 1"),
        (["--model", "dynamic", "--seconds", "nan"], "finite number of seconds"),
        (["--model", "dynamic", "--horizon", "0.001"], "shorter than one frame"),
        (["--model", "dynamic", "--scene", "nonesuch"], "no scene 'nonesuch'"),
    ],
)
def test_bad_options_are_refused_in_one_line_with_exit_2(argv, says, capsys, tmp_path):
    try:
        rc = cli.main(["accuracy", *argv, "--out", str(tmp_path / "out"), "--report-dir", str(tmp_path / "rep")])
    except SystemExit as e:
        rc = e.code
    err = capsys.readouterr().err.strip().splitlines()
    assert rc == 2 and len(err) == 1 and says in err[0], err
    assert not (tmp_path / "out").exists() and not (tmp_path / "rep").exists()


@pytest.fixture
def quiet():
    return lambda *_: None


def test_a_tiny_study_writes_its_table_report_and_refuses_to_overwrite(cpu_bin, tmp_path, quiet, monkeypatch):
    monkeypatch.setenv("HAIRBENCH_NO_GPU", "1")
    out, rep = tmp_path / "out", tmp_path / "rep"
    rc = accuracy_dynamic.run_study(accuracy_dynamic.Plan(**TINY), out, log=quiet)
    assert rc == 0 and not rep.exists()  # measuring only: the renderer draws
    accuracy_dynamic_report.write(out, rep)
    with open(out / accuracy_dynamic.CSV_NAME, newline="") as fh:
        reader = csv.DictReader(fh)
        rows = list(reader)
    assert tuple(reader.fieldnames) == accuracy_dynamic.COLUMNS
    cpu = variants.declared("cpu")
    # per variant and precision: xpbd at (1,1) (2,1) (1,2), ftl there at each s, the no-simulation mode once
    per = {"xpbd": 3, "ftl": 3 * len(TINY["ftl_damping"]), "rigid": 1}
    n_modes = sum(per[s] for v in cpu.running("simulate") for s in cpu.solvers_of(v)) * len(cpu.precisions)
    mode_rows = [r for r in rows if r["study"] == "mode"]
    assert len(mode_rows) == n_modes * 2  # two frames each
    assert all(float(r["time_per_frame_ms"]) > 0 and float(r["rms_err_L"]) > 0 for r in mode_rows)
    assert {r["verdict"] for r in mode_rows} == {"ok"}
    assert {r["ftl_damping"] for r in mode_rows if r["solver"] == "ftl"} == {"0.9", "1.0"}
    rigid = [r for r in mode_rows if r["solver"] == "rigid"]
    assert {r["variant"] for r in rigid} == {cpu.default_variant}  # the only variant that declares it
    assert all(0 < float(r["iou_front"]) <= 1 and float(r["kinetic"]) >= 0 for r in mode_rows)
    errs = [r for r in rows if r["study"] == "ref_error"]
    assert len(errs) == 2 and all(float(r["rms_err_L"]) >= 0 for r in errs)
    with open(out / "observables.csv", newline="") as fh:
        long = list(csv.DictReader(fh))
    assert {r["study"] for r in long} == {"mode", "reference"}
    assert {r["metric"] for r in long} == set(observables_long.METRICS) | set(observables_long.REFERENCE_ONLY)
    with open(out / "ensemble.csv", newline="") as fh:
        ens = list(csv.DictReader(fh))
    assert {r["study"] for r in ens} == {"mode", "member"}
    assert {r["mode"] for r in ens if r["study"] == "mode"} == {r["mode"] for r in mode_rows}
    ladder = [r for r in rows if r["study"] == "reference"]
    assert ladder and all(int(r["ref_substeps"]) == 2 * int(r["substeps"]) for r in ladder)
    meta = json.loads((out / "env.json").read_text())["study"]
    assert meta["predictability"]["twins"] == tolerances.DYN_LYAPUNOV_TWINS and len(meta["ensemble"]) >= 2
    assert meta["reference"]["converged"] and meta["reference"]["substeps"] == max(
        int(r["ref_substeps"]) for r in ladder
    )
    page = (rep / accuracy_dynamic_report.PAGE).read_text()
    for heading in (
        "Predictability",
        "What survives chaos: statistics against the reference ensemble",
        "The converged reference",
        "The no-simulation baseline",
        "Small steps against iterations",
        "What a user sees over seconds",
        "Which settings for which use",
    ):
        assert f"### {heading}" in page
    assert "**Converged**" in page and "No GPU reference: not used: HAIRBENCH_NO_GPU is set" in page
    for png in (
        accuracy_dynamic_report.PARETO_PNG,
        accuracy_dynamic_report.GROWTH_PNG,
        accuracy_dynamic_report.STEPS_PNG,
    ):
        assert (rep / png).stat().st_size > 5000
    assert not (out / "states").exists()
    # the convergence table re-derived from the CSV agrees with what the study decided
    table = accuracy_dynamic_report.section(out, rep, write_page=False)
    assert any("converged over the" in ln for ln in table)
    # --from-csv re-renders (the model read from the CSV's header), elsewhere
    assert (
        cli.main(["accuracy", "--from-csv", str(out / accuracy_dynamic.CSV_NAME), "--report-dir", str(tmp_path / "r2")])
        == 0
    )
    assert (tmp_path / "r2" / accuracy_dynamic_report.PAGE).read_text() == page
    before = (out / accuracy_dynamic.CSV_NAME).read_bytes()
    with pytest.raises(accuracy_dynamic.HarnessError, match="exists: pass --force"):
        accuracy_dynamic.run_study(accuracy_dynamic.Plan(**TINY), out, log=quiet)
    assert (out / accuracy_dynamic.CSV_NAME).read_bytes() == before


def test_modes_that_differ_only_in_ftl_damping_share_one_timed_run(cpu_bin, tmp_path, quiet, monkeypatch):
    """s is one factor of ftl's velocity update (no kernel branches on it): the study times
    each build × solver × S × I × precision once, and the modes alike but for s take its time."""
    monkeypatch.setenv("HAIRBENCH_NO_GPU", "1")
    timed, real = [], accuracy_dynamic.Study.timed_flags

    def counting(self, mode, repeat=None):  # the flags of each timed run (TINY: one round)
        timed.append(mode)
        return real(self, mode, repeat)

    monkeypatch.setattr(accuracy_dynamic.Study, "timed_flags", counting)
    out = tmp_path / "out"
    assert accuracy_dynamic.run_study(accuracy_dynamic.Plan(**TINY), out, log=quiet) == 0
    with open(out / accuracy_dynamic.CSV_NAME, newline="") as fh:
        modes = {r["mode"]: r for r in csv.DictReader(fh) if r["study"] == "mode"}
    keys = {m.timing_key for m in timed}
    assert len(timed) == len(keys) < len(modes)  # each key once, fewer than the modes
    ftl = [r for r in modes.values() if r["solver"] == "ftl"]
    by_key = {}
    for r in ftl:
        key = (r["variant"], r["precision"], r["substeps"], r["iterations"])
        by_key.setdefault(key, set()).add((r["ftl_damping"], r["time_per_frame_ms"]))
    assert all(len(v) == len(TINY["ftl_damping"]) for v in by_key.values())  # every s is a mode of its own
    assert all(len({t for _, t in v}) == 1 for v in by_key.values())  # and they share one time


def test_ctrl_c_in_the_study_ends_it_in_one_line_and_leaves_no_process(cpu_bin, tmp_path):
    """Ctrl-C (SIGINT to the process group, as a terminal sends it) while the study's reader
    processes are up: one line, exit 130, no traceback from any worker, none left running."""
    argv = [sys.executable, "-m", "harness", "accuracy", "--model", "dynamic", "--quick", "--gpu", "no"]
    argv += ["--out", str(tmp_path / "out"), "--report-dir", str(tmp_path / "rep")]
    env_ = dict(os.environ, PYTHONUNBUFFERED="1")
    # a shell's background job ignores SIGINT (a CI runner's may): the study gets it as a terminal delivers it
    proc = subprocess.Popen(argv, cwd=ROOT, env=env_, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                            start_new_session=True,
                            preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL))  # fmt: skip
    for line in proc.stdout:
        if "dynamic accuracy: reference cpu ref S = 64:" in line:  # its first comparison next
            break
    os.killpg(proc.pid, signal.SIGINT)
    out, err = proc.communicate(timeout=120)
    assert proc.returncode == 130, err
    assert "Traceback" not in err and err.strip().splitlines()[-1] == "harness: interrupted", err
    deadline = time.monotonic() + 10
    while time.monotonic() < deadline:  # every process of its group has ended
        try:
            os.killpg(proc.pid, 0)
        except ProcessLookupError:
            break
        time.sleep(0.1)
    else:
        pytest.fail("a process of the study outlived it")
    assert not (tmp_path / "out" / accuracy_dynamic.CSV_NAME).exists()


def test_the_reference_that_does_not_converge_says_so(cpu_bin, tmp_path, quiet, monkeypatch):
    monkeypatch.setenv("HAIRBENCH_NO_GPU", "1")
    plan = accuracy_dynamic.Plan(
        **{**TINY, "substeps": (1, 16), "ref_start": 32, "ref_max": 64, "long_seconds": 0, "ref_extra": 0}
    )
    assert accuracy_dynamic.run_study(plan, tmp_path / "o", log=quiet) == 1
    accuracy_dynamic_report.write(tmp_path / "o", tmp_path / "r")
    assert "**NOT converged**" in (tmp_path / "r" / accuracy_dynamic_report.PAGE).read_text()


@pytest.fixture
def standin_build(tmp_path, monkeypatch, cpu_bin):
    def make(perturb):
        d = tmp_path / ("build-perturbed" if perturb else "build")
        install(d, cpu_bin, perturb=perturb)
        monkeypatch.setenv("HAIRBENCH_BUILD_DIR", str(d))
        monkeypatch.delenv("HAIRBENCH_NO_GPU", raising=False)
        monkeypatch.setattr(env, "gpu_status", lambda: (True, "stand-in GPU"))
        variants.clear_cache()
        return d

    yield make
    variants.clear_cache()


@pytest.mark.parametrize("perturb", [False, True], ids=["gpu-agrees", "gpu-disagrees"])
def test_gpu_modes_and_the_gpu_reference_check(standin_build, tmp_path, quiet, perturb):
    """The GPU path on a stand-in cuda binary (tests/support/cuda_standin.py): GPU modes of
    the variant that runs simulate only, and a GPU fp64 reference used only when it agrees
    with the CPU's (tolerances.DYN_ACC_GPU_REF_SHARE)."""
    standin_build(perturb)
    out = tmp_path / "out"
    plan = accuracy_dynamic.Plan(
        **{**TINY, "iterations": (1,), "substeps": (1,), "ftl_damping": (1.0,), "long_seconds": 0, "ref_extra": 0}
    )
    assert accuracy_dynamic.run_study(plan, out, log=quiet) == 0
    with open(out / accuracy_dynamic.CSV_NAME, newline="") as fh:
        rows = list(csv.DictReader(fh))
    gpu = {r["variant"] for r in rows if r["study"] == "mode" and r["backend"] == "cuda"}
    assert gpu == {"strand"}
    check = [r for r in rows if r["study"] == "gpu_check"]
    assert len(check) == 2
    ref = json.loads((out / "env.json").read_text())["study"]["reference"]
    if perturb:
        assert float(check[-1]["rms_err_L"]) > 0
        assert ref["backend"] == "cpu" and ref["gpu_check"].startswith("rejected")
    else:
        assert all(float(r["rms_err_L"]) == 0 for r in check)
        assert ref["backend"] == "cuda" and ref["gpu_check"] == "validated"
    assert ref["gpu_share"] == tolerances.DYN_ACC_GPU_REF_SHARE


@pytest.mark.gpu
def test_a_tiny_study_on_the_gpu(tmp_path, quiet):
    """With a real GPU: every cuda build's simulate variants take part, and the GPU fp64
    reference is validated against the CPU (or rejected, which the report then says)."""
    out = tmp_path / "out"
    plan = accuracy_dynamic.Plan(**{**TINY, "strands": 64, "time_strands": 4096})
    assert accuracy_dynamic.run_study(plan, out, log=quiet) == 0
    with open(out / accuracy_dynamic.CSV_NAME, newline="") as fh:
        rows = list(csv.DictReader(fh))
    builds = {(r["build"], r["variant"]) for r in rows if r["study"] == "mode" and r["backend"] == "cuda"}
    assert builds and all(v in variants.declared("cuda", b).running("simulate") for b, v in builds)
    assert [r for r in rows if r["study"] == "gpu_check"]
    ref = json.loads((out / "env.json").read_text())["study"]["reference"]
    assert ref["gpu_check"] in ("validated",) or ref["gpu_check"].startswith("rejected")
