"""The harness's rows of the second fault probe (issue #46): signals forwarded to every child
and waited for, every input through one guarded opener, grooms from USD named as the user named
them, TOML that is not TOML, merges that know a shard's completeness, result folders owned by one
run at a time, writes whole or not at all on a full disk. Each test failed before its fix."""

import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest
from test_fault_probe import harness, no_traceback, temporaries, wait_for_child

from harness.core import runner
from support import fulldisk
from support.sweeps import sweep_toml

ROOT = Path(__file__).resolve().parents[2]


def one_line(p, code=2, words=None):
    no_traceback(p)
    lines = p.stderr.strip().splitlines()
    assert p.returncode == code and len(lines) == 1, (p.returncode, p.stderr)
    assert words is None or words in lines[0], lines[0]
    return lines[0]


def alive(pid):
    try:
        with open(f"/proc/{pid}/stat") as f:
            return f.read().rsplit(")", 1)[1].split()[0] != "Z"
    except OSError:
        return False


def child_pids(pid):
    out = []
    for p in filter(str.isdigit, os.listdir("/proc")):
        try:
            with open(f"/proc/{p}/stat") as f:
                if int(f.read().rsplit(")", 1)[1].split()[1]) == pid:
                    out.append(int(p))
        except (OSError, ValueError, IndexError):
            pass
    return out


# ---- D1: every terminating signal forwarded to the child's group, waited for ---------------


def default_signals():
    """In the child: every forwarded signal back to its default. The harness keeps a signal its caller
    ignores ignored (nohup; a background job of a script ignores SIGINT and SIGQUIT), so a suite run
    from one would otherwise test nothing."""
    for s in runner.FORWARDED:
        signal.signal(s, signal.SIG_DFL)


@pytest.mark.parametrize("sig", [signal.SIGTERM, signal.SIGHUP, signal.SIGQUIT, signal.SIGINT], ids=lambda s: s.name)
def test_signal_to_the_harness_stops_its_binary(cpu_bin, tmp_path, sig):
    out = tmp_path / "x.h5"
    out.write_bytes(b"mine")
    proc = subprocess.Popen(
        [sys.executable, "-m", "harness", "run", "dynamic", "--strands", "2000", "--frames", "4000", "--threads", "1"]
        + ["--output", str(out), "--force"],
        cwd=ROOT,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        preexec_fn=default_signals,
    )
    # the simulation itself: the harness first asks the binary for its limits (a child that exits at once)
    assert wait_for_child(proc, "hairsim-cpu", timeout=60, also="--strands")
    kids = child_pids(proc.pid)
    time.sleep(0.3)
    proc.send_signal(sig)
    _, err = proc.communicate(timeout=60)
    assert proc.returncode == 128 + sig, (proc.returncode, err)
    assert len(err.strip().splitlines()) == 1 and "Traceback" not in err, err
    assert kids and not any(alive(k) for k in kids), kids
    assert out.read_bytes() == b"mine" and temporaries(tmp_path) == []


# ---- D3: every input of the harness through one opener --------------------------------------


@pytest.fixture
def fifo(tmp_path):
    path = tmp_path / "ff"
    os.mkfifo(path)
    return path


@pytest.mark.parametrize(
    "args",
    [
        ["diff", "{f}", "{f}"],
        ["stability", "--from-csv", "{f}", "--report-dir", "{t}/rep"],
        ["accuracy", "--from-csv", "{f}", "--report-dir", "{t}/rep"],
        ["export", "{f}", "--out", "{t}/e"],
        ["run", "{f}"],
        ["sweep", "{f}", "--out", "{t}/s"],
    ],
    ids=lambda a: a[0] + (a[1] if a[1].startswith("--") else ""),
)
def test_fifo_input_refused_without_waiting(tmp_path, fifo, args):
    words = [a.format(f=fifo, t=tmp_path) for a in args]
    p = harness(*words, timeout=30)
    line = one_line(p, words="FIFO")
    assert str(fifo) in line or "ff" in line, line


def test_missing_input_named_as_missing(tmp_path):
    line = one_line(harness("export", tmp_path / "none.h5"), words="no such file")
    assert "none.h5" in line


def test_scene_groom_fifo_refused(tmp_path, fifo):
    scene = tmp_path / "s.toml"
    scene.write_text(f'model = "dynamic"\nstages = ["init", "simulate"]\ngroom = "{fifo}"\n')
    p = harness("run", scene, "--frames", "1", timeout=30)
    one_line(p, words="FIFO")


# ---- D12: TOML that is not TOML --------------------------------------------------------------


@pytest.mark.parametrize(
    "text", ["a = " + "[" * 5000 + "]" * 5000 + "\n", "a = " + "9" * 5000 + "\n"], ids=["deep", "long-integer"]
)
def test_scene_toml_beyond_the_parser_refused(tmp_path, text):
    scene = tmp_path / "s.toml"
    scene.write_text(text)
    one_line(harness("run", scene), words="not valid TOML")


