"""A frame budget's answer (`python -m harness budget`, docs/harness.md "A frame budget"): for a
scene, a strand count N and a budget B ms a frame, on each device measured, the most accurate
mode whose predicted time at N fits B, from measured data only:

  accuracy   the speed-against-accuracy study's RMS error of each mode over its horizon
             (<run>/dynamic-accuracy[-<scene>]/, studies/accuracy_rows_dynamic.summary);
  cost       the mode's own throughput curve, its time a frame measured at a ladder of strand
             counts by the stopping rule (<run>/budget-curves[-<scene>]/curves.csv,
             studies/budget_curves_dynamic.py).

The cost at N: measured at N; between two measured sizes, interpolated on the log-log line
through them; beyond the largest measured size M, t(M)·N/M, said as an extrapolation (strands
are independent, so the work grows as N while the per-strand cost only falls as the device
fills: an over-estimate); below the smallest, its time (an over-estimate too). A pick whose
predicted time is within its timing noise of B, or whose curve point is noise
(core/timing.py), says so. Rendering only: every number comes from those files."""

import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from harness import HarnessError
from harness.core import timing
from harness.core.paths import display
from harness.io import tables
from harness.studies import accuracy_results_dynamic as accuracy_results
from harness.studies import accuracy_rows_dynamic as accuracy_rows
from harness.studies.accuracy import CSV_NAME, CURVES_CSV, curves_name, results_name

# the report's table: budgets (ms a frame) down the side, strand counts across
BUDGETS_MS = (0.25, 0.5, 1.0, 2.0, 4.0, 8.0, 1000 / 60, 1000 / 30)
TABLE_STRANDS = (10_000, 50_000, 100_000)


@dataclass
class Data:
    """One run's measured data for one scene: per-mode accuracy, the curves, the study's facts."""

    summ: object  # studies/accuracy_rows_dynamic.summary: mode, rms, usable, …
    curves: object  # budget_curves rows that ran (no error)
    horizon_s: float
    holds_until_s: float
    where: str = ""


def load(root, scene="dynamic"):
    """The accuracy study's summary and the budget curves of `scene` in the run folder `root`."""
    acc_dir = Path(root) / results_name(scene)
    curves_path = Path(root) / curves_name(scene) / CURVES_CSV
    for path, cmd in (
        (acc_dir / CSV_NAME, f"python -m harness accuracy --model dynamic --scene {scene}"),
        (curves_path, f"python -m harness bench --scene {scene}"),
    ):
        if not path.is_file():
            raise HarnessError(f"budget: no {display(path)} (measure it: {cmd}, or give --run)", code=2)
    rows, study, _, _ = accuracy_results.load(acc_dir)
    summ = accuracy_rows.summary(rows, study["horizon_frames"])
    curves = tables.read_csv(curves_path)
    err = curves["error"]
    curves = curves[err.isna() | (err.astype(str) == "")].copy()  # the rows that ran
    ref = study.get("reference") or {}
    return Data(summ, curves, float(study["horizon"]), float(ref.get("converged_until_s", math.nan)), str(root))


def predict(curve, strands):
    """(ms, rsd, how) of a mode at `strands` from its curve (rows with strands, median_ms, rsd)."""
    c = curve.sort_values("strands")
    n = c["strands"].to_numpy(dtype=float)
    t = c["median_ms"].to_numpy(dtype=float)
    rsd = c["rsd"].to_numpy(dtype=float) if "rsd" in c else np.full(len(c), np.nan)
    if strands in n:
        i = int(np.flatnonzero(n == strands)[0])
        return t[i], rsd[i], "measured"
    if strands > n[-1]:
        return t[-1] * strands / n[-1], rsd[-1], f"extrapolated beyond the largest measured size ({int(n[-1]):,})"
    if strands < n[0]:
        return t[0], rsd[0], f"below the smallest measured size ({int(n[0]):,}): its time"
    j = int(np.searchsorted(n, strands))
    u = (math.log(strands) - math.log(n[j - 1])) / (math.log(n[j]) - math.log(n[j - 1]))
    ms = math.exp((1 - u) * math.log(t[j - 1]) + u * math.log(t[j]))
    return ms, max(rsd[j - 1], rsd[j]), f"interpolated between {int(n[j - 1]):,} and {int(n[j]):,}"


def devices(curves, gpu=None):
    """(backend, device name) pairs measured; `gpu`: only the GPUs whose name holds it."""
    pairs = sorted({(b, str(d)) for b, d in zip(curves["backend"], curves["device"])})
    if gpu is None:
        return pairs
    keep = [(b, d) for b, d in pairs if b == "cuda" and gpu.lower() in d.lower()]
    if not keep:
        seen = ", ".join(d for b, d in pairs if b == "cuda") or "none"
        raise HarnessError(f"budget: no GPU matching '{gpu}' was measured here (GPUs measured: {seen})", code=2)
    return keep


