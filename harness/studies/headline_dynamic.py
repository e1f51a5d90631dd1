"""`python -m harness headline --model dynamic`: the dynamic model's four headline targets,
measured in one run on this node (docs/harness.md "The dynamic headline").

  1. memory-bound case: gravity and stretch only (no collider), xpbd, S = 1, I = 1, at N
     strands: each simulate variant's frame time and its fraction of the GPU's copy
     bandwidth measured in the same run (bytes: roofline.simulate_bytes);
  2. the default dynamic scene (configs/scenes/dynamic.toml: every feature, its S and I)
     at N strands: point-substeps per second of each variant and build; with --ncu (and
     ncu on PATH) Nsight Compute's SM and DRAM throughput and the instructions per
     point-substep of the best variant's kernel, which name the limiter;
  3. the real-time regime: the default scene at REALTIME_STRANDS strands: the GPU time of
     a frame per variant and block size, and for the fastest the frame-to-frame cost of an
     application's loop (the tables' uploads and launches included), launched one by one
     and replayed as a CUDA graph (--frame-loop);
  4. the CPU: the fast variant in case 1 against the CPU's copy bandwidth, and the three
     CPU baselines (the oracle on one thread, the oracle on all cores, the fast variant on
     all cores) in cases 1 and 2, for the speedups; the CPU rows run fewer strands where a
     frame would take seconds (strands are independent, so point-substeps per second
     compare across sizes; each row records its N). The fast variant's rows are measured
     in --cpu-rounds rounds, each against the copy bandwidth measured just before it
     (roofline.in_rounds); the row reported is the median round, the others kept beside it.

Writes results/headline/headline_dynamic.json (with the environment: device, driver,
revision) and prints a table with the targets beside the numbers, met or not. Times are
medians of --repeat frames after a warm-up, kernel time only (CUDA events), except the
frame loop (host clock over the loop).
"""

import csv
import io
import shutil
from pathlib import Path

from harness import HarnessError
from harness.core import env, runner, scenes, variants
from harness.core.paths import RESULTS, binary_path, display
from harness.io.files import write_json
from harness.studies import roofline

# the targets (reported beside the numbers, never asserted)
TARGET_MEMORY_FRACTION = 0.90
TARGET_POINT_SUBSTEPS = 6.5e10
STRETCH_POINT_SUBSTEPS = 1e11
TARGET_FTL_POINT_SUBSTEPS = 3e10
TARGET_REALTIME_MS = 0.05
TARGET_CPU_FRACTION = 0.80

REALTIME_STRANDS = 10_000
MEMORY_CASE = ["--substeps", 1, "--iterations", 1, "--no-collider"]
BLOCKS = (128, 256, 512)
REALTIME_BLOCKS = (32, 64, 128, 256)
NCU_STRANDS = 1 << 20
NCU_METRICS = (
    "sm__throughput.avg.pct_of_peak_sustained_elapsed",
    "dram__throughput.avg.pct_of_peak_sustained_elapsed",
    "smsp__inst_executed.sum",
    "sm__warps_active.avg.pct_of_peak_sustained_active",
    "launch__registers_per_thread",
    "gpu__time_duration.sum",
    "smsp__issue_active.avg.pct_of_peak_sustained_active",
    "smsp__thread_inst_executed_per_inst_executed.ratio",
)


def default_scene():
    return scenes.load_scene("dynamic")


def _simulate_variants(build="default"):
    d = variants.declared("cuda", build)
    return d, [v for v in d.variants if d.runs(v)]


def _sim(rec):
    st = [s for s in rec["stages"] if s["stage"] == "simulate"]
    if not st:
        raise HarnessError(f"{rec.get('backend')} record has no simulate stage")
    return st[0]


def _scene_args(scene, strands, frames):
    return scenes.with_frames(scene.with_overrides(strands=strands), frames).flags()


def _memory_args(scene, strands, frames):
    """Gravity and stretch only: the default scene's geometry, no feature declared."""
    return [
        "--strands",
        strands,
        "--points",
        scene.points,
        "--seed",
        scene.seed,
        "--hair-length",
        repr(scene.hair_length),
        "--stages",
        "init,simulate",
        "--frames",
        frames,
        "--precision",
        "fp32",
        *MEMORY_CASE,
    ]


def _features(args):
    a = [str(x) for x in args]
    f = set()
    if "--bend-compliance" in a:
        f.add("bend")
    if "--shape-compliance" in a:
        f.add("shape")
    if "--head-motion" in a and a[a.index("--head-motion") + 1] != "still":
        f.add("motion")
    return f


