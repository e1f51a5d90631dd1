"""What the reduced-model study's rows (reduced_dynamic.py's CSV and references.csv) earn, as data
(render/reduced_dynamic_report.py words it), with the dynamic accuracy study's budgets
(tolerances.DYN_ACC_USES: RMS error and stretch per use; DYN_ACC_USES_CHAOS: the statistics'
allowance beyond the reference ensemble's spread): per use and strand count the fewest guides, and
the fewest simulated points, whose every measure is within it; whether LRA lowers the error
without raising the stretch."""

import math
from dataclasses import dataclass

from harness.core import tolerances
from harness.io.tables import cell

DISTANCES = ("tip_L", "curvature_rel", "envelope_rel")


def spreads(refs):
    """{(scene, strands): {distance: spread}} of references.csv."""
    return {(r["scene"], str(r["strands"])): {m: cell(r, f"{m}_spread") for m in DISTANCES} for r in refs}


def passes(r, use, spreads):
    """Whether a row meets a use: RMS error (up to the horizon) and stretch (the followers', a LOD
    row's rendered points, else every point's, against ℓ_k) within the use's budgets, and each
    statistic within the ensemble's spread plus the use's allowance."""
    rms_budget, stretch_budget, _ = tolerances.DYN_ACC_USES[use]
    if not cell(r, "rms_err_L") <= rms_budget or int(cell(r, "blown_up") or 0) > 0:
        return False
    stretch = cell(r, "stretch_followers") if math.isfinite(cell(r, "stretch_followers")) else cell(r, "stretch_max_k")
    if not stretch <= stretch_budget:
        return False
    scene = {"guides": "scene", "lod": "lod", "lra": "nod"}.get(r["study"], "scene")
    sp = spreads.get((scene, str(r["strands"])), {})
    allow = tolerances.DYN_ACC_USES_CHAOS[use]
    return all(not math.isfinite(cell(r, m)) or cell(r, m) <= sp.get(m, 0.0) + allow[m] for m in DISTANCES)


@dataclass(frozen=True)
class GuidePick:
    """At `strands` strands the row with the fewest guides that passes (None: none does), and the
    scene's pointwise horizon (s)."""

    strands: int
    row: dict | None
    horizon: float


@dataclass(frozen=True)
class UsePick:
    """A use's budgets (tolerances.DYN_ACC_USES), its guide pick at each strand count, the LOD row
    with the fewest simulated points that passes (None: none does) and whether any LOD row ran."""

    use: str
    budget: tuple
    guides: list
    lod: dict | None
    lod_measured: bool


def recommendations(rows, refs=()):
    """Per use: at each strand count the fewest guides (xpbd, the CPU's rows) and at the LOD's
    strand count the fewest simulated points that pass it."""
    sp = spreads(refs)
    horizon = {(r["scene"], str(r["strands"])): cell(r, "horizon_s") for r in refs}
    cpu = [r for r in rows if r["backend"] == "cpu"]
    out = []
    for use in tolerances.DYN_ACC_USES:
        guides = []
        for n in sorted({int(r["strands"]) for r in cpu if r["study"] == "guides"}):
            ok = [r for r in cpu if r["study"] == "guides" and r["solver"] == "xpbd" and int(r["strands"]) == n
                  and passes(r, use, sp)]  # fmt: skip
            pick = min(ok, key=lambda r: (cell(r, "guides"), cell(r, "rms_err_L"))) if ok else None
            guides.append(GuidePick(n, pick, horizon.get(("scene", str(n)), math.nan)))
        lod = [r for r in cpu if r["study"] == "lod" and r["solver"] == "xpbd" and passes(r, use, sp)]
        fewest = min(lod, key=lambda r: (int(r["points"]), cell(r, "rms_err_L"))) if lod else None
        measured = any(r["study"] == "lod" for r in cpu)
        out.append(UsePick(use, tolerances.DYN_ACC_USES[use], guides, fewest, measured))
    return out


@dataclass(frozen=True)
class LraVerdict:
    """LRA on against off (the same solver and I, the fast nod): whether it lowered the RMS error
    and left the largest stretch no higher."""

    solver: str
    iterations: str
    on: dict
    off: dict
    lower: bool
    not_raised: bool

    @property
    def worth_it(self):
        return self.lower and self.not_raised


def lra_verdicts(rows):
    """One verdict for each (solver, I) the LRA study ran both ways."""
    by = {(r["solver"], str(r["iterations"]), str(r["lra"])): r for r in rows if r["study"] == "lra"}
    out = []
    for (solver, i, lra), r in sorted(by.items()):
        off = by.get((solver, i, "0"))
        if lra != "1" or off is None:
            continue
        lower = cell(r, "rms_err_L") < cell(off, "rms_err_L")
        not_raised = cell(r, "stretch_max_k") <= cell(off, "stretch_max_k")
        out.append(LraVerdict(solver, i, r, off, lower, not_raised))
    return out
