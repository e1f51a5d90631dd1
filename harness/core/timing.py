"""Honest timings (docs/decisions/honest-timings.md): nvbench's stopping rule for timed repeats,
the host's load while a figure was measured, and when a figure is noise.

A figure is the samples of one timed stage (a binary's `--repeat` times; a simulate stage's
frame times). core/rounds.py runs cases in rounds: the first round takes `min_samples` repeats,
each later round as many as the rule still asks for (enough for `min_seconds` of samples, or
more while the relative standard deviation is above `max_rsd`), until every timed stage of the
case meets the rule, the case has run `timeout_s` since its first round, or it holds
`max_samples`. The binaries time each repeat from the same state, so rounds add samples of one
distribution (each round one more process start; a GPU round a batch, one context).

The load a round ran under is measured by core/load.py (others' CPU use, the load average, the
GPU's utilisation). `noisy()` says when a figure is noise (harness/core/tolerances.py TIMING_*): its spread is above
the rule's, or other processes took more than TIMING_OTHER_CORES of the host while it ran.
Noise never decides a recommendation: figures that overlap within their noise are ties
(`tie()`, `overlaps()`)."""

import math
from dataclasses import dataclass, field, replace

import numpy as np

from harness.core import tolerances


@dataclass(frozen=True)
class StopRule:
    """nvbench's rule (at least 10 samples and 0.5 s of them, stop once the relative standard
    deviation is at most 0.5 %, a timeout), per figure; max_samples bounds a record's size."""

    min_samples: int = 10
    min_seconds: float = 0.5
    max_rsd: float = tolerances.TIMING_MAX_RSD
    timeout_s: float = 3.0
    max_samples: int = 2000

    def within(self, seconds, figures):
        """This rule fitted to `seconds` for `figures` figures (a budget's share): its minimum
        time and timeout no more than an equal share each, the first round always taken."""
        share = max(seconds, 0.0) / max(figures, 1)
        return replace(self, min_seconds=min(self.min_seconds, share), timeout_s=min(self.timeout_s, share))

    def need(self, samples_ms):
        """How many more samples this figure needs (0: it meets the rule)."""
        n = len(samples_ms)
        if n == 0:
            return self.min_samples
        s = stats(samples_ms)
        more = self.min_samples - n
        if s["total_s"] < self.min_seconds and s["median_ms"] > 0:
            more = max(more, math.ceil((self.min_seconds - s["total_s"]) / (s["median_ms"] * 1e-3)))
        if more <= 0 and not s["rsd"] <= self.max_rsd:
            more = n  # as many again: the spread is re-measured over twice the samples
        return max(0, min(more, self.max_samples - n))

    def as_dict(self):
        return {k: getattr(self, k) for k in self.__dataclass_fields__}


# the rule the bench and the studies time with, unless given another
RULE = StopRule()


def fixed(repeat):
    """`repeat` samples in one round, whatever their spread (a sweep file without [timing])."""
    return StopRule(min_samples=repeat, min_seconds=0.0, max_rsd=math.inf, timeout_s=0.0, max_samples=repeat)


STOPS = ("rule met", "timeout", "max samples")


def stats(samples_ms):
    """n, median, mean, standard deviation, relative standard deviation (std/mean), the
    samples' total (s), min and max of a figure's samples (ms)."""
    a = np.asarray(samples_ms, dtype=np.float64)
    if a.size == 0:
        nan = float("nan")
        return dict(n=0, median_ms=nan, mean_ms=nan, std_ms=nan, rsd=nan, total_s=0.0, min_ms=nan, max_ms=nan)
    mean = float(a.mean())
    std = float(a.std(ddof=1)) if a.size > 1 else 0.0
    return dict(
        n=int(a.size),
        median_ms=float(np.median(a)),
        mean_ms=mean,
        std_ms=std,
        rsd=std / mean if mean > 0 else float("nan"),
        total_s=float(a.sum()) * 1e-3,
        min_ms=float(a.min()),
        max_ms=float(a.max()),
    )


# ---- a figure and its noise -------------------------------------------------------------------


@dataclass
class Figure:
    """One timed stage of one case: its samples, why they stopped, the load they ran under."""

    samples_ms: list = field(default_factory=list)
    stop: str = ""
    rounds: int = 0
    load: dict = field(default_factory=dict)
    backend: str = "cpu"

    @property
    def stats(self):
        return stats(self.samples_ms)

    def columns(self, prefix=""):
        """The figure's spread, rule and load as CSV columns (`prefix` before each name)."""
        s = self.stats
        out = {
            "n_samples": s["n"],
            "rsd": s["rsd"],
            "std_ms": s["std_ms"],
            "stop": self.stop,
            "rounds": self.rounds,
            "other_cores": self.load.get("other_cores"),
            "loadavg": self.load.get("loadavg"),
            "gpu_busy_pct": self.load.get("gpu_busy_pct"),
            "noisy": noise(self) or "",
        }
        return {prefix + k: v for k, v in out.items()}


def noise(fig, rule=RULE):
    """Why a figure is noise ('' when it is not): its spread above the rule's, or the host
    loaded by others while it ran (TIMING_OTHER_CORES; a GPU figure also when others kept the
    GPU busy, TIMING_GPU_BUSY_PCT)."""
    s = fig.stats
    why = []
    if s["n"] and not s["rsd"] <= rule.max_rsd:
        why.append(f"spread {100 * s['rsd']:.2g} % > {100 * rule.max_rsd:g} %")
    others = fig.load.get("other_cores")
    if others is not None and others == others and others > tolerances.TIMING_OTHER_CORES:
        why.append(f"others used {others:.2g} cores")
    gpu = fig.load.get("gpu_busy_pct")
    if fig.backend == "cuda" and gpu is not None and gpu > tolerances.TIMING_GPU_BUSY_PCT:
        why.append(f"GPU {gpu:.0f} % busy before")
    return "; ".join(why)


def band(median_ms, rsd):
    """The interval a figure's median stands for: ±TIMING_TIE_K standard deviations, at least
    ±TIMING_MAX_RSD (nvbench's resolution; also where the spread was not measured)."""
    w = max(tolerances.TIMING_MAX_RSD, tolerances.TIMING_TIE_K * rsd if rsd == rsd else 0.0)
    return median_ms * (1 - w), median_ms * (1 + w)


def overlaps(a, b):
    """Whether two (median_ms, rsd) figures are a tie within their noise."""
    lo_a, hi_a = band(*a)
    lo_b, hi_b = band(*b)
    return lo_a <= hi_b and lo_b <= hi_a


def tie(figures):
    """Indices of the figures (median_ms, rsd) that tie with the fastest, fastest first."""
    order = sorted(range(len(figures)), key=lambda i: figures[i][0])
    if not order:
        return []
    return [i for i in order if overlaps(figures[order[0]], figures[i])]
