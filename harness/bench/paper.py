"""`harness bench` — the `make bench` pipeline:

  1. the binaries exist (else one line: run make);
  2. validation before any timing, at VALIDATION_STRANDS × VALIDATION_POINTS:
     - always: the cpu binary at 1 thread and at all cores is bit-identical (--exact), its
       fp32 state is equivalent to its fp64 state, and a stage resumed from a saved state
       (--input) is bit-identical to the same stage in one run;
     - with a usable GPU, for every cuda build present × variant × block size × precision:
       run the GPU, diff against the cpu state of the same precision; and resume-diff one
       stage at a time (the cpu state after frame k → --input into the GPU for stage k+1,
       compare that frame) per build × variant × precision at block 64;
     any comparison not equivalent stops the bench here, before timing;
  3. the sweep (results/<name>/runs.csv, resumable);
  4. plots and report/report.md.
Without a GPU it runs the CPU rows and prints one line saying why the GPU rows are skipped.
"""

import json
from pathlib import Path

from harness import HarnessError
from harness.bench import validation
from harness.bench.validation import gpu_plan
from harness.check import diff
from harness.core import runner, variants
from harness.core.budget import TierGate
from harness.core.paths import RESULTS, binary_path, display
from harness.io import runfolder
from harness.io.files import write_json
from harness.io.sweepfile import load_sweep
from harness.render import report_paper
from harness.studies.sweep import figure_state, run_sweep

VALIDATION_STRANDS = 2000
VALIDATION_POINTS = 32
BLOCK_SIZES = (32, 64, 128, 256, 512, 1024)
RESUME_BLOCK = 64


class Validator:
    """Runs binaries into a scratch directory and records each comparison."""

    def __init__(self, scene, scratch, say):
        self.scene = scene.with_overrides(strands=VALIDATION_STRANDS, points=VALIDATION_POINTS)
        self.scratch = Path(scratch)
        self.say = say
        self.checks = []
        self.count = 0
        self.on_check = lambda: None  # called after each comparison (progress)

    def planned(self, builds):
        """How many comparisons cpu_checks and gpu_checks(builds) make."""
        resumes = len(self.scene.stages) - 1
        gpu = sum(
            len(variants.declared("cuda", b).precisions) * (len(BLOCK_SIZES) + resumes)
            for b in builds
            for _ in variants.names("cuda", b)
        )
        return 2 + resumes + gpu

    def state(self, backend, build="default", precision="fp32", stages=None, input_file=None, pool=None, **opts):
        """The state file of one run; with `pool`, a future of it (the run started there)."""
        self.count += 1
        path = self.scratch / f"s{self.count}-{backend}-{build}-{precision}.h5"
        scene = self.scene.with_overrides(precision=precision) if not input_file else self.scene
        flags = runner.run_flags(scene, backend, stages=stages, input_file=input_file, output=path, **opts)

        def run():
            runner.run_binary(binary_path(backend, build), flags, timeout=300)
            return path

        return pool.submit(run) if pool else run()

    def compare(self, what, a, b, **kw):
        try:
            r = diff.compare(a, b, **kw)
        except HarnessError as e:
            entry = {"what": what, "equivalent": False, "error": str(e)}
        else:
            compared = [f for f in r.frames if f.compared]
            entry = {
                "what": what,
                "pair": r.pair,
                "equivalent": r.equivalent,
                "max_abs": max((f.max_abs for f in compared), default=0.0),
                "max_k": max((f.max_k for f in compared), default=0.0),
                "over": sum(f.over for f in compared),
                "failures": r.failures()[:5],
            }
        self.checks.append(entry)
        self.on_check()
        if not entry["equivalent"]:
            self.say(
                f"harness: NOT EQUIVALENT: {what}: " + (entry.get("error") or "; ".join(entry.get("failures", [])))
            )
        return entry["equivalent"]

    def cpu_checks(self):
        ref = {p: self.state("cpu", precision=p) for p in variants.declared("cpu").precisions}
        one = self.state("cpu", precision="fp64", threads=1)
        self.compare("cpu fp64: 1 thread vs all cores (bit-identical)", ref["fp64"], one, exact=True)
        self.compare("cpu fp32 vs cpu fp64", ref["fp32"], ref["fp64"])
        stages = list(self.scene.stages)
        for k in range(1, len(stages)):  # the resume path itself, on the oracle
            prefix = self.state("cpu", precision="fp64", stages=stages[:k])
            resumed = self.state("cpu", precision="fp64", input_file=prefix, stages=[stages[k]])
            self.compare(
                f"cpu fp64: stage {k} ({stages[k]}) resumed from frame {k - 1} (bit-identical)",
                ref["fp64"],
                resumed,
                frames=[k],
                exact=True,
            )
        return ref

    def gpu_checks(self, builds, ref):
        stages = list(self.scene.stages)
        prefixes = {}
        pending = []  # (what, the cpu state, the GPU state's future, compare's options), in order
        with validation.parallel_runs() as pool:
            for build in builds:
                for variant in variants.names("cuda", build):
                    for precision in variants.declared("cuda", build).precisions:
                        for block in BLOCK_SIZES:
                            g = self.state("cuda", build, precision, variant=variant, block_size=block, pool=pool)
                            what = f"cuda {build} {variant} b{block} {precision} vs cpu"
                            pending.append((what, ref[precision], g, {}))
                        for k in range(1, len(stages)):
                            key = (precision, k)
                            if key not in prefixes:
                                prefixes[key] = self.state("cpu", precision=precision, stages=stages[:k])
                            g = self.state(
                                "cuda",
                                build,
                                precision,
                                variant=variant,
                                block_size=RESUME_BLOCK,
                                input_file=prefixes[key],
                                stages=[stages[k]],
                                pool=pool,
                            )
                            what = (
                                f"cuda {build} {variant} b{RESUME_BLOCK} {precision}: stage {k} "
                                f"({stages[k]}) from the cpu state"
                            )
                            pending.append((what, ref[precision], g, {"frames": [k]}))
            for what, cpu_state, g, kw in pending:
                self.compare(what, cpu_state, g.result(), **kw)


