"""hairbench harness: run, diff, sweep, plot and report the hair-strand backends.

The backends (build/hairsim-cpu, build/hairsim-cuda[-strict|-fastmath]) are driven only
through the interface of docs/interfaces.md; `python -m harness --help` lists the commands
and docs/harness.md explains them.
"""

__version__ = "0.1.0"


class HarnessError(Exception):
    """A user-facing error: printed as one line `harness: error: …`, never a traceback.

    `code` is the process exit status (2 = bad input or could not compare, unless a
    command documents another)."""

    def __init__(self, message, code=2):
        super().__init__(message)
        self.code = code
