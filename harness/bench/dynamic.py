"""The dynamic model's part of `make bench` (`python -m harness bench`, or alone with
`--model dynamic`): validation before any timing, the sweep, the studies, the report.

  1. validation, at VALIDATION_STRANDS strands of the default dynamic scene, 2 frames
     written with every frame's velocities:
     - always: the CPU oracle on one thread and on all cores bit-identical; a frame resumed
       from the file (--input-frame) bit-identical to the same frame of the run; every
       other CPU variant one frame from the oracle's state (harness.check.diff_dynamic's rule
       and the scene's spread, measured once per reference);
     - with a usable GPU: every cuda build × simulate variant × precision × block size
       one frame from the CPU's state, judged by the same rule (the strict build bit for
       bit where the scene has no gusts); and the strict build's variants bit-identical
       to each other;
     anything not equivalent stops the bench before timing;
  2. the sweeps configs/sweeps/dynamic.toml (results/<out>/dynamic/runs.csv) and, on curly
     hair, configs/sweeps/dynamic-curly.toml (results/<out>/dynamic-curly/runs.csv);
  3. the studies, each into results/<out>/<study>/: what each feature costs (featurecost,
     CPU and every cuda build), modelling less (reduced: guides and followers, LRA, sag-free,
     LOD; docs/model.md §3.14), speed against accuracy (accuracy --model dynamic, on the default
     scene and on curly hair, configs/scenes/curly.toml), stability at the
     extremes (stability), the peer (pypbd, optional), the grid's and the colliders' variants
     against their converged references (world: accuracy-world/), the animation;
  4. report/dynamic.md with all of it.
Without a GPU the GPU rows and checks are skipped with one line saying why.
"""

from pathlib import Path

from harness import HarnessError
from harness.bench import animate_dynamic as animate
from harness.bench import renders, validation
from harness.bench.validation import gpu_plan
from harness.check import diff_dynamic
from harness.core import runner, scenes, variants
from harness.core.budget import TierGate, largest_that_fits, run_study
from harness.core.paths import LOCAL_RUN, REPORT, binary_path, display
from harness.core.progress import StepTimes
from harness.core.scenes import with_frames
from harness.io import results_data
from harness.io.files import write_json
from harness.render import accuracy_dynamic_report, report_dynamic
from harness.render import peer_dynamic_report as peer_report
from harness.render import stability_dynamic_report as stability_report
from harness.studies import accuracy_dynamic
from harness.studies import accuracy_results_dynamic as accuracy_results
from harness.studies import accuracy_rows_dynamic as accuracy_rows
from harness.studies import accuracy_world_dynamic as accuracy_world
from harness.studies import budget_curves_dynamic as budget_curves
from harness.studies import featurecost_dynamic as featurecost
from harness.studies import peer_dynamic as peer
from harness.studies import reduced_dynamic as reduced
from harness.studies import stability_dynamic as stability
from harness.studies.accuracy import DEFAULT_SCENE, curves_name, results_name
from harness.studies.sweep import run_sweep

VALIDATION_STRANDS = 2000
BLOCK_SIZES = (32, 256)
SWEEP = "dynamic"
CURLY_SWEEP = report_dynamic.CURLY_SWEEP


