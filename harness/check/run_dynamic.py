"""`harness run` on a dynamic scene: run the binary, then print the per-frame observables
(docs/model.md §3.8) read back from the state file (harness/io/trajectory.py), every K-th
frame for long runs (the first and the last always), and the run's verdict: blown up or
not, and whether the file's dynamic invariants hold (harness/check/invariants_dynamic.py)."""

import json
import shutil
import tempfile
from pathlib import Path

from harness.check import invariants_dynamic
from harness.core import runner
from harness.io.trajectory import open_trajectory

LINES = 30


def table(obs, every=None):
    n = len(obs)
    k = every or max(1, -(-n // LINES))
    lines = [f"{'step':>6} {'time s':>9} {'stretch_max':>12} {'penetration':>12} {'kinetic':>12} {'blown up':>9}"]
    for i, row in enumerate(obs.itertuples(index=False)):
        if i % k and i != n - 1:
            continue
        lines.append(
            f"{row.step:>6} {row.time:9.4f} {row.stretch_max:12.4g} {row.penetration_max:12.4g} "
            f"{row.kinetic_energy:12.4g} {row.blown_up_strands:>9}"
        )
    if k > 1:
        lines.append(f"(one frame in {k} and the last; --every 1 prints all {n})")
    return lines


def run(binary, flags, output=None, timeout=None, as_json=False, every=None, out=print, named=lambda x: x):
    """Run the binary, then print its observables and verdict; `named` maps the record's names
    (a USD groom's temporary HAIR file back to the user's file)."""
    tmp = None
    if not output:
        tmp = Path(tempfile.mkdtemp(prefix="hb-run-"))
        flags = [*flags, "--output", str(tmp / "run.h5")]
        path = tmp / "run.h5"
    else:
        path = Path(output)
    try:
        record = named(runner.run_binary(binary, flags, timeout=timeout))
        if tmp:  # removed below: no path to claim
            record["output"] = None
        with open_trajectory(path) as t:
            obs = t.observables
            rep = invariants_dynamic.check(t)
            if as_json:
                record["observables"] = obs.to_dict(orient="list")
                record["invariants"] = rep.as_dict()
                out(json.dumps(record, indent=1))
            else:
                lines = [runner.summary(record), *table(obs, every)]
                blown = int(obs["blown_up_strands"].max()) if len(obs) else 0
                lines.append(
                    f"blown up: {'YES, up to ' + str(blown) + ' strand(s)' if blown else 'no'}; "
                    f"invariants: {'all hold' if rep.ok else str(len(rep.all_violations())) + ' violated'}"
                )
                lines += [f"  {v.message}" for v in rep.all_violations()[:5]]
                out("\n".join(lines))
    finally:
        if tmp:
            shutil.rmtree(tmp, ignore_errors=True)
    return 0
