"""`python -m harness headline`: the headline numbers, measured in one run.

At one size (default 4M strands x 32 points, the paper scene) and on this node:
  - the device copy bandwidth (hairsim-cuda --measure-bandwidth) and the CPU's STREAM-style
    copy and triad over all cores (hairsim-cpu --measure-bandwidth);
  - every CUDA variant's init and wind+collide time and its fraction of the copy bandwidth
    (bytes from roofline.py);
  - three CPU baselines: the plain reference on one thread (what the paper compared with),
    the plain reference on all cores, and the simd variant on all cores, each with its
    fraction of the CPU copy bandwidth (the simd rows in --cpu-rounds rounds, each against the
    copy measured just before it: roofline.in_rounds);
  - the speedup of the best GPU variant over each baseline (wind+collide, the pair the paper
    timed as "applying wind").
Writes results/headline/headline.json (render/headline_report.py makes its table). Times are medians of --repeat
runs after a warm-up, per-stage compute only (docs/interfaces.md).
"""

from harness.core import env, runner, variants
from harness.core.paths import CUDA_BUILDS, RESULTS, binary_path, display
from harness.io import runfolder
from harness.io.files import write_json
from harness.studies import roofline

STAGES = "init,collide,wind,collide"


def _wind_collide(rec):
    """(ms, bytes) of the wind+collide pair (frames 2 and 3 of the paper scene)."""
    st = rec["stages"]
    wind, coll = st[2], st[3]
    n, p, prec = rec["strands"], rec["points"], rec["precision"]
    if wind.get("fused") == "wind+collide":
        return wind["median_ms"], roofline.stage_bytes("wind", n, p, prec, fused="wind+collide")
    nbytes = roofline.stage_bytes("wind", n, p, prec) + roofline.stage_bytes(
        "collide", n, p, prec, moved=coll.get("moved_points")
    )
    return wind["median_ms"] + coll["median_ms"], nbytes


def _row(label, rec, copy_gbps):
    init = rec["stages"][0]
    init_bytes = roofline.stage_bytes("init", rec["strands"], rec["points"], rec["precision"])
    wc_ms, wc_bytes = _wind_collide(rec)
    frac = lambda b, ms: (roofline.achieved_gbps(b, ms) / copy_gbps) if copy_gbps else None  # noqa: E731
    return {
        "label": label,
        "backend": rec["backend"],
        "variant": rec["variant"],
        "precision": rec["precision"],
        "threads": rec.get("threads"),
        "block_size": rec.get("block_size"),
        "device": rec["device"],
        "init_ms": init["median_ms"],
        "init_fraction": frac(init_bytes, init["median_ms"]),
        "wind_collide_ms": wc_ms,
        "wind_collide_fraction": frac(wc_bytes, wc_ms),
        "flags": rec.get("flags"),
    }


def run(
    strands=4 * 1024 * 1024, points=32, repeat=9, cpu_repeat=3, cpu_rounds=5, block_size=256, out_dir=None, log=print
):
    out_dir = runfolder.claim(out_dir or RESULTS / "headline", "headline", force=True)
    base = ["--strands", strands, "--points", points, "--stages", STAGES]
    result = {"strands": strands, "points": points, "env": env.collect(), "rows": []}
    cpu = binary_path("cpu")
    bw = roofline.measure_bandwidth(cpu)
    result["cpu_copy_gbps"], result["cpu_triad_gbps"] = bw["copy_gbps"], bw.get("triad_gbps")
    log(
        f"headline: CPU copy {bw['copy_gbps']:.1f} GB/s, triad {bw.get('triad_gbps') or 0:.1f} GB/s "
        f"({bw.get('threads')} threads)"
    )
    gpu_ok, why = env.gpu_status()
    if gpu_ok and binary_path("cuda").exists():
        gbw = roofline.measure_bandwidth(binary_path("cuda"))
        result["gpu_copy_gbps"] = gbw["copy_gbps"]
        log(f"headline: GPU copy {gbw['copy_gbps']:.1f} GB/s on {gbw.get('device')}")
        for build in CUDA_BUILDS:
            declared = variants.declared("cuda", build)
            # every variant of the default build; the other builds' default variant only
            for variant in declared.variants if build == "default" else (declared.default_variant,):
                for prec in ("fp32", "fp64") if build == "default" else ("fp32",):
                    rec = runner.run_binary(
                        binary_path("cuda", build),
                        base
                        + [
                            "--variant",
                            variant,
                            "--precision",
                            prec,
                            "--block-size",
                            block_size,
                            "--repeat",
                            repeat,
                            "--warmup",
                            2,
                        ],
                    )
                    label = f"gpu {variant} {prec}" + ("" if build == "default" else f" ({build})")
                    result["rows"].append(_row(label, rec, gbw["copy_gbps"]))
                    log(f"headline: {label}: wind+collide {result['rows'][-1]['wind_collide_ms']:.3f} ms")
    else:
        result["gpu_skipped"] = why
        log(f"headline: GPU rows skipped: {why}")
    cpu_declared = variants.declared("cpu")
    oracle = cpu_declared.default_variant
    cpu_cases = [
        (f"cpu {oracle}, 1 thread", ["--variant", oracle, "--threads", 1]),
        (f"cpu {oracle}, all cores", ["--variant", oracle]),
    ]
    cpu_cases += [(f"cpu {v}, all cores", ["--variant", v]) for v in cpu_declared.variants if v != oracle]
    for label, extra in cpu_cases:
        args = base + extra + ["--precision", "fp32", "--repeat", cpu_repeat, "--warmup", 1]
        measure = lambda copy, label=label, args=args: _row(label, runner.run_binary(cpu, args), copy)  # noqa: E731
        if extra[1] == oracle:
            row = measure(bw["copy_gbps"])
        else:
            row = roofline.in_rounds(
                cpu, cpu_rounds, measure, "wind_collide_fraction", "wind_collide_ms", first_copy=bw["copy_gbps"]
            )
        result["rows"].append(row)
        log(f"headline: {label}: wind+collide {result['rows'][-1]['wind_collide_ms']:.1f} ms")
    gpu_fp32 = [
        r for r in result["rows"] if r["backend"] == "cuda" and r["precision"] == "fp32" and "(" not in r["label"]
    ]
    if gpu_fp32:
        best = min(gpu_fp32, key=lambda r: r["wind_collide_ms"])
        result["best_gpu"] = best["label"]
        result["speedups"] = {
            r["label"]: r["wind_collide_ms"] / best["wind_collide_ms"] for r in result["rows"] if r["backend"] == "cpu"
        }
    path = out_dir / "headline.json"
    write_json(path, result)
    log(f"wrote {display(path)}")
    return result
