"""The one way the harness writes a file: whole or not at all. `writing(path)` gives a temporary
name beside `path`, created exclusively (a random part, so two writers never share one), which
the caller fills; when the block ends the temporary is moved over `path`, and on any exception
(a full disk, an interrupt) it is removed in `finally`, nothing of it left. An OSError raised
inside names `path` (a write's "No space left on device" names no file by itself). Every other
writer here goes through it; tests/unit/test_layers.py holds that no module writes around it."""

import contextlib
import csv
import json
import os
import shutil
import tempfile
from collections.abc import Iterator
from pathlib import Path
from typing import Any


@contextlib.contextmanager
def writing(path: str | Path, create: bool = True) -> Iterator[Path]:
    """A temporary path beside `path` with `path`'s suffix (writers that pick a format by suffix,
    matplotlib and USD, keep it); moved over `path` after the block. `create`: the temporary
    exists, empty, when the block starts (exclusively created); False for a writer that must
    create the file itself (USD's CreateNew), which then gets a fresh unused name."""
    path = Path(path)
    fd, name = tempfile.mkstemp(prefix=f".{path.name}.", suffix=f".tmp{path.suffix}", dir=path.parent or ".")
    os.close(fd)
    tmp = Path(name)
    if not create:
        tmp.unlink()
    try:
        yield tmp
        fd = os.open(tmp, os.O_RDONLY)  # on disk before the name points at it
        try:
            os.fsync(fd)
        finally:
            os.close(fd)
        os.replace(tmp, path)
    except OSError as e:
        if e.filename is None:  # a write's ENOSPC or EIO: the file the user asked for
            raise OSError(e.errno, e.strerror or str(e), str(path)) from None
        raise
    finally:
        with contextlib.suppress(FileNotFoundError):
            tmp.unlink()


def write_bytes(path: str | Path, data: bytes) -> Path:
    with writing(path) as tmp:
        tmp.write_bytes(data)
    return Path(path)


def write_text(path: str | Path, text: str) -> Path:
    return write_bytes(path, text.encode("utf-8"))


def write_json(path: str | Path, data: Any) -> Path:
    """`data` as indented JSON (what JSON cannot hold, as text) at `path`."""
    return write_text(path, json.dumps(data, indent=1, default=str) + "\n")


def write_csv(path: str | Path, fields: Any, rows: Any, extrasaction: str = "raise") -> Path:
    """`rows` (dicts) as CSV with the header `fields` at `path` (its folder made if absent); a
    missing key is an empty cell, an extra one an error (or dropped: extrasaction="ignore")."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    with writing(path) as tmp, open(tmp, "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=fields, restval="", extrasaction=extrasaction)  # type: ignore[arg-type]
        w.writeheader()
        w.writerows(rows)
    return path


def write_rows(path: str | Path, header: list[str], rows: list[list[str]]) -> Path:
    """Plain rows (lists) under `header` as CSV at `path`."""
    with writing(path) as tmp, open(tmp, "w", newline="") as f:
        w = csv.writer(f, lineterminator="\n")
        w.writerow(header)
        w.writerows(rows)
    return Path(path)


def copy(src: str | Path, dst: str | Path) -> Path:
    """The file `src` at `dst` (its times and mode kept), whole or not at all."""
    with writing(dst) as tmp:
        shutil.copy2(src, tmp)
    return Path(dst)


def save_figure(fig: Any, path: str | Path, **kwargs: Any) -> Path:
    """A matplotlib figure at `path` (its format from the suffix), whole or not at all."""
    with writing(path) as tmp:
        fig.savefig(tmp, **kwargs)
    return Path(path)
