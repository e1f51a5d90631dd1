"""The world study's tables (harness/studies/accuracy_world_dynamic.py's world.csv) as Markdown: the
grid's and the colliders' variants, each's cost against its effect and its error against its
converged reference, and a verdict per group computed from those numbers."""

import math
import statistics

from harness.core import tolerances
from harness.core.paths import display
from harness.io.tables import read_csv
from harness.studies.accuracy import WORLD_CSV_NAME as CSV_NAME

TITLE = "The grid and the body: cost against effect against the converged reference"


def _f(r, key):
    try:
        return float(r[key])
    except (TypeError, ValueError, KeyError):
        return math.nan


def applied(rows, group):
    """The group's rows that apply something: grid rows with friction or volume on; every
    collider row but `off`."""
    out = [r for r in rows if r["group"] == group and r["variant"] != "off"]
    if group == "grid":
        out = [r for r in out if "on" in (r["friction"], r["volume"])]
    return out


def cheapest_close(rows):
    """The cheapest row whose RMS error is within WORLD_ACC_ERROR_FACTOR of the smallest (None: no
    finite error)."""
    finite = [r for r in rows if math.isfinite(_f(r, "rms_err_L")) and math.isfinite(_f(r, "ms_frame"))]
    if not finite:
        return None
    best = min(_f(r, "rms_err_L") for r in finite)
    close = [r for r in finite if _f(r, "rms_err_L") <= tolerances.WORLD_ACC_ERROR_FACTOR * best]
    return min(close, key=lambda r: _f(r, "ms_frame"))


def paired_ratio(rows, key, axis, a, b, match):
    """The median over matched pairs (equal in every `match` column) of row[axis] = b's `key` over
    a's; (ratio, pairs) with NaN where none pairs."""
    ratios = []
    for r in rows:
        if r[axis] != a:
            continue
        twin = next((o for o in rows if o[axis] == b and all(o[m] == r[m] for m in match)), None)
        if twin is not None and _f(r, key) > 0 and math.isfinite(_f(twin, key)):
            ratios.append(_f(twin, key) / _f(r, key))
    return (statistics.median(ratios) if ratios else math.nan), len(ratios)


def verdict(rows, group):
    """One sentence from the group's numbers."""
    on = applied(rows, group)
    pick = cheapest_close(on)
    if pick is None:
        return f"No {group} variant finished with a finite error: no verdict."
    factor = tolerances.WORLD_ACC_ERROR_FACTOR
    cheapest = (
        f"the cheapest within {factor:g}× of the smallest error against its converged reference is "
        f"{pick['variant']} ({_f(pick, 'ms_frame'):.3g} ms a frame, {_f(pick, 'cost_ratio'):.2f}× the scene "
        f"without it, RMS error {_f(pick, 'rms_err_L'):.2e} L)"
    )
    if group == "grid":
        cost, n = paired_ratio(on, "ms_frame", "rebuild", "frame", "substep", ("grid", "friction", "volume"))
        err, _ = paired_ratio(on, "rms_err_L", "rebuild", "frame", "substep", ("grid", "friction", "volume"))
        if n == 0:
            return f"For the grid, {cheapest}.{held_clause(on)}"
        return (
            f"Rebuilding the grid every substep costs {cost:.2f}× the once-a-frame build and moves the error "
            f"against its converged reference by {err:.2f}× (medians over {n} pairs); {cheapest}.{held_clause(on)}"
        )
    cost, n = paired_ratio(on, "ms_frame", "friction", "off", "on", ("sdf",))
    err, _ = paired_ratio(on, "rms_err_L", "friction", "off", "on", ("sdf",))
    text = f"For the body, {cheapest}."
    if n:
        text = (
            f"On the body, friction costs {cost:.2f}× the frictionless colliders and moves the error against the "
            f"converged reference by {err:.2f}× (medians over {n} SDF sizes); {cheapest}."
        )
    return text + sdf_clause(on)


def held_clause(rows):
    """What holding each point's sample for the frame (`held`) did against sampling every substep
    (`frame`): its cost and its error, medians over the matched pairs."""
    match = ("grid", "friction", "volume")
    cost, n = paired_ratio(rows, "ms_frame", "rebuild", "frame", "held", match)
    err, _ = paired_ratio(rows, "rms_err_L", "rebuild", "frame", "held", match)
    if n == 0:
        return ""
    return (
        f" Holding each point's sample for the frame (held) costs {cost:.2f}× the once-a-frame build sampled every "
        f"substep and moves the error by {err:.2f}× (medians over {n} pairs)."
    )


