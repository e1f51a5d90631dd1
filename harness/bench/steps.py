"""OUT/steps.json: where a bench's time went, step by step, written as each step ends (so a
stopped run keeps the steps it finished). Each step has its wall time and, where it sent work
to named GPUs (the sweeps' GPU cases, the stability map's GPU cells: core/gpus.py `working`),
the seconds of work each GPU got and how evenly: `balance` is the least-loaded GPU's work over
the busiest's, over every GPU of the run (0 when a step used one of two), and `gpu_work_per_s`
the GPU-seconds of work per second of the step (near the GPU count when a step kept them all
busy). A step without such work ran its GPU runs, if any, on the first GPU. Two runs' steps
are compared with `harness compare` (one GPU against several: each step's ratio)."""

from pathlib import Path

from harness.core import env, gpus
from harness.io.files import write_json

STEPS_JSON = "steps.json"


def node_gpus(gpu):
    """The GPUs a bench with `--gpu gpu` may spread its work over: none without a usable GPU."""
    return gpus.visible() if gpu != "no" and env.gpu_status()[0] else []


def record(times, gpu_list):
    """steps.json's content from a core.progress.StepTimes and the run's GPUs (core.gpus.Gpu)."""
    indices = [g.index for g in gpu_list]
    steps = []
    for (name, seconds), work in zip(times.steps, times.gpu_work):
        entry = {"name": name, "seconds": seconds}
        if work:
            per_gpu = {i: work.get(i, 0.0) for i in sorted(set(indices) | set(work))}
            entry["gpu_work_s"] = {str(i): s for i, s in per_gpu.items()}
            entry["balance"] = min(per_gpu.values()) / max(per_gpu.values())
            entry["gpu_work_per_s"] = sum(per_gpu.values()) / seconds if seconds > 0 else None
        steps.append(entry)
    return {
        "gpus": [{"index": g.index, "name": g.name} for g in gpu_list],
        "total_s": times.elapsed(),
        "steps": steps,
    }


def write(root, times, gpu_list):
    return write_json(Path(root) / STEPS_JSON, record(times, gpu_list))


def gpu_lines(times, gpu_list):
    """The log's lines on GPU work, one a step that had some, when the run had several GPUs."""
    if len(gpu_list) < 2:
        return []
    out = []
    for step in record(times, gpu_list)["steps"]:
        if "gpu_work_s" in step:
            each = ", ".join(f"GPU {i} {s:.0f} s" for i, s in step["gpu_work_s"].items())
            out.append(
                f"harness: GPU work of {step['name']} ({step['seconds']:.0f} s): {each}; "
                f"balance {step['balance']:.2f}, {step['gpu_work_per_s']:.2f} GPU-s a second"
            )
    return out
