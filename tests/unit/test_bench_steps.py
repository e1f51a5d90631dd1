"""The bench's step record (harness/bench/steps.py) and its report section
(harness/render/steps_report.py) on known steps: a fake clock and GPU work told to
core/gpus.py's counter, so each number has a known answer."""

from harness.bench import steps
from harness.core import gpus
from harness.core.progress import StepTimes
from harness.render import steps_report

NODE = [gpus.Gpu(0, "Fake GPU"), gpus.Gpu(1, "Fake GPU")]


class Clock:
    def __init__(self):
        self.t = 0.0

    def __call__(self):
        return self.t


def work(clock, seconds, on):
    """`seconds` of wall time, counted as work of each GPU in `on` (a dict index → seconds)."""
    for index, s in on.items():
        gpus._work[index] = gpus._work.get(index, 0.0) + s
    clock.t += seconds


def test_each_step_its_time_and_its_gpus_work(tmp_path):
    clock = Clock()
    times = StepTimes(clock=clock, on_step=lambda t: steps.write(tmp_path, t, NODE))
    times.step("validation", work, clock, 60.0, {})
    times.step("sweep", work, clock, 100.0, {0: 90.0, 1: 60.0})
    times.step("stability", work, clock, 50.0, {0: 40.0})
    r = steps.record(times, NODE)
    assert [s["name"] for s in r["steps"]] == ["validation", "sweep", "stability"] and r["total_s"] == 210.0
    validation, sweep, stability = r["steps"]
    assert "gpu_work_s" not in validation and validation["seconds"] == 60.0
    assert sweep["gpu_work_s"] == {"0": 90.0, "1": 60.0} and sweep["balance"] == 60.0 / 90.0
    assert sweep["gpu_work_per_s"] == 1.5
    assert stability["gpu_work_s"] == {"0": 40.0, "1": 0.0} and stability["balance"] == 0.0  # one GPU of two
    assert (tmp_path / "steps.json").is_file()  # written as each step ended
    lines = steps.gpu_lines(times, NODE)
    assert lines[0] == "harness: GPU work of sweep (100 s): GPU 0 90 s, GPU 1 60 s; balance 0.67, 1.50 GPU-s a second"
    assert len(lines) == 2 and steps.gpu_lines(times, NODE[:1]) == []
    page = "\n".join(steps_report.section(tmp_path))
    assert "## Where the time went" in page and "on 2 GPUs" in page
    assert "| sweep | 100 s | GPU 0: 90 s, GPU 1: 60 s | 0.67 |" in page and "| validation | 60 s | — | — |" in page


def test_no_steps_file_no_section(tmp_path):
    assert steps_report.section(tmp_path) == []
