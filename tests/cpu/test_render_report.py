"""The report's rendered hair end to end on the C reference, at a small size: the bench's
renders step (harness/bench/renders.py) simulates the default scene and each use the
committed accuracy study recommends, with its reference, and the dynamic report's section
(harness/render/hair_report.py) draws the animation, the hero frame and one picture a use."""

import json
import shutil

import numpy as np
import pytest

from conftest import ROOT
from harness.bench import renders
from harness.render import hair_report
from harness.render.gl import context

REASON = context.unavailable()
pytestmark = pytest.mark.skipif(REASON is not None, reason=f"no OpenGL on EGL: {REASON}")


def test_the_renders_step_and_the_report_section(cpu_bin, tmp_path, monkeypatch):
    from PIL import Image

    monkeypatch.setattr(renders, "ANIMATION_STRANDS", 60)
    monkeypatch.setattr(renders, "ANIMATION_FRAMES", 8)
    monkeypatch.setattr(renders, "MODE_STRANDS", 12)
    shutil.copytree(ROOT / "results" / "reference-h200" / "dynamic-accuracy", tmp_path / "dynamic-accuracy")
    first = json.loads(renders.simulate(tmp_path, lambda m: None).read_text())
    assert first["modes"] == [] and first["reference"] is None  # the bench draws them after the study
    record = json.loads(renders.simulate_modes(tmp_path, lambda m: None).read_text())
    assert {k: record[k] for k in ("dynamic", "world")} == {k: first[k] for k in ("dynamic", "world")}
    uses = {p["use"] for m in record["modes"] for p in m["picks"]}
    assert uses == {"previews", "games", "offline"} and record["reference"]["substeps"] == 1024
    lines = hair_report.dynamic_lines(tmp_path, tmp_path / "report")
    for use in uses:
        assert f"![{use} against the reference](dynamic_accuracy_render_{use}.png)" in lines
        sheet = np.asarray(Image.open(tmp_path / "report" / f"dynamic_accuracy_render_{use}.png"))
        assert sheet.shape[1] > 2 * hair_report.MODE_SIZE[0]  # the mode(s) and the reference side by side
    hero = Image.open(tmp_path / "report" / hair_report.HERO)
    assert hero.size == hair_report.HERO_SIZE
    gif = Image.open(tmp_path / "report" / hair_report.ANIMATION)
    assert gif.n_frames == 1 + 4  # the rest shape, then every written frame (every second of 8)


def test_without_a_record_the_section_says_how_to_make_it(tmp_path):
    lines = hair_report.dynamic_lines(tmp_path, tmp_path / "report")
    assert lines[2].startswith("Not rendered: no ") and "renders.json (make bench makes it)" in lines[2]
    assert not (tmp_path / "report").exists()
