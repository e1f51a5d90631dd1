"""report/report.md: what ran, how it was checked, how fast, and the paper beside it.
Rendering only: the numbers come from results_data.py.

Sections: environment; scenes and the stages that ran (skipped and fused ones named);
validation (results/<name>/validation.json, written by `harness bench`); the paper's
Fig. 3–4 numbers beside ours, with the strand counts at which our curves reach the
paper's times (the paper gives no strand count); wind+collide tables; the plots.
"""

import datetime
import json
import math
import os
from pathlib import Path

from harness.core.paths import REPORT, display, output_dir
from harness.io import files, results_data
from harness.io.results_data import curve_of, interp_time, strands_at_time
from harness.render import budget_report, hair_report, host_report
from harness.render.accuracy_paper_report import report_from_csv
from harness.render.headline_report import table
from harness.render.plots_paper import make_all

# The paper's Fig. 3 (release) and Fig. 4 (debug), milliseconds of "applying wind".
PAPER = {
    "release": {"cpu": 353.107, "gpu_b32": 309.174, "gpu_b64": 255.0},
    "debug": {"cpu": 4719.57, "gpu_b32": 762.796},
}


def fmt_n(n):
    return "—" if n is None else f"{n:,.0f}"


def fmt_ms(t):
    return "—" if t is None or (isinstance(t, float) and math.isnan(t)) else f"{t:.3f}"


def environment_section(env):
    lines = ["## Environment", ""]
    sessions = env.get("sessions", [])
    if not sessions:
        return lines + ["No env.json: the environment was not recorded.", ""]
    for i, s in enumerate(sessions):
        h = s.get("host", {})
        lines.append(
            f"- session {i} ({s.get('started_at', '?')}): CPU {h.get('cpu_model')} "
            f"× {h.get('cpu_cores')} cores; GPU {h.get('device') or 'none'} "
            f"(driver {h.get('driver') or '—'}); nvcc {h.get('nvcc') or '—'}; "
            f"{h.get('gcc') or 'gcc —'}; git {h.get('git_revision')}; {s.get('cases_run', 0)} case(s) run"
        )
        for name, b in s.get("binaries", {}).items():
            lines.append(
                f"  - `{name}` {b.get('version')} ({b.get('git_revision')}), {b.get('compiler')}: `{b.get('flags')}`"
            )
        for name, b in s.get("bandwidth", {}).items():
            gbps = b.get("copy_gbps")
            lines.append(
                f"  - copy bandwidth of `{name}`: "
                + (f"{gbps:.1f} GB/s" if gbps else f"not measured ({b.get('note')})")
            )
    return lines + [""]


def scenes_section(env, cases):
    lines = ["## Scenes and the stages that ran", ""]
    for scene, g in cases.groupby("scene"):
        lines.append(
            f"- **{scene}**: stages `{g['stages'].iloc[0]}` "
            f"({len(g)} case(s): {', '.join(sorted(g['backend'].unique()))})"
        )
        skipped = sorted({s for v in g["skipped_stages"] for s in v.split(",") if s})
        if skipped:
            lines.append(f"  - not launched (nil effect, e.g. w = 0): {', '.join(skipped)}")
        fused = sorted({f for v in g["fused"] for f in v.split(",") if f})
        if fused:
            lines.append(
                "  - fused: wind + collide ran as one kernel in the `fused` variant "
                "(its wind row carries the pair, the collide row is 0)"
            )
    sc = env.get("scene")
    if sc:
        lines.append(
            f"- scene parameters: R = {sc.get('head_radius')}, h = {sc.get('hair_offset')}, "
            f"L = {sc.get('hair_length')}, m = {sc.get('face_margin')}, "
            f"w = {sc.get('wind_strength')}, ψ = {sc.get('wind_angle')}, seed {sc.get('seed')}"
        )
    return lines + [""]


def gpu_section(cases, env):
    if (cases["backend"] == "cuda").any():
        return []
    return [
        "## GPU rows",
        "",
        f"**GPU rows are absent**: {results_data.gpu_absent_reason(env)}. The CPU rows, the "
        "plots' CPU lines and everything below still stand; rerun `make bench` on a GPU node "
        "for the GPU columns.",
        "",
    ]