def sdf_clause(rows):
    """What the mesh's SDF size did to the error: the finest against the coarsest, per friction."""
    sizes = sorted({int(r["sdf"]) for r in rows if str(r["sdf"]).isdigit()})
    if len(sizes) < 2:
        return ""
    lo, hi = str(sizes[0]), str(sizes[-1])
    ratio, n = paired_ratio(rows, "rms_err_L", "sdf", lo, hi, ("friction",))
    if n == 0:
        return ""
    if ratio == 1.0:
        return f" The SDF's size ({lo}³ to {hi}³) changed no error: the hair did not reach the mesh in this run."
    return f" The {hi}³ SDF moves the error by {ratio:.2f}× over the {lo}³ (median over {n} pairs)."


def _pair(r, key, fmt):
    return f"{format(_f(r, key), fmt)} ({format(_f(r, key + '_ref'), fmt)})"


def table(rows, group):
    """The group's rows as a Markdown table (the reference's value in brackets; the GPU's time where
    measured)."""
    part = [r for r in rows if r["group"] == group]
    if any(r.get("gpu_ms_frame") not in (None, "") for r in part):
        return _with_gpu(_cpu_table(part), part)
    return _cpu_table(part)


def _with_gpu(lines, rows):
    """The table with the GPU's time and its ratio to the off row added."""
    head = f" GPU ms / frame ({rows[0].get('gpu_strands') or '—'} strands) | GPU × off |"
    out = [lines[0] + head, lines[1] + " ---: | ---: |"]
    for line, r in zip(lines[2:], rows):
        gpu = f" {_f(r, 'gpu_ms_frame'):.3g} ({r.get('gpu_variant') or '—'}) | {_f(r, 'gpu_cost_ratio'):.2f} |"
        out.append(line + gpu)
    return out


def _cpu_table(rows):
    lines = [
        "| variant | ms / frame (rounds' range) | × off | RMS err / L | max err / L | hair volume cm³ | envelope cm "
        "| close pairs | penetration cm | stretch max |",
        "| --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: |",
    ]
    for r in rows:
        pen = f"{_f(r, 'penetration_max'):.2g} ({_f(r, 'penetration_ref'):.2g})"
        stretch = f"{_f(r, 'stretch_max'):.3f} ({_f(r, 'stretch_ref'):.3f})"
        lines.append(
            f"| {r['variant']} | {_f(r, 'ms_frame'):.3g} ({_f(r, 'ms_min'):.3g} … {_f(r, 'ms_max'):.3g}) "
            f"| {_f(r, 'cost_ratio'):.2f} | {_f(r, 'rms_err_L'):.2e} "
            f"| {_f(r, 'max_err_L'):.2e} | {_pair(r, 'hair_volume', '.0f')} | {_pair(r, 'envelope', '.2f')} "
            f"| {_pair(r, 'close_pairs', '.0f')} | {pen} | {stretch} |"
        )
    return lines


def section(results_dir, report_dir=None):
    """The report's section from results_dir/world.csv (report_dir: unused, the shared signature)."""
    path = results_dir / CSV_NAME
    lines = [f"## {TITLE}", ""]
    if not path.exists():
        return lines + [f"Not measured (no `{display(path)}`): `python -m harness bench --model dynamic`.", ""]
    rows = read_csv(path, "the world study", dtype=str, keep_default_na=False).to_dict("records")
    if not rows:
        return lines + [f"`{display(path)}` holds no rows: measure again.", ""]
    first = rows[0]
    lines += [
        f"Each variant at {first['strands']} strands, {first['frames']} frames, S = {first['substeps']}, "
        f"I = {first['iterations']}, fp32 on the CPU oracle, against the same features at S = {first['ref_substeps']} "
        f"in fp64 (in brackets: the reference's value); cost: the time per frame at {first['time_strands']} "
        "strands on one thread, the median of rounds that time every variant in turn, and over the same scene "
        "without the feature (× off). Hair volume, envelope and close pairs of "
        "the last frame (docs/model.md §3.16), penetration and stretch of the worst (§3.8). From "
        f"`{display(path)}`.",
        "",
        "### The hair–hair grid (the default scene)",
        "",
        *table(rows, "grid"),
        "",
        verdict(rows, "grid"),
        "",
        "### The body's colliders (configs/scenes/body.toml without its grid)",
        "",
        *table(rows, "body"),
        "",
        verdict(rows, "body"),
        "",
    ]
    return lines