def _row(label, rec, args, copy_gbps, **extra):
    sim = _sim(rec)
    n, p = rec["strands"], rec["points"]
    nbytes = roofline.simulate_bytes(n, p, rec["precision"], _features(args))
    gbps = roofline.achieved_gbps(nbytes, sim["median_ms"])
    return {
        "label": label,
        "backend": rec["backend"],
        "variant": rec["variant"],
        "build": extra.pop("build", "default"),
        "precision": rec["precision"],
        "strands": n,
        "points": p,
        "substeps": sim["substeps"],
        "iterations": sim["iterations"],
        "features": sim["features"],
        "threads": rec.get("threads"),
        "block_size": rec.get("block_size"),
        "median_ms": sim["median_ms"],
        "min_ms": sim["min_ms"],
        "max_ms": sim["max_ms"],
        "point_substeps_per_s": sim["point_substeps_per_s"],
        "bytes": nbytes,
        "gbps": gbps,
        "fraction": (gbps / copy_gbps) if gbps and copy_gbps else None,
        "frame_loop_ms": sim.get("frame_loop_ms"),
        "frame_loop_graph_ms": sim.get("frame_loop_graph_ms"),
        "device": rec.get("device"),
        **extra,
    }


def _ncu(binary, args, log):
    """Nsight Compute's metrics of the first simulate kernel of `binary args`, or a reason."""
    ncu = shutil.which("ncu")
    if not ncu:
        return {"skipped": "ncu is not on PATH"}
    cmd = [
        ncu,
        "--clock-control",
        "none",
        "--kernel-name",
        "regex:k_(strand|warp|warpreg|lanes)$",
        "--launch-count",
        "1",
        "--csv",
        "--metrics",
        ",".join(NCU_METRICS),
        str(binary),
        *map(str, args),
        "--quiet",
    ]
    try:
        p = runner.run_command(cmd, timeout=600)
    except (OSError, runner.TimedOut) as e:
        return {"skipped": f"ncu failed: {e}"}
    rows = [ln for ln in p.stdout.splitlines() if ln.startswith('"')]
    if p.returncode != 0 or len(rows) < 2:
        why = runner.last_line(p.stderr) or runner.last_line(p.stdout)
        return {"skipped": f"ncu exited {p.returncode}: {why}"}
    out = {"command": " ".join(cmd[1:])}
    for r in csv.DictReader(io.StringIO("\n".join(rows))):
        name, value = r.get("Metric Name"), (r.get("Metric Value") or "").replace(",", "")
        out["kernel"] = r.get("Kernel Name")
        try:
            out[name] = float(value)
        except ValueError:
            out[name] = value
    log(f"headline: ncu {out.get('kernel')}: {', '.join(f'{k}={out.get(k)}' for k in NCU_METRICS)}")
    return out


