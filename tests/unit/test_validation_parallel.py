"""The bench's validators start their GPU runs in parallel (harness.bench.validation.parallel_runs)
and compare them in the order asked for: the same checks, in the same order, each against the
state of its own run; a run that fails stops the validation. The binaries and the diff are stood
in for; nothing is run."""

import threading
import time
from contextlib import contextmanager
from types import SimpleNamespace

import pytest

from harness.bench import dynamic as bench_dynamic
from harness.bench import paper as bench_paper
from harness.bench import validation
from harness.check import diff, diff_dynamic
from harness.core import runner, variants
from harness.core.runner import BackendError
from harness.io.sweepfile import load_sweep

VARIANTS = ("alpha", "beta")
PRECISIONS = ("fp32", "fp64")


class FakeBinaries:
    """runner.run_binary: records each run's flags by its --output, how many GPU runs (those
    with --block-size) ran at once (a CPU prefix state is made beside them, outside the pool),
    and fails the runs whose flags contain `fail_on`."""

    def __init__(self, fail_on=None, seconds=0.02):
        self.flags, self.lock, self.active, self.most = {}, threading.Lock(), 0, 0
        self.fail_on, self.seconds = fail_on, seconds

    def __call__(self, binary, flags, timeout=None, **kw):
        flags = [str(f) for f in flags]
        gpu = "--block-size" in flags
        with self.lock:
            self.active += gpu
            self.most = max(self.most, self.active)
        try:
            if gpu:  # a GPU run takes a while; the CPU's prefix states none
                time.sleep(self.seconds)
            if self.fail_on and all(f in flags for f in self.fail_on):
                raise BackendError("hairsim-cuda exited with status 1: stood-in failure")
            self.flags[flags[flags.index("--output") + 1]] = flags
            return {}
        finally:
            with self.lock:
                self.active -= gpu


def flag(flags, name):
    return flags[flags.index(name) + 1]


@pytest.fixture(scope="module")
def paper_scene():
    return load_sweep("default").scene  # read before variants.declared is stood in for


@pytest.fixture
def fake(monkeypatch):
    decl = SimpleNamespace(variants=VARIANTS, precisions=PRECISIONS, runs=lambda *a, **k: True, default_variant="alpha")
    decl.runs_features, decl.per_segment = (lambda *a: True), VARIANTS
    decl.solvers, decl.dynamic_solvers = ("xpbd", "ftl", "rigid"), ("xpbd", "ftl")  # rigid: no simulation
    monkeypatch.setattr(variants, "names", lambda backend, build="default": VARIANTS)
    monkeypatch.setattr(variants, "declared", lambda backend, build="default": decl)
    binaries = FakeBinaries()
    monkeypatch.setattr(runner, "run_binary", binaries)
    compared = []

    def compare(a, b, **kw):
        compared.append((str(a), str(b), kw))
        frame = SimpleNamespace(compared=True, max_abs=0.0, max_k=0.0, over=0, max_rel_L=0.0, ulp_max=0)
        return SimpleNamespace(pair="a vs b", equivalent=True, frames=[frame], failures=lambda: [])

    monkeypatch.setattr(diff, "compare", compare)
    monkeypatch.setattr(diff_dynamic, "compare", compare)
    return binaries, compared


def test_paper_validation_runs_in_parallel_and_compares_in_order(paper_scene, fake, tmp_path):
    binaries, compared = fake
    v = bench_paper.Validator(paper_scene, tmp_path, lambda m: None)
    ref = {p: f"cpu-{p}.h5" for p in PRECISIONS}
    v.gpu_checks(["default"], ref)
    stages, resume = list(v.scene.stages), bench_paper.RESUME_BLOCK
    expected = []  # the order of the one-at-a-time loop
    for variant in VARIANTS:
        for p in PRECISIONS:
            expected += [(f"cuda default {variant} b{b} {p} vs cpu", variant, p, b) for b in bench_paper.BLOCK_SIZES]
            expected += [
                (
                    f"cuda default {variant} b{resume} {p}: stage {k} ({stages[k]}) from the cpu state",
                    variant,
                    p,
                    resume,
                )
                for k in range(1, len(stages))
            ]
    assert [c["what"] for c in v.checks] == [e[0] for e in expected]
    for (what, variant, p, block), (a, b, kw) in zip(expected, compared):  # each against its own run
        flags = binaries.flags[b]
        assert a == ref[p] and flag(flags, "--variant") == variant and flag(flags, "--block-size") == str(block), what
        assert ("frames" in kw) == ("stage" in what)
    assert 1 < binaries.most <= validation.GPU_RUNS_AT_ONCE


def test_dynamic_validation_runs_in_parallel_and_compares_in_order(fake, tmp_path, monkeypatch):
    binaries, compared = fake

    @contextmanager
    def trajectory(path):
        yield SimpleNamespace(n_frames=3)

    monkeypatch.setattr(diff_dynamic, "open_trajectory", trajectory)
    monkeypatch.setattr(bench_dynamic.DynValidator, "last_step", lambda self, path: 1)
    v = bench_dynamic.DynValidator(tmp_path, lambda m: None)
    refs = {(p, s): f"cpu-{p}-{s}.h5" for p in PRECISIONS for s in ("xpbd", "ftl")}
    builds = ["default", "strict"]
    v.gpu_checks(builds, refs)
    gpu_checks = len(v.checks)
    expected = []
    for (p, s), ref in refs.items():
        cases = [(b, var, blk) for b in builds for var in VARIANTS for blk in bench_dynamic.BLOCK_SIZES]
        expected += [
            (f"cuda {b} {var} b{blk} {p} {s}: one frame from the cpu state", ref, var, blk) for b, var, blk in cases
        ]
        expected.append((f"cuda strict {p} {s}: alpha and beta bit-identical", None, None, None))
    assert [c["what"] for c in v.checks] == [e[0] for e in expected]
    for (what, ref, var, blk), (a, b, kw) in zip(expected, compared):
        if ref is None:  # the strict pair: the two strict runs at the largest block
            assert kw.get("exact") and flag(binaries.flags[a], "--variant") == "alpha"
            assert flag(binaries.flags[b], "--variant") == "beta"
            continue
        flags = binaries.flags[b]
        assert a == ref and flag(flags, "--input") == ref, what
        assert flag(flags, "--variant") == var and flag(flags, "--block-size") == str(blk), what
    assert 1 < binaries.most <= validation.GPU_RUNS_AT_ONCE
    # the progress line's total: every comparison made, the CPU's of the simulating solvers only
    v.checks = []
    v.cpu_checks()
    cpu_checks = len(v.checks)
    assert cpu_checks == len(PRECISIONS) * 2 * 3  # 1 thread, resumed, the other CPU variant; xpbd and ftl
    assert v.planned(builds) == cpu_checks + gpu_checks


def test_a_failing_run_stops_the_validation_and_cancels_the_runs_not_started(paper_scene, fake, tmp_path, monkeypatch):
    binaries = FakeBinaries(fail_on=("--variant", "alpha", "--block-size", "32"), seconds=0.05)
    monkeypatch.setattr(runner, "run_binary", binaries)
    v = bench_paper.Validator(paper_scene, tmp_path, lambda m: None)
    with pytest.raises(BackendError, match="stood-in failure"):
        v.gpu_checks(["default"], {p: f"cpu-{p}.h5" for p in PRECISIONS})
    total = len(VARIANTS) * len(PRECISIONS) * (len(bench_paper.BLOCK_SIZES) + len(v.scene.stages) - 1)
    finished = [f for f in binaries.flags.values() if "--block-size" in f]
    assert v.checks == [] and len(finished) < total - 1
