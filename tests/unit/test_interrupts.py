"""A Ctrl-C that Python drops (it arrived inside a weakref callback) still ends the command."""

import subprocess
import sys

import pytest

from conftest import ROOT

# KeyboardInterrupt raised inside a weakref callback, as SIGINT arriving there raises it;
# then work that lasts about a second, or none
SCRIPT = """
import contextlib, sys, weakref
from harness.core import interrupts
class Held: pass
def callback(_): raise KeyboardInterrupt
try:
    with interrupts.redelivered() if sys.argv[1] == "on" else contextlib.nullcontext():
        held = Held(); ref = weakref.ref(held, callback); del held
        for _ in range(int(sys.argv[2])): pass
    print("ran to its end")
except KeyboardInterrupt:
    print("interrupted")
"""


def run(mode, work):
    argv = [sys.executable, "-c", SCRIPT, mode, str(work)]
    return subprocess.run(argv, cwd=ROOT, capture_output=True, text=True, timeout=60)


def test_python_alone_drops_it_with_a_traceback():
    p = run("off", 10**7)
    assert p.stdout == "ran to its end\n" and "Traceback" in p.stderr


@pytest.mark.parametrize("work", [10**7, 0], ids=["during-the-work", "at-its-end"])
def test_redelivered_raises_it_again_and_prints_nothing(work):
    p = run("on", work)
    assert p.stdout == "interrupted\n" and p.stderr == ""