class DynValidator:
    def __init__(self, scratch, say, scene="dynamic", strands=VALIDATION_STRANDS):
        """`scene`: the dynamic scene validated (a user's, bench --scene), at `strands` strands."""
        base = scenes.load_scene(scene).with_overrides(strands=strands)
        self.scene = with_frames(base, 2)
        self.scratch = Path(scratch)
        self.say = say
        self.checks = []
        self.count = 0
        self.on_check = lambda: None  # called after each comparison (progress)

    def cpu_others(self):
        """The CPU variants other than the oracle that simulate: each is stepped one frame."""
        cpu = variants.declared("cpu")
        feats = variants.features_of(self.scene.dynamic)
        return [
            v
            for v in cpu.variants
            if v != cpu.default_variant
            and cpu.runs(v)
            and cpu.runs_features(v, feats)
            and (not self.scene.groom or v in cpu.per_segment)
        ]

    def gpu_cases(self, builds):
        """(build, variant, block) of every GPU comparison of one precision and solver."""
        out = []
        feats = variants.features_of(self.scene.dynamic)
        for build in builds:
            decl = variants.declared("cuda", build)
            for v in decl.variants:
                if not decl.runs(v, points=self.scene.points) or not decl.runs_features(v, feats):
                    continue
                if self.scene.groom and v not in decl.per_segment:  # a groom's rest lengths: not every variant
                    continue
                out += [(build, v, b) for b in BLOCK_SIZES if decl.runs(v, points=self.scene.points, block=b)]
        return out

    def planned(self, builds):
        """How many comparisons cpu_checks and gpu_checks(builds) make."""
        cpu = variants.declared("cpu")
        pairs = len(cpu.precisions) * len(cpu.dynamic_solvers)  # the pairs cpu_checks makes
        cases = self.gpu_cases(builds)
        strict = {v for b, v, blk in cases if b == "strict" and blk == BLOCK_SIZES[-1]}
        return pairs * (2 + len(self.cpu_others()) + len(cases) + max(0, len(strict) - 1))

    def cpu_file(self, precision, solver, **opts):
        self.count += 1
        out = self.scratch / f"cpu{self.count}-{precision}-{solver}.h5"
        scene = self.scene.with_overrides(precision=precision)
        flags = runner.run_flags(scene, "cpu", output=out, **opts)
        runner.run_binary(binary_path("cpu"), flags + ["--solver", solver, "--velocities", "all"], timeout=600)
        return out

    def record(self, what, fn):
        try:
            r = fn()
        except HarnessError as e:
            entry = {"what": what, "equivalent": False, "error": str(e)}
        else:
            f = r.frames[-1]
            entry = {
                "what": what,
                "pair": r.pair,
                "equivalent": r.equivalent,
                "max_abs": f.max_abs,
                "max_rel_L": f.max_rel_L,
                "ulp_max": f.ulp_max,
                "spread": getattr(f, "spread", float("nan")),
                "limit": getattr(f, "limit", float("nan")),
                "failures": r.failures()[:5],
            }
        self.checks.append(entry)
        self.on_check()
        if not entry["equivalent"]:
            why = entry.get("error") or "; ".join(entry.get("failures", []))
            self.say(f"harness: NOT EQUIVALENT: {what}: {why}")
        return entry["equivalent"]

    def step(self, ref, binary, extra, tag, pool=None):
        """One frame from the reference's second-to-last frame; the new file (with `pool`, a
        future of it: the run started there)."""
        self.count += 1
        out = self.scratch / f"step{self.count}-{tag}.h5"
        with diff_dynamic.open_trajectory(ref) as t:
            k = t.n_frames - 2
        cmd = ["--input", ref, "--input-frame", k, "--stages", "simulate", "--frames", 1, *extra, "--output", out]

        def run():
            runner.run_binary(binary, cmd, timeout=600)
            return out

        return pool.submit(run) if pool else run()

    def last_step(self, path):
        with diff_dynamic.open_trajectory(path) as t:
            return int(t.step[-1])

    def cpu_checks(self):
        refs = {}
        cpu = variants.declared("cpu")  # the solvers and precisions of --list-variants
        for precision in cpu.precisions:
            for solver in cpu.dynamic_solvers:
                ref = refs[(precision, solver)] = self.cpu_file(precision, solver)
                one = self.cpu_file(precision, solver, threads=1)
                self.record(
                    f"cpu {precision} {solver}: 1 thread vs all cores (bit-identical)",
                    lambda a=ref, b=one: diff_dynamic.compare(a, b, exact=True),
                )
                oracle = variants.declared("cpu").default_variant
                resumed = self.step(ref, binary_path("cpu"), ["--variant", oracle], f"cpu-{precision}-{solver}")
                self.record(
                    f"cpu {precision} {solver}: the last frame resumed from the file (bit-identical)",
                    lambda a=ref, b=resumed: diff_dynamic.compare(a, b, frames=[self.last_step(b)], exact=True),
                )
                for v in self.cpu_others():
                    other = self.step(ref, binary_path("cpu"), ["--variant", v], f"cpu-{v}-{precision}-{solver}")
                    self.record(
                        f"cpu {v} {precision} {solver}: one frame from the oracle's state",
                        lambda a=ref, b=other: diff_dynamic.compare(a, b, frames=[self.last_step(b)], spread=True),
                    )
        return refs

    def gpu_checks(self, builds, refs):
        with validation.parallel_runs() as pool:
            started = {}  # every run first, then the comparisons in the same order
            for (precision, solver), ref in refs.items():
                for build, v, block in self.gpu_cases(builds):
                    tag = f"cuda-{build}-{v}-b{block}-{precision}-{solver}"
                    extra = ["--variant", v, "--block-size", block]
                    started[(precision, solver, build, v, block)] = self.step(
                        ref, binary_path("cuda", build), extra, tag, pool=pool
                    )
            for (precision, solver), ref in refs.items():
                strict = {}
                for build, v, block in self.gpu_cases(builds):
                    g = started[(precision, solver, build, v, block)].result()
                    if build == "strict" and block == BLOCK_SIZES[-1]:
                        strict[v] = g
                    self.record(
                        f"cuda {build} {v} b{block} {precision} {solver}: one frame from the cpu state",
                        lambda a=ref, b=g: diff_dynamic.compare(a, b, frames=[self.last_step(b)], spread=True),
                    )
                names = list(strict)
                for other in names[1:]:
                    self.record(
                        f"cuda strict {precision} {solver}: {names[0]} and {other} bit-identical",
                        lambda a=strict[names[0]], b=strict[other]: diff_dynamic.compare(
                            a, b, frames=[self.last_step(b)], exact=True, check_paper=False
                        ),
                    )


