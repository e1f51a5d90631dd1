"""report/dynamic.md: the dynamic model's report, rendered from a bench root (the results
of harness/bench/dynamic.py: <root>/dynamic/{runs.csv, env.json, validation.json},
<root>/featurecost/*.csv, <root>/peer/, <root>/dynamic-accuracy/, <root>/dynamic-accuracy-curly/,
<root>/stability/, <root>/headline/headline_dynamic.json, <root>/judge/). Rendering only: every number comes from those
files, every missing piece is named with the command that makes it."""

import json
import os
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import pandas as pd  # noqa: E402

from harness.core.paths import REPORT, display  # noqa: E402
from harness.io import (
    files,
    results_data,  # noqa: E402
)
from harness.render import (  # noqa: E402
    accuracy_dynamic_report,
    budget_report,
    hair_report,
    host_report,
    judge_report,
    steps_report,
)
from harness.render import accuracy_world_dynamic_report as accuracy_world_report  # noqa: E402
from harness.render import featurecost_dynamic_report as featurecost_report  # noqa: E402
from harness.render import frame_budget_dynamic as frame_budget  # noqa: E402
from harness.render import peer_dynamic_report as peer_report  # noqa: E402
from harness.render import reduced_dynamic_report as reduced_report  # noqa: E402
from harness.render import stability_dynamic_report as stability_report  # noqa: E402
from harness.render.headline_report import rounds_note  # noqa: E402
from harness.studies.accuracy import (  # noqa: E402
    BODY_SCENE,
    WORLD_RESULTS_NAME,
    curves_name,
    results_name,
)

CURLY_SCENE = "curly"  # configs/scenes/curly.toml: the accuracy study's second scene
CURLY_TITLE = "curly hair"
CURLY_SWEEP = "dynamic-curly"  # configs/sweeps/dynamic-curly.toml, in <root>/dynamic-curly


def _save(fig, path):
    try:
        return files.save_figure(fig, path, dpi=110, bbox_inches="tight")
    finally:
        plt.close(fig)


def sim_rows(results_dir):
    """The simulate rows of a dynamic sweep, with a `label` per configuration."""
    rows, env = results_data.load(results_dir)
    rows = rows[rows["stage"] == "simulate"].copy()
    if rows.empty:
        return rows, env
    rows["point_substeps_per_s"] = pd.to_numeric(rows["point_substeps_per_s"], errors="coerce")

    def label(r):
        if r["backend"] == "cpu":
            return f"cpu {r['variant']} {'1 thread' if str(r['threads']) == '1' else 'all cores'}"
        build = "" if r["build"] in ("", "default") else f" {r['build']}"
        return f"gpu {r['variant']}{build} b{int(r['block_size'])}"

    rows["label"] = rows.apply(label, axis=1)
    return rows, env


def split_world(rows):
    """(the sweep's rows of its own scene, those of the body scene's groups); every row stays its
    own scene's when the sweep itself ran the body scene."""
    body = rows["scene"].astype(str) == BODY_SCENE if "scene" in rows else None
    if body is None or body.all():
        return rows, rows.iloc[0:0]
    return rows[~body], rows[body]


def throughput_plot(rows, solver, precision, out_dir):
    sel = rows[(rows["solver"] == solver) & (rows["precision"] == precision)]
    if sel.empty:
        return None
    fig, ax = plt.subplots(figsize=(7.5, 4.8))
    for lab, g in sorted(sel.groupby("label"), key=lambda kv: -kv[1]["point_substeps_per_s"].max()):
        g = g.sort_values("strands")
        ls = "--" if lab.startswith("cpu") else "-"
        ax.plot(g["strands"], g["point_substeps_per_s"], ls, marker="o", ms=3, label=lab)
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlabel("strands (32 points)")
    ax.set_ylabel("point-substeps per second")
    ax.set_title(f"dynamic default scene, {solver}, {precision}: throughput per frame")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=6, ncol=2)
    return _save(fig, Path(out_dir) / f"dynamic_throughput_{solver}_{precision}.png")


