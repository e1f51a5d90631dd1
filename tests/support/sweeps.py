"""Sweep files for the tests: one writer of the TOML a sweep test runs (harness.io.sweepfile reads it)."""

import json


def _array(values) -> str:
    return json.dumps(list(values))


def sweep_toml(
    name: str,
    *,
    strands,
    points,
    precision,
    warmup: int = 0,
    threads=(1,),
    cuda: dict | None = None,
) -> str:
    """A paper-scene sweep of `repeat = 9` over the given axes, CPU `ref` variant; `cuda` maps
    each [cuda] key (variant, block_size, build) to its values, None for a CPU-only sweep."""
    lines = [
        f"name = {json.dumps(name)}",
        'scene = "paper"',
        "repeat = 9",
        f"warmup = {warmup}",
        "[axes]",
        f"strands = {_array(strands)}",
        f"points = {_array(points)}",
        f"precision = {_array(precision)}",
        "[cpu]",
        'variant = ["ref"]',
        f"threads = {_array(threads)}",
    ]
    if cuda is not None:
        lines.append("[cuda]")
        lines += [f"{key} = {_array(values)}" for key, values in cuda.items()]
    return "\n".join(lines) + "\n"