def validate(out_dir, builds, gpu_note, say, scene="dynamic", strands=VALIDATION_STRANDS):
    def header(v):
        return {"model": "dynamic", "strands": v.scene.strands, "points": v.scene.points, "scene": v.scene.name}

    def make(scratch, say_):
        return DynValidator(scratch, say_, scene, strands)

    validation.validate(make, "dynamic validation", out_dir, builds, gpu_note, say, header)


def fastest_gpu_variants(sweep_dir):
    """The default build's simulate variant with the most point-substeps per second at the
    sweep's largest fp32 strand count; every simulate variant when the sweep has no GPU row."""
    decl = variants.declared("cuda")
    every = list(decl.running("simulate", points=32))
    try:
        rows, _ = results_data.load(sweep_dir)
    except HarnessError:
        return every
    g = rows[(rows["stage"] == "simulate") & (rows["backend"] == "cuda") & (rows["precision"] == "fp32")]
    g = g[g["build"].isin(["", "default"])]
    if g.empty:
        return every
    top = g[g["strands"] == g["strands"].max()]
    best = top.loc[top["point_substeps_per_s"].astype(float).idxmax()]
    return [str(best["variant"])]


FEATURECOST_STRANDS = (100_000, 30_000, 10_000, 3_000, 1_000)  # the CPU rows' size ladder; the first is the full run's
FEATURECOST_FRAMES_A_CASE = 3 * (3 + 1)  # featurecost.measure's frames × (repeat + the untimed first)


def featurecost_size(sweep_dir, allowance_s):
    """The largest FEATURECOST_STRANDS whose CPU rows should fit allowance_s, estimated from
    the dynamic sweep's slowest point-substep rate of the CPU oracle on all cores at its
    largest size (the smallest size when the sweep has no such row)."""
    scene = scenes.load_scene("dynamic")
    work = scene.points * int(scene.dynamic.get("--substeps", 1))  # point-substeps a strand a frame
    try:
        rows, _ = results_data.load(sweep_dir)
    except HarnessError:
        return FEATURECOST_STRANDS[-1]
    oracle = variants.declared("cpu").default_variant
    cpu = rows[(rows["backend"] == "cpu") & (rows["variant"] == oracle) & (rows["threads"].astype(str) == "all")]
    cpu = cpu[cpu["stage"] == "simulate"]
    if cpu.empty:
        return FEATURECOST_STRANDS[-1]
    rate = float(cpu[cpu["strands"] == cpu["strands"].max()]["point_substeps_per_s"].astype(float).min())
    cases = len(featurecost.FEATURES) * 2 + 2

    def seconds(n):
        return cases * FEATURECOST_FRAMES_A_CASE * n * work / rate

    return largest_that_fits(FEATURECOST_STRANDS, seconds, allowance_s)


