"""The reduced-model study (harness/studies/reduced_dynamic.py) and its report section
(harness/render/reduced_dynamic_report.py): a tiny plan runs every case on the cpu oracle, the references
climb their ladder and get their twins, and the report renders it; the recommendations pick, from
known rows, the fewest guides and the fewest simulated points that pass each use's budgets (the
followers' stretch and the ensemble's statistics included); a guide spacing has its known value."""

import math

import numpy as np
import pytest

from harness.core import tolerances, variants
from harness.render import reduced_dynamic_report as reduced_report
from harness.studies import reduced_dynamic as reduced
from harness.studies import reduced_verdicts_dynamic as reduced_verdicts

TINY = reduced.Plan(strands=(8, 16), seconds=4 / 60, write_every=1 / 60, fractions=(1.0, 0.5), ref_start=8,
                    ref_max=32, lra_iterations=(1,), sag_seconds=0.25, lod_points=(33, 9), time_strands=16, repeat=1,
                    gpu="no", threads=2)  # fmt: skip


@pytest.fixture(scope="module")
def rows(tmp_path_factory):
    out = tmp_path_factory.mktemp("reduced") / "reduced.csv"
    got = reduced.measure(TINY, out=out, progress=lambda *_: None)
    return got, out


def test_every_case_is_measured_and_written(rows):
    got, out = rows
    # per N: solvers × (all + fraction × schemes); solvers × I × LRA; solvers × (ranges × sag-free
    # + wind step × sag-free); solvers × P_s
    want = 2 * 2 * (1 + 2) + 2 * 2 + 2 * (2 * 2 + 2) + 2 * 2
    assert len(got) == want and all(r["backend"] == "cpu" for r in got)
    assert len(reduced_report.read(out)) == want
    for r in got:
        assert r["median_ms"] > 0 and r["rest_max_L"] >= r["rest_rms_L"] >= 0
        if not r["study"].startswith("sag"):
            assert r["rms_err_L"] >= 0 and r["max_err_L"] >= r["rms_err_L"] and r["horizon_s"] > 0
            assert all(r[m] >= 0 for m in ("tip_L", "curvature_rel", "envelope_rel"))
        if r["study"] == "sagfreq":
            assert r["tip_hz"] > 0
        if r["study"] == "lod":
            assert r["render_points"] == 33 and (r["render_ms"] >= 0 if r["points"] < 33 else r["render_ms"] is None)
        if r["study"] == "guides" and r["guides"] < 1:
            assert r["guide_spacing_cm"] > 0 and r["stretch_followers"] <= 1e-5  # followers keep ℓ_k (§3.14)
        if r["study"] == "lra" and r["lra"]:
            assert r["lra_moved_cm"] > 0
    sag = {(r["solver"], r["shape_range"], r["sag_free"]): r["rest_max_L"] for r in got if r["study"] == "sagfree"}
    assert all(sag[(s, 1.0, 1)] < 0.1 * sag[(s, 1.0, 0)] for s in ("xpbd", "ftl")), sag
    refs = reduced_report.read(out.with_name("references.csv"))
    assert {(r["scene"], int(r["strands"])) for r in refs} == {("scene", 8), ("scene", 16), ("nod", 16), ("lod", 16)}
    assert all(int(r["substeps"]) in (16, 32) and float(r["horizon_s"]) > 0 for r in refs)


def test_report_section_renders_every_table(rows):
    _, out = rows
    text = "\n".join(reduced_report.section(out))
    assert "| xpbd | 16 | 50% (8) |" in text and "| xpbd | 1 | on |" in text and "- **games**" in text
    assert "| xpbd | 0.5 | on |" in text and "it removes" in text and "tip Hz" in text
    assert "| xpbd | 9 |" in text and "| xpbd | 33 (all) |" in text and "References" in text


