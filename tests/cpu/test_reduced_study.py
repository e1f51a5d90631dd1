"""The reduced-model study (harness/studies/reduced_dynamic.py) and its report section
(harness/render/reduced_dynamic_report.py): a tiny plan runs every case on the cpu oracle, the references
climb their ladder and get their twins, and the report renders it; the recommendations pick, from
known rows, the fewest guides and the fewest simulated points that pass each use's budgets (the
followers' stretch and the ensemble's statistics included); a guide spacing has its known value. A run
stopped after some timings leaves them in OUT.partial and no CSV; --resume keeps them (not timed again)
and ends with the CSV an uninterrupted run writes, and refuses a partial file of another device, plan or
revision, or none, in one line."""

import json
import math
import shutil
import signal
from dataclasses import replace

import numpy as np
import pytest

from harness import HarnessError
from harness.cli.main import main as harness_main
from harness.core import env, runner, tolerances, variants
from harness.io.files import write_csv, write_json
from harness.render import reduced_dynamic_report as reduced_report
from harness.studies import reduced_dynamic as reduced
from harness.studies import reduced_partial_dynamic as reduced_partial
from harness.studies import reduced_reference_dynamic as reduced_ref
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
            if r["horizon_s"] > 0:  # else the reference holds the ladder's rule at no frame: none judged pointwise
                assert r["rms_err_L"] >= 0 and r["max_err_L"] >= r["rms_err_L"]
            else:
                assert r["horizon_s"] == 0 and r.get("rms_err_L") is None
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
    assert all(int(r["substeps"]) in (16, 32) for r in refs)
    for r in refs:  # the pointwise horizon: within T_p and the frames the ladder's rule holds over
        h, c = float(r["horizon_s"]), float(r["converged_s"])
        assert 0 <= h <= min(c, float(r["predictability_s"]) + 1 / 60, TINY.seconds) + 1e-9
        assert (str(r["converged"]) == "True") == (h > 0)


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
    # the guides are simulated strands too: their stretch counts, however well the followers keep ℓ_k
    stretched_guides = dict(_row(0.5, "blend3", 0.5 * game, stretch=1e-6), stretch_max_k="0.5")
    assert reduced_verdicts.failures(stretched_guides, "previews", {}) == ["stretch"]
    far = dict(_row(0.5, "blend3", 0.5 * game), tip_L="0.02")
    spreads = {("scene", "1000"): {"tip_L": 0.001, "curvature_rel": 0.0, "envelope_rel": 0.0}}
    assert reduced_verdicts.passes(far, "previews", spreads) and not reduced_verdicts.passes(far, "games", spreads)


def test_a_row_is_judged_against_the_spread_of_the_reference_it_was_compared_with():
    # a study run in shares: the ftl share's ladder stopped at S = 256, the xpbd share's at 4096
    game = tolerances.DYN_ACC_USES["games"][0]
    zero = {"curvature_rel_spread": "0", "envelope_rel_spread": "0"}
    refs = [{"scene": "scene", "strands": "1000", "substeps": str(S), "tip_L_spread": str(w), **zero}
            for S, w in ((256, 0.5), (4096, 0.0))]  # fmt: skip
    sp = reduced_verdicts.spreads(refs)
    row = dict(_row(0.5, "blend3", 0.5 * game), tip_L=str(2 * game))
    assert not reduced_verdicts.passes(dict(row, ref_substeps="4096"), "games", sp)
    assert reduced_verdicts.passes(dict(row, ref_substeps="256"), "games", sp)


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


SMALL = replace(TINY, strands=(8,), parts=("guides",))  # 6 cases, one reference: seconds a run
STOP_AFTER = 3  # timings before the stop


def _quiet(*_):
    pass


@pytest.fixture(scope="module")
def uninterrupted(tmp_path_factory):
    out = tmp_path_factory.mktemp("whole") / "reduced.csv"
    reduced.measure(SMALL, out=out, progress=_quiet)
    return out


@pytest.fixture(scope="module")
def stopped(tmp_path_factory):
    """The folder of a run stopped (as by SIGTERM) after STOP_AFTER timings."""
    out = tmp_path_factory.mktemp("stopped") / "reduced.csv"
    real, made = reduced._timings, []

    def timings(*args):
        for t in real(*args):
            if len(made) == STOP_AFTER:
                raise runner.Stopped(signal.SIGTERM)
            made.append(t)
            yield t

    with pytest.MonkeyPatch.context() as mp:
        mp.setattr(reduced, "_timings", timings)
        with pytest.raises(runner.Stopped):
            reduced.measure(SMALL, out=out, progress=_quiet)
    return out.parent


def _copy(folder, tmp_path):
    dst = tmp_path / "run"
    shutil.copytree(folder, dst)
    return dst / "reduced.csv"


