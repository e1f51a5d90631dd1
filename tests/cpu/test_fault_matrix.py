"""The fault matrix, generated (issue #46): the binary's flags are read from its --help and the
harness's inputs from its argparse parser, so a flag or command added later is covered without
anyone listing it. Each declared input meets each fault kind: a file input a FIFO, a directory,
a missing, empty, truncated or garbage file; a value NaN, Inf, an overflowing or garbage number;
an --output a directory, a FIFO, a symbolic link or a full disk. Each must end within its time
(no hang), refused in one line with no traceback and nothing left behind, or run. The suite
prints the counts (tests/conftest.py)."""

import argparse
import contextlib
import io
import os
import re
import signal
import subprocess

import pytest

from conftest import CPU_BIN
from harness.cli.main import main as harness_main
from harness.cli.main import parser as harness_parser
from support import fulldisk
from support.faults import FILE_FAULTS, make_fault

SIM = ["--stages", "init,simulate", "--strands", "4", "--points", "4", "--hair-length", "5", "--quiet"]
BAD_VALUES = ("nan", "inf", "-inf", "1e999", "99999999999999999999999", "x1", "")
OUTPUT_FAULTS = ("directory", "fifo", "symlink", "full-disk")


def binary_flags():
    """(flag, value name) of every flag the binary's --help lists; value name '' for a switch."""
    if not CPU_BIN.exists():
        return []
    text = subprocess.run([str(CPU_BIN), "--help"], capture_output=True, text=True, timeout=30).stdout
    return [(m[1], m[2] or "") for m in re.finditer(r"^  (--[a-z0-9-]+)(?: (\S+))?", text, re.M)]


FLAGS = binary_flags()
FILE_FLAGS = [f for f, v in FLAGS if v in ("FILE", "G") and f != "--output"]
VALUE_FLAGS = [f for f, v in FLAGS if v and v not in ("FILE", "G", "rng", "[S]") and f != "--output"]


# the flags a file flag needs beside it to be read at all
FILE_FLAG_CONTEXT = {
    "--batch": [],
    "--groom": ["--stages", "init,simulate"],
    "--motion-track": ["--head-motion", "track", "--stages", "init,simulate"],
    "--colliders": ["--stages", "init,simulate"],
}


def refused_in_one_line(p, *words):
    lines = p.stderr.strip().splitlines()
    assert p.returncode == 2 and len(lines) == 1 and "Traceback" not in p.stderr, (p.returncode, p.stderr)
    assert all(w in lines[0] for w in words), lines[0]


def test_the_matrix_sees_the_binarys_flags():
    """--help lists every flag the parser takes (cli.c's one table), so the rows below are all of them."""
    names = {f for f, _ in FLAGS}
    assert {"--groom", "--input", "--batch", "--output", "--seed", "--frames", "--lra"} <= names, names
    assert len(VALUE_FLAGS) >= 40, VALUE_FLAGS
    assert {"--groom", "--input", "--batch", "--motion-track", "--colliders"} <= set(FILE_FLAGS), FILE_FLAGS


@pytest.mark.parametrize("kind", FILE_FAULTS)
@pytest.mark.parametrize("flag", FILE_FLAGS)
def test_binary_file_input(cpu_bin, tmp_path, flag, kind):
    path = make_fault(tmp_path, kind)
    args = [flag, path, *FILE_FLAG_CONTEXT.get(flag, ["--stages", "simulate"])]
    p = subprocess.run([str(cpu_bin), *map(str, args)], capture_output=True, text=True, timeout=30)
    refused_in_one_line(p, flag, str(path))


@pytest.mark.parametrize("value", BAD_VALUES, ids=repr)
@pytest.mark.parametrize("flag", VALUE_FLAGS)
def test_binary_bad_value(cpu_bin, tmp_path, flag, value):
    p = subprocess.run([str(cpu_bin), *SIM, flag, value], capture_output=True, text=True, timeout=30, cwd=tmp_path)
    if value.isdigit() and p.returncode == 0:  # 1e23 is a legitimate real (an angle, a compliance)
        assert p.stderr == ""
    else:
        refused_in_one_line(p, flag)
    assert os.listdir(tmp_path) == []


