"""Ctrl-C that Python drops is delivered again.

Python raises KeyboardInterrupt at whichever line runs when SIGINT arrives. Inside a
weakref callback or a `__del__` it cannot propagate: Python prints "Exception ignored …"
with a traceback and carries on, and the command would run to its end. While `redelivered`
is active, such a dropped interrupt is silenced and raised again a millisecond later (by
SIGALRM: raised from the hook itself, it would be dropped again), so the command still
ends in its one line and exit 130. One raised inside a C extension's callback can come out as a
SystemError caused by it (h5py iterating a file's attributes): `signal_cause` finds it there."""

import contextlib
import signal
import sys
import threading

AGAIN_S = 0.001


@contextlib.contextmanager
def redelivered():
    if threading.current_thread() is not threading.main_thread():  # signals reach the main thread only
        yield
        return
    dropped = []
    previous_hook, previous_alarm = sys.unraisablehook, signal.getsignal(signal.SIGALRM)

    def hook(unraisable):
        if unraisable.exc_type is not None and issubclass(unraisable.exc_type, KeyboardInterrupt):
            dropped.append(True)
            signal.setitimer(signal.ITIMER_REAL, AGAIN_S)
        else:
            previous_hook(unraisable)

    def again(signum, frame):
        while frame is not None:
            if frame.f_code is hook.__code__:  # still inside the hook: later
                signal.setitimer(signal.ITIMER_REAL, AGAIN_S)
                return
            frame = frame.f_back
        dropped.clear()
        raise KeyboardInterrupt

    sys.unraisablehook = hook
    signal.signal(signal.SIGALRM, again)
    try:
        yield
        signal.setitimer(signal.ITIMER_REAL, 0)
        if dropped:  # the command ended before the alarm: it was interrupted all the same
            raise KeyboardInterrupt
    finally:
        signal.setitimer(signal.ITIMER_REAL, 0)
        signal.signal(signal.SIGALRM, previous_alarm if previous_alarm is not None else signal.SIG_DFL)
        sys.unraisablehook = previous_hook


def signal_cause(error, kinds):
    """The exception of one of `kinds` (a signal's: KeyboardInterrupt, the runner's Stopped) among
    `error`'s causes and contexts, else None."""
    seen = set()
    while error is not None and id(error) not in seen:
        if isinstance(error, kinds):
            return error
        seen.add(id(error))
        error = error.__cause__ or error.__context__
    return None