# ---- M6: HB_GPUS checked where there is no GPU too -----------------------------------------


def test_hb_gpus_checked_without_a_gpu(tmp_path):
    p = subprocess.run(
        [sys.executable, "-m", "harness", "sweep", "quick", "--gpu", "no", "--out", str(tmp_path / "s")],
        cwd=ROOT,
        capture_output=True,
        text=True,
        timeout=300,
        env=dict(os.environ, HB_GPUS="x"),
    )
    one_line(p, words="HB_GPUS")
    assert not (tmp_path / "s").exists()


# ---- M5: a budget that starts with a minus ----------------------------------------------------


def test_negative_budget_said_as_a_budget(tmp_path):
    """make passes BUDGET as --budget=V, so a value that starts with a minus is a budget, not a flag
    (the command make would run, from make -n, run here: a real make bench would rebuild)."""
    p = subprocess.run(
        ["make", "-n", "--no-print-directory", "bench", "BUDGET=-5m", f"OUT={tmp_path / 'b'}"],
        cwd=ROOT,
        capture_output=True,
        text=True,
        timeout=120,
    )
    line = next(ln for ln in p.stdout.splitlines() if " -m harness bench " in ln)
    words = line.split(" -m harness ", 1)[1].split()
    assert "--budget=-5m" in words, line
    one_line(harness(*words), words="--budget")
    assert not (tmp_path / "b").exists()


# ---- the record's names -------------------------------------------------------------------


def test_json_of_a_run_names_no_removed_file(cpu_bin, tmp_path):
    p = harness("run", "dynamic", "--strands", 10, "--frames", 2, "--json")
    assert p.returncode == 0, p.stderr
    assert json.loads(p.stdout)["output"] is None


# ---- D8, D9, M4: USD grooms -----------------------------------------------------------------


def usd_groom(path, meters=0.01, nan=False):
    """Six radial strands of 6 cm around a 10 cm head, as a USD BasisCurves file (usd-core)."""
    pytest.importorskip("pxr", reason="usd-core is not installed (optional: USD grooms need it)")
    from pxr import Usd, UsdGeom
    from test_grooms import radial_strands

    strands = radial_strands((0, 0, 0), 10.0, [6.0] * 6, [4] * 6)
    points = [tuple(map(float, p)) for s in strands for p in s]
    if nan:
        points[5] = (float("nan"), 0.0, 0.0)
    stage = Usd.Stage.CreateNew(str(path))
    UsdGeom.SetStageMetersPerUnit(stage, meters)
    curves = UsdGeom.BasisCurves.Define(stage, "/hair")
    curves.CreateTypeAttr("linear")
    curves.CreatePointsAttr(points)
    curves.CreateCurveVertexCountsAttr([len(s) for s in strands])
    stage.GetRootLayer().Save()
    return path


@pytest.mark.parametrize(
    "name, data",
    [("garbage.usda", b"#usda 1.0\n(\n  this is not usd\n"), ("random.usdc", bytes(range(256)) * 8)],
)
def test_unreadable_usd_refused_in_one_line(tmp_path, name, data):
    pytest.importorskip("pxr", reason="usd-core is not installed (optional: USD grooms need it)")
    (tmp_path / name).write_bytes(data)
    line = one_line(harness("groom", "convert", tmp_path / name, tmp_path / "o.hair"))
    assert name in line and not (tmp_path / "o.hair").exists()


@pytest.mark.parametrize("meters", [0.0, -1.0, float("nan")], ids=["zero", "negative", "nan"])
def test_usd_meters_per_unit_must_be_positive(tmp_path, meters):
    usd_groom(tmp_path / "g.usda", meters=meters)
    one_line(harness("groom", "convert", tmp_path / "g.usda", tmp_path / "o.hair"), words="metersPerUnit")


def scene_of(tmp_path, groom):
    scene = tmp_path / "s.toml"
    scene.write_text(f'model = "dynamic"\nstages = ["init", "simulate"]\ngroom = "{groom}"\n[hair]\npoints = 5\n')
    return scene


def test_usd_groom_errors_name_the_users_file(cpu_bin, tmp_path):
    usd_groom(tmp_path / "nan.usda", nan=True)
    line = one_line(harness("run", scene_of(tmp_path, "nan.usda"), "--frames", 1))
    assert "nan.usda" in line and "hairbench-groom" not in line and "groom.hair" not in line, line


def test_usd_groom_record_names_the_users_file(cpu_bin, tmp_path):
    usd_groom(tmp_path / "g.usda")
    p = harness("run", scene_of(tmp_path, "g.usda"), "--frames", 1, "--json")
    assert p.returncode == 0, p.stderr
    assert json.loads(p.stdout)["groom"]["source"] == str(tmp_path / "g.usda")


