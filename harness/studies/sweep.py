"""`harness sweep SWEEP.toml`: run every case of a sweep and append its rows to
results/<name>/runs.csv, resuming where a killed run stopped (runlog.py).

Per case the backend runs the sweep's scene with --repeat/--warmup and --json; each stage
of the record becomes one row with median, min, max and the IQR of its `times_ms`, the
bytes the stage must move (roofline.py), the achieved GB/s and its fraction of the copy
bandwidth measured on the same device at the start of this run. The environment goes to
results/<name>/env.json, one entry per session (a resumed run adds one).
"""

import json
import os
import time
from pathlib import Path

import numpy as np

from harness import HarnessError
from harness.core import budget, env, gpus, rounds, scenes, timing
from harness.core.paths import RESULTS, binary_path, display
from harness.core.progress import Progress
from harness.core.runner import BATCH_MAX, BackendError, DoesNotFit, batches, run_binary, run_flags
from harness.core.scenes import SceneError
from harness.io import results_data, runfolder, runlog
from harness.io.files import write_json
from harness.io.sweepfile import Sweep, load_sweep
from harness.studies import roofline


def quartiles(times):
    """(q1, q3) of a list of times (linear interpolation); (None, None) if empty."""
    if not times:
        return None, None
    q1, q3 = np.percentile(np.asarray(times, dtype=float), [25, 75])
    return float(q1), float(q3)


def rows_of_record(case, record, copy_gbps, session, binary, figures=None):
    """One row per stage of a case's record; `figures` (timing.Figure by stage index): each timed
    stage's spread, stopping rule and the load it ran under, as columns (timing.Figure.columns)."""
    rows = []
    stages = record.get("stages", [])
    for i, st in enumerate(stages):
        times = st.get("times_ms") or []
        q1, q3 = quartiles(times)
        fused = st.get("fused") or ""
        sim = st["stage"] == "simulate"
        if sim:  # per frame; the rest shape counts where a feature reads it
            feats = (st.get("features") or "").split("+")
            nbytes = roofline.simulate_bytes(case.strands, case.points, case.precision, feats)
        else:
            nbytes = roofline.stage_bytes(
                st["stage"],
                case.strands,
                case.points,
                case.precision,
                fused=fused,
                skipped=bool(st.get("skipped")),
                moved=st.get("moved_points"),
            )
        gbps = roofline.achieved_gbps(nbytes, st.get("median_ms"))
        rows.append(
            {
                "case_id": case.case_id,
                "stage_index": i,
                "n_stages": len(stages),
                "stage": st["stage"],
                "scene": case.scene,
                "backend": case.backend,
                "build": case.build,
                "variant": case.variant,
                "precision": case.precision,
                "block_size": case.block_size or "",
                "threads": case.threads or "",
                "strands": case.strands,
                "points": case.points,
                "repeat": case.repeat,
                "warmup": case.warmup,
                "skipped": int(bool(st.get("skipped"))),
                "fused": fused,
                "n_times": len(times),
                "median_ms": st.get("median_ms"),
                "min_ms": st.get("min_ms"),
                "max_ms": st.get("max_ms"),
                "q1_ms": q1,
                "q3_ms": q3,
                "iqr_ms": (q3 - q1) if q1 is not None else None,
                "moved_points": st.get("moved_points"),
                "bytes_moved": nbytes,
                "achieved_gbps": gbps,
                "copy_gbps": copy_gbps,
                "bandwidth_fraction": (gbps / copy_gbps) if (gbps and copy_gbps) else None,
                "solver": st.get("solver", "") if sim else "",
                "substeps": st.get("substeps", "") if sim else "",
                "iterations": st.get("iterations", "") if sim else "",
                "features": st.get("features", "") if sim else "",
                "point_substeps_per_s": st.get("point_substeps_per_s") if sim else None,
                "end_to_end_ms": record.get("end_to_end_ms"),
                "h2d_ms": record.get("h2d_ms"),
                "d2h_ms": record.get("d2h_ms"),
                "state_bytes": record.get("state_bytes"),
                "device": record.get("device"),
                "binary": binary.name,
                "session": session,
                "finished_at": env.now(),
                **(figures[i].columns() if figures and i in figures else timing.Figure().columns()),
            }
        )
    return rows


