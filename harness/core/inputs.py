"""The one way the harness opens a file a user names (a state, a CSV, a scene or sweep, a groom,
a shard's records): a regular file only, checked before any reader touches it (a FIFO with no
writer would block it, a directory or device never ends), not empty, readable; each refusal one
line naming the file as the user gave it (HarnessError, exit 2). The binaries keep the same rule
in c_ref/runtime/input.c. Readers that open the path themselves (h5py, pandas, tomllib) are
called through here: `open_h5`, `read_text`, `read_bytes`, `read_json`."""

import json
import os
import stat
from pathlib import Path
from typing import Any

from harness import HarnessError

KINDS = (
    (stat.S_ISDIR, "a directory"),
    (stat.S_ISFIFO, "a FIFO"),
    (stat.S_ISSOCK, "a socket"),
    (stat.S_ISCHR, "a device"),
    (stat.S_ISBLK, "a device"),
)


def kind(mode: int) -> str:
    return next((name for test, name in KINDS if test(mode)), "not a regular file")


def regular(path: str | Path, what: str, empty_ok: bool = False) -> Path:
    """`path`, checked to be a readable regular file (non-empty unless `empty_ok`); `what` names
    the input in the message ('diff', '--from-csv', 'scene')."""
    p = Path(path)
    try:
        fd = os.open(p, os.O_RDONLY | os.O_NONBLOCK | os.O_NOCTTY)
    except FileNotFoundError:
        raise HarnessError(f"{what} {path}: no such file") from None
    except IsADirectoryError:
        raise HarnessError(f"{what} {path} is a directory; it must be a regular file") from None
    except OSError as e:
        raise HarnessError(f"{what} {path}: cannot read it ({e.strerror})") from None
    try:
        st = os.fstat(fd)
    finally:
        os.close(fd)
    if not stat.S_ISREG(st.st_mode):
        raise HarnessError(f"{what} {path} is {kind(st.st_mode)}; it must be a regular file")
    if st.st_size == 0 and not empty_ok:
        raise HarnessError(f"{what} {path} is empty")
    return p


def read_bytes(path: str | Path, what: str) -> bytes:
    p = regular(path, what, empty_ok=True)
    try:
        return p.read_bytes()
    except OSError as e:
        raise HarnessError(f"{what} {path}: cannot read it ({e.strerror})") from None


def read_text(path: str | Path, what: str) -> str:
    data = read_bytes(path, what)
    try:
        return data.decode("utf-8")
    except UnicodeDecodeError as e:
        raise HarnessError(f"{what} {path}: not UTF-8 text (byte {e.start})") from None


def read_json(path: str | Path, what: str) -> Any:
    text = read_text(path, what)
    try:
        return json.loads(text)
    except (json.JSONDecodeError, RecursionError) as e:
        line = f" (line {e.lineno})" if isinstance(e, json.JSONDecodeError) else ""
        raise HarnessError(f"{what} {path}: not valid JSON{line}") from None


def open_h5(path: str | Path, what: str) -> Any:
    """The HDF5 file at `path`, read-only (an h5py.File); refused in one line when it is not one."""
    import h5py  # lazily: `--help` needs no h5py

    regular(path, what)
    try:
        return h5py.File(str(path), "r")
    except (OSError, ValueError) as e:
        reason = "not an HDF5 file" if "signature" in str(e) else str(e).split("(")[0].strip()
        raise HarnessError(f"{what} {path}: cannot read it as HDF5: {reason}") from None
