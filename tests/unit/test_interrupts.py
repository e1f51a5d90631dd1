"""A Ctrl-C that Python drops (it arrived inside a weakref callback), or that a C extension's callback
turns into a SystemError, still ends the command."""

import argparse
import signal
import subprocess
import sys

import pytest

from conftest import ROOT
from harness.cli import main as cli_main
from harness.core import runner

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


class _Parser:
    """main's parser, with one command: `command`."""

    def __init__(self, command):
        self.command = command

    def parse_args(self, argv):
        return argparse.Namespace(func=self.command)


def _inside_a_callback(exc):
    """A command whose signal's exception came out of a C extension's callback as h5py raises it:
    a SystemError caused by it (CI, 2026-11-27: Ctrl-C while the accuracy study read a state)."""

    def command(args):
        try:
            raise exc
        except BaseException as e:
            raise SystemError("<cyfunction FastRLock.__exit__> returned a result with an exception set") from e

    return command


@pytest.mark.parametrize(
    "exc, rc, line",
    [
        (KeyboardInterrupt(), 130, "harness: interrupted\n"),
        (runner.Stopped(signal.SIGTERM), 143, "harness: stopped by SIGTERM\n"),
    ],
    ids=["ctrl-c", "sigterm"],
)
def test_a_signal_raised_inside_a_c_callback_still_ends_in_one_line(monkeypatch, capsys, exc, rc, line):
    monkeypatch.setattr(cli_main, "parser", lambda: _Parser(_inside_a_callback(exc)))
    assert cli_main.main([]) == rc
    assert capsys.readouterr().err == line


def test_a_system_error_of_its_own_is_not_taken_for_a_signal(monkeypatch):
    def command(args):
        raise SystemError("a defect")

    monkeypatch.setattr(cli_main, "parser", lambda: _Parser(command))
    with pytest.raises(SystemError, match="a defect"):
        cli_main.main([])