def validation_section(results_dir):
    path = Path(results_dir) / "validation.json"
    lines = ["## Validation (before timing)", ""]
    if not path.exists():
        return lines + [
            "No validation.json: this results directory was not made by "
            "`harness bench` (which validates before it times).",
            "",
        ]
    v = json.loads(path.read_text())
    checks = v.get("checks", [])
    ok = sum(1 for c in checks if c.get("equivalent"))
    lines.append(
        f"{ok} of {len(checks)} comparisons equivalent at {v.get('strands')} strands × "
        f"{v.get('points')} points. {v.get('gpu_note', '')}"
    )
    shards = sorted({c["shard"] for c in checks if "shard" in c})
    if len(shards) > 1:  # a merged run: each shard validated its own node before it timed
        lines.append(f"{len(shards)} shards, each validated on its own node before it timed anything.")
    shown = checks
    if len(checks) > 30:  # every failure, the CPU checks, and the worst of each GPU build × precision × kind
        worst = {}
        for i, c in enumerate(checks):
            words = c["what"].split()
            if words[0] == "cuda":
                precision = next((w for w in words if w.startswith("fp")), "").rstrip(":")
                key = (words[1], precision, "stage" in words)  # a whole run, or one stage resumed
                if key not in worst or c.get("max_k", 0) > checks[worst[key]].get("max_k", 0):
                    worst[key] = i
        keep = set(worst.values())
        shown = [
            c for i, c in enumerate(checks) if not c.get("equivalent") or not c["what"].startswith("cuda") or i in keep
        ]
        lines.append(
            "Shown: the CPU checks, every failure, and the worst of each GPU build × precision, "
            f"whole run and resumed stage ({len(shown)} of {len(checks)}; all in validation.json)."
        )
    lines += [
        "",
        "| check | pair | max abs error | max / u | points over | verdict |",
        "| --- | --- | --- | --- | --- | --- |",
    ]
    for c in shown:
        what = c["what"] + (f" (shard {c['shard']})" if len(shards) > 1 else "")
        lines.append(
            f"| {what} | {c.get('pair', '')} | {c.get('max_abs', float('nan')):.3g} | "
            f"{c.get('max_k', float('nan')):.3g} | {c.get('over', '')} | "
            f"{'ok' if c.get('equivalent') else 'FAIL'} |"
        )
    return lines + [""]