def budget_modes(acc_dir):
    """The modes the frame budget's curves time (studies/budget_curves_dynamic.py): each backend's Pareto
    front of the accuracy study in `acc_dir` (studies/accuracy_rows_dynamic.front_of: the usable
    modes no other is both faster and more accurate than, the no-simulation mode among them), as
    dicts of the study's columns."""
    rows, study, _, _ = accuracy_results.load(acc_dir)
    summ = accuracy_rows.summary(rows, study["horizon_frames"])
    modes = []
    for backend, part in summ.groupby("backend"):
        for _, r in accuracy_rows.front_of(part).iterrows():
            s = r["ftl_damping"]
            modes.append(dict(mode=r["mode"], backend=backend, build=r["build"], variant=r["variant"],
                              solver=r["solver"], ftl_damping=None if s != s else float(s),
                              substeps=int(r["substeps"]), iterations=int(r["iterations"]),
                              precision=r["precision"]))  # fmt: skip
    return modes


# (scene, the study's name in the log and the budget): the straight default scene, then curly hair
ACCURACY_STUDIES = (
    (DEFAULT_SCENE, "accuracy"),
    (report_dynamic.CURLY_SCENE, f"accuracy {report_dynamic.CURLY_SCENE}"),
)
# the studies measured once (the stability map is sharded by its cells instead), in the order
# `--shard K/N` deals them out: study i runs on shard i mod N + 1
ONE_MEASUREMENT_STUDIES = ("featurecost", "reduced", *(name for _, name in ACCURACY_STUDIES), "peer", "world")


def accuracy(root, scene, gpu, quick, say, report_dir=None):
    """The speed-against-accuracy study of one scene into root/<its results folder>, rendered
    into report_dir when given. Another scene than the default one skips the analytic tables:
    they run their own scenes, so they would repeat the default scene's."""
    acc_dir = root / results_name(scene)
    changes = dict(gpu=gpu, scene=scene)
    if scene != DEFAULT_SCENE:
        changes["analytic"] = "none"
    plan = accuracy_dynamic.Plan.quick(**changes) if quick else accuracy_dynamic.Plan(**changes)
    where = f" --scene {scene} --analytic none" if "analytic" in changes else ""
    say(f"harness: accuracy --model dynamic{where}{' --quick' if quick else ''} --gpu {gpu}")
    accuracy_dynamic.run_study(plan, out_dir=acc_dir, force=True, command="python -m harness bench --model dynamic")
    if report_dir is not None:
        title = report_dynamic.CURLY_TITLE if scene == report_dynamic.CURLY_SCENE else None
        accuracy_dynamic_report.write(acc_dir, report_dir, title=title)
    return acc_dir


