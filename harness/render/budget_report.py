"""The report's section on a time budget (`harness bench --budget`): what the run left out,
from RUN/budget.json; nothing when the run had no budget."""

import json
from pathlib import Path

from harness.core.paths import display


def section(root):
    path = Path(root) / "budget.json"
    if not path.is_file():
        return []
    b = json.loads(path.read_text())
    lines = [
        "## Time budget",
        "",
        f"This run had a budget of {b['budget_s']:.0f} s (`harness bench --budget`) and used "
        f"{b['used_s']:.0f} s (`{display(path)}`).",
        "",
    ]
    if not b["left_out"]:
        return lines + ["Nothing was left out.", ""]
    lines += ["Left out to fit it:", ""]
    lines += [f"- {x['step']}: {x['what']} ({x['reason']})" for x in b["left_out"]]
    return lines + [""]
