"""The report's section on where a bench's time went: each step's wall time and, on a node with
several GPUs, the work each GPU got and how evenly (from RUN/steps.json, harness/bench/steps.py);
nothing when the run wrote none. The page is rendered before the bench's last steps end: the
section lists the steps that had ended, and says so."""

from pathlib import Path

from harness.core import inputs
from harness.core.paths import display


def section(root):
    path = Path(root) / "steps.json"
    if not path.is_file():
        return []
    data = inputs.read_json(path, "report")
    steps = data.get("steps") or []
    gpus = data.get("gpus") or []
    several = len(gpus) > 1
    lines = [
        "## Where the time went",
        "",
        f"The bench's steps that had ended when this page was rendered, {data.get('total_s', 0):.0f} s in "
        f"(`{display(path)}` holds every step; `harness compare` sets two runs' steps side by side)"
        + (f", on {len(gpus)} GPUs ({', '.join(g['name'] for g in gpus)})." if gpus else "."),
        "",
    ]
    if several:
        lines += [
            "A step's work on each GPU is the time of the runs sent to it; balance is the least-loaded GPU's "
            "work over the busiest's (1: even; 0: one GPU did it all). A step without GPU work listed ran its "
            "GPU runs, if any, on the first GPU.",
            "",
            "| step | wall time | work per GPU | balance |",
            "| --- | --- | --- | --- |",
        ]
        for s in steps:
            work = s.get("gpu_work_s")
            each = ", ".join(f"GPU {i}: {w:.0f} s" for i, w in work.items()) if work else "—"
            balance = f"{s['balance']:.2f}" if work else "—"
            lines.append(f"| {s['name']} | {s['seconds']:.0f} s | {each} | {balance} |")
    else:
        lines += ["| step | wall time |", "| --- | --- |"] + [f"| {s['name']} | {s['seconds']:.0f} s |" for s in steps]
    return lines + [""]