# ---- D19: Ctrl-C during a study run in its own session ---------------------------------------

STUDY = """
import contextlib, sys, time
from pathlib import Path
from harness.core import budget, runner

out = Path(sys.argv[1])

def study():
    (out / "reduced").mkdir()
    for i in range(1200):
        (out / "reduced" / f"part{i}.csv").write_text("x")
        time.sleep(0.05)

with getattr(runner, "forwarding", contextlib.nullcontext)():  # as harness/cli/main.py runs a command
    try:
        budget.run_study(budget.Budget(600), "reduced", study, [out], print)
    except KeyboardInterrupt:
        sys.exit(130)
"""


def test_interrupt_stops_a_budgeted_study_and_removes_what_it_added(tmp_path):
    (tmp_path / "mine.txt").write_text("mine")
    proc = subprocess.Popen(
        [sys.executable, "-c", STUDY, str(tmp_path)],
        cwd=ROOT,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        preexec_fn=default_signals,
    )
    deadline = time.monotonic() + 60
    while time.monotonic() < deadline and not (tmp_path / "reduced" / "part3.csv").exists():
        time.sleep(0.02)
    proc.send_signal(signal.SIGINT)
    _, err = proc.communicate(timeout=60)
    assert proc.returncode == 130 and "Traceback" not in err, err
    time.sleep(0.5)  # a study left running would write on
    assert sorted(os.listdir(tmp_path)) == ["mine.txt"], os.listdir(tmp_path)


# ---- D16, D20: writes on a full disk ---------------------------------------------------------


def test_usd_export_on_a_full_disk_leaves_nothing(cpu_bin, tmp_path):
    pytest.importorskip("pxr", reason="usd-core is not installed (optional: USD export needs it)")
    state = tmp_path / "s.h5"
    subprocess.run([str(cpu_bin), "--strands", "20000", "--points", "32", "--output", str(state)], check=True)
    p = fulldisk.run(
        tmp_path,
        f'cd "$HERE"; printf mine > "$D/mine"; "{sys.executable}" -m harness export {state} --usd-only --force '
        '--out "$D/x"; echo "rc=$?"; ls -A "$D"',
    )
    assert p.stdout.split() == ["rc=4", "mine"], (p.stdout, p.stderr)
    one_line(subprocess.CompletedProcess([], 4, "", p.stderr), code=4, words="x.usdc")


SWEEP_TOML = sweep_toml("disk", strands=list(range(10, 410, 10)), points=[4], precision=["fp32"])


def test_sweep_on_a_full_disk_names_the_file_and_leaves_no_temporary(tmp_path):
    from support.fakebackend import install

    build = install(tmp_path / "build", ["hairsim-cpu"])
    (tmp_path / "disk.toml").write_text(SWEEP_TOML)
    p = fulldisk.run(
        tmp_path,
        f'cd "$HERE"; HAIRBENCH_BUILD_DIR={build} HAIRBENCH_NO_GPU=1 "{sys.executable}" -m harness sweep '
        f'{tmp_path / "disk.toml"} --out "$D/s" --gpu no; echo "rc=$?"; ls -A "$D/s"',
        size="16k",
    )
    lines = p.stdout.split()
    assert "rc=4" in lines and not [n for n in lines if ".tmp" in n], (p.stdout, p.stderr)
    line = p.stderr.strip().splitlines()[-1]
    assert "No space left on device" in line and "/s/" in line, p.stderr


# ---- D17, D18: one owner of a results folder -------------------------------------------------


def tree(folder):
    return sorted((str(p.relative_to(folder)), p.read_bytes() if p.is_file() else b"") for p in folder.rglob("*"))


def test_bench_refuses_a_users_folder(tmp_path):
    user = tmp_path / "U"
    (user / "report").mkdir(parents=True)
    (user / "report" / "report.md").write_text("my report")
    (user / "stability").mkdir()
    before = tree(user)
    line = one_line(harness("bench", "--out", user, "--budget", "1m"), words="not a hairbench run folder")
    assert str(user) in line and tree(user) == before


@pytest.mark.parametrize("where", ["..", "/", "."], ids=["parent", "root", "repository"])
def test_bench_refuses_the_repository_and_above(where):
    one_line(harness("bench", "--out", where, "--budget", "1m"), words="refusing to write results into")


def test_a_run_folder_in_use_is_refused(tmp_path):
    from harness.io import runfolder

    folder = runfolder.claim(tmp_path / "S", "test")
    try:
        p = harness("sweep", "quick", "--out", folder, "--gpu", "no")
        one_line(p, words="in use by another hairbench run")
    finally:
        runfolder.release(folder)
    assert sorted(os.listdir(folder)) == [".hairbench-run.json", ".hairbench-run.lock"]