def studies(root, builds, say, report_dir=None, quick=False, shard=None, budget=None, times=None):
    """The dynamic studies, each measured into root/<study> (`quick`: their small versions)
    and rendered into report_dir (none with `shard` of several). A shard runs its share of the
    stability map and its share of ONE_MEASUREMENT_STUDIES. With `budget`, a study
    that starts after the budget is spent is left out (and said so). `times`
    (core.progress.StepTimes): each study timed."""
    render = report_dir is not None
    times = times or StepTimes()

    def fits(study):
        if budget is None or budget.left() > 0:
            return True
        budget.leave_out(study, "the whole study", "left out to fit the budget: no time left when it was due")
        say(f"harness: {study}: left out to fit the budget (no time left)")
        return False

    def within(study, fn, *outputs):
        """fn() now, or under a budget stopped when it runs out (core.budget.run_study); timed."""

        def go():
            if budget is None:
                fn()
                return True
            return run_study(budget, study, fn, outputs, say)

        return times.step(study, go)

    def mine(study):
        return shard is None or shard.takes(ONE_MEASUREMENT_STUDIES.index(study))

    gpu = "auto" if builds else "no"
    reports = [report_dir] if render else []
    # the pictures first: short, and a report without them is blind, so a budget spends itself on
    # the open-ended studies after them (the accuracy study's modes are drawn once it has run)
    if render and fits("animate"):

        def make_animation():
            say("harness: animate")
            animate.run(out=Path(report_dir) / "dynamic.gif", force=True, log=say, state_dir=root / "animation")

        within("animate", make_animation, root / "animation", *reports)
    if render and fits("renders"):
        within("renders", lambda: renders.simulate(root, say), root / renders.FOLDER)
    if mine("featurecost") and fits("featurecost"):
        fc = root / "featurecost"
        fc.mkdir(parents=True, exist_ok=True)
        strands = FEATURECOST_STRANDS[0]
        if budget is not None:  # its share of the time left: a quarter (four studies follow the sweep)
            strands = featurecost_size(root / SWEEP, budget.left() / 4)
            if strands != FEATURECOST_STRANDS[0]:
                budget.leave_out(
                    "featurecost",
                    f"the CPU rows at {FEATURECOST_STRANDS[0]} strands (measured at {strands})",
                    "left out to fit the budget: the larger size's estimate did not fit",
                )
        gpu_variants = fastest_gpu_variants(root / SWEEP) if builds else []

        def measure_featurecost():
            say(f"harness: featurecost --backend cpu --strands {strands}")
            featurecost.measure(backend="cpu", strands=strands, out=fc / "cpu.csv")
            for v in gpu_variants:  # the sweep's fastest variant (else every one that simulates), filling the GPU
                say(f"harness: featurecost --backend cuda --variant {v} --strands 1000000")
                featurecost.measure(backend="cuda", variant=v, strands=1_000_000, out=fc / f"cuda-{v}.csv")

        within("featurecost", measure_featurecost, fc)
    if mine("reduced") and fits("reduced"):

        def measure_reduced():
            # at full scale wherever a GPU runs the references (minutes there); quick on a CPU alone
            small = quick and not builds
            say(f"harness: reduced{' --quick' if small else ''}")
            plan = reduced.Plan.quick(gpu=gpu) if small else reduced.Plan(gpu=gpu)
            reduced.measure(plan, out=root / "reduced" / "reduced.csv", progress=say)

        within("reduced", measure_reduced, root / "reduced")
    for scene, study in ACCURACY_STUDIES:
        if mine(study) and fits(study):
            ran = within(
                study,
                lambda s=scene: accuracy(root, s, gpu, quick, say, report_dir),
                root / results_name(scene),
                *reports,
            )
            if ran and scene == DEFAULT_SCENE and render and fits("mode renders"):  # its modes drawn
                within("mode renders", lambda: renders.simulate_modes(root, say), root / renders.FOLDER)
            if ran and scene == DEFAULT_SCENE and fits("budget curves"):  # the frame budget's answer needs them
                gate = TierGate(budget.allowance("budget curves")) if budget else None
                within(
                    "budget curves",
                    lambda s=scene, g=gate: budget_curves.measure(
                        root, s, budget_modes(root / results_name(s)), gate=g, log=say
                    ),
                    root / curves_name(scene),
                )
    if fits("stability"):

        def measure_stability():
            say(f"harness: stability{' --quick' if quick else ''} --gpu {gpu}" + (f" (shard {shard})" if shard else ""))
            csv_path = stability.run_study(quick=quick, gpu=gpu, out_dir=root / "stability", shard=shard)
            if render:
                stability_report.report_from_csv(csv_path, report_dir=report_dir, log=say)

        within("stability", measure_stability, root / "stability", *reports)
    if mine("peer") and fits("peer"):

        def measure_peer():
            say("harness: peer")
            try:
                peer.run_study(peer.Plan(out=str(root / "peer")), log=say)
            except peer.PeerUnavailable as e:  # an optional dependency: skipped, not failed
                say(f"harness: peer: skipped: {e}")
            else:
                peer_report.write(root / "peer", root / "peer")

        within("peer", measure_peer, root / "peer")
    if mine("world") and fits("world"):

        def measure_world():
            say(f"harness: world{' --quick' if quick else ''}")
            plan = accuracy_world.Plan.quick(gpu=gpu) if quick else accuracy_world.Plan(gpu=gpu)
            accuracy_world.run_study(plan, out_dir=root / accuracy_world.RESULTS_NAME, log=say)

        within("world", measure_world, root / accuracy_world.RESULTS_NAME)


