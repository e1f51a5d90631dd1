"""Progress of a long step: a bar (tqdm) on a terminal; elsewhere (a CI job's log, a file)
a line at most every `every` seconds and at the end: done/total, time elapsed, an estimate
of what is left. Without tqdm the lines are printed on a terminal too."""

import sys
import time

try:
    from tqdm import tqdm as _tqdm
except ImportError:  # the harness works without it
    _tqdm = None

LOG_EVERY_S = 30.0  # a log shows a step is alive at least this often


class Progress:
    def __init__(self, total, desc, stream=None, clock=time.monotonic, every=LOG_EVERY_S):
        self.total, self.desc, self.clock, self.every = total, desc, clock, every
        self.stream = stream if stream is not None else sys.stderr
        tty = bool(getattr(self.stream, "isatty", lambda: False)())
        self.bar = None
        if _tqdm is not None and total and tty:
            self.bar = _tqdm(total=total, desc=desc, unit="case", file=self.stream, dynamic_ncols=True, leave=True)
        self.lines = bool(total) and self.bar is None
        self.done = 0
        self.start = self.last = clock()

    def update(self, n=1):
        if self.bar is not None:
            self.bar.update(n)
            return
        self.done += n
        now = self.clock()
        if self.lines and (now - self.last >= self.every or self.done >= self.total):
            self.last = now
            self._line(now)

    def _line(self, now):
        elapsed = now - self.start
        left = elapsed / self.done * (self.total - self.done) if self.done else float("nan")
        print(
            f"{self.desc}: {self.done}/{self.total} done, {elapsed:.0f} s elapsed, about {left:.0f} s left",
            file=self.stream,
            flush=True,
        )

    def write(self, message):
        """Print a line without breaking the bar."""
        if self.bar is not None:
            self.bar.write(message, file=self.stream)
        else:
            print(message, file=self.stream, flush=True)

    def close(self):
        if self.bar is not None:
            self.bar.close()
