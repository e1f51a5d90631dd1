"""What the reduced-model study's rows (reduced_dynamic.py's CSV and references.csv) earn, as data
(render/reduced_dynamic_report.py words it), with the dynamic accuracy study's budgets
(tolerances.DYN_ACC_USES: RMS error and stretch per use; DYN_ACC_USES_CHAOS: the statistics'
allowance beyond the reference ensemble's spread): per use and strand count the fewest guides, and
the fewest simulated points, whose every measure is within it, where the same step with every strand
and point simulated is within it too (a reduction is not recommended for a use its own full model
fails: a guided row that passes where the full one fails passes by the statistics' noise); whether
LRA lowers the error without raising the stretch."""

import math
from dataclasses import dataclass

from harness.core import tolerances
from harness.io.tables import cell

DISTANCES = ("tip_L", "curvature_rel", "envelope_rel")


def _ref_key(scene, strands, substeps=None):
    s = cell({"s": substeps}, "s")
    return (scene, str(strands)) + ((int(s),) if math.isfinite(s) else ())


def spreads(refs):
    """{(scene, strands, S): {distance: spread}} of references.csv: a study run in shares may hold two
    references of one scene and strand count (each share's ladder ranks its own rows), so a row is
    judged against the spread of the reference it was compared with (its ref_substeps)."""
    return {_ref_key(r["scene"], r["strands"], r["substeps"]): {m: cell(r, f"{m}_spread") for m in DISTANCES}
            for r in refs}  # fmt: skip


def failures(r, use, spreads):
    """The measures by which a row misses a use, in this order: blown_up, rms_err_L (up to the
    horizon; not where the horizon is no frame), stretch (stretch_of) past the use's budgets, and
    each statistic past the ensemble's spread plus the use's allowance."""
    rms_budget, stretch_budget, _ = tolerances.DYN_ACC_USES[use]
    out = []
    if int(cell(r, "blown_up") or 0) > 0:
        out.append("blown_up")
    if cell(r, "horizon_s") != 0 and not cell(r, "rms_err_L") <= rms_budget:  # 0: no frame judged pointwise
        out.append("rms_err_L")
    stretch = stretch_of(r)
    if not stretch <= stretch_budget:
        out.append("stretch")
    scene = {"guides": "scene", "lod": "lod", "lra": "nod"}.get(r["study"], "scene")
    sp = spreads.get(_ref_key(scene, r["strands"], r.get("ref_substeps")))
    if sp is None:  # a row without its reference's S (older files): the one reference of its scene
        same = [v for k, v in spreads.items() if k[:2] == (scene, str(r["strands"]))]
        sp = same[0] if len(same) == 1 else {}
    allow = tolerances.DYN_ACC_USES_CHAOS[use]
    out += [m for m in DISTANCES if math.isfinite(cell(r, m)) and not cell(r, m) <= sp.get(m, 0.0) + allow[m]]
    return out


def stretch_of(r):
    """A row's largest stretch against ℓ_k: every strand's (a guided row's guides and followers alike;
    a LOD row's rendered points), and the followers' where only they were measured."""
    vals = [cell(r, c) for c in ("stretch_max_k", "stretch_followers")]
    vals = [v for v in vals if math.isfinite(v)]
    return max(vals) if vals else math.nan


def passes(r, use, spreads):
    """Whether a row meets a use: no failures()."""
    return not failures(r, use, spreads)


@dataclass(frozen=True)
class GuidePick:
    """At `strands` strands the row with the fewest guides that passes (None: none does, or the full
    row fails), the scene's pointwise horizon (s), and the row with every strand simulated with the
    measures by which it misses the use (empty: it meets it; `full` None: not measured)."""

    strands: int
    row: dict | None
    horizon: float
    full: dict | None = None
    full_fails: tuple = ()


@dataclass(frozen=True)
class UsePick:
    """A use's budgets (tolerances.DYN_ACC_USES), its guide pick at each strand count, the LOD row
    with the fewest simulated points that passes (None: none does, or the row simulating every point
    fails), whether any LOD row ran, and the every-point row with the measures by which it misses the use."""

    use: str
    budget: tuple
    guides: list
    lod: dict | None
    lod_measured: bool
    lod_full: dict | None = None
    lod_full_fails: tuple = ()


def recommendations(rows, refs=()):
    """Per use: at each strand count the fewest guides (xpbd, the CPU's rows) and at the LOD's
    strand count the fewest simulated points that pass it."""
    sp = spreads(refs)
    horizon = {(r["scene"], str(r["strands"])): cell(r, "horizon_s") for r in refs}  # rows without horizon_s
    cpu = [r for r in rows if r["backend"] == "cpu"]
    out = []
    for use in tolerances.DYN_ACC_USES:
        guides = []
        for n in sorted({int(r["strands"]) for r in cpu if r["study"] == "guides"}):
            rows_n = [r for r in cpu if r["study"] == "guides" and r["solver"] == "xpbd" and int(r["strands"]) == n]
            full = next((r for r in rows_n if cell(r, "guides") >= 1.0), None)
            full_fails = tuple(failures(full, use, sp)) if full is not None else ()
            ok = [r for r in rows_n if passes(r, use, sp)] if not full_fails else []
            pick = min(ok, key=lambda r: (cell(r, "guides"), cell(r, "rms_err_L"))) if ok else None
            h = cell(pick or full or {}, "horizon_s")
            h = h if math.isfinite(h) else horizon.get(("scene", str(n)), math.nan)
            guides.append(GuidePick(n, pick, h, full, full_fails))
        lod_rows = [r for r in cpu if r["study"] == "lod" and r["solver"] == "xpbd"]
        every = [r for r in lod_rows if int(r["points"]) == int(r.get("render_points") or r["points"])]
        every_fails = tuple(failures(every[0], use, sp)) if every else ()
        lod = [r for r in lod_rows if passes(r, use, sp)] if not every_fails else []
        fewest = min(lod, key=lambda r: (int(r["points"]), cell(r, "rms_err_L"))) if lod else None
        measured = any(r["study"] == "lod" for r in cpu)
        out.append(UsePick(use, tolerances.DYN_ACC_USES[use], guides, fewest, measured, every[0] if every else None,
                           every_fails))  # fmt: skip
    return out


@dataclass(frozen=True)
class LraVerdict:
    """LRA on against off (the same solver and I, the fast nod): whether it lowered the error
    (`measure`: the RMS error up to the pointwise horizon, or the tip distribution's distance from
    the reference ensemble where no frame is judged pointwise) and left the largest stretch no higher."""

    solver: str
    iterations: str
    on: dict
    off: dict
    lower: bool
    not_raised: bool
    measure: str = "rms_err_L"

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
        measure = "rms_err_L" if cell(r, "horizon_s") != 0 else "tip_L"
        lower = cell(r, measure) < cell(off, measure)
        not_raised = cell(r, "stretch_max_k") <= cell(off, "stretch_max_k")
        out.append(LraVerdict(solver, i, r, off, lower, not_raised, measure))
    return out