def case_flags(sweep, case, repeat=None):
    """The binary flags of a case; `repeat`: this round's timed repeats (default the case's)."""
    scene = sweep.scene_of(case).with_overrides(strands=case.strands, points=case.points, precision=case.precision)
    if case.solver:
        from dataclasses import replace

        scene = replace(scene, dynamic={**scene.dynamic, "--solver": case.solver})
    threads = None if case.threads in ("", "all") else case.threads
    flags = run_flags(
        scene,
        case.backend,
        variant=case.variant,
        block_size=case.block_size,
        threads=threads,
        repeat=repeat or case.repeat,
        warmup=case.warmup,
    )
    if scene.model == "dynamic":  # simulate times each frame on its own (--end-to-end is refused)
        return flags
    return flags + ["--end-to-end"]  # end_to_end_ms (and h2d/d2h on cuda) in the record


def backend_reasons(cases, gpu):
    """binary key → reason it cannot run (absent when it can)."""
    reasons = {}
    keys = {(c.backend, c.build or "default") for c in cases}
    gpu_ok, gpu_why = env.gpu_status()
    for backend, build in sorted(keys):
        path = binary_path(backend, build)
        if backend == "cuda":
            if gpu == "no":
                reasons[(backend, build)] = "--gpu no was given"
                continue
            if not gpu_ok:
                if gpu == "yes":
                    raise HarnessError(f"--gpu yes but no GPU is usable: {gpu_why}")
                reasons[(backend, build)] = gpu_why
                continue
        if not path.exists():
            if backend == "cpu" or gpu == "yes":
                raise HarnessError(f"{display(path)} not found: run make")
            reasons[(backend, build)] = f"{display(path)} is not built (run make)"
    return reasons


def load_env(path):
    if path.exists():
        try:
            with open(path) as f:
                return json.load(f)
        except (OSError, json.JSONDecodeError):
            raise HarnessError(f"{path}: not readable JSON; move it away to start a new record") from None
    return None


def machine_of(host):
    """What makes two sessions' times comparable: the CPU, its cores and the GPUs."""
    gpus = tuple(g.get("name") for g in host.get("gpus") or [])
    return host.get("cpu_model"), host.get("cpu_cores"), gpus


def check_same_machine(before, now, out_dir):
    """A resumed sweep must run where its rows were measured: rows of two machines in one
    runs.csv would make curves that no machine produced."""
    if machine_of(before) != machine_of(now):

        def describe(h):
            cpu, cores, gpus = machine_of(h)
            return f"{cpu}, {cores} cores, {', '.join(gpus) if gpus else 'no GPU'}"

        raise HarnessError(
            f"{display(out_dir)} holds rows measured on another machine ({describe(before)}); "
            f"this one is {describe(now)}: give another --out (make bench OUT=results/NAME) "
            f"or move it away"
        )


