"""The frame budget's answer (harness/render/frame_budget_dynamic.py) on synthetic Pareto data with known
answers: the most accurate mode whose predicted time fits, its prediction interpolated between
measured sizes or extrapolated (and said so) beyond them, a blown-up mode never picked, nothing
fitting said so, a GPU chosen by name, and the budget's edge within noise."""

import math

import pandas as pd
import pytest

from harness import HarnessError
from harness.render import frame_budget_dynamic as frame_budget

# mode → (RMS error / L, usable, ms a frame per 1,000 strands): a Pareto front (faster, less accurate)
CPU = {
    "cpu ref rigid fp32": (0.06, True, 0.001),
    "cpu ref ftl s=1 S4 I1 fp32": (0.015, True, 0.02),
    "cpu ref ftl s=1 S16 I1 fp32": (0.0055, True, 0.08),
    "cpu ref xpbd S32 I1 fp32": (0.003, True, 0.3),
    "cpu ref xpbd S1 I1 fp32": (math.nan, False, 0.005),  # blown up: fast, never a pick
}
GPU = {
    "gpu normal lanes ftl s=1 S16 I1 fp32": (0.0055, True, 0.0005),
    "gpu normal lanes xpbd S32 I1 fp32": (0.003, True, 0.002),
}
SIZES = (1_000, 10_000, 100_000)


def data(rsd=0.001, noisy=""):
    summ = pd.DataFrame(
        [dict(mode=m, rms=r, usable=u) for m, (r, u, _) in {**CPU, **GPU}.items()],
    )
    rows = []
    for table, backend, device in ((CPU, "cpu", "AMD EPYC"), (GPU, "cuda", "NVIDIA H200")):
        for m, (_, _, per_k) in table.items():
            for n in SIZES:  # time linear in N: the log-log line through two sizes is exact
                rows.append(dict(mode=m, backend=backend, device=device, strands=n, median_ms=per_k * n / 1000,
                                 rsd=rsd, noisy=noisy, error=""))  # fmt: skip
    return frame_budget.Data(summ, pd.DataFrame(rows), horizon_s=0.25, holds_until_s=0.4, where="synthetic")


def pick(d, n, ms, backend="cpu", gpu=None):
    return next(a for a in frame_budget.answer(d, n, ms, gpu) if a["backend"] == backend)


def test_the_most_accurate_mode_that_fits_is_picked():
    d = data()
    a = pick(d, 10_000, 1.0)  # rigid 0.01, ftl S4 0.2, ftl S16 0.8 fit; xpbd S32 3.0 does not
    assert a["pick"]["mode"] == "cpu ref ftl s=1 S16 I1 fp32" and a["pick"]["ms"] == pytest.approx(0.8)
    assert a["pick"]["how"] == "measured" and a["pick"]["rms"] == 0.0055 and not a["edge"]
    g = pick(d, 10_000, 1.0, "cuda")  # the GPU's curve: xpbd S32 at 0.02 ms fits
    assert g["pick"]["mode"] == "gpu normal lanes xpbd S32 I1 fp32"


def test_between_measured_sizes_the_prediction_is_interpolated():
    a = pick(data(), 50_000, 2.0)  # ftl S4 at 50k: 1.0 ms on the line through 10k and 100k; S16: 4 ms
    assert a["pick"]["mode"] == "cpu ref ftl s=1 S4 I1 fp32"
    assert a["pick"]["ms"] == pytest.approx(1.0) and a["pick"]["how"] == "interpolated between 10,000 and 100,000"


def test_beyond_the_largest_size_it_is_extrapolated_and_said():
    a = pick(data(), 1_000_000, 5.0)  # only rigid fits: 0.1 ms at 100k, 1.0 ms at 1M
    assert a["pick"]["mode"] == "cpu ref rigid fp32" and a["pick"]["ms"] == pytest.approx(1.0)
    assert a["pick"]["how"].startswith("extrapolated beyond the largest measured size (100,000)")
    text = "\n".join(frame_budget.lines(data(), 1_000_000, 5.0))
    assert "**cpu ref rigid fp32**, predicted 1 ms a frame (extrapolated" in text and "over the first 0.25 s" in text


def test_nothing_fitting_and_a_blown_up_mode_are_said():
    a = pick(data(), 100_000, 0.01)
    assert a["pick"] is None and a["fastest"]["mode"] == "cpu ref rigid fp32"  # not the blown-up xpbd S1
    assert "no measured mode fits 0.01 ms" in "\n".join(frame_budget.lines(data(), 100_000, 0.01))


def test_a_gpu_is_chosen_by_name():
    assert [a["device"] for a in frame_budget.answer(data(), 10_000, 1.0, gpu="h200")] == ["NVIDIA H200"]
    with pytest.raises(HarnessError, match="no GPU matching 'A100'.*NVIDIA H200"):
        frame_budget.answer(data(), 10_000, 1.0, gpu="A100")


def test_a_budget_within_the_times_noise_and_a_noisy_curve_are_flagged():
    a = pick(data(rsd=0.02), 10_000, 0.81)  # ftl S16 at 0.8 ms ± 4 %: the budget lies inside its band
    assert a["pick"]["mode"] == "cpu ref ftl s=1 S16 I1 fp32" and a["edge"]
    text = "\n".join(frame_budget.lines(data(noisy="others used 2 cores"), 10_000, 1.0))
    assert "its curve is flagged as noise: others used 2 cores" in text


def test_the_reports_table_has_each_device_budget_and_size(tmp_path, monkeypatch):
    monkeypatch.setattr(frame_budget, "load", lambda root, scene: data())
    lines = frame_budget.section(tmp_path, budgets=(1.0, 5.0), sizes=(10_000, 1_000_000))
    text = "\n".join(lines)
    assert "**CPU (AMD EPYC)**" in text and "**GPU NVIDIA H200**" in text
    # 1M strands: extrapolated (*), and rigid's 1 ms is the 1 ms budget within noise (~)
    assert "| 1 | ref ftl s=1 S16 I1 fp32: 0.8 ms, 5.5e-03·L | ref rigid fp32: 1*~ ms, 6.0e-02·L |" in text
    assert "| 5 | lanes xpbd S32 I1 fp32: 0.02 ms, 3.0e-03·L | lanes xpbd S32 I1 fp32: 2* ms, 3.0e-03·L |" in text
