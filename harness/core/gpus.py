"""Every GPU of the node: which GPUs the sweep spreads its GPU cases over, and the spreading.

`visible()` lists the GPUs as nvidia-smi -L names them, kept to CUDA_VISIBLE_DEVICES when a
scheduler set it (indices or UUIDs) and to HB_GPUS when given (indices as nvidia-smi -L
numbers them, e.g. HB_GPUS=0,1; HB_GPUS=0 keeps one GPU). `spread()` runs cases on one
worker per GPU, each worker's child seeing only its GPU (CUDA_VISIBLE_DEVICES), a worker
taking the next case when its last one ends; the caller runs the CPU cases before or after,
never while GPU workers load the host.

`working(gpu)` counts the wall time of a run sent to a named GPU as that GPU's work (the
sweeps' GPU cases, the stability map's GPU cells; runs that overlap on one GPU add up), so a
bench step can say how its GPU work was shared (core/progress.py StepTimes). Runs left to the
first GPU without naming it (the validations, the other studies) are not counted."""

import contextlib
import os
import queue
import re
import shutil
import threading
import time
from dataclasses import dataclass

from harness import HarnessError


@dataclass(frozen=True)
class Gpu:
    index: int  # as nvidia-smi -L numbers it
    name: str
    uuid: str = ""

    @property
    def select(self):
        """The CUDA_VISIBLE_DEVICES value that shows a child this GPU alone."""
        return self.uuid or str(self.index)


_LINE = re.compile(r"GPU (\d+): (.*?) \(UUID: ([^)]+)\)")


def parse_smi(text):
    return [Gpu(int(m[1]), m[2].strip(), m[3].strip()) for m in _LINE.finditer(text or "")]


def _smi_list():
    smi = shutil.which("nvidia-smi")
    if smi is None:
        return []
    from harness.core import runner

    try:
        return parse_smi(runner.run_command([smi, "-L"], timeout=30).stdout)
    except (OSError, runner.TimedOut):
        return []


def wanted(environ=None):
    """HB_GPUS's indices, or None when it is unset or 'all'; a value that is not indices is refused
    in one line whether or not this machine has a GPU (harness/cli/main.py checks it first)."""
    environ = os.environ if environ is None else environ
    text = environ.get("HB_GPUS", "").strip()
    if not text or text == "all":
        return None
    try:
        indices = [int(x, 10) for x in text.split(",")]
    except ValueError:
        raise HarnessError(f"HB_GPUS needs GPU indices like 0,1 (got '{text}')") from None
    if any(i < 0 for i in indices):
        raise HarnessError(f"HB_GPUS needs GPU indices like 0,1 (got '{text}')")
    return indices


def visible(listed=None, environ=None):
    """The GPUs to use (see the module's text); `listed` and `environ` replace nvidia-smi -L's
    GPUs and os.environ (tests)."""
    environ = os.environ if environ is None else environ
    gpus = _smi_list() if listed is None else list(listed)
    cvd = environ.get("CUDA_VISIBLE_DEVICES")
    if cvd is not None and cvd.strip() != "":
        keep = [x.strip() for x in cvd.split(",") if x.strip()]
        gpus = [
            g for g in gpus if str(g.index) in keep or g.uuid in keep or any(k and g.uuid.startswith(k) for k in keep)
        ]
    indices = wanted(environ)
    if indices is not None:
        by_index = {g.index: g for g in gpus}
        missing = [i for i in indices if i not in by_index]
        if missing:
            have = ", ".join(str(g.index) for g in gpus) or "none"
            raise HarnessError(
                f"HB_GPUS names GPU(s) {', '.join(map(str, missing))} that are not visible (visible: {have})"
            )
        gpus = [by_index[i] for i in dict.fromkeys(indices)]
    return gpus


_work: dict[int, float] = {}  # GPU index → seconds of runs sent to it, in this process
_work_lock = threading.Lock()


@contextlib.contextmanager
def working(gpu):
    """The block's wall time counted as work of `gpu` (a Gpu; None counts nothing)."""
    t = time.monotonic()
    try:
        yield
    finally:
        if gpu is not None:
            with _work_lock:
                _work[gpu.index] = _work.get(gpu.index, 0.0) + time.monotonic() - t


def work_seconds():
    """Each GPU's work so far (index → seconds), a copy."""
    with _work_lock:
        return dict(_work)


def spread(cases, gpus, run_case, on_done):
    """run_case(case, gpu) for every case, on one worker thread per GPU; on_done(case, gpu,
    result, error) is called in the calling thread as each ends (in the order they end)."""
    todo = queue.Queue()
    for c in cases:
        todo.put(c)
    ended = queue.Queue()
    stop = threading.Event()

    def worker(gpu):
        while not stop.is_set():
            try:
                case = todo.get_nowait()
            except queue.Empty:
                return
            try:
                ended.put((case, gpu, run_case(case, gpu), None))
            except Exception as e:  # reported to the caller, which decides
                ended.put((case, gpu, None, e))

    threads = [threading.Thread(target=worker, args=(g,), name=f"gpu {g.index}", daemon=True) for g in gpus]
    for t in threads:
        t.start()
    try:
        for _ in range(len(cases)):
            on_done(*ended.get())
    finally:
        stop.set()
        for t in threads:
            t.join()
