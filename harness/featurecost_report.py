"""The feature-cost table (harness/featurecost.py's rows) as Markdown."""


def markdown(rows):
    full = next((r for r in rows if r["row"] == "full"), None)
    first = rows[0]
    where = f"{first['backend']}/{first['variant']}"
    if first.get("threads"):
        where += f", {first['threads']} threads"
    if first.get("block_size"):
        where += f", block {first['block_size']}"
    lines = [
        f"{first['strands']:,} strands × {first['points']} points, {first['precision']}, {first['solver']} "
        f"S = {first['substeps']}, I = {first['iterations']}; {where}; {first['device']}",
        "",
        "| case | features compiled in | ms / frame (median) | min … max | point-substeps/s | vs full |",
        "| --- | --- | ---: | ---: | ---: | ---: |",
    ]
    for r in rows:
        rel = f"{float(r['median_ms']) / float(full['median_ms']):.2f}" if full else "—"
        lines.append(
            f"| {r['row']} | {r['features']} | {float(r['median_ms']):.3f} | {float(r['min_ms']):.3f} … "
            f"{float(r['max_ms']):.3f} | {float(r['point_substeps_per_s']):.3g} | {rel} |"
        )
    return "\n".join(lines) + "\n"
