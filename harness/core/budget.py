"""A time budget for `harness bench --budget 10m` (docs/decisions/bench-runs.md).

The size ladder is the sweep's own: its cases grouped into tiers of one size (strands ×
points), smallest first. The first tier always runs; before each further tier its time is
estimated from the tier just measured in this run (time per case × the size ratio: the
per-strand cost only falls as the size grows, so this over-estimates), and the tier and all
larger ones are left out when the estimate does not fit the time left to the step. The
bench gives each step a declared share of what is left when it starts (SHARES)."""

import contextlib
import multiprocessing
import os
import re
import signal
import sys
import time
from dataclasses import dataclass, field
from pathlib import Path

from harness import HarnessError
from harness.core import runner

# of the time left when the step starts: the paper sweep, then the dynamic sweep; the
# dynamic studies get what is left after that (each runs while any is left); the frame
# budget's curves a share of what is left after the accuracy study (docs/decisions/honest-timings.md)
SHARES = {"paper sweep": 0.45, "dynamic sweep": 0.5, "curly sweep": 0.15, "budget curves": 0.3}
# kept back from the measuring steps for the reports rendered after the last study: at
# de894b7f904c a BUDGET=10m run on the H200 node spent 14.6 s rendering after its last study
# was stopped, so it took 615 s of its 600
REPORT_RESERVE_S = 20.0

_UNIT = {"s": 1, "m": 60, "h": 3600}


def parse_duration(text):
    """'600', '600s', '10m', '1h', '1h30m' → seconds (> 0); anything else refused in one line."""
    t = str(text).strip()
    if re.fullmatch(r"[0-9]+", t):
        value = float(t)
    else:
        parts = re.findall(r"([0-9]+)([smh])", t)
        if not parts or "".join(n + u for n, u in parts) != t:
            raise HarnessError(f"--budget needs a time like 600, 90s, 10m or 1h30m (got '{text}')", code=2)
        value = float(sum(int(n) * _UNIT[u] for n, u in parts))
    if value <= 0:
        raise HarnessError(f"--budget must be more than 0 s (got '{text}')", code=2)
    return value


@dataclass
class Budget:
    """The run's deadline; `allowance(step)` the share of what is left for a step; `reserve`
    seconds of it are kept for the reports after the last step (left() never counts them)."""

    seconds: float
    clock: object = time.monotonic
    reserve: float = 0.0
    start: float = field(default=0.0)
    left_out: list = field(default_factory=list)  # what was not run, for budget.json and the report
    stop_studies: bool = True  # run_study in a child stopped at the end (False: in-process, for a fake clock)

    def __post_init__(self):
        self.start = self.clock()

    def left(self):
        return self.seconds - self.reserve - (self.clock() - self.start)

    def allowance(self, step):
        return max(0.0, self.left() * SHARES.get(step, 1.0))

    def leave_out(self, step, what, reason):
        self.left_out.append({"step": step, "what": what, "reason": reason})

    def record(self):
        return {"budget_s": self.seconds, "used_s": round(self.clock() - self.start, 1), "left_out": self.left_out}


def _entries(dirs):
    """Every file and folder in and under `dirs` (the folders themselves included)."""
    return {q for d in map(Path, dirs) if d.exists() for q in [d, *d.rglob("*")]}


def _remove_added(outputs, before):
    """What a stopped study added to its folders since `before`, deepest first."""
    for q in sorted(_entries(outputs) - before, key=lambda q: len(q.parts), reverse=True):
        if q.is_dir():
            with contextlib.suppress(OSError):
                q.rmdir()
        else:
            q.unlink(missing_ok=True)


def _study_child(fn):
    os.setsid()  # its own process group: the binaries it starts end with it
    runner.reset_after_fork()
    code = 0
    try:
        fn()
    except KeyboardInterrupt:  # forwarded by the parent (runner): its own children are stopped by now
        code = 130
    except runner.Stopped as e:
        code = 128 + e.signum
    except HarnessError as e:
        print(f"harness: error: {e}", file=sys.stderr)
        code = e.code or 1
    except Exception as e:  # one line, as the CLI would say it
        print(f"harness: error: {type(e).__name__}: {e}", file=sys.stderr)
        code = 1
    sys.stdout.flush()
    sys.stderr.flush()
    os._exit(code)


