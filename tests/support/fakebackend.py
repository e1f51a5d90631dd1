"""A stand-in backend for the harness's own tests: `python -m support.fakebackend FLAGS`
(from tests/).

It speaks the interface of docs/interfaces.md (the flags the harness passes, the JSON
record, HDF5 states via synthetic.py) without simulating anything, so the sweep, resume,
report and bench logic can be tested fast and without a build. Behaviour knobs, from the
environment:
  FAKE_SLEEP=s            sleep s seconds per run (to kill a sweep mid-way)
  FAKE_NO_BANDWIDTH=1     refuse --measure-bandwidth like a binary without it
  FAKE_TOO_BIG=N          exit 3 (does not fit in memory) for more than N strands
  FAKE_SHIFT_FP32=d       move every fp32 point by d (a planted inequivalence)
  FAKE_BACKEND=name       the backend named in the record (default: from the program name)
  FAKE_LOG=path           append "start|end backend strands CUDA_VISIBLE_DEVICES pid" lines per timed run
`--batch FILE` runs each line of FILE (flags separated by tabs) in turn, as the binaries do.
"""

import json
import os
import sys
import time

import numpy as np

NAMES = (
    "strands",
    "points",
    "seed",
    "head-radius",
    "hair-offset",
    "hair-length",
    "face-margin",
    "wind-strength",
    "wind-angle",
    "stages",
    "precision",
    "variant",
    "threads",
    "block-size",
    "input",
    "output",
    "repeat",
    "warmup",
)
SWITCHES = ("force", "json", "quiet", "end-to-end", "measure-bandwidth", "list-variants", "limits")
# what --list-variants prints, per backend (the binaries declare theirs the same way)
VARIANTS = {"cpu": ("ref", ["ref", "simd"]), "cuda": ("fused", ["paper", "soa", "fused"])}
# what --limits prints: the fake's own bounds, in the binaries' shape (docs/interfaces.md)
LIMITS = {
    "strands_min": 1,
    "points_min": 2,
    "stages_max": 64,
    "substeps_max": 1000,
    "iterations_max": 1000,
    "substep_s": [1e-9, 1.0],
    "grid_n": [2, 64],
    "grid_points_max": 1 << 20,
    "collider_sweeps": [1, 8],
    "block_size": {"min": 32, "max": 1024, "multiple": 32},
    "threads": [1, 64],
}


def parse(argv):
    opts = {}
    i = 0
    while i < len(argv):
        a = argv[i]
        if not a.startswith("--"):
            sys.exit(f"hairsim-fake: error: unexpected argument '{a}'")
        name = a[2:]
        if name in SWITCHES:
            opts[name] = True
            i += 1
        elif name in NAMES and i + 1 < len(argv):
            opts[name] = argv[i + 1]
            i += 2
        else:
            print(f"hairsim-fake: error: unknown flag {a}", file=sys.stderr)
            sys.exit(2)
    return opts


def main(argv=None):
    argv = sys.argv[1:] if argv is None else argv
    if argv[:1] == ["--batch"]:  # one run a line, flags separated by tabs, until one fails
        with open(argv[1]) as f:
            for line in f:
                if line.strip():
                    rc = run(line.rstrip("\n").split("\t"))
                    sys.stdout.flush()
                    if rc:
                        return rc
        return 0
    return run(argv)


