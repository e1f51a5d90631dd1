"""`python -m harness accuracy`: the speed/accuracy table, the Pareto plot and the
recommendation, on the modes this machine can run."""

import csv

import numpy as np

from harness.core import scenes, tolerances
from harness.render import accuracy_paper_report
from harness.studies import accuracy_paper


def test_along_curve_error_is_zero_on_a_straight_strand_and_sees_a_bend():
    fine = np.zeros((1, 9, 3))
    fine[0, :, 2] = np.arange(9) * 0.5  # a straight strand of length 4
    coarse = fine[:, ::4, :].copy()  # P = 3 on the same curve
    assert np.allclose(accuracy_paper.along_curve_error(coarse, fine), 0)
    bent = coarse.copy()
    bent[0, 1, 1] = 0.3  # the middle point off the curve by 0.3
    assert np.isclose(accuracy_paper.along_curve_error(bent, fine).max(), 0.3)


def test_accuracy_study_writes_table_plot_and_recommendation(cpu_bin, tmp_path):
    rows = accuracy_paper.run_study(
        "paper",
        strands=1500,
        points=16,
        repeat=3,
        resolution=(4, 16, 46),
        res_strands=500,
        out_dir=tmp_path / "acc",
        log=lambda *_: None,
    )
    assert not (tmp_path / "rep").exists()  # measuring only: the renderer draws
    accuracy_paper_report.report_from_csv(tmp_path / "acc" / "accuracy.csv", tmp_path / "rep", log=lambda *_: None)
    with open(tmp_path / "acc" / "accuracy.csv") as fh:
        table = list(csv.DictReader(fh))
    assert set(accuracy_paper.COLUMNS) <= set(table[0])
    modes = {r["mode"] for r in table if r["study"] == "mode"}
    assert {"cpu fp64 ref", "cpu fp32 ref"} <= modes
    fp32 = [r for r in rows if r["mode"] == "cpu fp32 ref"]
    assert len(fp32) == 4  # one row per frame of the paper scene
    # fp32 rounding, not a bug: within harness diff's fp32↔fp64 limit at its largest
    scene = scenes.load_scene("paper")
    R, h, L = scene.head_radius, scene.hair_offset, scene.hair_length
    largest_u = tolerances.point_unit(np.zeros(1), np.zeros(1), R, h, L, 16, tolerances.EPS["fp32"])[0]
    limit_L = tolerances.pair_tolerance("fp32", "fp64").point_k * largest_u / L
    assert all(0 < r["max_err_L"] < limit_L for r in fp32)
    assert all(r["time_ms"] > 0 for r in rows)
    ref = [r for r in rows if r["mode"] == "cpu fp64 ref"]
    assert all(r["max_err_L"] == 0 for r in ref)
    res = sorted((r for r in rows if r["study"] == "resolution"), key=lambda r: r["points"])
    assert [r["points"] for r in res] == [4, 16, 46]
    assert res[0]["max_err_L"] > res[1]["max_err_L"] > 0 and res[2]["max_err_L"] == 0
    png = tmp_path / "rep" / "accuracy_pareto.png"
    assert png.stat().st_size > 5000
    md = (tmp_path / "rep" / "accuracy.md").read_text()
    assert "| cpu fp32 ref |" in md and "Which mode for which use" in md
    assert "GPU modes absent" in md or "gpu fp32 strict" in md
    assert not (tmp_path / "acc" / "states").exists()  # scratch states removed


def test_a_fused_wind_frame_is_not_checked_for_penetration(tmp_path):
    """Regression: the GPU's fused wind frame (stage 'wind', fused 'wind+collide') holds the
    state after the wind half, inside the shell by design; accuracy once counted it as a
    collide frame and reported 6% penetration."""
    from harness.io.states import open_state
    from support.synthetic import write_state

    inside = np.zeros((1, 1, 3, 3))
    inside[0, 0, :, 2] = [10.0, 9.0, 8.0]  # root on the head, then two points inside
    frames = np.concatenate([inside, inside])  # frame 0 init, frame 1 the fused wind frame
    a = write_state(
        tmp_path / "a.h5", frames, ["init", "wind"], fused=["", "wind+collide"], params={"hair_length": 2.0}
    )
    with open_state(a) as s:
        e = accuracy_paper.frame_measures(s, s, 1, 2.0)
    assert e["penetration"] == 0
    b = write_state(tmp_path / "b.h5", frames, ["init", "collide"], params={"hair_length": 2.0})
    with open_state(b) as s:
        assert accuracy_paper.frame_measures(s, s, 1, 2.0)["penetration"] > 0.1
