"""The limits a binary checks its flags against: `hairsim-* --limits` (one JSON object,
docs/interfaces.md). The harness checks a value early (a scene file, a sweep, a command line)
with these numbers, read once per binary, and restates none of them."""

from dataclasses import dataclass
from functools import lru_cache

from harness import HarnessError
from harness.core.paths import binary_path
from harness.core.variants import ask


@dataclass(frozen=True)
class Limits:
    substeps_max: int
    iterations_max: int
    substep_s: tuple  # (shortest, longest) h = frame_dt / substeps, s
    grid_n: tuple  # (fewest, most) grid nodes per axis
    grid_points_max: int  # strands x points with a grid
    collider_sweeps: tuple  # (fewest, most) --collider-sweeps
    block_size: tuple  # (min, max, multiple) cuda threads per block
    threads: tuple  # (min, max) cpu threads

    def count_error(self, key, value):
        """Why `value` is refused as `key` ("substeps" or "iterations"), or None."""
        most = self.substeps_max if key == "substeps" else self.iterations_max
        return None if 1 <= value <= most else f"must lie in 1 … {most}, got {value}"

    def substep_error(self, h):
        """Why a substep of h s is refused, or None."""
        lo, hi = self.substep_s
        return None if lo <= h <= hi else f"the substep {h:g} s is outside [{lo:g}, {hi:g}] s"

    def block_size_error(self, value):
        """Why `value` threads a block is refused, or None."""
        lo, hi, step = self.block_size
        return None if lo <= value <= hi and value % step == 0 else f"{value} is not a multiple of {step} in {lo}…{hi}"


@lru_cache(maxsize=None)
def _read(path):
    d = ask(path, "--limits")
    try:
        block = d["block_size"]
        return Limits(
            substeps_max=int(d["substeps_max"]),
            iterations_max=int(d["iterations_max"]),
            substep_s=(float(d["substep_s"][0]), float(d["substep_s"][1])),
            grid_n=(int(d["grid_n"][0]), int(d["grid_n"][1])),
            grid_points_max=int(d["grid_points_max"]),
            collider_sweeps=(int(d["collider_sweeps"][0]), int(d["collider_sweeps"][1])),
            block_size=(int(block["min"]), int(block["max"]), int(block["multiple"])),
            threads=(int(d["threads"][0]), int(d["threads"][1])),
        )
    except (KeyError, IndexError, TypeError, ValueError):
        raise HarnessError(f"{path} --limits did not print the documented JSON object") from None


def limits(backend="cpu", build="default"):
    """The limits of the binary of `backend`/`build` (the cpu binary's by default: both backends
    parse their flags with the same code); HarnessError if it is not built."""
    path = binary_path(backend, build)
    if not path.exists():
        raise HarnessError(f"{path} not found: run make")
    return _read(str(path))


def clear_cache():
    """Forget what was read (a test that swaps the build directory)."""
    _read.cache_clear()