def run(strands=4 * 1024 * 1024, repeat=5, frames=2, cpu_repeat=3, cpu_rounds=5, ncu=False, out_dir=None, log=print):
    out_dir = Path(out_dir or RESULTS / "headline")
    out_dir.mkdir(parents=True, exist_ok=True)
    scene = default_scene()
    result = {
        "model": "dynamic",
        "strands": strands,
        "points": scene.points,
        "scene": scene.file or "dynamic",
        "env": env.collect(),
        "targets": {
            "memory_fraction": TARGET_MEMORY_FRACTION,
            "point_substeps_per_s": TARGET_POINT_SUBSTEPS,
            "stretch_point_substeps_per_s": STRETCH_POINT_SUBSTEPS,
            "ftl_point_substeps_per_s": TARGET_FTL_POINT_SUBSTEPS,
            "realtime_ms": TARGET_REALTIME_MS,
            "cpu_fraction": TARGET_CPU_FRACTION,
        },
        "memory": [],
        "default": [],
        "ftl": [],
        "realtime": [],
        "cpu": [],
    }
    cpu_bin = binary_path("cpu")
    bw = roofline.measure_bandwidth(cpu_bin)
    result["cpu_copy_gbps"] = bw["copy_gbps"]
    log(f"headline: CPU copy {bw['copy_gbps']:.1f} GB/s ({bw.get('threads')} threads)")
    timing = ["--repeat", repeat, "--warmup", 1]

    gpu_ok, why = env.gpu_status()
    if gpu_ok and binary_path("cuda").exists():
        gbw = roofline.measure_bandwidth(binary_path("cuda"))
        gpu_copy = result["gpu_copy_gbps"] = gbw["copy_gbps"]
        log(f"headline: GPU copy {gpu_copy:.1f} GB/s on {gbw.get('device')}")
        declared, names = _simulate_variants()
        runs = lambda v: declared.runs(v, points=scene.points)  # noqa: E731
        for v in filter(runs, names):
            for b in (b for b in BLOCKS if declared.runs(v, block=b)):
                args = _memory_args(scene, strands, frames) + ["--variant", v, "--block-size", b]
                rec = runner.run_binary(binary_path("cuda"), args + timing)
                result["memory"].append(_row(f"gpu {v} b{b}", rec, args, gpu_copy))
                log(f"headline: memory {v} b{b}: {result['memory'][-1]['median_ms']:.3f} ms")
        for build in ("default", "fastmath", "strict"):
            if not binary_path("cuda", build).exists():
                continue
            bdecl, bnames = _simulate_variants(build)
            for v in (n for n in bnames if bdecl.runs(n, points=scene.points)):
                args = _scene_args(scene, strands, frames) + ["--variant", v, "--block-size", 256]
                rec = runner.run_binary(binary_path("cuda", build), args + ["--repeat", 3, "--warmup", 1])
                tag = "" if build == "default" else f" ({build})"
                result["default"].append(_row(f"gpu {v}{tag}", rec, args, gpu_copy, build=build))
                log(f"headline: default {v}{tag}: {result['default'][-1]['point_substeps_per_s']:.3g} point-substeps/s")
        for v in filter(runs, names):  # the other solver: follow the leader
            args = _scene_args(scene, strands, frames) + ["--solver", "ftl", "--variant", v, "--block-size", 128]
            rec = runner.run_binary(binary_path("cuda"), args + ["--repeat", 3, "--warmup", 1])
            result["ftl"].append(_row(f"gpu {v} ftl", rec, args, gpu_copy))
            log(f"headline: default ftl {v}: {result['ftl'][-1]['point_substeps_per_s']:.3g} point-substeps/s")
        for v in filter(runs, names):
            for b in REALTIME_BLOCKS:
                args = _scene_args(scene, REALTIME_STRANDS, 10) + ["--variant", v, "--block-size", b]
                rec = runner.run_binary(binary_path("cuda"), args + timing)
                result["realtime"].append(_row(f"gpu {v} b{b}", rec, args, gpu_copy))
        best_rt = min(result["realtime"], key=lambda r: r["median_ms"])
        args = _scene_args(scene, REALTIME_STRANDS, 200) + [
            "--variant",
            best_rt["variant"],
            "--block-size",
            best_rt["block_size"],
            "--frame-loop",
        ]
        rec = runner.run_binary(binary_path("cuda"), args)
        result["realtime_loop"] = _row(f"gpu {best_rt['variant']} b{best_rt['block_size']} loop", rec, args, gpu_copy)
        loop = result["realtime_loop"]
        log(
            f"headline: real-time {best_rt['label']}: {best_rt['median_ms']:.4f} ms a frame (kernel); loop "
            f"{loop['frame_loop_ms']:.4f} ms, graph {loop['frame_loop_graph_ms']:.4f} ms"
        )
        if ncu:
            best = max(
                (r for r in result["default"] if r["build"] == "default"), key=lambda r: r["point_substeps_per_s"]
            )
            args = _scene_args(scene, NCU_STRANDS, 1) + ["--variant", best["variant"], "--block-size", 256]
            m = _ncu(binary_path("cuda"), args, log)
            if "smsp__inst_executed.sum" in m:
                ps = NCU_STRANDS * scene.points * best["substeps"]
                m["thread_instructions_per_point_substep"] = 32.0 * m["smsp__inst_executed.sum"] / ps
                m["point_substeps"] = ps
            result["ncu"] = {"variant": best["variant"], "strands": NCU_STRANDS, **m}
    else:
        result["gpu_skipped"] = why
        log(f"headline: GPU rows skipped: {why}")

    cpu = variants.declared("cpu")
    oracle = cpu.default_variant
    fast = [v for v in cpu.variants if v != oracle and cpu.runs(v)]
    # (label, variant, threads or None, strands in case 1, strands in case 2)
    cases = [(f"cpu {oracle}, 1 thread", oracle, 1, strands // 16, strands // 256)]
    cases.append((f"cpu {oracle}, all cores", oracle, None, strands // 2, strands // 16))
    cases += [(f"cpu {v}, all cores", v, None, strands, strands // 4) for v in fast]
    cpu_timing = ["--repeat", cpu_repeat, "--warmup", 1]

    def cpu_row(label, args, case):
        return lambda copy: _row(label, runner.run_binary(cpu_bin, args + cpu_timing), args, copy, case=case)

    for label, v, threads, n_mem, n_def in cases:
        extra = ["--variant", v] + (["--threads", threads] if threads else [])
        for case, args in (
            ("memory", _memory_args(scene, max(n_mem, 1), frames) + extra),
            ("default", _scene_args(scene, max(n_def, 1), frames) + extra),
        ):
            measure = cpu_row(label, args, case)
            if v == oracle:
                result["cpu"].append(measure(bw["copy_gbps"]))
                continue
            result["cpu"].append(roofline.in_rounds(cpu_bin, cpu_rounds, measure, first_copy=bw["copy_gbps"]))
        log(f"headline: {label}: {result['cpu'][-2]['median_ms']:.1f} / {result['cpu'][-1]['median_ms']:.1f} ms")

    summarise(result)
    path = out_dir / "headline_dynamic.json"
    write_json(path, result)
    log(f"wrote {display(path)}")
    return result


def summarise(result):
    """The best row of each case, the targets met or not, and the speedups over the CPU."""
    s = {}
    if result["memory"]:
        best = max(result["memory"], key=lambda r: r["fraction"] or 0)
        s["memory"] = {
            "row": best["label"],
            "fraction": best["fraction"],
            "met": best["fraction"] >= TARGET_MEMORY_FRACTION,
        }
    gpu_default = [r for r in result["default"] if r["build"] == "default"]
    if gpu_default:
        best = max(gpu_default, key=lambda r: r["point_substeps_per_s"])
        s["default"] = {
            "row": best["label"],
            "point_substeps_per_s": best["point_substeps_per_s"],
            "met": best["point_substeps_per_s"] >= TARGET_POINT_SUBSTEPS,
            "stretch_met": best["point_substeps_per_s"] >= STRETCH_POINT_SUBSTEPS,
        }
    if result.get("ftl"):
        best = max(result["ftl"], key=lambda r: r["point_substeps_per_s"])
        s["ftl"] = {
            "row": best["label"],
            "point_substeps_per_s": best["point_substeps_per_s"],
            "met": best["point_substeps_per_s"] >= TARGET_FTL_POINT_SUBSTEPS,
        }
    if result["realtime"]:
        best = min(result["realtime"], key=lambda r: r["median_ms"])
        loop = result.get("realtime_loop") or {}
        s["realtime"] = {
            "row": best["label"],
            "kernel_ms": best["median_ms"],
            "frame_loop_ms": loop.get("frame_loop_ms"),
            "frame_loop_graph_ms": loop.get("frame_loop_graph_ms"),
            "met": best["median_ms"] <= TARGET_REALTIME_MS,
        }
    cpu_mem = [r for r in result["cpu"] if r["case"] == "memory"]
    if cpu_mem:
        best = max(cpu_mem, key=lambda r: r["fraction"] or 0)
        s["cpu"] = {
            "row": best["label"],
            "fraction": best["fraction"],
            "met": (best["fraction"] or 0) >= TARGET_CPU_FRACTION,
        }
        if best.get("rounds"):
            s["cpu"]["rounds"] = [r["fraction"] for r in best["rounds"]]
            s["cpu"]["fraction_of_first_copy"] = best.get("fraction_of_first_copy")
    speedups = {}
    for case, gpu_rows in (("memory", result["memory"]), ("default", gpu_default)):
        if not gpu_rows:
            continue
        g = max(gpu_rows, key=lambda r: r["point_substeps_per_s"])
        for r in (r for r in result["cpu"] if r["case"] == case):
            speedups.setdefault(case, {})[r["label"]] = g["point_substeps_per_s"] / r["point_substeps_per_s"]
        if speedups.get(case):
            fastest = max((r for r in result["cpu"] if r["case"] == case), key=lambda r: r["point_substeps_per_s"])
            speedups[case]["headline"] = {
                "gpu": g["label"],
                "cpu": fastest["label"],
                "speedup": speedups[case][fastest["label"]],
            }
    s["speedups"] = speedups
    result["summary"] = s
    return s
