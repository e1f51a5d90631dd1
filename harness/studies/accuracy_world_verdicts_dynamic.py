"""What the world study's rows (accuracy_world_dynamic.py's world.csv) earn, as data
(render/accuracy_world_dynamic_report.py words it): per group the cheapest variant within
tolerances.WORLD_ACC_ERROR_FACTOR of the smallest error against its converged reference, and
the medians over matched pairs of what a setting costs and moves (the grid rebuilt every
substep, each point's sample held for the frame, friction on the body, the SDF's size, the body's
colliders as contact planes, the collision step once a substep)."""

import math
import statistics
from dataclasses import dataclass

from harness.core import tolerances
from harness.io.tables import cell


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
    finite = [r for r in rows if math.isfinite(cell(r, "rms_err_L")) and math.isfinite(cell(r, "ms_frame"))]
    if not finite:
        return None
    best = min(cell(r, "rms_err_L") for r in finite)
    close = [r for r in finite if cell(r, "rms_err_L") <= tolerances.WORLD_ACC_ERROR_FACTOR * best]
    return min(close, key=lambda r: cell(r, "ms_frame"))


def paired_ratio(rows, key, axis, a, b, match):
    """The median over matched pairs (equal in every `match` column) of row[axis] = b's `key` over
    a's; (ratio, pairs) with NaN where none pairs."""
    ratios = []
    for r in rows:
        if r.get(axis) != a:
            continue
        twin = next((o for o in rows if o.get(axis) == b and all(o.get(m, "") == r.get(m, "") for m in match)), None)
        if twin is not None and cell(r, key) > 0 and math.isfinite(cell(twin, key)):
            ratios.append(cell(twin, key) / cell(r, key))
    return (statistics.median(ratios) if ratios else math.nan), len(ratios)


@dataclass(frozen=True)
class Change:
    """What going from one setting to another did: time and error ratios, medians over `pairs`."""

    cost: float
    err: float
    pairs: int


def change(rows, axis, a, b, match):
    cost, n = paired_ratio(rows, "ms_frame", axis, a, b, match)
    err, _ = paired_ratio(rows, "rms_err_L", axis, a, b, match)
    return Change(cost, err, n)


@dataclass(frozen=True)
class SdfChange:
    """The finest SDF against the coarsest: the error ratio (median over `pairs`); `unchanged`
    where every pair's error was the same (the hair did not reach the mesh)."""

    lo: str
    hi: str
    ratio: float
    pairs: int

    @property
    def unchanged(self):
        return self.ratio == 1.0


def sdf_change(rows):
    """The finest mesh SDF's error over the coarsest's, per friction (None: fewer than two sizes or
    no pair)."""
    sizes = sorted({int(r["sdf"]) for r in rows if str(r["sdf"]).isdigit()})
    if len(sizes) < 2:
        return None
    lo, hi = str(sizes[0]), str(sizes[-1])
    ratio, n = paired_ratio(rows, "rms_err_L", "sdf", lo, hi, ("friction", "planes", "once"))
    return SdfChange(lo, hi, ratio, n) if n else None


GRID_MATCH = ("grid", "friction", "volume")


@dataclass(frozen=True)
class Verdict:
    """A group's verdict: its pick (None: no finite error), the setting each group varies
    (the grid's rebuild, the body's friction), holding the sample (grid), the SDF's size and the
    contact planes at each margin against the exact colliders ((margin, Change), body) and the collision
    step once a substep against every iteration (body)."""

    group: str
    pick: dict | None
    factor: float
    change: Change | None = None
    held: Change | None = None
    sdf: SdfChange | None = None
    planes: tuple = ()
    once: Change | None = None


def verdict(rows, group):
    """The group's verdict from its rows."""
    on = applied(rows, group)
    pick = cheapest_close(on)
    if pick is None:
        return Verdict(group, None, tolerances.WORLD_ACC_ERROR_FACTOR)
    if group == "grid":
        return Verdict(
            group,
            pick,
            tolerances.WORLD_ACC_ERROR_FACTOR,
            change=change(on, "rebuild", "frame", "substep", GRID_MATCH),
            held=change(on, "rebuild", "frame", "held", GRID_MATCH),
        )
    return Verdict(
        group,
        pick,
        tolerances.WORLD_ACC_ERROR_FACTOR,
        change=change(on, "friction", "off", "on", ("sdf", "planes", "once")),
        sdf=sdf_change(on),
        planes=planes_changes(on),
        once=change(on, "once", "off", "on", ("sdf", "friction", "planes")),
    )


def planes_changes(rows):
    """(margin, Change) for each contact planes margin among the rows: its rows against the exact
    colliders' of the same SDF size and friction (cost, and error against the exact order's reference)."""
    margins = sorted({str(r.get("planes", "")) for r in rows} - {"", "off"}, key=float)
    out = [(m, change(rows, "planes", "off", m, ("sdf", "friction", "once"))) for m in margins]
    return tuple((m, c) for m, c in out if c.pairs)
