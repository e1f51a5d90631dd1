"""The world study's tables (harness/studies/accuracy_world_dynamic.py's world.csv) as Markdown: the
grid's and the colliders' variants, each's cost against its effect and its error against its
converged reference, and each group's verdict (studies/accuracy_world_verdicts_dynamic.py) in words."""

from harness.core.paths import display
from harness.io.tables import cell as _f
from harness.io.tables import read_csv
from harness.studies import accuracy_world_verdicts_dynamic as verdicts
from harness.studies.accuracy import WORLD_CSV_NAME as CSV_NAME

TITLE = "The grid and the body: cost against effect against the converged reference"


def verdict(rows, group):
    """One sentence from the group's verdict (studies/accuracy_world_verdicts_dynamic.py)."""
    v = verdicts.verdict(rows, group)
    pick = v.pick
    if pick is None:
        return f"No {group} variant finished with a finite error: no verdict."
    cheapest = (
        f"the cheapest within {v.factor:g}× of the smallest error against its converged reference is "
        f"{pick['variant']} ({_f(pick, 'ms_frame'):.3g} ms a frame, {_f(pick, 'cost_ratio'):.2f}× the scene "
        f"without it, RMS error {_f(pick, 'rms_err_L'):.2e} L)"
    )
    c = v.change
    if group == "grid":
        if c.pairs == 0:
            return f"For the grid, {cheapest}.{held_clause(v.held)}"
        return (
            f"Rebuilding the grid every substep costs {c.cost:.2f}× the once-a-frame build and moves the error "
            f"against its converged reference by {c.err:.2f}× (medians over {c.pairs} pairs); {cheapest}."
            f"{held_clause(v.held)}"
        )
    text = f"For the body, {cheapest}."
    if c.pairs:
        text = (
            f"On the body, friction costs {c.cost:.2f}× the frictionless colliders and moves the error against the "
            f"converged reference by {c.err:.2f}× (medians over {c.pairs} SDF sizes); {cheapest}."
        )
    return text + sdf_clause(v.sdf) + planes_clause(v.planes) + once_clause(v.once)


def once_clause(once):
    """What meeting the colliders once a substep (--collide-once) did against every iteration."""
    if once is None or once.pairs == 0:
        return ""
    return (
        f" Colliding once a substep (in the last iteration alone) costs {once.cost:.2f}× colliding in every "
        f"iteration and moves the error against the exact order's converged reference by {once.err:.2f}× "
        f"(medians over {once.pairs} SDF sizes)."
    )


def planes_clause(planes):
    """What meeting the colliders as contact planes (--contact-planes M) did against the exact colliders."""
    return "".join(
        f" As contact planes within {m} cm the colliders cost {c.cost:.2f}× the exact ones and move the error "
        f"against the exact order's converged reference by {c.err:.2f}× (medians over {c.pairs} SDF sizes)."
        for m, c in planes
    )


def held_clause(held):
    """What holding each point's sample for the frame (`held`) did against sampling every substep
    (`frame`): its cost and its error, medians over the matched pairs."""
    if held.pairs == 0:
        return ""
    return (
        f" Holding each point's sample for the frame (held) costs {held.cost:.2f}× the once-a-frame build sampled "
        f"every substep and moves the error by {held.err:.2f}× (medians over {held.pairs} pairs)."
    )


def sdf_clause(sdf):
    """What the mesh's SDF size did to the error: the finest against the coarsest, per friction."""
    if sdf is None:
        return ""
    if sdf.unchanged:
        return (
            f" The SDF's size ({sdf.lo}³ to {sdf.hi}³) changed no error: the hair did not reach the mesh in this run."
        )
    return f" The {sdf.hi}³ SDF moves the error by {sdf.ratio:.2f}× over the {sdf.lo}³ (median over {sdf.pairs} pairs)."


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