def run_study(plan, study, fn, outputs, say):
    """fn() (a study: it measures and writes into the folders `outputs`) in a child process
    that is stopped, with every binary it started, when the budget runs out; the files it
    had added by then are removed and the study is recorded as left out. True when it ran
    to the end; a HarnessError when it failed."""
    if not plan.stop_studies:
        fn()
        return True
    before = _entries(outputs)
    child = multiprocessing.get_context("fork").Process(target=_study_child, args=(fn,))
    sys.stdout.flush()
    sys.stderr.flush()
    child.start()
    try:
        with runner.supervised(child):  # a signal to the harness reaches the study's group, waited for
            child.join(max(plan.left(), 0.0))
    except BaseException:
        _remove_added(outputs, before)
        raise
    if child.is_alive():
        try:
            os.killpg(child.pid, signal.SIGKILL)
        except ProcessLookupError:
            pass
        child.join()
        _remove_added(outputs, before)
        plan.leave_out(study, "the whole study", "stopped when the budget ran out; what it had written was removed")
        say(f"harness: {study}: stopped when the budget ran out (what it had written is removed)")
        return False
    if child.exitcode != 0:
        code = child.exitcode if child.exitcode > 0 else 1
        raise HarnessError(f"{study} failed (exit {child.exitcode}; its error is above)", code=code)
    return True


def say_fixed_cost(plan, say=None):
    """One line after the validations (which always run): what they took of the budget, and
    when nothing is left, that only each sweep's smallest tier runs and no study."""
    say = say or (lambda m: print(m, flush=True))
    used = plan.clock() - plan.start
    if plan.left() > 0:
        say(
            f"harness: budget: the validations took {used:.0f} s; {plan.left():.0f} s left for the sweeps and studies"
            + (f" ({plan.reserve:.0f} s kept for the reports)" if plan.reserve else "")
        )
    else:
        say(
            f"harness: budget: the validations alone took {used:.0f} s of the {plan.seconds:.0f} s budget: "
            "each sweep runs its smallest size only and no study runs "
            f"(give at least {used + plan.reserve + 60:.0f} s for more)"
        )


def tiers(cases, size):
    """The cases grouped by size(case), smallest first (the sweep's order kept within a tier)."""
    out = {}
    for c in cases:
        out.setdefault(size(c), []).append(c)
    return [(s, out[s]) for s in sorted(out)]


def estimate(last, nxt, work=1.0):
    """Seconds the tier `nxt` = (size, n_cases) should take, from the measured tier
    `last` = (size, n_cases, seconds) of which the share `work` was the timed samples: they
    grow with the size, the rest (process starts, set-up, the stopping rule's rounds) stays."""
    size, n, seconds = last
    per_case = seconds / max(n, 1)
    return per_case * ((1.0 - work) + work * nxt[0] / size) * nxt[1]


class TierGate:
    """Decides, before each tier, whether it fits the allowance: `admit(size, n)` → (True,
    None) or (False, reason); `measured(size, n, seconds)` after a tier ran."""

    def __init__(self, allowance_s, clock=time.monotonic):
        self.allowance, self.clock = allowance_s, clock
        self.start = clock()
        self.last = None
        self.work = 1.0  # the share of the last tier's time that was timed samples
        self.closed = None  # the reason, once a tier was refused (all larger ones are too)
        self.refused = []  # (size, cases) of every tier left out

    def admit(self, size, n):
        if self.closed:
            self.refused.append((size, n))
            return False, self.closed
        if self.last is None:
            return True, None  # the first tier is the measurement the rest is judged by
        need = estimate(self.last, (size, n), self.work)
        left = self.allowance - (self.clock() - self.start)
        if need > left:
            self.closed = (
                f"left out to fit the budget: from size {size} (strands × points) on, the next tier was "
                f"estimated at {need:.0f} s with {max(left, 0):.0f} s of this step's {self.allowance:.0f} s left"
            )
            self.refused.append((size, n))
            return False, self.closed
        return True, None

    def summary(self):
        """What was left out, in words (None when nothing was)."""
        if not self.refused:
            return None
        n = sum(c for _, c in self.refused)
        sizes = ", ".join(str(sz) for sz, _ in self.refused)
        return f"{n} case(s) at sizes {sizes} (strands × points)"

    def measured(self, size, n, seconds, sampled=None):
        """A tier ran: `sampled` of its `seconds` were timed samples (None: all of them)."""
        if n:
            self.last = (size, n, seconds)
            self.work = 1.0 if sampled is None or seconds <= 0 else min(1.0, max(sampled / seconds, 0.0))


def largest_that_fits(ladder, seconds_at, allowance_s):
    """The largest size of `ladder` whose estimate seconds_at(size) fits allowance_s; the
    smallest when none does (a study's smallest size still says something)."""
    fitting = [n for n in ladder if seconds_at(n) <= allowance_s]
    return max(fitting) if fitting else min(ladder)
