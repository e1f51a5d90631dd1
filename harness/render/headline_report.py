"""The headline numbers as text tables: the paper model's (results/headline/headline.json) and
the dynamic model's (headline_dynamic.json)."""


def table(result):
    """The rows of headline.json with their bandwidth fractions, then the speedups."""
    pct = lambda v: "" if v is None else f"{100 * v:5.1f}%"  # noqa: E731
    lines = [
        f"{result['strands']:,} strands x {result['points']} points, paper scene; median ms",
        f"{'case':34} {'init ms':>9} {'init %BW':>8} {'wind+coll ms':>13} {'w+c %BW':>8}",
    ]
    for r in result["rows"]:
        lines.append(
            f"{r['label']:34} {r['init_ms']:9.3f} {pct(r['init_fraction']):>8} "
            f"{r['wind_collide_ms']:13.3f} {pct(r['wind_collide_fraction']):>8}"
        )
    for r in (r for r in result["rows"] if r.get("rounds")):
        fractions = [x["fraction"] for x in r["rounds"]]
        lines.append(f"{r['label']}, w+c %BW: {rounds_note(fractions, r.get('wind_collide_fraction_of_first_copy'))}")
    for label, s in (result.get("speedups") or {}).items():
        lines.append(f"speedup of {result['best_gpu']} over {label}: {s:.1f}x")
    return "\n".join(lines)


def rounds_note(fractions, first=None):
    """One line on a row measured in rounds (roofline.in_rounds): the median round of how many,
    their spread, and the fraction against the run's first copy measurement."""
    lo, hi = min(fractions), max(fractions)
    note = f"the median of {len(fractions)} rounds, each against its own copy ({100 * lo:.1f}–{100 * hi:.1f}%)"
    return note + (f"; against the run's first copy {100 * first:.1f}%" if first is not None else "")


def dynamic_table(result):
    """headline_dynamic.json as a text table, the targets beside the numbers, met or not."""
    pct = lambda v: "" if v is None else f"{100 * v:5.1f}%"  # noqa: E731
    yes = lambda m: "met" if m else "NOT met"  # noqa: E731
    lines = [f"dynamic model headline, {result['points']} points a strand; medians"]
    for case in ("memory", "default", "ftl", "realtime", "cpu"):
        rows = result.get(case) or []
        if not rows:
            continue
        lines.append(f"-- {case}")
        lines.append(f"{'case':34} {'N':>9} {'S':>3} {'I':>3} {'ms/frame':>10} {'pt-substeps/s':>14} {'%BW':>7}")
        for r in rows:
            lines.append(
                f"{r['label'] + (' ' + r['case'] if r.get('case') else ''):34} {r['strands']:9d} {r['substeps']:3d} "
                f"{r['iterations']:3d} {r['median_ms']:10.4f} {r['point_substeps_per_s']:14.3e} {pct(r['fraction']):>7}"
            )
    s = result.get("summary", {})
    t = result["targets"]

    def target(name, what, measured, m):
        lines.append(f"target {name} ({what}): {measured} {m['row']}: {yes(m['met'])}")

    if "memory" in s:
        m = s["memory"]
        target(1, f"memory-bound >= {100 * t['memory_fraction']:.0f}% of copy", pct(m["fraction"]), m)
    if "default" in s:
        d = s["default"]
        goal = f"{t['point_substeps_per_s']:.2g} pt-substeps/s"
        target(2, f"default scene >= {goal}", f"{d['point_substeps_per_s']:.3e}", d)
        stretch = t.get("stretch_point_substeps_per_s")
        if stretch:
            lines.append(f"  stretch goal {stretch:.2g} pt-substeps/s: {yes(d.get('stretch_met'))}")
    if "ftl" in s:
        f = s["ftl"]
        goal = f"{t['ftl_point_substeps_per_s']:.2g} pt-substeps/s"
        target("ftl", f"default scene, ftl >= {goal}", f"{f['point_substeps_per_s']:.3e}", f)
    if "realtime" in s:
        r = s["realtime"]
        target(3, f"10k strands <= {t['realtime_ms']} ms/frame GPU", f"{r['kernel_ms']:.4f} ms", r)
        lines.append(f"  frame loop {r['frame_loop_ms']:.4f} ms a frame, as a graph {r['frame_loop_graph_ms']:.4f} ms")
    if "cpu" in s:
        c = s["cpu"]
        target(4, f"CPU fast variant >= {100 * t['cpu_fraction']:.0f}% of CPU copy", pct(c["fraction"]), c)
        if c.get("rounds"):
            lines.append(f"  {rounds_note(c['rounds'], c.get('fraction_of_first_copy'))}")
    for case, d in s.get("speedups", {}).items():
        h = d.get("headline")
        if h:
            lines.append(f"speedup ({case}): {h['gpu']} over {h['cpu']}: {h['speedup']:.1f}x")
    if "ncu" in result:
        m = result["ncu"]
        if "skipped" in m:
            lines.append(f"ncu: {m['skipped']}")
        else:
            pct_of = lambda unit, k: m.get(f"{unit}.avg.pct_of_peak_sustained_{k}")  # noqa: E731
            lines.append(
                f"ncu ({m['variant']}, {m['strands']} strands): SM {pct_of('sm__throughput', 'elapsed')}% "
                f"DRAM {pct_of('dram__throughput', 'elapsed')}% warps active {pct_of('sm__warps_active', 'active')}% "
                f"regs {m.get('launch__registers_per_thread')}; "
                f"{m.get('thread_instructions_per_point_substep', 0):.0f} thread instructions per point-substep; "
                f"issue slots busy {pct_of('smsp__issue_active', 'active')}%, "
                f"{m.get('smsp__thread_inst_executed_per_inst_executed.ratio')} lanes active an instruction"
            )
    return "\n".join(lines)