def run_sweep(sweep_ref, out=None, gpu="auto", log=None, announce_skips=True, shard=None, gate=None, force=False):
    """Run (or resume) a sweep (`sweep_ref`: a sweep file, or a loaded io.sweepfile.Sweep); return
    (results dir, number of failed cases). `shard` (a core.shards.Shard): only its share of the
    cases; `gate` (a core.budget.TierGate): the cases run smallest size first and a tier that does
    not fit is left out with every larger one."""
    sweep = sweep_ref if isinstance(sweep_ref, Sweep) else load_sweep(sweep_ref)
    cases = shard.share(sweep.cases()) if shard is not None else sweep.cases()
    reasons = backend_reasons(cases, gpu)  # a refusal (--gpu yes without a GPU) before anything is written
    out_dir = runfolder.claim(out if out else RESULTS / sweep.name, f"sweep {sweep.name}", force=force)
    csv_path = out_dir / "runs.csv"
    env_path = out_dir / "env.json"
    say = log or (lambda m: print(m, flush=True))

    record = load_env(env_path) or {
        "sweep": sweep.name,
        "sweep_file": display(sweep.path),
        "scene": {k: v for k, v in sweep.scene.__dict__.items() if k != "source"},
        "sessions": [],
    }
    done, dropped = runlog.resume(csv_path)
    if done and record.get("sessions"):
        check_same_machine(record["sessions"][-1].get("host") or {}, env.collect(), out_dir)
    if done and record.get("shard") != (str(shard) if shard else None):
        was = f"shard {record['shard']}" if record.get("shard") else "the whole sweep"
        raise HarnessError(
            f"{display(out_dir)} holds rows of {was}; this run is "
            + (f"shard {shard}" if shard else "the whole sweep")
            + ": give another --out"
        )
    if shard is not None:
        record["shard"] = str(shard)
    skipped = []
    for why in sorted(set(reasons.values())):
        keys = [k for k, r in reasons.items() if r == why]
        n = sum(1 for c in cases if (c.backend, c.build or "default") in keys)
        backends = sorted({k[0] for k in keys})
        builds = [k[1] for k in keys if k[0] == "cuda"]
        label = "/".join(backends) + (f" (builds {', '.join(builds)})" if builds else "")
        skipped.append({"backends": backends, "builds": builds, "cases": n, "reason": why})
        if announce_skips:
            say(f"harness: skipping {n} {label} case(s): {why}")
    todo = [c for c in cases if (c.backend, c.build or "default") not in reasons and c.case_id not in done]
    if done or dropped:
        say(
            f"harness: resuming {display(csv_path)}: {len(done)} case(s) already complete"
            + (f", dropped {dropped} byte(s) of a partial case" if dropped else "")
        )

    session_index = len(record["sessions"])
    session = {
        "started_at": env.now(),
        "host": env.collect(),
        "bandwidth": {},
        "binaries": {},
        "skipped": skipped,
        "failed": [],
        "done_before": len(done),
        "cases_total": len(cases),
        "cases_run": 0,
    }
    record["sessions"].append(session)
    bandwidth = {}
    for key in sorted({(c.backend, c.build or "default") for c in todo}):
        binary = binary_path(*key)
        gbps, note = roofline.measure_copy_bandwidth(binary)
        bandwidth[key] = gbps
        session["bandwidth"][binary.name] = {"copy_gbps": gbps, "note": note}
        say(f"harness: {note}")
    write_json(env_path, record)

    gpu_list = gpus.visible() if any(c.backend == "cuda" for c in todo) else []
    session["gpus"] = [{"index": g.index, "name": g.name} for g in gpu_list]
    if len(gpu_list) > 1:
        say(
            f"harness: sweep {sweep.name}: GPU cases spread over {len(gpu_list)} GPUs "
            f"({', '.join(str(g.index) for g in gpu_list)}); the CPU cases run before them, alone"
        )
    # the stopping rule, its minimum time and timeout within the budget's share for the cases
    rule = sweep.rule.within(gate.allowance, len(todo)) if gate is not None else sweep.rule
    session["timing"] = rule.as_dict()
    groups = budget.tiers(todo, case_size) if gate is not None else [(None, todo)]
    progress = Progress(len(todo), f"sweep {sweep.name}", work=sum(case_size(c) for c in todo))
    failed = 0
    try:
        for size, tier in groups:
            if gate is not None:
                fits, why = gate.admit(size, len(tier))
                if not fits:
                    session["skipped"].append({"cases": len(tier), "size": size, "reason": why, "budget": True})
                    progress.write(f"harness: sweep {sweep.name}: {len(tier)} case(s) of size {size} {why}")
                    progress.update(len(tier), work=sum(case_size(c) for c in tier), skip=True)
                    continue
            t0 = time.monotonic()
            sampled = []  # each case's timed samples, seconds (the gate scales these with the size)
            failed += _run_cases(
                tier, sweep, csv_path, env_path, record, session, session_index, bandwidth, progress, gpu_list, rule,
                sampled,
            )  # fmt: skip
            if gate is not None:
                gate.measured(size, len(tier), time.monotonic() - t0, sum(sampled))
        session["finished_at"] = env.now()
        write_json(env_path, record)
    finally:
        progress.close()
    say(
        f"harness: sweep {sweep.name}: {session['cases_run']} case(s) run, {len(done)} resumed, "
        f"{failed} failed; rows in {display(csv_path)}"
    )
    return out_dir, failed


def case_size(case):
    """A case's rung on the budget's size ladder, and its weight in the progress estimate:
    strands × points (one sweep's cases share the scene's substeps and iterations)."""
    return case.strands * case.points


