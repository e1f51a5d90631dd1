"""harness.core.gpus: which GPUs the sweep spreads over, and the spreading (fake GPU lists
and a fake case runner; nothing is timed)."""

import threading

import pytest

from harness import HarnessError
from harness.core import gpus

SMI = """GPU 0: NVIDIA H200 (UUID: GPU-aaaa-0000)
GPU 1: NVIDIA H200 (UUID: GPU-bbbb-1111)
GPU 2: NVIDIA H200 (UUID: GPU-cccc-2222)
"""


def test_nvidia_smi_lines_are_read():
    got = gpus.parse_smi(SMI)
    assert [(g.index, g.name, g.select) for g in got] == [
        (0, "NVIDIA H200", "GPU-aaaa-0000"),
        (1, "NVIDIA H200", "GPU-bbbb-1111"),
        (2, "NVIDIA H200", "GPU-cccc-2222"),
    ]
    assert gpus.parse_smi("") == [] and gpus.parse_smi(None) == []


def test_cuda_visible_devices_and_hb_gpus_narrow_the_list():
    listed = gpus.parse_smi(SMI)
    assert [g.index for g in gpus.visible(listed, {})] == [0, 1, 2]
    assert [g.index for g in gpus.visible(listed, {"CUDA_VISIBLE_DEVICES": "2,0"})] == [0, 2]
    assert [g.index for g in gpus.visible(listed, {"CUDA_VISIBLE_DEVICES": "GPU-bbbb"})] == [1]
    assert [g.index for g in gpus.visible(listed, {"HB_GPUS": "2,1"})] == [2, 1]
    assert [g.index for g in gpus.visible(listed, {"HB_GPUS": "all"})] == [0, 1, 2]


@pytest.mark.parametrize(
    ("environ", "message"),
    [({"HB_GPUS": "0,x"}, "needs GPU indices"), ({"HB_GPUS": "1", "CUDA_VISIBLE_DEVICES": "0"}, "not visible")],
)
def test_bad_hb_gpus_is_refused_in_one_line(environ, message):
    with pytest.raises(HarnessError, match=message) as e:
        gpus.visible(gpus.parse_smi(SMI), environ)
    assert "\n" not in str(e.value)


def test_spread_runs_every_case_once_one_worker_per_gpu():
    listed = gpus.parse_smi(SMI)[:2]
    running, most, lock = {}, [0], threading.Lock()
    both = threading.Barrier(2)

    def run_case(case, gpu):
        with lock:
            running[gpu.index] = running.get(gpu.index, 0) + 1
            assert running[gpu.index] == 1, "two cases on one GPU at once"
            most[0] = max(most[0], sum(running.values()))
        if case < 2:
            both.wait(timeout=10)  # the first two cases meet: one on each GPU, at once
        with lock:
            running[gpu.index] -= 1
        if case == 5:
            raise ValueError("case 5 failed")
        return case * 10

    ended = []
    gpus.spread(list(range(8)), listed, run_case, lambda c, g, r, e: ended.append((c, g.index, r, e)))
    assert sorted(c for c, *_ in ended) == list(range(8))
    assert most[0] == 2 and {g for _, g, _, _ in ended} == {0, 1}
    assert all(r == c * 10 for c, _, r, e in ended if e is None)
    assert [str(e) for c, _, _, e in ended if e is not None] == ["case 5 failed"]
