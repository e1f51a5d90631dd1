"""Progress of a long step: a bar (tqdm) on a terminal; elsewhere (a CI job's log, a file)
a line when it starts (how many to do), then at least every LOG_EVERY_S seconds and at the
end: done/total, time elapsed, an estimate of what is left. A timer thread prints the line
when no case has ended for `every` seconds (one case can take minutes), so the log never goes
quiet for longer. Without tqdm the lines are printed on a terminal too.

The estimate is by work, not by count, where the step gives each case's size (`work`: the
total, and each update's share; a sweep's strands × points): small cases first and large ones
last would otherwise promise seconds for minutes. A case left out (`skip`) leaves the total."""

import sys
import threading
import time

from harness.core import gpus

try:
    from tqdm import tqdm as _tqdm
except ImportError:  # the harness works without it
    _tqdm = None

LOG_EVERY_S = 30.0  # a log shows a step is alive at least this often
LINE_AFTER_S = LOG_EVERY_S - 1.0  # a line is due this long after the last: the second left covers the timer's wake-up


class Progress:
    def __init__(self, total, desc, stream=None, clock=time.monotonic, every=LINE_AFTER_S, timer=None, work=None):
        """`timer`: run the thread that prints when nothing ends for `every` s (default: with
        the real clock off a terminal; tests drive tick() with a fake clock instead). `work`:
        the cases' total size, to estimate by (each update then gives its case's)."""
        self.total, self.desc, self.clock, self.every = total, desc, clock, every
        self.work_total, self.work_done = work, 0.0
        self.stream = stream if stream is not None else sys.stderr
        tty = bool(getattr(self.stream, "isatty", lambda: False)())
        self.bar = None
        if _tqdm is not None and total and tty:
            self.bar = _tqdm(total=total, desc=desc, unit="case", file=self.stream, dynamic_ncols=True, leave=True)
        self.lines = bool(total) and self.bar is None
        self.done = 0
        self.start = self.last = clock()
        if self.lines:
            print(f"{desc}: {total} to do", file=self.stream, flush=True)
        self._lock = threading.Lock()
        self._stop = threading.Event()
        self._thread = None
        if timer is None:
            timer = clock is time.monotonic
        if self.lines and timer:
            self._thread = threading.Thread(target=self._beat, name=f"progress {desc}", daemon=True)
            self._thread.start()

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()

    def update(self, n=1, work=0.0, skip=False):
        """`n` cases ended, of size `work` (with `work` given at the start); `skip`: left out,
        not run, so their work leaves the total instead of counting as done."""
        with self._lock:
            if self.work_total is not None:
                if skip:
                    self.work_total -= work
                else:
                    self.work_done += work
        if self.bar is not None:
            self.bar.update(n)
            return
        with self._lock:
            self.done += n
            now = self.clock()
            if self.lines and (now - self.last >= self.every or self.done >= self.total):
                self._line(now)

    def tick(self):
        """Print the line if none was printed for `every` seconds (the timer calls this)."""
        with self._lock:
            now = self.clock()
            if self.lines and self.done < self.total and now - self.last >= self.every:
                self._line(now)

    def _beat(self):
        """Wake when the next line is due (a case ending in between moves that time on)."""
        while not self._stop.wait(max(0.01, self.last + self.every - self.clock())):
            self.tick()

    def _line(self, now):
        self.last = now
        elapsed = now - self.start
        if self.work_total is not None and self.work_done > 0:
            left = f"about {elapsed / self.work_done * max(0.0, self.work_total - self.work_done):.0f} s left"
        elif self.done and self.work_total is None:
            left = f"about {elapsed / self.done * (self.total - self.done):.0f} s left"
        else:
            left = "no estimate before the first is done"
        print(
            f"{self.desc}: {self.done}/{self.total} done, {elapsed:.0f} s elapsed, {left}", file=self.stream, flush=True
        )

    def write(self, message):
        """Print a line without breaking the bar."""
        if self.bar is not None:
            self.bar.write(message, file=self.stream)
        else:
            print(message, file=self.stream, flush=True)

    def close(self):
        self._stop.set()
        if self._thread is not None:
            self._thread.join()
            self._thread = None
        if self.bar is not None:
            self.bar.close()


class StepTimes:
    """How long each step of a run took, in the order they ran, and the work each step sent to
    each named GPU (core/gpus.py `working`); summary() is the log's last line, so a CI log says
    where a run's time went (each step's own lines say how far it got). `on_step(self)` is
    called as each step ends (the bench writes OUT/steps.json then)."""

    def __init__(self, clock=time.monotonic, on_step=None):
        self.clock = clock
        self.start = clock()
        self.steps = []  # (name, seconds)
        self.gpu_work = []  # per step: {GPU index: seconds of work sent to it}
        self.on_step = on_step

    def step(self, name, fn, *args, **kwargs):
        """fn(*args, **kwargs), timed as `name`; its result."""
        t, before = self.clock(), gpus.work_seconds()
        try:
            return fn(*args, **kwargs)
        finally:
            self.steps.append((name, self.clock() - t))
            after = gpus.work_seconds()
            self.gpu_work.append({i: s - before.get(i, 0.0) for i, s in after.items() if s > before.get(i, 0.0)})
            if self.on_step is not None:
                self.on_step(self)

    def elapsed(self):
        return self.clock() - self.start

    def summary(self, what):
        parts = ", ".join(f"{name} {s:.0f} s" for name, s in self.steps)
        return f"harness: {what} took {self.clock() - self.start:.0f} s" + (f" ({parts})" if parts else "")