def best_table(rows):
    """Per solver and strand count: the best of each family (cpu 1 thread, cpu all cores,
    gpu), its point-substeps/s and ms per frame, and the GPU's speedup over each CPU row."""
    lines = [
        "| solver | strands | best CPU, 1 thread | best CPU, all cores | best GPU | GPU over CPU all cores |",
        "| --- | ---: | --- | --- | --- | ---: |",
    ]
    fp32 = rows[(rows["precision"] == "fp32") & (rows["build"].isin(["", "default"]))]
    for (solver, n), g in fp32.groupby(["solver", "strands"]):
        fam = {
            "one": g[(g["backend"] == "cpu") & (g["threads"].astype(str) == "1")],
            "all": g[(g["backend"] == "cpu") & (g["threads"].astype(str) != "1")],
            "gpu": g[g["backend"] == "cuda"],
        }
        best = {k: (v.loc[v["point_substeps_per_s"].idxmax()] if not v.empty else None) for k, v in fam.items()}

        def cell(r):
            if r is None:
                return "—"
            noise = " (noise)" if isinstance(r.get("noisy"), str) and r.get("noisy") else ""
            return f"{r['label']}: {float(r['median_ms']):.3g} ms ({float(r['point_substeps_per_s']):.3g}/s){noise}"

        sp = "—"
        if best["gpu"] is not None and best["all"] is not None:
            sp = f"{best['gpu']['point_substeps_per_s'] / best['all']['point_substeps_per_s']:.1f}×"
        cells = " | ".join(cell(best[k]) for k in ("one", "all", "gpu"))
        lines.append(f"| {solver} | {int(n):,} | {cells} | {sp} |")
    return lines


def curly_throughput_lines(sweep_dir):
    """The curly scene's sweep (configs/sweeps/dynamic-curly.toml): the best of each family
    per strand count, beside the straight scene's."""
    lines = [f"### Throughput on {CURLY_TITLE}", ""]
    if not (Path(sweep_dir) / "runs.csv").exists():
        cmd = f"python -m harness sweep {CURLY_SWEEP} --out {display(sweep_dir)}"
        return lines + [f"Not measured (no `{display(Path(sweep_dir) / 'runs.csv')}`): `{cmd}`.", ""]
    rows, env = sim_rows(sweep_dir)
    sess = (env.get("sessions") or [{}])[-1]
    host = sess.get("host") or sess
    lines += [
        "The same measure on configs/scenes/curly.toml (the default scene's physics on helices, "
        "per-segment rest lengths, docs/model.md §3.15; GPU block 128):",
        "",
    ]
    lines += best_table(rows) + [""]
    where = {k: host.get(k) for k in ("cpu_model", "cpu_cores", "gpus", "git_revision") if k in host}
    return lines + [f"Sweep environment: {json.dumps(where)}", ""]


def _num(x):
    return f"{x:.3g}" if isinstance(x, (int, float)) and x == x else ""


def validation_summary(results_dir):
    """One line for the page's top: how many comparisons were equivalent (the table is at the end)."""
    path = Path(results_dir) / "validation.json"
    if not path.exists():
        return []
    checks = json.loads(path.read_text()).get("checks", [])
    bad = sum(1 for c in checks if not c.get("equivalent"))
    verdict = f"**{bad} NOT equivalent**" if bad else "all equivalent"
    return [f"Every backend was validated against the C reference before any timing: {len(checks)} comparisons, "
            f"{verdict} (the table: \"Validation\", at the end).", ""]  # fmt: skip


def validation_lines(results_dir, what="the default scene"):
    path = Path(results_dir) / "validation.json"
    if not path.exists():
        return [f"Not validated with these results (no `{display(path)}`)."]
    v = json.loads(path.read_text())
    checks = v.get("checks", [])
    bad = [c for c in checks if not c.get("equivalent")]
    lines = [
        f"Before any timing, at {v.get('strands')} strands × {v.get('points')} points of {what}: "
        f"{len(checks)} comparisons, {len(checks) - len(bad)} equivalent"
        + (f" ({len(bad)} NOT)" if bad else "")
        + ". One frame from the same input state, judged by `harness.check.diff_dynamic` (the rule of "
        "`harness stepdiff` and of the GPU tests: a point is over beyond the larger of DYN_STEP_K·ε·E·S·I and "
        "DYN_SPREAD_K × the scene's spread, docs/judge.md); bit-identical where marked. " + (v.get("gpu_note") or ""),
        "",
        "| check | pair | max abs (cm) | max / L | ulp max | spread (cm) | limit (cm) | verdict |",
        "| --- | --- | ---: | ---: | ---: | ---: | ---: | --- |",
    ]
    for c in checks:
        why = c.get("error") or "; ".join(c.get("failures", []))
        verdict = "equivalent" if c.get("equivalent") else "NOT: " + why
        lines.append(
            f"| {c['what']} | {c.get('pair', '')} | {c.get('max_abs', float('nan')):.3g} | "
            f"{c.get('max_rel_L', float('nan')):.3g} | {c.get('ulp_max', float('nan')):.3g} | "
            f"{_num(c.get('spread'))} | {_num(c.get('limit'))} | {verdict} |"
        )
    return lines