def run(argv):
    prog = os.path.basename(os.environ.get("FAKE_PROG", "hairsim-cpu"))
    backend = os.environ.get("FAKE_BACKEND") or ("cuda" if "cuda" in prog else "cpu")
    o = parse(argv)
    if o.get("limits"):
        print(json.dumps({"backend": backend, **LIMITS}))
        return 0
    if o.get("list-variants"):
        default, names = VARIANTS[backend]
        build = next((b for b in ("strict", "fastmath") if prog.endswith(b)), "default")
        print(
            json.dumps(
                {
                    "backend": backend,
                    "build": build,
                    "default_variant": default,
                    "precisions": ["fp32", "fp64"],
                    "variants": [{"name": n, "stages": ["init", "collide", "wind"], "summary": "fake"} for n in names],
                }
            )
        )
        return 0
    log = os.environ.get("FAKE_LOG") if not o.get("measure-bandwidth") else None
    seen = os.environ.get("CUDA_VISIBLE_DEVICES", "-")
    if log:
        with open(log, "a") as f:
            f.write(f"start {backend} {o.get('strands', '-')} {seen} {os.getpid()}\n")
    time.sleep(float(os.environ.get("FAKE_SLEEP", "0")))
    if log:
        with open(log, "a") as f:
            f.write(f"end {backend} {o.get('strands', '-')} {seen} {os.getpid()}\n")
    if o.get("measure-bandwidth"):
        if os.environ.get("FAKE_NO_BANDWIDTH"):
            print("hairsim-fake: error: unknown flag --measure-bandwidth", file=sys.stderr)
            return 2
        print(json.dumps({"backend": backend, "copy_gbps": 10.0, "bytes": 1 << 20}))
        return 0
    strands, points = int(o.get("strands", 1000)), int(o.get("points", 32))
    if os.environ.get("FAKE_TOO_BIG") and strands > int(os.environ["FAKE_TOO_BIG"]):
        print(f"hairsim-fake: error: {strands} strands do not fit in memory", file=sys.stderr)
        return 3
    stages = o.get("stages", "init,collide,wind,collide").split(",")
    precision = o.get("precision", "fp32")
    repeat = int(o.get("repeat", 1))
    # known times: stage i takes (i + 1) · (1 … repeat) ms, so quartiles are predictable
    records = []
    for i, st in enumerate(stages):
        times = [float((i + 1) * (r + 1)) for r in range(repeat)]
        records.append(
            {
                "frame": i,
                "stage": st,
                "skipped": False,
                "fused": None,
                "median_ms": float(np.median(times)),
                "min_ms": min(times),
                "max_ms": max(times),
                "times_ms": times,
                "moved_points": 0 if st == "collide" else None,
            }
        )
    if o.get("output"):
        from support.synthetic import radial_strands, write_state

        dtype = np.float64 if precision == "fp64" else np.float32
        pos = radial_strands(strands, points, stages, dtype=np.float64, seed=int(o.get("seed", 1)))
        shift = float(os.environ.get("FAKE_SHIFT_FP32", "0"))
        if precision == "fp32" and shift:
            pos[1:, :, 1:, 1] += shift
        write_state(
            o["output"],
            pos.astype(dtype),
            stages,
            precision=precision,
            params={"backend": backend, "variant": o.get("variant", "ref"), "seed": int(o.get("seed", 1))},
        )
    record = {
        "backend": backend,
        "variant": o.get("variant", "ref"),
        "precision": precision,
        "strands": strands,
        "points": points,
        "seed": int(o.get("seed", 1)),
        "threads": int(o.get("threads", 2)),
        "block_size": o.get("block-size"),
        "repeat": repeat,
        "warmup": int(o.get("warmup", 0)),
        "input": o.get("input"),
        "output": o.get("output"),
        "stages": records,
        "end_to_end_ms": 1.0,
        "h2d_ms": None,
        "d2h_ms": None,
        "hdf5_write_ms": None,
        "state_bytes": strands * points * 3 * (8 if precision == "fp64" else 4),
        "git_revision": "fake",
        "compiler": "none",
        "flags": "fake",
        "device": "fake device",
        "driver": None,
        "version": "0.0.0",
    }
    print(json.dumps(record))
    return 0


def install(directory, names=("hairsim-cpu",)):
    """Write executable stand-ins named `names` into `directory` (for HAIRBENCH_BUILD_DIR)."""
    from pathlib import Path

    tests = Path(__file__).resolve().parent.parent
    root = tests.parent
    directory = Path(directory)
    directory.mkdir(parents=True, exist_ok=True)
    for name in names:
        path = directory / name
        path.write_text(
            f'#!/bin/sh\nFAKE_PROG="$0" PYTHONPATH="{tests}:{root}${{PYTHONPATH:+:$PYTHONPATH}}" '
            f'exec "{sys.executable}" -m support.fakebackend "$@"\n'
        )
        path.chmod(0o755)
    return directory


if __name__ == "__main__":
    sys.exit(main())