@pytest.mark.parametrize("kind", OUTPUT_FAULTS)
def test_binary_output(cpu_bin, tmp_path, kind):
    out = tmp_path / "o.h5"
    if kind == "full-disk":
        p = fulldisk.run(
            tmp_path, f'"{cpu_bin}" --strands 20000 --points 32 --output "$D/o.h5" --quiet; echo "rc=$?"; ls -A "$D"'
        )
        assert p.stdout.split() == ["rc=4"] and len(p.stderr.strip().splitlines()) == 1, (p.stdout, p.stderr)
        return
    if kind == "directory":
        out.mkdir()
    elif kind == "fifo":
        os.mkfifo(out)
    else:
        (tmp_path / "target").write_bytes(b"mine")
        out.symlink_to(tmp_path / "target")
    p = subprocess.run(
        [str(cpu_bin), *SIM, "--output", str(out), "--force"], capture_output=True, text=True, timeout=30
    )
    refused_in_one_line(p, "--output")
    assert sorted(os.listdir(tmp_path)) == sorted(["o.h5"] + (["target"] if kind == "symlink" else []))


# ---- the harness: every positional input of every command, and every option naming a file ----

FOLDER_WORDS = re.compile(r"\b(folder|root|directory)\b", re.I)
FOLDERS: set[tuple[str, ...]] = set()  # commands whose positional is a folder: a directory is no fault there
FILE_WORDS = re.compile(r"\b(file|state|csv|toml|path|folder|scene|sweep|usd|hair)\b", re.I)


def harness_inputs():
    """(command words, option or None, nargs of positionals) of every declared input that names a
    file: each subcommand's positionals and the options whose help names a file."""
    out = []

    def walk(p, words):
        for a in p._actions:
            if isinstance(a, argparse._SubParsersAction):
                for name, sub in a.choices.items():
                    walk(sub, [*words, name])
            elif not a.option_strings and a.nargs != argparse.REMAINDER and a.dest != "help":
                out.append((tuple(words), None))
                if FOLDER_WORDS.search(a.help or ""):
                    FOLDERS.add(tuple(words))
            elif (
                a.option_strings
                and a.nargs is None
                and a.type is None
                and a.choices is None
                and not isinstance(a, (argparse._StoreTrueAction, argparse._HelpAction, argparse._VersionAction))
                and FILE_WORDS.search(a.help or "")
                and not re.search(r"\b(out|report|keep)", a.dest)
            ):
                out.append((tuple(words), a.option_strings[-1]))

    walk(harness_parser(), [])
    return out


DECLARED = harness_inputs()  # one entry a positional (a command with two has two) or option
POSITIONALS = {w: sum(1 for v, o in DECLARED if v == w and o is None) for w, _ in DECLARED}
INPUTS = sorted(set(DECLARED), key=str)


class Hung(Exception):
    pass


def run_harness(argv, seconds=20):
    """main(argv) in this process, its stderr captured; Hung past `seconds` (SIGALRM)."""

    def ring(signum, frame):
        raise Hung(" ".join(argv))

    err = io.StringIO()
    old = signal.signal(signal.SIGALRM, ring)
    signal.alarm(seconds)
    try:
        with contextlib.redirect_stderr(err), contextlib.redirect_stdout(io.StringIO()):
            code = harness_main(argv)
    except SystemExit as e:  # argparse
        code = e.code
    finally:
        signal.alarm(0)
        signal.signal(signal.SIGALRM, old)
    return code, err.getvalue()


def test_the_matrix_sees_the_harness_inputs():
    commands = {w for w, _ in INPUTS}
    assert {("diff",), ("export",), ("run",), ("sweep",), ("merge",), ("groom", "convert")} <= commands, commands
    assert ("stability",) in {w for w, o in INPUTS if o == "--from-csv"}


@pytest.mark.parametrize("kind", ("fifo", "directory", "missing", "empty", "garbage"))
@pytest.mark.parametrize("words, option", INPUTS, ids=lambda x: " ".join(x) if isinstance(x, tuple) else str(x))
def test_harness_input(tmp_path, monkeypatch, words, option, kind):
    if kind == "directory" and option is None and words in FOLDERS:
        pytest.skip(f"{' '.join(words)} takes a folder")
    monkeypatch.setenv("HAIRBENCH_NO_GPU", "1")
    monkeypatch.chdir(tmp_path)
    path = str(make_fault(tmp_path, kind))
    positionals = POSITIONALS[words]
    if option:
        argv = [*words, *([path] * positionals), option, path]
    else:
        argv = [*words, *([path] * positionals)]
    code, err = run_harness(argv)
    lines = err.strip().splitlines()
    assert code not in (0, None) and len(lines) == 1 and "Traceback" not in err, (argv, code, err)
    expected = [] if kind == "missing" else [f"input-{kind}"]
    assert sorted(os.listdir(tmp_path)) == expected, (argv, os.listdir(tmp_path))
