"""The bench's first step for either model: a validator's CPU checks, then its GPU checks,
recorded in validation.json; nothing is timed unless every comparison is equivalent."""

import shutil
import tempfile
from concurrent.futures import ThreadPoolExecutor
from contextlib import contextmanager
from pathlib import Path

from harness import HarnessError
from harness.core import env
from harness.core.paths import CUDA_BUILDS, binary_path, display
from harness.core.progress import Progress
from harness.io.files import write_json


def validate(make_validator, what, out_dir, builds, gpu_note, say, header):
    """Run the validator `make_validator(scratch, say)` (cpu_checks(), gpu_checks(builds, ref),
    checks); `what` names it in messages ("validation", "dynamic validation"), header(v) the
    model's own fields of validation.json. HarnessError (exit 1) when a comparison fails, the
    states kept for a look. The validator's states live in a temporary directory under
    OUT_DIR/_scratch (never under results/ unless OUT_DIR is there), removed when the
    comparisons pass or the validator stops with an error."""
    scratch_root = Path(out_dir) / "_scratch"
    scratch_root.mkdir(parents=True, exist_ok=True)
    scratch = tempfile.mkdtemp(prefix=f"bench-{what.replace(' ', '-')}-", dir=scratch_root)
    try:
        v = make_validator(scratch, say)
        with Progress(v.planned(builds), what) as progress:
            v.on_check = progress.update
            ref = v.cpu_checks()
            if builds:
                v.gpu_checks(builds, ref)
    except BaseException:
        _remove(scratch, scratch_root)
        raise
    failed = [c for c in v.checks if not c["equivalent"]]
    record = {"date": env.now(), **header(v), "gpu_builds": builds}
    record["gpu_note"] = f"GPU not validated: {gpu_note}." if gpu_note else ""
    write_json(out_dir / "validation.json", dict(record, checks=v.checks))
    if failed:
        raise HarnessError(
            f"{what} failed: {len(failed)} of {len(v.checks)} comparisons not equivalent "
            f"(details in {display(out_dir / 'validation.json')}, states kept in {display(scratch)}); "
            "nothing was timed",
            code=1,
        )
    _remove(scratch, scratch_root)
    say(f"harness: {what}: all {len(v.checks)} comparisons equivalent")


GPU_RUNS_AT_ONCE = 8  # concurrent validation runs on one GPU (docs/decisions/bench-runs.md)


@contextmanager
def parallel_runs(jobs=None):
    """A pool for a validator's GPU runs: nothing in a validation is timed, so its small runs
    share the GPU (min(GPU_RUNS_AT_ONCE, cores) at once). The validator submits every run, then
    compares them in the order submitted, so validation.json is the same as one at a time.
    On an error the runs not yet started are cancelled."""
    pool = ThreadPoolExecutor(max_workers=jobs or min(GPU_RUNS_AT_ONCE, env.usable_cores()))
    try:
        yield pool
    except BaseException:
        pool.shutdown(wait=True, cancel_futures=True)
        raise
    pool.shutdown(wait=True)


def _remove(scratch, scratch_root):
    """Remove the scratch directory, and OUT_DIR/_scratch when that leaves it empty."""
    shutil.rmtree(scratch, ignore_errors=True)
    try:
        scratch_root.rmdir()
    except OSError:
        pass  # other runs' kept states


def gpu_plan(gpu):
    """(cuda builds to validate, None) or ([], the one-line reason there are none)."""
    if gpu == "no":
        return [], "--gpu no was given"
    ok, why = env.gpu_status()
    if not ok:
        if gpu == "yes":
            raise HarnessError(f"--gpu yes but no GPU is usable: {why}")
        return [], why
    builds = [b for b in CUDA_BUILDS if binary_path("cuda", b).exists()]
    if not builds:
        why = f"{display(binary_path('cuda'))} is not built (run make where nvcc is installed)"
        if gpu == "yes":
            raise HarnessError(why)
        return [], why
    return builds, None
