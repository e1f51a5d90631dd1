"""The report's feature-cost section (harness/render/featurecost_dynamic_report.py) from hand-made rows:
costs against the right base rows, spread marks, and the row faster than `none` named."""

import csv
import shutil

import pytest

from harness.render import featurecost_dynamic_report as featurecost_report
from harness.studies import featurecost_dynamic as featurecost

FIELDS = featurecost.FIELDS


def _rows(times):
    """Rows named as featurecost.cases names them, with (median, min, max) from `times`
    (default 10 ms ± 0.1)."""
    names = [name for name, _ in featurecost.cases(["--substeps", "8"])]
    rows = []
    for name in names:
        med, lo, hi = times.get(name, (10.0, 9.9, 10.1))
        rows.append(
            dict(
                row=name, features="x", solver="xpbd", substeps=8, iterations=2, strands=1000, points=32,
                precision="fp32", backend="cpu", variant="ref", threads=1, block_size="", median_ms=med,
                min_ms=lo, max_ms=hi, point_substeps_per_s=1e9, device="test cpu",
            )
        )  # fmt: skip
    return rows


def _write(path, rows):
    with open(path, "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=FIELDS)
        w.writeheader()
        w.writerows(rows)
    return path


def test_costs_use_the_base_each_feature_needs():
    rows = _rows(
        {
            "none (gravity, stretch)": (10.0, 9.9, 10.1),
            "only bend": (14.0, 13.9, 14.1),
            "only drag": (11.0, 10.9, 11.1),
            "only drag+wind": (12.5, 12.4, 12.6),
            "only drag+gust+wind": (13.0, 12.9, 13.1),
            "full": (20.0, 19.9, 20.1),
            "full − bend": (16.0, 15.9, 16.1),
        }
    )
    got = {feat: (a, na, b, nb) for feat, a, na, b, nb in featurecost_report.costs(rows)}
    assert got["bend"][0] == 4.0 and not got["bend"][1] and got["bend"][2] == 4.0
    assert got["wind"][0] == 1.5  # against drag alone, which it needs
    assert got["gust"][0] == 0.5  # against wind and drag
    assert got["motion"][0] == 0.0 and got["motion"][1]  # same as none: inside the spread


def test_section_names_a_row_faster_than_none(tmp_path):
    fast = _rows({"only motion": (7.0, 6.9, 7.1)})
    text = "\n".join(featurecost_report.section([_write(tmp_path / "cpu.csv", fast)]))
    assert "Faster than `none` beyond the spread: only motion." in text
    calm = _rows({})
    text = "\n".join(featurecost_report.section([_write(tmp_path / "cpu.csv", calm)]))
    assert "No row is faster than `none` beyond the runs' spread." in text
    assert "### cpu" in text and "| bend |" in text


def test_section_names_a_feature_whose_removal_slows_the_full_scene(tmp_path):
    slower = _rows({"full − collide": (12.0, 11.9, 12.1), "full − gust": (10.05, 9.95, 10.15)})
    text = "\n".join(featurecost_report.section([_write(tmp_path / "cpu.csv", slower)]))
    assert "Slower without it than `full`, beyond the spread: collide." in text  # gust: within the spread
    text = "\n".join(featurecost_report.section([_write(tmp_path / "cpu.csv", _rows({}))]))
    assert "Slower without it" not in text


def test_csv_paths_cpu_first_and_a_note_without_any(tmp_path):
    results = tmp_path / "sweep"
    results.mkdir()
    assert featurecost_report.csv_paths(results) == []
    assert any("Not measured" in line for line in featurecost_report.section([]))
    d = tmp_path / "featurecost"
    d.mkdir()
    for name in ("cuda.csv", "cpu.csv", "cuda-strict.csv"):
        _write(d / name, _rows({}))
    assert [p.name for p in featurecost_report.csv_paths(results)] == ["cpu.csv", "cuda.csv", "cuda-strict.csv"]


@pytest.mark.skipif(shutil.which("valgrind") is None, reason="valgrind is not installed: no instruction counts")
def test_instruction_counts_are_deterministic(tmp_path, monkeypatch):
    """featurecost --instructions counts the frame function's instructions under callgrind:
    the same run counted twice gives the same number, and the full scene costs more than
    gravity and stretch alone (those two rows alone: every row under callgrind took a minute)."""
    every = featurecost.cases
    two = ("none (gravity, stretch)", "full")
    monkeypatch.setattr(featurecost, "cases", lambda flags, world=True: [c for c in every(flags, world) if c[0] in two])

    def count():
        return featurecost.measure(strands=20, frames=1, repeat=1, threads=1, instructions=True, progress=lambda *_: 0)

    rows = [count(), count()]
    a = {r["row"]: r["instructions_per_point_substep"] for r in rows[0]}
    b = {r["row"]: r["instructions_per_point_substep"] for r in rows[1]}
    assert a == b and set(a) == set(two)
    assert a["full"] > a["none (gravity, stretch)"] > 0