def paper_section(cases):
    lines = [
        "## The paper's Fig. 3–4 beside ours",
        "",
        'The paper times "applying wind", i.e. our `wind` + `collide` pair, in float '
        "(fp32), plain single-threaded CPU code (our `ref` variant at 1 thread) against one "
        "CUDA thread per strand (our `paper` variant). **It gives no "
        "strand count** (nor points per strand, nor hardware), so its times cannot be set "
        "beside ours at a known size; instead the table shows at which strand count our "
        "curves take the paper's times, and our speedup there.",
        "",
    ]
    points = results_data.main_points(cases)
    sel = (cases["precision"] == "fp32") & (cases["points"] == points)
    cpu1 = results_data.cpu_baseline(cases[sel], "single")
    cpu1 = dict(zip(cpu1.index.get_level_values("strands"), cpu1))
    cpu_all = results_data.cpu_baseline(cases[sel], "all")
    cpu_all = dict(zip(cpu_all.index.get_level_values("strands"), cpu_all))
    gpu = cases[sel & (cases["backend"] == "cuda") & (cases["build"].isin(["", "default"]))]
    paper_variant = (
        "paper" if (gpu["variant"] == "paper").any() else (gpu["variant"].iloc[0] if not gpu.empty else None)
    )
    g32 = curve_of(gpu, (gpu["variant"] == paper_variant) & (gpu["block_size"] == 32)) if paper_variant else {}
    g64 = curve_of(gpu, (gpu["variant"] == paper_variant) & (gpu["block_size"] == 64)) if paper_variant else {}

    lines += [
        "| | paper (ms) | paper speedup | our N at the paper's CPU time | our CPU ref 1 thread there (ms) | "
        "our GPU there (ms) | our speedup there |",
        "| --- | --- | --- | --- | --- | --- | --- |",
    ]
    for mode, p in PAPER.items():
        n_star, how = strands_at_time(cpu1, p["cpu"])
        for label, key, curve in (("block 32", "gpu_b32", g32), ("block 64", "gpu_b64", g64)):
            if key not in p:
                continue
            ours_gpu = interp_time(curve, n_star) if curve else None
            ours_cpu = interp_time(cpu1, n_star)
            speed = (ours_cpu / ours_gpu) if (ours_gpu and ours_cpu) else None
            lines.append(
                f"| {mode}, {label} | CPU {p['cpu']} / GPU {p[key]} | {p['cpu'] / p[key]:.2f}× | "
                f"{fmt_n(n_star)} ({how}) | {fmt_ms(ours_cpu)} | "
                f"{fmt_ms(ours_gpu) if curve else 'no GPU rows'} | "
                f"{'—' if speed is None else f'{speed:.1f}×'} |"
            )
    lines.append("")
    notes = [
        f"Ours: fp32, {points} points per strand, "
        + (f"the `{paper_variant}` GPU variant; " if paper_variant else "no GPU rows; ")
        + "the CPU is our optimised C reference (-O2), so the paper's debug-mode times map to "
        "larger N than its release-mode ones only because its debug CPU was slow."
    ]
    if g32:
        n_gpu, how = strands_at_time(g32, PAPER["release"]["gpu_b32"])
        notes.append(
            f"Our GPU (block 32) takes the paper's GPU time of {PAPER['release']['gpu_b32']} ms "
            f"at N ≈ {fmt_n(n_gpu)} ({how})."
        )
    if cpu_all:
        n_all, how = strands_at_time(cpu_all, PAPER["release"]["cpu"])
        notes.append(
            f"{results_data.BASELINES['all']} takes {PAPER['release']['cpu']} ms at N ≈ {fmt_n(n_all)} ({how})."
        )
    return lines + notes + [""]


def timing_table(cases):
    lines = [
        "## wind + collide median times (ms)",
        "",
        '"(noise)": a stage\'s spread above 0.5 % or a host loaded by others while it ran (core/timing.py).',
        "",
    ]
    c = cases.dropna(subset=["pair_ms"])
    if c.empty:
        return lines + ["No case ran a wind stage.", ""]
    for (precision, points), g in c.groupby(["precision", "points"]):
        labels = sorted(g["label"].unique(), key=lambda s: (not s.startswith("CPU"), s))
        if len(labels) > 12:  # keep the table readable: CPU rows and the paper-relevant GPU ones
            labels = [
                lab for lab in labels if lab.startswith("CPU") or " b32" in lab or " b64" in lab or " b256" in lab
            ]
        counts = sorted(g["strands"].unique())
        lines += [
            f"{precision}, {points} points per strand:",
            "",
            "| strands | " + " | ".join(labels) + " |",
            "| --- |" + " --- |" * len(labels),
        ]
        for n in counts:
            row = []
            for lab in labels:
                hit = g[(g["strands"] == n) & (g["label"] == lab)]
                noise = " (noise)" if len(hit) and hit["noisy"].iloc[0] else ""
                row.append(fmt_ms(float(hit["pair_ms"].iloc[0])) + noise if len(hit) else "—")
            lines.append(f"| {n:,} | " + " | ".join(row) + " |")
        lines.append("")
    return lines


