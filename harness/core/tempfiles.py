"""The binaries' temporary outputs (docs/interfaces.md, "Writing the output"): the one rule,
on the Python side, for which files the harness may remove after a child it killed or that
was interrupted. A file is a binary's temporary only with both its name
(`.hairsim-<pid>-<16 hex>.tmp`) and its marker (the first bytes of its HDF5 user block);
c_ref/runtime/safe_write.h holds the same two."""

import os
import re
from collections.abc import Iterable, Sequence
from pathlib import Path
from typing import Any

NAME = re.compile(r"\.hairsim-([1-9][0-9]*)-[0-9a-f]{16}\.tmp")
MARKER = b"HAIRSIM-TEMPORARY-OUTPUT\n"


def owner_pid(name: str) -> int | None:
    """The pid in a temporary's name, or None for any other name."""
    m = NAME.fullmatch(name)
    return int(m.group(1)) if m else None


def is_marked(path: Path) -> bool:
    """A regular file (not a link) of this user that starts with the marker."""
    try:
        st = path.lstat()
        if not path.is_file() or path.is_symlink() or st.st_uid != os.geteuid():
            return False
        fd = os.open(path, os.O_RDONLY | os.O_NOFOLLOW | os.O_NONBLOCK)
        try:
            return os.read(fd, len(MARKER)) == MARKER
        finally:
            os.close(fd)
    except OSError:
        return False


def owned_by(directory: Path, pid: int) -> list[Path]:
    """The marked temporaries of process `pid` in `directory`."""
    try:
        names = os.listdir(directory)
    except OSError:
        return []
    return [directory / n for n in names if owner_pid(n) == pid and is_marked(directory / n)]


def remove_left_by(pid: int, directories: Iterable[Path]) -> list[Path]:
    """Remove what the dead child `pid` left in `directories`; the paths removed."""
    removed = []
    for d in directories:
        for p in owned_by(Path(d), pid):
            try:
                p.unlink()
                removed.append(p)
            except FileNotFoundError:
                pass
    return removed


def output_dirs(args: Sequence[Any]) -> list[Path]:
    """The directory of each `--output FILE` in a binary's flags."""
    a = [str(x) for x in args]
    return [Path(a[i + 1]).parent for i in range(len(a) - 1) if a[i] == "--output"]
