"""A progress bar (tqdm) that falls back silently to none when tqdm is missing."""

import sys

try:
    from tqdm import tqdm as _tqdm
except ImportError:  # the harness works without it
    _tqdm = None


class Progress:
    def __init__(self, total, desc):
        self.bar = None
        if _tqdm is not None and total:
            self.bar = _tqdm(
                total=total, desc=desc, unit="case", file=sys.stderr, dynamic_ncols=True, leave=True, disable=None
            )  # no bar off a terminal

    def update(self, n=1):
        if self.bar is not None:
            self.bar.update(n)

    def write(self, message):
        """Print a line without breaking the bar."""
        if self.bar is not None:
            self.bar.write(message, file=sys.stderr)
        else:
            print(message, file=sys.stderr, flush=True)

    def close(self):
        if self.bar is not None:
            self.bar.close()