def headline_section(path):
    """The headline numbers (python -m harness headline), when they were measured."""
    if not path.exists():
        return []
    h = json.loads(path.read_text())
    host = h.get("env", {})
    gpus = ", ".join(g.get("name", "?") for g in host.get("gpus") or []) or "no GPU"
    lines = [
        "## Headline: bandwidth fractions and speedups",
        "",
        f"From `{display(path)}` (`python -m harness headline`, git {host.get('git_revision')}, "
        f"{gpus}, {host.get('cpu_model')} with {host.get('cpu_cores')} cores, {host.get('date')}). "
        f"Copy bandwidth: GPU {h.get('gpu_copy_gbps') or 0:.0f} GB/s (device to device), CPU "
        f"{h.get('cpu_copy_gbps') or 0:.1f} GB/s (STREAM-style copy, all cores; triad "
        f"{h.get('cpu_triad_gbps') or 0:.1f} GB/s). %BW = bytes the stage must move (roofline below) "
        "over its median time, over that copy bandwidth.",
        "",
        "```",
    ]
    lines += table(h).splitlines() + ["```", ""]
    if h.get("gpu_skipped"):
        lines += [f"GPU rows skipped: {h['gpu_skipped']}", ""]
    return lines


def build(results_dir="results/default", report_dir=None):
    rows, env = results_data.load(results_dir)  # a run without results is refused before a folder is made
    out_dir = output_dir(report_dir if report_dir else REPORT, "--report-dir")
    cases = results_data.per_case(rows)
    pictures = make_all(results_dir, out_dir)
    lines = [
        "# hairbench report",
        "",
        f"Generated {datetime.datetime.now(datetime.timezone.utc):%Y-%m-%d %H:%M UTC} from "
        f"`{display(results_dir)}` ({len(rows)} rows, {len(cases)} cases) by `python -m harness report`.",
        "Times are medians of ≥ 9 repetitions per stage after warm-up (min, max and IQR in "
        "`runs.csv`); per-stage kernel time only, not transfers or HDF5 writes.",
        "",
    ]
    if env.get("provenance"):
        lines += ["## Provenance", "", env["provenance"], ""]
    lines += host_report.section(Path(results_dir).parent)
    lines += budget_report.section(Path(results_dir).parent)
    lines += headline_section(Path(results_dir).parent / "headline" / "headline.json")
    lines += gpu_section(cases, env)
    lines += scenes_section(env, cases)
    lines += hair_report.paper_lines(Path(results_dir) / results_data.FIGURE_STATE, out_dir)
    lines += paper_section(cases) if not cases.empty else []
    lines += ["## Plots", ""]
    for p in pictures:
        lines.append(f"![{p.stem}]({os.path.relpath(p, out_dir)})")
        lines.append("")
    lines += timing_table(cases) if not cases.empty else []
    lines += [
        "## Roofline",
        "",
        "Bytes a stage must move (harness/studies/roofline.py): init writes N·P·3·s; wind reads and "
        "writes y and z: N·P·2·s·2; collide reads y and z and writes the points it moves: "
        "N·P·2·s + M·2·s (M = moved points); a fused wind+collide counts N·P·2·s·2 once; "
        "s = 4 (fp32) or 8 (fp64). The fraction is those bytes over the stage's median time, "
        "over the copy bandwidth the binary measured on the same device in the same sweep. "
        "A fraction above 1 means the state fit in the caches (the GPU's L2, the CPU's L2/L3): "
        "the limit is the memory's copy bandwidth, and a state that small beats it.",
        "",
    ]
    # the accuracy study of the same machine (`python -m harness accuracy`): its CSV
    # beside this results directory, rendered again here so the report never mixes machines
    accuracy_csv = Path(results_dir).parent / "accuracy" / "accuracy.csv"
    if accuracy_csv.exists():
        md = report_from_csv(accuracy_csv, out_dir, log=lambda *_: None)
        lines += md.read_text().splitlines() + [""]
    else:
        lines += [
            "## Speed against accuracy",
            "",
            f"Not measured with these results (no `{display(accuracy_csv)}`): run "
            "`python3 -m harness accuracy` on this machine.",
            "",
        ]
    # the dynamic model has its own page (harness/render/report_dynamic.py)
    lines += [
        "## The dynamic model",
        "",
        "The time-stepped model (validation, throughput, the headline targets, speed against "
        "accuracy, stability, the peer, the animation) is reported in [dynamic.md](dynamic.md).",
        "",
    ]
    lines += validation_section(results_dir)  # how the results were checked, after them
    lines += environment_section(env)
    path = out_dir / "report.md"
    return files.write_text(path, "\n".join(lines) + "\n")