def test_a_stopped_run_leaves_its_rows_and_no_csv(stopped):
    out = stopped / "reduced.csv"
    assert not out.exists() and not (stopped / "references.csv").exists()
    kept = reduced_report.read(reduced_partial.partial_path(out))
    assert len(kept) == STOP_AFTER and all(float(r["median_ms"]) > 0 for r in kept)
    assert list(kept[0]) == ["case", *reduced.FIELDS]
    record = json.loads((stopped / "reduced.csv.partial.json").read_text())
    assert record["plan"]["strands"] == [8] and record["git_revision"] == env.git_revision()


def test_resume_keeps_the_timings_and_ends_as_an_uninterrupted_run(stopped, uninterrupted, tmp_path, monkeypatch):
    out = _copy(stopped, tmp_path)
    kept = reduced_report.read(reduced_partial.partial_path(out))
    real, asked = reduced._timings, []

    def timings(plan, scene, case, timers, memo):
        asked.extend((case.key, *t) for t in timers)
        return real(plan, scene, case, timers, memo)

    monkeypatch.setattr(reduced, "_timings", timings)
    reduced.measure(SMALL, out=out, progress=_quiet, resume=True)
    assert not {(r["case"], r["backend"], r["variant"]) for r in kept} & set(asked)  # none timed again
    assert len(asked) == 6 - STOP_AFTER
    got, want = reduced_report.read(out), reduced_report.read(uninterrupted)
    assert out.read_text().splitlines()[0] == uninterrupted.read_text().splitlines()[0]  # the header
    assert len(got) == len(want) == 6
    timing_values = ("median_ms", "render_ms")
    for g, w in zip(got, want):
        assert {k: v for k, v in g.items() if k not in timing_values} == {
            k: v for k, v in w.items() if k not in timing_values
        }
    assert [r["median_ms"] for r in got[:STOP_AFTER]] == [r["median_ms"] for r in kept]  # as written before
    assert reduced_report.read(out.with_name("references.csv")) == reduced_report.read(
        uninterrupted.with_name("references.csv")
    )
    assert sorted(p.name for p in out.parent.iterdir()) == ["reduced.csv", "references.csv"]


def _refused(out, plan=SMALL):
    before = {p.name: p.read_bytes() for p in out.parent.iterdir()}
    with pytest.raises(HarnessError) as e:
        reduced.measure(plan, out=out, progress=_quiet, resume=True)
    assert "\n" not in str(e.value)
    assert {p.name: p.read_bytes() for p in out.parent.iterdir()} == before  # nothing written
    return str(e.value)


def _rewrite_rows(out, **changes):
    path = reduced_partial.partial_path(out)
    rows = reduced_report.read(path)
    write_csv(path, list(rows[0]), [{**rows[0], **changes}, *rows[1:]])


def test_resume_refuses_rows_timed_on_another_device(stopped, tmp_path, monkeypatch):
    out = _copy(stopped, tmp_path)
    _rewrite_rows(out, device="Another CPU 9000")
    assert "cpu/ref timings on Another CPU 9000" in _refused(out)
    _rewrite_rows(out, backend="cuda", device="NVIDIA H100 80GB HBM3")  # a cuda row: this machine's GPUs
    monkeypatch.setattr(env, "gpu_info", lambda: [{"name": "NVIDIA H200"}])
    assert "on NVIDIA H100 80GB HBM3; this machine has NVIDIA H200" in _refused(out)
    monkeypatch.setattr(env, "gpu_info", lambda: None)
    assert "this machine has no GPU" in _refused(out)


def test_resume_refuses_another_plan_or_revision(stopped, tmp_path, capsys):
    out = _copy(stopped, tmp_path)
    assert "another plan (seconds" in _refused(out, replace(SMALL, seconds=2 / 60))
    # the command line's plan (--quick) is not the one that measured it: one line, exit 2
    assert harness_main(["reduced", "--quick", "--gpu", "no", "--out", str(out), "--resume"]) == 2
    err = capsys.readouterr().err
    assert err.startswith("harness: error: reduced:") and "another plan" in err and err.count("\n") == 1
    record = json.loads(out.with_name("reduced.csv.partial.json").read_text())
    write_json(out.with_name("reduced.csv.partial.json"), {**record, "git_revision": "0000000"})
    assert "at revision 0000000" in _refused(out)


