"""`make report` (the Makefile's front door) renders a bench root and also one sweep's folder
(`REPORT_FROM=results/reference-h200/sweep`, which the layering issue found failing), and refuses
a folder with nothing to render in one line, exit 2."""

import shutil
import subprocess

import pytest

from conftest import ROOT

pytestmark = pytest.mark.skipif(shutil.which("make") is None, reason="make is not installed")


def _make_report(src, dst):
    return subprocess.run(
        ["make", "-s", "--no-print-directory", "report", f"REPORT_FROM={src}", f"REPORT_TO={dst}"],
        cwd=ROOT, capture_output=True, text=True, timeout=600,
    )  # fmt: skip


def test_make_report_renders_one_sweep_folder(tmp_path):
    sweep = tmp_path / "reference-h200" / "sweep"
    shutil.copytree(ROOT / "results" / "reference-h200" / "sweep", sweep)
    out = tmp_path / "rep"
    done = _make_report(sweep, out)
    assert done.returncode == 0, done.stderr
    assert f"wrote {out / 'report.md'}" in done.stdout
    md = (out / "report.md").read_text()
    rows = len((sweep / "runs.csv").read_text().splitlines()) - 1
    assert md.startswith("# hairbench report") and f"({rows} rows," in md
    assert not (out / "dynamic.md").exists()  # a sweep folder holds the paper sweep only


def test_make_report_refuses_a_folder_with_nothing_to_render(tmp_path):
    done = _make_report(tmp_path, tmp_path / "rep")
    assert done.returncode != 0
    assert "nothing to render" in done.stdout + done.stderr
    assert "Traceback" not in done.stdout + done.stderr
    assert not (tmp_path / "rep").exists()