def answer(data, strands, frame_ms, gpu=None):
    """Per device: dict(backend, device, pick (the accuracy summary's row, or None), ms, rsd, how,
    edge (B within the pick's noise), noise (the curve's flag), fastest (ms, mode) of all)."""
    out = []
    usable = data.summ[data.summ["usable"]].set_index("mode")
    for backend, device in devices(data.curves, gpu):
        mine = data.curves[(data.curves["backend"] == backend) & (data.curves["device"].astype(str) == device)]
        options = []
        for mode, curve in mine.groupby("mode"):
            if mode not in usable.index:
                continue
            ms, rsd, how = predict(curve, strands)
            noise = [x if isinstance(x, str) else "" for x in curve.sort_values("strands")["noisy"]]
            options.append(dict(mode=mode, rms=float(usable.loc[mode, "rms"]), ms=ms, rsd=rsd, how=how,
                                noise=next((x for x in noise if x), "")))  # fmt: skip
        fits = [o for o in options if o["ms"] <= frame_ms]
        best = min(fits, key=lambda o: (o["rms"], o["ms"])) if fits else None
        fastest = min(options, key=lambda o: o["ms"]) if options else None
        entry = dict(backend=backend, device=device, pick=best, fastest=fastest, edge=False)
        if best is not None:
            lo, hi = timing.band(best["ms"], best["rsd"])
            entry["edge"] = hi > frame_ms
        out.append(entry)
    return out


def _who(backend, device):
    return f"CPU ({device})" if backend == "cpu" else f"GPU {device}"


def lines(data, strands, frame_ms, gpu=None, scene="dynamic"):
    """The answer as text (the `budget` command's output)."""
    out = [
        f"{scene}: {strands:,} strands in {frame_ms:g} ms a frame (measured in {data.where}; accuracy: RMS error "
        f"over the first {data.horizon_s:g} s, the study's horizon, against its converged reference, which "
        f"holds to t = {data.holds_until_s:.3g} s)"
    ]
    for a in answer(data, strands, frame_ms, gpu):
        who, p, f = _who(a["backend"], a["device"]), a["pick"], a["fastest"]
        if p is None:
            why = f"the fastest, {f['mode']}, is predicted at {f['ms']:.3g} ms ({f['how']})" if f else "no mode"
            out.append(f"- {who}: no measured mode fits {frame_ms:g} ms: {why}")
            continue
        notes = [p["how"]]
        if a["edge"]:
            notes.append(f"within timing noise of the budget (±{100 * max(p['rsd'], 0.005):.2g} %)")
        if p["noise"]:
            notes.append(f"its curve is flagged as noise: {p['noise']}")
        out.append(
            f"- {who}: **{p['mode']}**, predicted {p['ms']:.3g} ms a frame ({'; '.join(notes)}); RMS error "
            f"{p['rms']:.2e}·L over the first {data.horizon_s:g} s"
        )
    return out


def _short(mode):
    """A mode's name without its device label (cpu ref … → ref …)."""
    parts = mode.split()
    return " ".join(parts[1:]) if parts and parts[0] == "cpu" else " ".join(parts[2:])


def section(root, scene="dynamic", budgets=BUDGETS_MS, sizes=TABLE_STRANDS):
    """The report's "budget → settings" tables, one per device, from the run `root`."""
    head = [f"## Frame budget → settings ({scene})", ""]
    try:
        data = load(root, scene)
    except HarnessError as e:
        return head + [f"Not measured: {e}.", ""]
    out = head + [
        "For a budget of B ms a frame and N strands, the most accurate mode whose time at N, predicted from its "
        "own measured curve, fits B (`python -m harness budget --strands N --frame-ms B`; "
        "render/frame_budget_dynamic.py). "
        f"Each cell: the mode, its predicted ms, its RMS error over the first {data.horizon_s:g} s; * where the "
        "time is extrapolated beyond the largest measured size, ~ where the budget is within the time's noise.",
        "",
    ]
    for backend, device in devices(data.curves):
        out += [f"**{_who(backend, device)}**", ""]
        out += ["| budget (ms) | " + " | ".join(f"{n:,} strands" for n in sizes) + " |"]
        out += ["| ---: |" + " --- |" * len(sizes)]
        for b in budgets:
            cells = []
            for n in sizes:
                a = next(x for x in answer(data, n, b) if (x["backend"], x["device"]) == (backend, device))
                p = a["pick"]
                if p is None:
                    cells.append("nothing fits")
                    continue
                mark = ("*" if p["how"].startswith("extrapolated") else "") + ("~" if a["edge"] else "")
                cells.append(f"{_short(p['mode'])}: {p['ms']:.3g}{mark} ms, {p['rms']:.1e}·L")
            out.append(f"| {b:.3g} | " + " | ".join(cells) + " |")
        out.append("")
    return out
