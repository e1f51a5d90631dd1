"""The reduced-model study (harness/studies/reduced.py) and its report section
(harness/render/reduced_report.py): a tiny plan runs every case on the cpu oracle and the
report renders it; the recommendations pick, from known rows, the fewest guides and the
fewest simulated points within each budget."""

import pytest

from harness.core import variants
from harness.render import reduced_report
from harness.studies import reduced

TINY = reduced.Plan(
    strands=8, seconds=2 / 60, ref_substeps=16, time_strands=16, repeat=1, gpu="no", sag_seconds=0.1, lod_points=(33, 9)
)


@pytest.fixture(scope="module")
def rows(tmp_path_factory):
    out = tmp_path_factory.mktemp("reduced") / "reduced.csv"
    got = reduced.measure(TINY, out=out, progress=lambda *_: None)
    return got, out


def test_every_case_is_measured_and_written(rows):
    got, out = rows
    # solvers × (all + fractions × schemes), I × LRA, solvers × sag-free (still, wind step), solvers × P_s
    want = 2 * (1 + 4 * 2) + 2 * 2 + 2 * 2 + 2 * 2 + 2 * 2
    assert len(got) == want and all(r["backend"] == "cpu" for r in got)
    assert len(reduced_report.read(out)) == want
    for r in got:
        assert r["median_ms"] > 0 and r["rest_max_L"] >= r["rest_rms_L"] >= 0
        if not r["study"].startswith("sag"):
            assert r["rms_err_L"] >= 0 and r["max_err_L"] >= r["rms_err_L"]
        if r["study"] == "sagfreq":
            assert r["tip_hz"] > 0
        if r["study"] == "lod":
            assert r["render_points"] == 33 and (r["render_ms"] >= 0 if r["points"] < 33 else r["render_ms"] is None)
    sag = {(r["solver"], r["sag_free"]): r["rest_max_L"] for r in got if r["study"] == "sagfree"}
    assert all(sag[(s, 1)] < sag[(s, 0)] for s in ("xpbd", "ftl")), sag


def test_report_section_renders_both_tables(rows):
    _, out = rows
    text = "\n".join(reduced_report.section(out))
    assert "| xpbd | 5% | blend3 |" in text and "| 1 | on |" in text and "For a game" in text
    assert "| xpbd | on |" in text and "Sag-free rest for every scene" in text and "tip Hz" in text
    assert "| xpbd | 9 |" in text and "| xpbd | 33 (all) |" in text


def _row(guides, follow, rms):
    return {"study": "guides", "solver": "xpbd", "backend": "cpu", "guides": str(guides), "follow": follow,
            "rms_err_L": str(rms)}  # fmt: skip


def test_recommendations_take_the_fewest_guides_within_each_budget():
    rows = [_row(1.0, "", 0.001), _row(0.5, "blend3", 0.01), _row(0.25, "one", 0.03), _row(0.1, "blend3", 0.2)]
    lines = reduced_report.recommend(rows)
    assert "25% guides, one" in lines[0] and "50% guides, blend3" in lines[1]


def _lod(points, rms):
    return {"study": "lod", "solver": "xpbd", "backend": "cpu", "points": str(points), "render_points": "33",
            "rms_err_L": str(rms)}  # fmt: skip


def test_recommendations_take_the_fewest_simulated_points_within_each_budget():
    rows = [_row(1.0, "", 0.001), _lod(33, 0.005), _lod(17, 0.015), _lod(9, 0.04), _lod(5, 0.2)]
    lines = reduced_report.recommend(rows)
    assert "9 simulated points rendered as 33" in lines[0] and "17 simulated points rendered as 33" in lines[1]
    lines = reduced_report.recommend([_row(1.0, "", 0.001), _lod(33, 0.005), _lod(9, 0.5)])
    assert "every point simulated" in lines[1]


def test_each_row_is_timed_by_the_variants_that_run_its_features():
    assert reduced.row_features(["--guides", 0.5, "--follow", "one"]) == {"guides"}
    assert reduced.row_features(["--lra", "--iterations", 1]) == {"lra"}
    assert reduced.row_features(["--sag-free", "--render-points", 33]) == {"sagfree", "lod"}
    assert reduced.row_features([]) == set()
    # a variant declaring sagfree and lod only (cuda lanes) times those rows, not the guided or LRA ones
    d = variants.Declared("cuda", "default", "v", ("fp32",), ("v",), {"v": ("simulate",)}, {},
                          variant_features={"v": ("sagfree", "lod")})  # fmt: skip
    assert d.runs_features("v", reduced.row_features(["--sag-free"]))
    assert d.runs_features("v", reduced.row_features(["--render-points", 33]))
    assert d.runs_features("v", reduced.row_features([]))
    assert not d.runs_features("v", reduced.row_features(["--guides", 0.1, "--follow", "blend3"]))
    assert not d.runs_features("v", reduced.row_features(["--lra"]))