def _row(guides, follow, rms, stretch=0.0, strands=1000, spacing=1.0):
    return {"study": "guides", "solver": "xpbd", "backend": "cpu", "guides": str(guides), "follow": follow,
            "rms_err_L": str(rms), "strands": str(strands), "guide_count": str(int(guides * strands)),
            "guide_spacing_cm": str(spacing), "stretch_followers": str(stretch) if follow else "",
            "stretch_max_k": "0.001", "blown_up": "0", "tip_L": "", "curvature_rel": "",
            "envelope_rel": ""}  # fmt: skip


def _use_line(lines, use):
    return next(ln for ln in lines if ln.startswith(f"- **{use}**"))


def test_recommendations_take_the_fewest_guides_within_each_budget():
    prev, game = tolerances.DYN_ACC_USES["previews"][0], tolerances.DYN_ACC_USES["games"][0]
    rows = [_row(1.0, "", 0.1 * game), _row(0.5, "blend3", 0.5 * game), _row(0.25, "one", 0.5 * prev),
            _row(0.1, "blend3", 2 * prev)]  # fmt: skip
    picks = {p.use: p.guides[0].row for p in reduced_verdicts.recommendations(rows)}
    assert (picks["previews"]["guides"], picks["games"]["guides"]) == ("0.25", "0.5")
    lines = reduced_report.recommend(rows)
    assert "at 1,000 strands 25% guides (250, 1 cm apart), one" in _use_line(lines, "previews")
    assert "at 1,000 strands 50% guides (500, 1 cm apart), blend3" in _use_line(lines, "games")


def test_a_stretched_follower_or_a_statistic_past_the_spread_fails_a_use():
    game = tolerances.DYN_ACC_USES["games"][0]
    stretched = _row(0.5, "blend3", 0.5 * game, stretch=0.5)
    assert not reduced_verdicts.passes(stretched, "previews", {})
    far = dict(_row(0.5, "blend3", 0.5 * game), tip_L="0.02")
    spreads = {("scene", "1000"): {"tip_L": 0.001, "curvature_rel": 0.0, "envelope_rel": 0.0}}
    assert reduced_verdicts.passes(far, "previews", spreads) and not reduced_verdicts.passes(far, "games", spreads)


def _lod(points, rms):
    return {"study": "lod", "solver": "xpbd", "backend": "cpu", "points": str(points), "render_points": "33",
            "rms_err_L": str(rms), "strands": "1000", "stretch_max_k": "0.001", "stretch_followers": "",
            "blown_up": "0"}  # fmt: skip


def test_recommendations_take_the_fewest_simulated_points_within_each_budget():
    prev, game = tolerances.DYN_ACC_USES["previews"][0], tolerances.DYN_ACC_USES["games"][0]
    rows = [_row(1.0, "", 0.001), _lod(33, 0.1 * game), _lod(17, 0.5 * game), _lod(9, 0.5 * prev), _lod(5, 2 * prev)]
    picks = {p.use: p.lod for p in reduced_verdicts.recommendations(rows)}
    assert (picks["previews"]["points"], picks["games"]["points"]) == ("9", "17")
    lines = reduced_report.recommend(rows)
    assert "9 simulated points rendered as 33" in _use_line(lines, "previews")
    assert "17 simulated points rendered as 33" in _use_line(lines, "games")
    lines = reduced_report.recommend([_row(1.0, "", 0.001), _lod(33, 0.1 * game), _lod(9, 2 * prev)])
    assert "every point simulated" in _use_line(lines, "games")


def test_guide_spacing_of_known_roots():
    """Roots on a line 1 cm apart, every other one a guide: each follower is 1 cm from its nearest."""
    roots = np.zeros((8, 3))
    roots[:, 0] = np.arange(8)
    assert reduced.guide_spacing(roots, 8, 4) == pytest.approx(1.0)
    assert reduced.guide_spacing(roots, 8, 8) == 0.0
    assert math.isclose(reduced.lra_excess(np.array([[[[0, 0, 0], [0, -1, 0], [0, -2.2, 0]]]], float), 2.0), 0.1)


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