def validate(sweep, out_dir, builds, gpu_note, say):
    def header(v):
        return {"strands": VALIDATION_STRANDS, "points": VALIDATION_POINTS, "scene": sweep.scene.name}

    def make(scratch, say):
        return Validator(sweep.scene, scratch, say)

    validation.validate(make, "validation", out_dir, builds, gpu_note, say, header)


def validate_first(sweep_ref="default", out=None, gpu="auto", log=None):
    """Only the validation of run() (the bench validates both models before it times anything)."""
    say = log or (lambda m: print(m, flush=True))
    runner.require_binary(binary_path("cpu"))
    sweep = load_sweep(sweep_ref)
    builds, gpu_note = gpu_plan(gpu)
    validate(sweep, runfolder.claim(out if out else RESULTS / sweep.name, "bench"), builds, gpu_note, say)


def run(
    sweep_ref="default",
    out=None,
    gpu="auto",
    report_dir=None,
    log=None,
    shard=None,
    budget=None,
    root=None,
    validated=False,
):
    """`shard`: only its share of the sweep (no report: harness merge joins the shards);
    `budget` (core.budget.Budget): the sweep's sizes fit its share of the time left, what is
    left out recorded in ROOT/budget.json and the report; `validated`: validate_first ran."""
    say = log or (lambda m: print(m, flush=True))
    runner.require_binary(binary_path("cpu"))
    sweep = load_sweep(sweep_ref)
    out_dir = runfolder.claim(out if out else RESULTS / sweep.name, "bench")
    root = Path(root) if root else out_dir.parent
    builds, gpu_note = gpu_plan(gpu)
    if gpu_note:
        say(f"harness: GPU rows skipped: {gpu_note}")
    if not validated:
        validate(sweep, out_dir, builds, gpu_note, say)
    gate = TierGate(budget.allowance("paper sweep")) if budget else None
    if gate:
        say(f"harness: budget: the paper sweep gets {gate.allowance:.0f} s of the {budget.left():.0f} s left")
    _, failed = run_sweep(
        sweep_ref, out=out_dir, gpu="no" if gpu_note else gpu, log=say, announce_skips=False, shard=shard, gate=gate
    )
    if gpu_note:  # the sweep's record says why, for the report
        _note_gpu_skip(out_dir / "env.json", gpu_note)
    if gate and gate.summary():
        budget.leave_out(f"sweep {sweep.name}", gate.summary(), gate.closed)
    if budget:
        write_json(root / "budget.json", budget.record())
    if shard is not None and shard.n > 1:
        if shard.first:
            figure_state(out_dir)
        say(f"harness: shard {shard}: no report (harness merge OUT SHARD... joins the shards, then make report)")
        return 1 if failed else 0
    figure_state(out_dir)
    path = report_paper.build(out_dir, report_dir)
    say(f"harness: report in {display(path)}")
    return 1 if failed else 0


def _note_gpu_skip(env_path, why):
    data = json.loads(env_path.read_text())
    session = data["sessions"][-1]
    for k in session.get("skipped", []):
        if "cuda" in k.get("backends", []):
            k["reason"] = why
    write_json(env_path, data)
