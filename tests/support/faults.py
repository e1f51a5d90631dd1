"""A faulty input file for a refusal test: a FIFO, a directory, a missing, empty, truncated or
garbage file at tmp_path/input-<kind>."""

import os

FILE_FAULTS = ("fifo", "directory", "missing", "empty", "truncated", "garbage")


def make_fault(tmp_path, kind):
    path = tmp_path / f"input-{kind}"
    if kind == "fifo":
        os.mkfifo(path)
    elif kind == "directory":
        path.mkdir()
    elif kind == "empty":
        path.write_bytes(b"")
    elif kind == "truncated":
        path.write_bytes(b"HAIR\x01\x00\x00\x00" + b"\x89HDF\r\n\x1a\n")
    elif kind == "garbage":
        path.write_bytes(bytes(range(256)) * 4)
    return path