def _run_cases(
    todo, sweep, csv_path, env_path, record, session, session_index, bandwidth, progress, gpu_list, rule, sampled
):
    """Run the cases by the stopping rule (core.rounds.measure: rounds of timed repeats until
    each stage's samples meet `rule`), appending their rows; the number that failed. The CPU
    cases run one to a process, alone; the GPU cases of one binary several to a process (one
    context for them), with several GPUs on one worker per GPU (core/gpus.py)."""
    failed = 0
    pin = len(gpu_list) > 1 or bool(os.environ.get("HB_GPUS"))  # else the one GPU as the binary finds it

    def key(case):
        return case.backend, case.build or "default"

    def run_cases(cases, gpu, batch):
        """(case, timed) of each case, in order, after all have ended (rounds.Timed)."""
        env_add = {"CUDA_VISIBLE_DEVICES": gpu.select} if gpu is not None and pin else None
        ready, out = [], []
        for case in cases:
            try:
                case_flags(sweep, case)
                ready.append(case)
            except SceneError as e:
                out.append((case, rounds.Timed(error=e)))
        with gpus.working(gpu):  # this GPU's work, for the bench's steps.json
            timed = rounds.measure(
                ready,
                lambda c, n: case_flags(sweep, c, n),
                lambda c: binary_path(*key(c)),
                rule=rule,
                timeout=sweep.timeout_s,
                env=env_add,
                gpu_index=gpu.index if gpu is not None else None,
                batch=batch,
            )
        return out + list(zip(ready, timed))

    def done(case, gpu, t):
        nonlocal failed
        binary = binary_path(*key(case))
        error, rec = t.error, t.record
        if isinstance(error, (DoesNotFit, SceneError)):
            session["skipped"].append({"case": case.case_id, "reason": str(error)})
            progress.write(f"harness: skipping {case.case_id}: {error}")
        elif isinstance(error, BackendError):
            failed += 1
            session["failed"].append({"case": case.case_id, "error": str(error)})
            progress.write(f"harness: case {case.case_id} failed: {error}")
        elif error is not None:
            raise error
        else:
            sampled.append(sum(f.stats["total_s"] for f in t.figures.values()))
            rows = rows_of_record(case, rec, bandwidth.get(key(case)), session_index, binary, t.figures)
            for r in rows:
                r["gpu"] = gpu.index if gpu is not None else ""
            runlog.append_case(csv_path, rows)
            session["cases_run"] += 1
            session["binaries"].setdefault(
                binary.name,
                {k: rec.get(k) for k in ("version", "git_revision", "compiler", "flags", "device", "driver")},
            )
        progress.update(work=case_size(case))
        session["last_case_at"] = env.now()  # finished_at only when the whole session ends
        write_json(env_path, record)

    one = gpu_list[0] if gpu_list else None
    on_cpu = [c for c in todo if c.backend != "cuda"]
    on_gpu = [c for c in todo if c.backend == "cuda"]
    for case in on_cpu:  # the CPU baselines, one process each, no GPU worker running
        for c, t in run_cases([case], None, 1):
            done(c, None, t)
    if len(gpu_list) <= 1:
        for chunk in batches(on_gpu, key, BATCH_MAX):
            for c, t in run_cases(chunk, one, BATCH_MAX):
                done(c, one, t)
        return failed
    # several GPUs: smaller batches, so that the workers end together
    size = max(1, min(BATCH_MAX, -(-len(on_gpu) // (4 * len(gpu_list)))))

    def run_chunk(chunk, gpu):
        return run_cases(chunk, gpu, size)

    def chunk_done(chunk, gpu, results, error):
        if error is not None:
            raise error
        for c, t in results:
            done(c, gpu, t)

    gpus.spread(batches(on_gpu, key, size), gpu_list, run_chunk, chunk_done)
    return failed


FIGURE_STRANDS = 2000  # strands in the Fig. 1/2 state (the plots draw 160 of them, the renders all)


def figure_state(results_dir):
    """The small state Fig. 1/2 are drawn from; made with the cpu binary if absent."""
    path = Path(results_dir) / results_data.FIGURE_STATE
    if path.exists():
        return path
    binary = binary_path("cpu")
    if not binary.exists():
        return None
    path.parent.mkdir(parents=True, exist_ok=True)
    scene = scenes.load_scene("paper").with_overrides(strands=FIGURE_STRANDS)
    run_binary(binary, run_flags(scene, "cpu", output=path, force=True))  # the binary writes it whole or not at all
    return path