def headline_lines(path):
    if not path.exists():
        cmd = "python -m harness headline --model dynamic"
        return [f"Not measured with these results (no `{display(path)}`): `{cmd}`."]
    h = json.loads(path.read_text())
    s, t = h.get("summary", {}), h["targets"]
    env = h.get("env", {})
    gpus = ", ".join(g.get("name", "?") for g in env.get("gpus") or []) or "no GPU"
    where = f"{gpus} (driver {env.get('driver') or '?'}), {env.get('cpu_model') or '?'} × {env.get('cpu_cores') or '?'}"
    out = [
        f"Measured by `python -m harness headline --model dynamic` on {where} "
        f"(revision {env.get('git_revision', '?')}), {h['strands']:,} strands × {h['points']} points, fp32.",
        "",
        "| target | goal | measured | where | met |",
        "| --- | --- | --- | --- | --- |",
    ]

    def target(key, what, goal, measured, met="met"):
        """The row of summary[key] where the headline measured it; measured(m) its measured cell."""
        m = s.get(key)
        if m is not None:
            out.append(f"| {what} | {goal} | {measured(m)} | {m['row']} | {'yes' if m.get(met) else '**no**'} |")

    rate = "≥ {:.2g} point-substeps/s".format
    target(
        "memory",
        "memory-bound case (gravity + stretch, S = I = 1)",
        f"≥ {100 * t['memory_fraction']:.0f}% of copy",
        lambda m: f"{100 * m['fraction']:.1f}%",
    )
    target("default", "default scene", rate(t["point_substeps_per_s"]), lambda m: f"{m['point_substeps_per_s']:.3g}")
    if t.get("stretch_point_substeps_per_s"):
        goal = rate(t["stretch_point_substeps_per_s"])
        target(
            "default", "default scene, stretch goal", goal, lambda m: f"{m['point_substeps_per_s']:.3g}", "stretch_met"
        )
    target(
        "ftl",
        "default scene, solver ftl",
        rate(t["ftl_point_substeps_per_s"]),
        lambda m: f"{m['point_substeps_per_s']:.3g}",
    )
    target(
        "realtime",
        "10,000 strands, default scene",
        f"≤ {t['realtime_ms']} ms GPU time a frame",
        lambda m: (
            f"{m['kernel_ms']:.4f} ms (frame loop {m['frame_loop_ms']:.4f} ms, "
            f"as a CUDA graph {m['frame_loop_graph_ms']:.4f} ms)"
        ),
    )
    target(
        "cpu",
        "CPU fast variant, memory-bound case",
        f"≥ {100 * t['cpu_fraction']:.0f}% of CPU copy",
        lambda m: (
            f"{100 * m['fraction']:.1f}%"
            + (f" ({rounds_note(m['rounds'], m.get('fraction_of_first_copy'))})" if m.get("rounds") else "")
        ),
    )
    for case, d in s.get("speedups", {}).items():
        hl = d.get("headline")
        if hl:
            out.append(f"\nSpeedup ({case} case): {hl['gpu']} over {hl['cpu']}: {hl['speedup']:.1f}×.")
    m = h.get("ncu")
    if m and "skipped" not in m:
        out.append(
            f"\nNsight Compute on the {m['variant']} kernel of the default scene ({m['strands']:,} strands"
            + (f"; revision {m['revision']}" if m.get("revision") else "")
            + "): "
            f"SM throughput {m.get('sm__throughput.avg.pct_of_peak_sustained_elapsed')}% of peak, DRAM "
            f"{m.get('dram__throughput.avg.pct_of_peak_sustained_elapsed')}%, "
            f"{m.get('launch__registers_per_thread'):.0f} registers, "
            f"{m.get('thread_instructions_per_point_substep', 0):.0f} thread instructions per point-substep"
            + (
                f", issue slots busy {m['smsp__issue_active.avg.pct_of_peak_sustained_active']}% of the time, "
                f"{m['smsp__thread_inst_executed_per_inst_executed.ratio']} of 32 lanes active an instruction"
                if "smsp__issue_active.avg.pct_of_peak_sustained_active" in m
                else ""
            )
            + "."
        )
    return out


def _study(root, name, module, what, command, out_dir, **options):
    """A study's section from its own renderer (section(results_dir, report_dir, **options)),
    or a line saying how to make it."""
    d = Path(root) / name
    if not d.exists():
        return [f"## {what}", "", f"Not measured with these results (no `{display(d)}`): `{command}`.", ""]
    return module.section(d, out_dir, **options) + [""]


