"""`harness compare A B`: is B faster than A, and by more than the noise? Two runs' timed figures
(harness/io/figures.py) matched case by case, each pair's ratio B/A, and a verdict by the
project's one noise rule (harness/core/timing.py, docs/decisions/honest-timings.md): the two
figures are *within noise* when they tie — their bands median·(1 ± max(TIMING_MAX_RSD,
TIMING_TIE_K·rsd)) overlap — else B is *slower* or *faster*. A slower figure whose ratio is
above `fail_above` fails the comparison (the command's exit 1, for CI); one within noise never
does, whatever its ratio, and neither does one that the stopping rule marked as noise in
either run (its `noisy` column: a spread above the rule's, a loaded host): noise never decides.
Such a figure keeps its verdict and its mark, and the summary says to measure it again."""

import math
from dataclasses import dataclass, field
from pathlib import Path

import pandas as pd

from harness import HarnessError
from harness.core import timing, tolerances
from harness.io import figures

VERDICTS = ("slower", "faster", "within noise")


@dataclass
class Comparison:
    """The matched figures (one row each: both medians and noises, ratio, the ratio's
    within-noise interval, verdict, fails) and what only one run had."""

    a: dict
    b: dict
    fail_above: float
    table: pd.DataFrame
    only_a: list = field(default_factory=list)
    only_b: list = field(default_factory=list)

    def counts(self):
        return {v: int((self.table["verdict"] == v).sum()) for v in VERDICTS}

    def noisy_slower(self):
        """Slower beyond the fail ratio, but marked as noise: not failing, to be measured again."""
        t = self.table
        return int(((t["verdict"] == "slower") & (t["ratio"] > self.fail_above) & (t["noisy"] != "")).sum())

    @property
    def failed(self):
        return bool(self.table["fails"].any())

    def record(self):
        """The comparison as JSON-able data (compare.json)."""
        rows = self.table.astype(object).where(self.table.notna(), None).to_dict("records")
        return {
            "a": self.a,
            "b": self.b,
            "rule": {
                "within_noise": "the two figures' bands median·(1 ± max(TIMING_MAX_RSD, TIMING_TIE_K·rsd)) overlap",
                "TIMING_MAX_RSD": tolerances.TIMING_MAX_RSD,
                "TIMING_TIE_K": tolerances.TIMING_TIE_K,
                "fail_above": self.fail_above,
            },
            "counts": self.counts(),
            "noisy_slower": self.noisy_slower(),
            "failed": self.failed,
            "only_in_a": self.only_a,
            "only_in_b": self.only_b,
            "figures": rows,
        }


def _rsd(noise):
    return noise if noise == noise else float("nan")


def ratio_interval(noise_a, noise_b):
    """The ratios B/A within which the two figures tie: (1 − w_a)/(1 + w_b) … (1 + w_a)/(1 − w_b),
    w the half-width of each figure's band (timing.band)."""
    lo_a, hi_a = timing.band(1.0, _rsd(noise_a))
    lo_b, hi_b = timing.band(1.0, _rsd(noise_b))
    return lo_a / hi_b, (hi_a / lo_b if lo_b > 0 else math.inf)


def verdict(median_a, noise_a, median_b, noise_b):
    if timing.overlaps((median_a, _rsd(noise_a)), (median_b, _rsd(noise_b))):
        return "within noise"
    return "slower" if median_b > median_a else "faster"


def match(fa, fb, on):
    """The figures of both runs joined on `on`, and the keys only one run holds."""
    both = fa.merge(fb, on=on, suffixes=("_a", "_b"), how="outer", indicator=True)
    label = both[on].astype(str).agg(" ".join, axis=1)
    only_a = sorted(label[both["_merge"] == "left_only"])
    only_b = sorted(label[both["_merge"] == "right_only"])
    return both[both["_merge"] == "both"].drop(columns="_merge").reset_index(drop=True), only_a, only_b


def compare(path_a, path_b, fail_above=1.05):
    """Compare the runs at `path_a` (before) and `path_b` (after): two run folders, or two files
    (runs.csv, a headline JSON, steps.json)."""
    if not (fail_above >= 1.0 and math.isfinite(fail_above)):
        raise HarnessError(f"compare: --fail-above must be a finite ratio ≥ 1 (got {fail_above})")
    dirs = [Path(p).is_dir() for p in (path_a, path_b)]
    if dirs[0] != dirs[1]:
        raise HarnessError("compare: give two run folders or two files, not one of each")
    fa, fb = figures.read(path_a), figures.read(path_b)
    on = ["source", "key"] if dirs[0] else ["key"]
    if not dirs[0]:
        fb = fb.drop(columns="source")
    t, only_a, only_b = match(fa, fb, on)
    if t.empty:
        raise HarnessError(f"compare: {path_a} and {path_b} have no case in common: nothing to compare")
    t["ratio"] = t["median_ms_b"] / t["median_ms_a"]
    interval = [ratio_interval(a, b) for a, b in zip(t["noise_a"], t["noise_b"])]
    t["within_lo"] = [lo for lo, _ in interval]
    t["within_hi"] = [hi for _, hi in interval]
    t["verdict"] = [verdict(*x) for x in zip(t["median_ms_a"], t["noise_a"], t["median_ms_b"], t["noise_b"])]
    marks = [" / ".join(m for m in (a, b) if m) for a, b in zip(t["noisy_a"].fillna(""), t["noisy_b"].fillna(""))]
    t["noisy"] = marks
    t["fails"] = (t["verdict"] == "slower") & (t["ratio"] > fail_above) & (t["noisy"] == "")
    keep = ["source", "key", "strands_a", "points_a", "median_ms_a", "noise_a", "noise_from_a", "n_a"]
    keep += ["median_ms_b", "noise_b", "noise_from_b", "n_b", "ratio", "within_lo", "within_hi", "verdict"]
    keep += ["fails", "noisy"]
    t = t[keep].set_axis([{"strands_a": "strands", "points_a": "points"}.get(c, c) for c in keep], axis=1)
    sides = [{"path": str(p), **figures.provenance(p)} for p in (path_a, path_b)]
    return Comparison(sides[0], sides[1], fail_above, t, only_a, only_b)