def curly_sweep(root, gpu, say, shard=None, budget=None):
    """The sweep on curly hair (configs/sweeps/dynamic-curly.toml) into <root>/dynamic-curly,
    its share of the time left under a budget; whether a case failed."""
    gate = TierGate(budget.allowance("curly sweep")) if budget else None
    if gate:
        say(f"harness: budget: the curly sweep gets {gate.allowance:.0f} s of the {budget.left():.0f} s left")
    _, failed = run_sweep(
        CURLY_SWEEP, out=root / CURLY_SWEEP, gpu=gpu, log=say, announce_skips=False, shard=shard, gate=gate
    )
    if gate and gate.summary():
        budget.leave_out(f"sweep {CURLY_SWEEP}", gate.summary(), gate.closed)
    return failed


def validate_first(out=None, gpu="auto", log=None):
    """Only the validation of run() (the bench validates both models before it times anything)."""
    say = log or (lambda m: print(m, flush=True))
    runner.require_binary(binary_path("cpu"))
    sweep_dir = (Path(out) if out else LOCAL_RUN) / SWEEP
    sweep_dir.mkdir(parents=True, exist_ok=True)
    builds, gpu_note = gpu_plan(gpu)
    validate(sweep_dir, builds, gpu_note, say)


def run(
    out=None,
    gpu="auto",
    report_dir=None,
    quick_studies=True,
    log=None,
    shard=None,
    budget=None,
    validated=False,
    times=None,
):
    """`shard`: its share of the sweep, the stability map and the one-measurement studies,
    no report; `budget` (core.budget.Budget): the sweep fits its share of the time left, the
    studies run while time is left; what is left out goes to OUT/budget.json and the report;
    `validated`: validate_first ran; `times` (core.progress.StepTimes): each sweep and study timed."""
    times = times or StepTimes()
    say = log or (lambda m: print(m, flush=True))
    runner.require_binary(binary_path("cpu"))
    root = Path(out) if out else LOCAL_RUN
    sweep_dir = root / SWEEP
    sweep_dir.mkdir(parents=True, exist_ok=True)
    builds, gpu_note = gpu_plan(gpu)
    if gpu_note:
        say(f"harness: dynamic GPU rows skipped: {gpu_note}")
    if not validated:
        validate(sweep_dir, builds, gpu_note, say)
    gate = TierGate(budget.allowance("dynamic sweep")) if budget else None
    if gate:
        say(f"harness: budget: the dynamic sweep gets {gate.allowance:.0f} s of the {budget.left():.0f} s left")
    gpu_sweep = "no" if gpu_note else gpu
    _, failed = times.step(
        f"sweep {SWEEP}",
        run_sweep,
        SWEEP,
        out=sweep_dir,
        gpu=gpu_sweep,
        log=say,
        announce_skips=False,
        shard=shard,
        gate=gate,
    )
    if gate and gate.summary():
        budget.leave_out(f"sweep {SWEEP}", gate.summary(), gate.closed)
    failed = times.step(f"sweep {CURLY_SWEEP}", curly_sweep, root, gpu_sweep, say, shard, budget) or failed
    several = shard is not None and shard.n > 1
    studies(
        root,
        builds,
        say,
        report_dir=None if several else report_dir or REPORT,
        quick=quick_studies,
        shard=shard,
        budget=budget,
        times=times,
    )
    if budget:
        write_json(root / "budget.json", budget.record())
    if several:
        say(f"harness: shard {shard}: no report (harness merge OUT SHARD... joins the shards, then make report)")
        return 1 if failed else 0
    path = report_dynamic.build(root, report_dir)
    say(f"harness: dynamic report in {display(path)}")
    return 1 if failed else 0
