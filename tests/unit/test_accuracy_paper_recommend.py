"""The paper accuracy page's recommendation (harness/studies/accuracy_verdicts_paper.py, worded by
harness/render/accuracy_paper_report.py) on known
rows: the fastest mode within a use's error bound, unless another ties with it within timing
noise (core/timing.py: these tables keep no spread, so within its 0.5 % floor), when the more
accurate of the tie is named and the tie said. The committed H200 table had fast-math 0.86 %
faster than the normal build and twice its error, and named fast-math for production."""

from harness.render import accuracy_paper_report as rep
from harness.studies import accuracy_verdicts_paper as verdicts


def mode(name, time_ms, err):
    return {"study": "mode", "mode": name, "frame": 3, "time_ms": time_ms, "max_err_L": err}


def line(rows, use):
    return next(ln for ln in rep.recommend(rows) if ln.startswith(f"- For {use}"))


def picked(rows, use):
    return next(u for u in verdicts.recommendation(rows).uses if u.use.startswith(use))


def test_a_tie_within_noise_goes_to_the_more_accurate_mode():
    rows = [mode("cpu fp64 ref", 18.0, 0.0), mode("normal", 0.052576, 2.6e-6), mode("fast-math", 0.052128, 5.4e-6)]
    production = picked(rows, "production")
    assert production.best["mode"] == "normal" and production.tied_with == ["fast-math"]
    rec = verdicts.recommendation(rows)
    assert rec.fastest["mode"] == "fast-math" and rec.fastest_tied_with == ["normal"]
    assert picked(rows, "references").best is None  # no mode within 1e-12·L
    assert "**normal**" in line(rows, "production") and "a tie within timing noise with fast-math" in line(
        rows, "production"
    )
    fastest = rep.recommend(rows)[0]
    assert "**fast-math**" in fastest and "a tie within timing noise with normal" in fastest


def test_a_clear_difference_still_goes_to_the_faster_mode():
    rows = [mode("cpu fp64 ref", 18.0, 0.0), mode("normal", 0.060, 2.6e-6), mode("fast-math", 0.050, 5.4e-6)]
    assert (picked(rows, "production").best["mode"], picked(rows, "production").tied_with) == ("fast-math", [])
    assert "**fast-math**" in line(rows, "production") and "tie" not in line(rows, "production")
