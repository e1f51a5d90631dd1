"""`python -m harness headline` (the paper model) on the CPU alone at a tiny size: the CPU
baselines are timed and tabled. The bandwidth measurement (a 1 GB copy) is stood in for, and
the GPU is reported absent."""

import json

from harness.core import env, variants
from harness.render import headline_report
from harness.studies import headline_paper, roofline


def test_headline_times_the_cpu_baselines(cpu_bin, tmp_path, monkeypatch):
    copies = iter([10.0, 20.0, 5.0, 40.0])
    monkeypatch.setattr(roofline, "measure_bandwidth", lambda binary, timeout=None: {"copy_gbps": next(copies)})
    monkeypatch.setattr(env, "gpu_status", lambda: (False, "no GPU in this test"))
    result = headline_paper.run(
        strands=64, points=8, repeat=1, cpu_repeat=1, cpu_rounds=3, out_dir=tmp_path, log=lambda *_: None
    )
    cpu = variants.declared("cpu")
    labels = [r["label"] for r in result["rows"]]
    assert labels == [f"cpu {cpu.default_variant}, 1 thread"] + [f"cpu {v}, all cores" for v in cpu.variants]
    assert all(r["backend"] == "cpu" and r["wind_collide_ms"] > 0 for r in result["rows"])
    assert result["gpu_skipped"] == "no GPU in this test" and "speedups" not in result
    assert result["cpu_copy_gbps"] == 10.0 and "rounds" not in result["rows"][0]
    fast = result["rows"][-1]  # the fast variant: three rounds against copies of 20, 5 and 40 GB/s
    assert [r["copy_gbps"] for r in fast["rounds"]] == [20.0, 5.0, 40.0]
    assert fast["wind_collide_fraction"] == sorted(r["fraction"] for r in fast["rounds"])[1]
    assert json.loads((tmp_path / "headline.json").read_text())["rows"] == result["rows"]
    text = headline_report.table(result)
    assert text.startswith("64 strands x 8 points") and labels[0] in text
    assert f"{labels[-1]}, w+c %BW: the median of 3 rounds, each against its own copy" in text
