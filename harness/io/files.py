"""Writing a results file whole or not at all: to a temporary name beside it, then renamed
over it, so a killed run never leaves half a file."""

import json
import os


def write_json(path, data):
    """`data` as indented JSON (what JSON cannot hold, as text) at `path`."""
    tmp = f"{path}.tmp.{os.getpid()}"
    with open(tmp, "w") as f:
        json.dump(data, f, indent=1, default=str)
        f.write("\n")
    os.replace(tmp, path)
