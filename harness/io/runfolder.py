"""The one owner of a results folder (bench, sweep, merge and the studies that write a folder):
a marker file naming the folder as a hairbench run (`.hairbench-run.json`: the command that made
it), an exclusive lock held while this process runs (`.hairbench-run.lock`, flock), and refusal
of a folder that is not ours: one that holds files but no marker (a user's folder) unless
`force`, and always `/`, the home folder, the repository itself and any folder above it. A
sub-folder of a run folder (the bench's sweep/, stability/) belongs to that run."""

import contextlib
import fcntl
import json
import os
from pathlib import Path

from harness import HarnessError
from harness.core.paths import ROOT, display
from harness.io import files

MARKER = ".hairbench-run.json"
LOCK = ".hairbench-run.lock"
_held: dict[Path, int] = {}  # folder → the locked descriptor, kept until the process ends
_made: list[Path] = []  # the folders a claim created, outermost first


def _forbidden(path: Path) -> str | None:
    if path == Path(path.anchor):
        return "the file system's root"
    if path == Path.home().resolve():
        return "your home folder"
    if path == ROOT or path in ROOT.parents:
        return "the repository or a folder above it"
    return None


def is_run(path: Path) -> bool:
    return (path / MARKER).is_file() or (path.parent / MARKER).is_file()


def claim(folder: str | Path, command: str, force: bool = False, what: str = "--out") -> Path:
    """Make `folder` (parents too) this run's, marked and locked; refused in one line (exit 2)."""
    path = Path(folder).resolve()
    why = _forbidden(path)
    if why:
        raise HarnessError(f"{what} {folder}: refusing to write results into {why}; give a folder of its own")
    if path in _held:
        return path
    if path.exists() and not path.is_dir():
        raise HarnessError(f"{what} {folder} exists and is not a directory")
    if path.is_dir() and not is_run(path) and any(path.iterdir()) and not force:
        raise HarnessError(
            f"{what} {folder} holds files but is not a hairbench run folder (no {MARKER}); give a new or empty "
            "folder, or --force to write into it"
        )
    new = [q for q in (path, *path.parents) if not q.exists()][::-1]
    try:
        path.mkdir(parents=True, exist_ok=True)
        _made.extend(new)
        fd = os.open(path / LOCK, os.O_RDWR | os.O_CREAT | os.O_CLOEXEC, 0o644)
    except OSError as e:
        raise HarnessError(f"{what} {folder}: cannot make the folder ({e.strerror or e})") from None
    try:
        fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
    except BlockingIOError:
        os.close(fd)
        raise HarnessError(
            f"{what} {display(path)} is in use by another hairbench run; wait for it or give another folder"
        ) from None
    _held[path] = fd
    if not (path / MARKER).is_file():
        files.write_text(path / MARKER, json.dumps({"hairbench": "run folder", "command": command}) + "\n")
    return path


def abandon_unused() -> None:
    """After a command that failed: each folder a claim created that holds nothing but its marker
    and lock is removed (deepest first), with the lock given up; a refused command creates nothing."""
    for path in reversed(_made):
        names = set(os.listdir(path)) if path.is_dir() else {""}
        if names <= {MARKER, LOCK}:
            release(path)
            for name in names:
                (path / name).unlink(missing_ok=True)
            with contextlib.suppress(OSError):
                path.rmdir()
    _made.clear()


def release(folder: str | Path) -> None:
    """Give up the lock of `folder` (a test; a process's end does it by itself)."""
    fd = _held.pop(Path(folder).resolve(), None)
    if fd is not None:
        os.close(fd)