def build(root, report_dir=None):
    root = Path(root)
    out_dir = Path(report_dir) if report_dir else REPORT
    out_dir.mkdir(parents=True, exist_ok=True)
    sweep_dir = root / "dynamic"
    lines = ["# hairbench: the dynamic model", ""]
    lines += [
        "The time-stepped model of docs/model.md §3: XPBD and follow-the-leader strands under "
        "gravity and a gusting wind on a nodding head (configs/scenes/dynamic.toml). Generated "
        f"by `python -m harness bench` from `{display(root)}`; rendering only.",
        "",
    ]
    lines += host_report.section(root)
    lines += validation_summary(sweep_dir)
    lines += budget_report.section(root)
    lines += ["## Headline targets", ""] + headline_lines(root / "headline" / "headline_dynamic.json") + [""]
    lines += ["## Throughput over strand counts", ""]
    if (sweep_dir / "runs.csv").exists():
        rows, env = sim_rows(sweep_dir)
        rows, world = split_world(rows)
        pics = [throughput_plot(rows, s, p, out_dir) for s in ("xpbd", "ftl") for p in ("fp32", "fp64")]
        lines += [
            "Time per frame of the default scene (S = 8, I = 2, every feature), kernel or loop time "
            "only (docs/interfaces.md), the median of the sweep's repeats; point-substeps per "
            'second = N·P·S over it. The best of each family per strand count ("(noise)": its time\'s spread '
            "or the host's load marks it as noise, core/timing.py):",
            "",
        ]
        lines += best_table(rows) + [""]
        if not world.empty:
            lines += [
                f"The same on a body with the hair–hair grid (configs/scenes/{BODY_SCENE}.toml: four "
                "capsules and a face-mesh SDF with friction, the 32³ grid with friction and volume), in the variants "
                "that run them (the sweep's groups with its `scene`):",
                "",
                *best_table(world),
                "",
            ]
        for p in pics:
            if p:
                lines += [f"![{p.stem}]({os.path.relpath(p, out_dir)})", ""]
        sess = (env.get("sessions") or [{}])[-1]
        host = sess.get("host") or sess
        where = {k: host.get(k) for k in ("cpu_model", "cpu_cores", "gpus", "git_revision") if k in host}
        lines += [f"Sweep environment: {json.dumps(where)}", ""]
    else:
        cmd = "python -m harness bench --model dynamic"
        lines += [f"Not measured (no `{display(sweep_dir / 'runs.csv')}`): `{cmd}`.", ""]
    lines += curly_throughput_lines(root / CURLY_SWEEP)
    lines += featurecost_report.section(sorted((root / "featurecost").glob("*.csv"))) + [""]
    lines += reduced_report.section(root / "reduced" / "reduced.csv") + [""]
    lines += _study(
        root,
        "dynamic-accuracy",
        accuracy_dynamic_report,
        "Speed against accuracy",
        "harness accuracy --model dynamic",
        out_dir,
    )
    lines += frame_budget.section(root) if (root / curves_name("dynamic")).exists() else []
    curly = results_name(CURLY_SCENE)
    lines += _study(
        root,
        curly,
        accuracy_dynamic_report,
        f"Speed against accuracy: {CURLY_TITLE}",
        f"harness accuracy --model dynamic --scene {CURLY_SCENE} --quick",
        out_dir,
        scene=CURLY_SCENE,
        title=CURLY_TITLE,
    )
    lines += _study(
        root, WORLD_RESULTS_NAME, accuracy_world_report, accuracy_world_report.TITLE, "harness world", out_dir
    )
    lines += _study(root, "stability", stability_report, "Stability at the extremes", "harness stability", out_dir)
    lines += _study(root, "judge", judge_report, "The judge's power", "harness judge", out_dir)
    lines += peer_report.section(root / "peer", out_dir, missing_ok=True) + [""]
    lines += hair_report.dynamic_lines(root, out_dir)
    gif = out_dir / "dynamic.gif"
    lines += ["## The default scene in motion, plotted", ""]
    if gif.exists():
        lines += [f"![the default dynamic scene, side and front]({os.path.relpath(gif, out_dir)})", ""]
    else:
        lines += ["No animation here: `python -m harness animate`.", ""]
    # how the results were checked and made, after the results themselves
    lines += ["## Validation", ""] + validation_lines(sweep_dir) + [""]
    lines += steps_report.section(root)
    path = out_dir / "dynamic.md"
    return files.write_text(path, "\n".join(lines) + "\n")