def test_resume_without_a_partial_file_and_a_fresh_run_over_one_are_refused(stopped, tmp_path, capsys):
    out = tmp_path / "empty" / "reduced.csv"
    assert harness_main(["reduced", "--gpu", "no", "--out", str(out), "--resume"]) == 2
    err = capsys.readouterr().err
    assert "no " in err and "reduced.csv.partial to resume" in err and err.count("\n") == 1
    assert harness_main(["reduced", "--gpu", "no", "--resume"]) == 2
    assert "--resume needs --out" in capsys.readouterr().err
    assert not out.parent.exists()
    out = _copy(stopped, tmp_path)
    before = reduced_partial.partial_path(out).read_bytes()
    assert harness_main(["reduced", "--gpu", "no", "--out", str(out)]) == 2
    assert "did not finish: --resume finishes it" in capsys.readouterr().err
    assert reduced_partial.partial_path(out).read_bytes() == before and not out.exists()


def test_a_case_partly_timed_keeps_the_binaries_order_and_saves_each_new_timing(monkeypatch):
    timers = [("cpu", "ref"), ("cuda", "a"), ("cuda", "b")]
    kept = {("cuda", "a"): {"backend": "cuda", "variant": "a", "time_strands": 10, "median_ms": 1.5,
                            "render_ms": None, "device": "GPU"}}  # fmt: skip
    asked = []

    def timings(plan, scene, case, todo, memo):
        asked.extend(todo)
        for backend, variant in todo:
            yield backend, variant, 10, {"stages": [{"stage": "simulate", "median_ms": 2.0}], "device": "X"}

    monkeypatch.setattr(reduced, "_timings", timings)
    case = reduced.Case("guides", "xpbd", 8, 2, 8)
    saved = []
    base = {"rms_err_L": 0.1}
    got = reduced._case_rows(SMALL, None, case, base, timers, kept, saved.append, _quiet, {})
    assert asked == [("cpu", "ref"), ("cuda", "b")]
    assert [(r["backend"], r["variant"], r["median_ms"]) for _, r in got] == [
        ("cpu", "ref", 2.0),
        ("cuda", "a", 1.5),
        ("cuda", "b", 2.0),
    ]
    assert [len(s) for s in saved] == [2, 3] and all(k == case.key for k, _ in got)


def test_a_timing_with_the_same_binary_and_flags_runs_once(monkeypatch):
    # a guide row at 1,000 and at 10,000 strands is timed at the timing's own strand count: one run
    runs = []

    def flags(plan, scene, case, backend, variant):
        return (10, ["--strands", "10", "--guides", repr(case.guides), "--variant", variant])

    def run_binary(path, fl):
        runs.append(tuple(fl))
        return {"stages": [{"stage": "simulate", "median_ms": float(len(runs))}], "device": "X"}

    monkeypatch.setattr(reduced, "_timing_flags", flags)
    monkeypatch.setattr(reduced.runner, "run_binary", run_binary)
    timers = [("cpu", "ref"), ("cuda", "lanes")]
    memo = {}
    shapes = ((1000, 0.1), (10000, 0.1), (1000, 0.5))  # the first two differ in strands alone
    got = []
    for n, g in shapes:
        case = reduced.Case("guides", "xpbd", 8, 2, n, g)
        timed = reduced._timings(SMALL, None, case, timers, memo)
        got.append([(b, v, r["stages"][0]["median_ms"]) for b, v, _, r in timed])
    assert len(runs) == 4 and len(set(runs)) == 4
    assert got[0] == got[1] == [("cpu", "ref", 1.0), ("cuda", "lanes", 2.0)]
    assert got[2] == [("cpu", "ref", 3.0), ("cuda", "lanes", 4.0)]


def test_a_resumed_run_does_not_time_again_the_twin_of_a_kept_timing(monkeypatch):
    def flags(plan, scene, case, backend, variant):
        return (10, ["--guides", repr(case.guides), "--variant", variant])

    runs = []
    monkeypatch.setattr(reduced, "_timing_flags", flags)
    monkeypatch.setattr(reduced.runner, "run_binary", lambda path, fl: runs.append(fl))
    small, big = (reduced.Case("guides", "xpbd", 8, 2, n, 0.1) for n in (1000, 10000))
    kept = {small.key: {("cuda", "lanes"): {"backend": "cuda", "variant": "lanes", "time_strands": 10,
                                             "median_ms": 1.25, "render_ms": None, "device": "GPU"}}}  # fmt: skip
    memo = reduced._memo_from_kept(SMALL, None, [small, big], kept)
    got = [(b, v, n, r["stages"][0]["median_ms"], r["device"]) for b, v, n, r in
           reduced._timings(SMALL, None, big, [("cuda", "lanes")], memo)]  # fmt: skip
    assert got == [("cuda", "lanes", 10, 1.25, "GPU")] and runs == []


