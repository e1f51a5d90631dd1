"""Timed runs by the stopping rule (core/timing.py): cases measured in rounds of timed repeats,
each round's binaries in batches (runner.run_batch), the load each round ran under recorded.
The one module of the timing machinery that starts binaries (renderers import core/timing.py)."""

import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import Any

from harness.core.load import LoadProbe, worst_load
from harness.core.runner import BATCH_MAX, batches, run_batch
from harness.core.timing import RULE, Figure, StopRule, stats


def _timed_stages(record):
    return [i for i, s in enumerate(record.get("stages", [])) if s.get("times_ms")]


def merge(record, more):
    """`record` with the stage times of `more` (a later round of the same case) appended, and
    each stage's median/min/max recomputed from all of them."""
    for st, extra in zip(record["stages"], more["stages"]):
        if st.get("times_ms") and extra.get("times_ms"):
            st["times_ms"] = list(st["times_ms"]) + list(extra["times_ms"])
            s = stats(st["times_ms"])
            st["median_ms"], st["min_ms"], st["max_ms"] = s["median_ms"], s["min_ms"], s["max_ms"]
            if st.get("point_substeps_per_s") and s["median_ms"] > 0 and extra.get("median_ms"):
                st["point_substeps_per_s"] = extra["point_substeps_per_s"] * extra["median_ms"] / s["median_ms"]
    return record


@dataclass
class Timed:
    """A case measured by the rule: its record (stage times merged over the rounds), one Figure
    per timed stage (by stage index), or the error that ended it."""

    record: dict | None = None
    figures: dict = field(default_factory=dict)
    error: Exception | None = None


def measure(
    cases: Sequence[Any],
    flags: Callable[[Any, int], list],
    binary: Callable[[Any], Any],
    rule: StopRule = RULE,
    timeout: float | None = None,
    env: dict | None = None,
    gpu_index: Any = None,
    on_done: Callable[[int, Timed], None] | None = None,
    batch: int = BATCH_MAX,
) -> list[Timed]:
    """Time each case (`flags(case, repeat)`: its binary flags for `repeat` timed repeats;
    `binary(case)`: its binary) by the rule, in rounds batched per binary, `batch` cases to a
    process (runner.run_batch). `on_done(i, timed)` as each case ends. Returns one Timed per
    case, in order."""
    out = [Timed() for _ in cases]
    started = [None] * len(cases)
    todo = {i: rule.min_samples for i in range(len(cases))}
    rounds = [0] * len(cases)
    loads: list[list] = [[] for _ in cases]
    while todo:
        work = sorted(todo)
        for chunk in batches(work, lambda i: str(binary(cases[i])), batch):
            b = binary(cases[chunk[0]])
            probe = LoadProbe(gpu="cuda" in str(b), gpu_index=gpu_index)
            argv = [flags(cases[i], todo[i]) for i in chunk]
            ended = list(run_batch(b, argv, timeout, env=env))
            load = probe.stop()
            for k, rec, error in ended:
                i = chunk[k]
                started[i] = started[i] or time.monotonic() - load["wall_s"]
                rounds[i] += 1
                loads[i].append(load)
                if error is not None:
                    out[i].error = error
                    todo.pop(i)
                    continue
                out[i].record = rec if out[i].record is None else merge(out[i].record, rec)
                more, stop = _next(out[i].record, rule, time.monotonic() - started[i])
                if more:
                    todo[i] = more
                    continue
                todo.pop(i)
                backend = "cuda" if "cuda" in str(b) else "cpu"
                out[i].figures = {
                    j: Figure(out[i].record["stages"][j]["times_ms"], stop, rounds[i], worst_load(loads[i]), backend)
                    for j in _timed_stages(out[i].record)
                }
            for i in chunk:
                if i not in todo and on_done:
                    on_done(i, out[i])
    return out


def _next(record, rule, elapsed_s):
    """(repeats the next round takes, why it stopped): (n, '') while the rule asks for more."""
    timed = _timed_stages(record)
    if not timed:
        return 0, "rule met"
    n = max(len(record["stages"][j]["times_ms"]) for j in timed)
    more = max(rule.need(record["stages"][j]["times_ms"]) for j in timed)
    if more == 0:
        return 0, "rule met"
    if n >= rule.max_samples:
        return 0, "max samples"
    if elapsed_s >= rule.timeout_s:
        return 0, "timeout"
    if n > 0:  # no more than fits the time left to the timeout, at the median's pace
        pace = max(stats(record["stages"][j]["times_ms"])["median_ms"] for j in timed) * 1e-3
        if pace > 0:
            more = min(more, max(1, int((rule.timeout_s - elapsed_s) / pace)))
    return more, ""
