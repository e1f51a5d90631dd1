"""The judge's section of report/dynamic.md, from <root>/judge/judge.json and judge.csv (made by
`python -m harness judge`, harness/studies/judge.py). Rendering only."""

import json
import math
from pathlib import Path

from harness.core.paths import display
from harness.io import tables


def _g(x):
    try:
        x = float(x)
    except (TypeError, ValueError):
        return ""
    return f"{x:.3g}" if math.isfinite(x) else ""


def _by_model(s, num, den):
    bm = s.get("by_model")
    if not bm:
        return ""
    return " (" + ", ".join(f"{m} {bm[m][num]} / {bm[m][den]}" for m in ("dynamic", "paper", "lod") if m in bm) + ")"


def section(results_dir, out_dir=None):
    d = Path(results_dir)
    path = d / "judge.json"
    head = ["## The judge's power", ""]
    if not path.exists():
        return head + [f"Not measured with these results (no `{display(path)}`): `python -m harness judge`."]
    s = json.loads(path.read_text())
    lines = head + [
        f"Each frame of a comparison is judged as `harness stepdiff` judges it: a point is over when farther "
        f"than max({s['rule_k']:g}·ε·E·S·I, {s['spread_k']:g} × the scene's spread), the spread being how far "
        "the C reference built with FMA contraction lands from the same input; the paper model's defects and "
        "variants are judged by whole runs as `harness diff` judges them; simulated-point LOD runs (not "
        "resumable) by stepdiff of the same run without LOD, their simulated rows against it bit for bit and "
        "their rendered rows recomputed from them (docs/judge.md).",
        "",
        f"- planted defects caught on the standard scenes: **{s['caught']} / {s['planted']}**"
        + _by_model(s, "caught", "planted"),
        f"- false alarms on the extreme scenes: **{s['false_alarms']} / {s['honest_runs']}** honest runs "
        f"({', '.join(s.get('honest', []))})"
        + _by_model(s, "false_alarms", "honest_runs")
        + (f"; GPU builds not run: {s['gpu_note']}" if s.get("gpu_note") else ""),
        "",
        "| plant | model | defect | caught on |",
        "| ---: | --- | --- | --- |",
    ]
    for n, p in s["plants"].items():
        seen = ", ".join(p["caught_on"]) if p["caught_on"] else f"NOT CAUGHT (needs {p['needs']})"
        lines.append(f"| {n} | {p.get('model', 'dynamic')} | {p['what']} | {seen} |")
    csv = d / "judge.csv"
    if csv.exists():
        rows = tables.read_csv(csv)
        honest = rows[rows["kind"] == "honest"]
        if not honest.empty:
            honest = honest.assign(ratio=honest["max_abs"] / honest["limit"])
            worst = honest.sort_values("ratio", ascending=False).drop_duplicates(["scene", "precision"]).head(12)
            lines += [
                "",
                "Honest runs closest to their limit (the worst frame per scene and precision):",
                "",
                "| scene | precision | run | max abs (cm) | rule (cm) | spread (cm) | limit (cm) | error / limit |",
                "| --- | --- | --- | ---: | ---: | ---: | ---: | ---: |",
            ]
            for _, r in worst.iterrows():
                lines.append(
                    f"| {r['scene']} | {r['precision']} | {r['who']} | {_g(r['max_abs'])} | {_g(r['rule'])} | "
                    f"{_g(r['spread'])} | {_g(r['limit'])} | {_g(r['ratio'])} |"
                )
        planted = rows[rows["kind"] == "planted"]
        if not planted.empty:
            weakest = planted.assign(ratio=planted["max_abs"] / planted["limit"])
            weakest = weakest.sort_values("ratio", ascending=False).drop_duplicates("who").sort_values("ratio")
            lines += [
                "",
                "Each planted defect at its most visible frame (error over the limit; above 1 is caught):",
                "",
                "| plant | scene | precision | max abs (cm) | limit (cm) | error / limit |",
                "| --- | --- | --- | ---: | ---: | ---: |",
            ]
            for _, r in weakest.iterrows():
                lines.append(
                    f"| {r['who']} | {r['scene']} | {r['precision']} | {_g(r['max_abs'])} | {_g(r['limit'])} | "
                    f"{_g(r['ratio'])} |"
                )
    return lines