def test_no_reduction_is_recommended_for_a_use_the_full_model_misses():
    # every strand simulated misses the previews' curvature allowance; a guided row that happens to
    # pass it passes by the statistic's noise and is not recommended
    prev = tolerances.DYN_ACC_USES["previews"][0]
    allow = tolerances.DYN_ACC_USES_CHAOS["previews"]["curvature_rel"]
    full = dict(_row(1.0, "", 0.1 * prev), curvature_rel=str(allow * 1.05))
    guided = dict(_row(0.1, "blend3", 0.2 * prev), curvature_rel=str(allow * 0.95))
    (pick,) = [p.guides[0] for p in reduced_verdicts.recommendations([full, guided]) if p.use == "previews"]
    assert pick.row is None and pick.full_fails == ("curvature_rel",)
    line = _use_line(reduced_report.recommend([full, guided]), "previews")
    assert "misses it with every strand simulated (curvature W1" in line and "10% guides" not in line
    # the same guided row is recommended once the full model meets the use
    full_ok = dict(full, curvature_rel=str(allow * 0.5))
    (pick,) = [p.guides[0] for p in reduced_verdicts.recommendations([full_ok, guided]) if p.use == "previews"]
    assert pick.row is guided and pick.full_fails == ()


def test_no_lod_is_recommended_for_a_use_every_point_simulated_misses():
    prev = tolerances.DYN_ACC_USES["previews"][0]
    rows = [_row(1.0, "", 0.001), _lod(33, 2 * prev), _lod(9, 0.5 * prev)]
    (pick,) = [p for p in reduced_verdicts.recommendations(rows) if p.use == "previews"]
    assert pick.lod is None and pick.lod_full_fails == ("rms_err_L",)
    assert (
        f"no P_s is recommended: the step misses it with every point simulated (RMS error {2 * prev:g})"
        in _use_line(reduced_report.recommend(rows), "previews")
    )


def test_a_study_split_by_solver_has_every_case_once_and_shares_no_timing():
    scene = reduced.scenes.load_scene(reduced.Plan().scene)
    whole = reduced.cases(reduced.Plan(), scene)
    shares = [reduced.cases(reduced.Plan(solvers=(s,)), scene) for s in reduced.SOLVERS]
    assert sorted(c.key for c in shares[0] + shares[1]) == sorted(c.key for c in whole)
    assert {c.solver for c in shares[0]} == {"xpbd"} and {c.solver for c in shares[1]} == {"ftl"}
    timed = [{tuple(map(str, reduced._timing_flags(reduced.Plan(), scene, c, "cpu", "ref")[1])) for c in share}
             for share in shares]  # fmt: skip
    assert timed[0] and timed[1] and not timed[0] & timed[1]


def test_the_solvers_option_reaches_the_plan(monkeypatch):
    plans = []

    def measure(plan, **_):
        plans.append(plan)
        return []

    monkeypatch.setattr(reduced, "measure", measure)
    monkeypatch.setattr(reduced_report, "markdown", lambda rows, refs: "")
    assert harness_main(["reduced", "--solvers", "ftl", "--gpu", "no"]) == 0
    assert harness_main(["reduced", "--solvers", "ftl", "xpbd", "--gpu", "no"]) == 0
    assert harness_main(["reduced", "--gpu", "no"]) == 0
    assert [p.solvers for p in plans] == [("ftl",), ("xpbd", "ftl"), ("xpbd", "ftl")]


def test_the_pointwise_horizon_is_where_the_reference_holds_the_rule_from_the_start():
    f = tolerances.DYN_ACC_REF_FACTOR
    q = [math.nan, 0.5 * f, 0.9 * f, 2 * f, 0.5 * f]  # converged over 3 frames, not the 4th, again the 5th
    assert reduced_ref.pointwise_frames(q, within=5) == (3, 3)
    assert reduced_ref.pointwise_frames(q, within=2) == (2, 3)
    assert reduced_ref.pointwise_frames([2 * f, 0.5 * f], within=2) == (0, 0)
    assert reduced_ref.pointwise_frames([0.5 * f] * 4, within=4) == (4, 4)


def test_with_no_frame_judged_pointwise_a_row_is_judged_by_its_statistics_alone():
    row = dict(_row(1.0, "", math.nan), horizon_s="0", rms_err_L="")
    assert "rms_err_L" not in reduced_verdicts.failures(row, "previews", {})
    judged = dict(row, horizon_s="0.05")
    assert "rms_err_L" in reduced_verdicts.failures(judged, "previews", {})
    lra = {"study": "lra", "solver": "xpbd", "iterations": "1", "horizon_s": "0", "rms_err_L": "",
           "stretch_max_k": "0.1"}  # fmt: skip
    off, on = dict(lra, lra="0", tip_L="0.02"), dict(lra, lra="1", tip_L="0.01")
    (v,) = reduced_verdicts.lra_verdicts([off, on])
    assert v.measure == "tip_L" and v.lower and v.worth_it
