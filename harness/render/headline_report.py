"""The paper model's headline numbers (results/headline/headline.json) as a text table."""


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
    for label, s in (result.get("speedups") or {}).items():
        lines.append(f"speedup of {result['best_gpu']} over {label}: {s:.1f}x")
    return "\n".join(lines)
