"""`python -m harness accuracy`: speed against accuracy (issue #5).

Ground truth is `hairsim-cpu --precision fp64`. Every other mode runs the same scene (same
seed, so the same roots) and is compared with it frame by frame:

  max_err_L, rms_err_L   position error |p − p_ref| over the hair length L
  seg_drift              max |segment length − ℓ| / ℓ
  penetration            deepest point inside its shell after a collide frame, over rc
                         (0 when none is inside; the backends allow 16 ε·rc of rounding)

and timed apart from that run (`--repeat`, no output file; never a run that also checks):
`time_ms` is the sum of the stage medians of the scene.

Model resolution: the fp64 reference at P points per strand is compared with the finest
P of the study by distance along the curve (each coarse point against the fine polyline at
the same arc length), and timed with the fastest backend available.

Writes results/accuracy/accuracy.csv and env.json, report/accuracy_pareto.png and
report/accuracy.md (a table and a recommendation: which mode for which use).
"""
import csv
import json
import os
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from . import HarnessError, env, invariants, runner, scenes
from .paths import REPORT, RESULTS, binary_path, display
from .states import open_state


@dataclass(frozen=True)
class Mode:
    name: str
    backend: str     # cpu | cuda
    build: str       # default | strict | fastmath (cuda)
    variant: str
    precision: str
    use: str         # what a user would pick it for, in a few words


MODES = (
    Mode("cpu fp64 ref", "cpu", "default", "ref", "fp64", "ground truth"),
    Mode("cpu fp32 ref", "cpu", "default", "ref", "fp32", "the readable fp32 oracle"),
    Mode("cpu fp32 simd", "cpu", "default", "simd", "fp32", "fast CPU baseline"),
    Mode("gpu fp32 strict", "cuda", "strict", "fused", "fp32", "validation against the CPU"),
    Mode("gpu fp32 normal", "cuda", "default", "fused", "fp32", "production"),
    Mode("gpu fp32 fast-math", "cuda", "fastmath", "fused", "fp32", "previews"),
    Mode("gpu fp64", "cuda", "default", "fused", "fp64", "reference on the GPU"),
)

COLUMNS = ("study", "mode", "backend", "build", "variant", "precision", "strands", "points",
           "frame", "stage", "max_err_L", "rms_err_L", "seg_drift", "penetration", "time_ms",
           "device")


def _mode_available(mode, gpu_ok, cpu_variants):
    if mode.backend == "cuda":
        if not gpu_ok:
            return False
        return binary_path("cuda", mode.build).exists()
    return mode.variant in cpu_variants


def _cpu_variants():
    """The variants hairsim-cpu knows, read from its --help."""
    import subprocess

    out = subprocess.run([str(binary_path("cpu")), "--help"], capture_output=True, text=True).stdout
    line = next((ln for ln in out.splitlines() if "--variant" in ln), "")
    known = {"ref"}
    if "simd" in line:
        known.add("simd")
    return known


def frame_errors(test, ref, f, L):
    """The four error measures of frame f of `test` against `ref` (both [N][P][3])."""
    a = test.frame(f).astype(np.float64)
    b = ref.frame(f).astype(np.float64)
    d = np.linalg.norm(a - b, axis=-1)
    if not np.isfinite(a).all():
        return dict(max_err_L=float("nan"), rms_err_L=float("nan"), seg_drift=float("nan"),
                    penetration=float("nan"))
    ell = test.segment_length
    seg = np.linalg.norm(np.diff(a, axis=1), axis=-1)
    drift = float(np.abs(seg - ell).max() / ell) if seg.size else 0.0
    pen = 0.0
    if invariants.is_collide_frame(test, f):
        rc = np.hypot(a[:, 0, 1], a[:, 0, 2]) + float(test.params["hair_offset"])
        r = np.hypot(a[:, 1:, 1], a[:, 1:, 2])
        pen = float(max(0.0, ((rc[:, None] - r) / rc[:, None]).max())) if r.size else 0.0
    return dict(max_err_L=float(d.max() / L), rms_err_L=float(np.sqrt((d * d).mean()) / L),
                seg_drift=drift, penetration=pen)


def along_curve_error(coarse, fine):
    """Distance of each coarse point to the fine polyline at the same arc length, for
    strands [N][Pc][3] and [N][Pf][3] of the same length L (all segments equal)."""
    Pc, Pf = coarse.shape[1], fine.shape[1]
    s = np.arange(Pc) * (Pf - 1) / (Pc - 1)  # arc length in units of the fine segment
    j = np.minimum(np.floor(s).astype(int), Pf - 2)
    t = (s - j)[None, :, None]
    interp = fine[:, j, :] * (1 - t) + fine[:, j + 1, :] * t
    return np.linalg.norm(coarse - interp, axis=-1)


def _time(binary, flags, repeat):
    rec = runner.run_binary(binary, flags + ["--repeat", str(repeat)])
    return sum(s["median_ms"] for s in rec["stages"] if not s.get("skipped")), rec


def run_study(scene_name="paper", *, strands=100_000, points=32, repeat=9, resolution=(4, 8, 16, 32, 64, 128, 256),
              res_strands=20_000, out_dir=None, report_dir=None, log=print):
    scene = scenes.load_scene(scene_name).with_overrides(strands=strands, points=points)
    out_dir = Path(out_dir or RESULTS / "accuracy")
    report_dir = Path(report_dir or REPORT)
    scratch = out_dir / "states"
    scratch.mkdir(parents=True, exist_ok=True)
    report_dir.mkdir(parents=True, exist_ok=True)
    gpu_ok, why = env.gpu_status()
    cpu_variants = _cpu_variants()
    L = scene.hair_length
    rows = []

    def state_path(tag):
        return scratch / f"{tag.replace(' ', '_')}.h5"

    # ---- precision / build modes against the fp64 reference ----
    ref_path = state_path("cpu fp64 ref")
    for mode in MODES:
        if not _mode_available(mode, gpu_ok, cpu_variants):
            log(f"accuracy: skipping {mode.name}: " + (why if mode.backend == "cuda" and not gpu_ok
                                                      else "not built here"))
            continue
        binary = binary_path(mode.backend, mode.build)
        sc = scene.with_overrides(precision=mode.precision)
        path = state_path(mode.name)
        flags = runner.run_flags(sc, mode.backend, variant=mode.variant, output=path, force=True)
        rec = runner.run_binary(binary, flags)
        t_ms, trec = _time(binary, runner.run_flags(sc, mode.backend, variant=mode.variant), repeat)
        log(f"accuracy: {mode.name}: {t_ms:.2f} ms")
        with open_state(path) as test, open_state(ref_path) as ref:
            for f in range(test.n_frames):
                e = frame_errors(test, ref, f, L)
                rows.append(dict(study="mode", mode=mode.name, backend=mode.backend, build=mode.build,
                                 variant=mode.variant, precision=mode.precision, strands=strands,
                                 points=points, frame=f, stage=test.stages[f], time_ms=t_ms,
                                 device=rec.get("device"), **e))

    # ---- model resolution, fp64, against the finest P ----
    fine_p = max(resolution)
    res_scene = scene.with_overrides(strands=res_strands, precision="fp64")
    fast = (("cuda", "default", "fused") if gpu_ok and binary_path("cuda").exists() else
            ("cpu", "default", "simd" if "simd" in cpu_variants else "ref"))
    for P in sorted(resolution):
        sc = res_scene.with_overrides(points=P)
        path = state_path(f"res_P{P}")
        runner.run_binary(binary_path("cpu"), runner.run_flags(sc, "cpu", output=path, force=True))
        t_ms, trec = _time(binary_path(fast[0], fast[1]),
                           runner.run_flags(sc.with_overrides(strands=strands, precision="fp32"), fast[0],
                                            variant=fast[2]), repeat)
        rows.append(dict(study="resolution", mode=f"P={P}", backend=fast[0], build=fast[1], variant=fast[2],
                         precision="fp32", strands=strands, points=P, frame=-1, stage="", time_ms=t_ms,
                         device=trec.get("device"), max_err_L=float("nan"), rms_err_L=float("nan"),
                         seg_drift=float("nan"), penetration=float("nan")))
    with open_state(state_path(f"res_P{fine_p}")) as fine:
        for row in rows:
            if row["study"] != "resolution":
                continue
            with open_state(state_path(f"res_P{row['points']}")) as coarse:
                for f in range(coarse.n_frames):
                    d = along_curve_error(coarse.frame(f).astype(np.float64), fine.frame(f).astype(np.float64))
                    if f == coarse.n_frames - 1:
                        row.update(frame=f, stage=coarse.stages[f], max_err_L=float(d.max() / L),
                                   rms_err_L=float(np.sqrt((d * d).mean()) / L))

    csv_path = out_dir / "accuracy.csv"
    tmp = csv_path.with_suffix(".csv.tmp")
    with open(tmp, "w", newline="") as fh:
        w = csv.DictWriter(fh, fieldnames=COLUMNS)
        w.writeheader()
        for row in rows:
            w.writerow({k: row.get(k) for k in COLUMNS})
    os.replace(tmp, csv_path)
    (out_dir / "env.json").write_text(json.dumps(dict(env.collect(), resolution_strands=res_strands), indent=1) + "\n")
    png = pareto_plot(rows, report_dir / "accuracy_pareto.png", strands, points)
    md = write_markdown(rows, report_dir / "accuracy.md", strands, points, res_strands, gpu_ok, why)
    for p in scratch.glob("*.h5"):
        p.unlink()
    scratch.rmdir()
    log(f"wrote {display(csv_path)}, {display(png)}, {display(md)}")
    return rows


def load_rows(csv_path):
    """The rows of an accuracy.csv, numbers as numbers."""
    ints = ("strands", "points", "frame")
    floats = ("max_err_L", "rms_err_L", "seg_drift", "penetration", "time_ms")
    try:
        with open(csv_path, newline="") as fh:
            rows = list(csv.DictReader(fh))
    except OSError as e:
        raise HarnessError(f"{display(csv_path)}: cannot read ({e.strerror})") from None
    for r in rows:
        for k in ints:
            r[k] = int(r[k])
        for k in floats:
            r[k] = float(r[k]) if r[k] not in ("", None) else float("nan")
    return rows


def report_from_csv(csv_path, report_dir=None, log=print):
    """Rewrite report/accuracy.md and the Pareto plot from a committed accuracy.csv."""
    rows = load_rows(csv_path)
    if not rows:
        raise HarnessError(f"{display(csv_path)} has no rows")
    report_dir = Path(report_dir or REPORT)
    report_dir.mkdir(parents=True, exist_ok=True)
    mode_rows = [r for r in rows if r["study"] == "mode"]
    res_rows = [r for r in rows if r["study"] == "resolution"]
    strands, points = mode_rows[0]["strands"], mode_rows[0]["points"]
    res_note = _res_strands_note(csv_path)
    gpu_ran = any(r["backend"] == "cuda" for r in mode_rows)
    png = pareto_plot(rows, report_dir / "accuracy_pareto.png", strands, points)
    md = write_markdown(rows, report_dir / "accuracy.md", strands, points, res_note, gpu_ran,
                        "no GPU rows in this results file")
    log(f"wrote {display(png)}, {display(md)} from {display(csv_path)} ({len(mode_rows)} mode rows, "
        f"{len(res_rows)} resolution rows)")
    return md


def _res_strands_note(csv_path):
    """Strands of the resolution study, from env.json beside the CSV (recorded by run_study)."""
    try:
        return int(json.loads((Path(csv_path).parent / "env.json").read_text()).get("resolution_strands"))
    except (OSError, ValueError, TypeError, AttributeError):
        return None


def _end_to_end(rows):
    """One row per mode: its last frame (the end-to-end error)."""
    last = {}
    for r in rows:
        if r["study"] == "mode":
            if r["mode"] not in last or r["frame"] > last[r["mode"]]["frame"]:
                last[r["mode"]] = r
    return list(last.values())


def pareto_plot(rows, path, strands, points):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(7, 4.5))
    floor = 1e-17
    for r in _end_to_end(rows):
        if r["mode"] == "cpu fp64 ref":
            continue
        err = max(r["max_err_L"], floor)
        ax.scatter(r["time_ms"], err, s=40)
        ax.annotate(r["mode"], (r["time_ms"], err), textcoords="offset points", xytext=(5, 3), fontsize=8)
    res = [r for r in rows if r["study"] == "resolution" and np.isfinite(r["max_err_L"]) and r["max_err_L"] > 0]
    if res:
        ax.plot([r["time_ms"] for r in res], [r["max_err_L"] for r in res], "k.--", lw=0.8,
                label="model resolution P (vs finest, fp64)")
        for r in res:
            ax.annotate(r["mode"], (r["time_ms"], r["max_err_L"]), textcoords="offset points", xytext=(4, -9),
                        fontsize=7, color="0.3")
        ax.legend(fontsize=8)
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlabel(f"time of the scene's stages, median (ms), {strands:,} strands x {points} points")
    ax.set_ylabel("max position error / hair length (end to end)")
    ax.set_title("Speed against accuracy (reference: cpu fp64)")
    ax.grid(True, which="both", alpha=0.3)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path


def recommend(rows):
    """Which mode for which use, from the measured end-to-end errors and times."""
    e2e = [r for r in _end_to_end(rows) if r["mode"] != "cpu fp64 ref" and np.isfinite(r["max_err_L"])]
    if not e2e:
        return ["No mode other than the reference ran."]
    lines = []
    fastest = min(e2e, key=lambda r: r["time_ms"])
    lines.append(f"- Fastest overall: **{fastest['mode']}** ({fastest['time_ms']:.2f} ms, end-to-end error "
                 f"{fastest['max_err_L']:.1e}·L).")
    for limit, use in ((1e-5, "production runs and benchmarks"), (1e-12, "references and validation")):
        ok = [r for r in e2e if r["max_err_L"] <= limit]
        if ok:
            best = min(ok, key=lambda r: r["time_ms"])
            lines.append(f"- For {use} (error ≤ {limit:.0e}·L): **{best['mode']}** ({best['time_ms']:.2f} ms, "
                         f"{best['max_err_L']:.1e}·L).")
        else:
            lines.append(f"- For {use} (error ≤ {limit:.0e}·L): no mode measured here meets it.")
    res = sorted((r for r in rows if r["study"] == "resolution" and np.isfinite(r["max_err_L"])),
                 key=lambda r: r["points"])
    enough = [r for r in res if r["max_err_L"] <= 0.01 and r["max_err_L"] > 0]
    if enough:
        lines.append(f"- Model resolution: {enough[0]['points']} points per strand stay within 1% of L of the "
                     f"finest strand measured ({max(r['points'] for r in res)} points); the discretisation error "
                     "dwarfs every precision's rounding error above.")
    return lines


def write_markdown(rows, path, strands, points, res_strands, gpu_ok, why):
    fmt = lambda v: "n/a" if v is None or not np.isfinite(v) else f"{v:.2e}"  # noqa: E731
    out = ["## Speed against accuracy", "",
           f"Paper scene, {strands:,} strands x {points} points; reference `hairsim-cpu --precision fp64`; "
           "errors of the last frame (end to end) and the worst over all frames; time = sum of the stage "
           "medians of a separate timing run (`--repeat`), never a run that also checks.", ""]
    if not gpu_ok:
        out += [f"GPU modes absent: {why}.", ""]
    out += ["| mode | use | time (ms) | max err / L (end) | rms err / L (end) | worst max err / L | "
            "segment drift | penetration / rc |", "|---|---|---|---|---|---|---|---|"]
    uses = {m.name: m.use for m in MODES}
    for r in _end_to_end(rows):
        frames = [x for x in rows if x["study"] == "mode" and x["mode"] == r["mode"]]
        worst = max(x["max_err_L"] for x in frames)
        drift = max(x["seg_drift"] for x in frames)
        pen = max(x["penetration"] for x in frames)
        out.append(f"| {r['mode']} | {uses.get(r['mode'], '')} | {r['time_ms']:.2f} | {fmt(r['max_err_L'])} | "
                   f"{fmt(r['rms_err_L'])} | {fmt(worst)} | {fmt(drift)} | {fmt(pen)} |")
    res = [r for r in rows if r["study"] == "resolution"]
    if res:
        how_many = f"{res_strands:,} strands, " if res_strands else ""
        out += ["", f"Model resolution ({how_many}fp64, compared with the finest strand along the "
                "curve; timed with " f"{res[0]['backend']}/{res[0]['variant']} fp32 at {strands:,} strands):", "",
                "| points per strand | time (ms) | max err / L | rms err / L |", "|---|---|---|---|"]
        for r in sorted(res, key=lambda r: r["points"]):
            out.append(f"| {r['points']} | {r['time_ms']:.2f} | {fmt(r['max_err_L'])} | {fmt(r['rms_err_L'])} |")
    out += ["", "### Which mode for which use", ""] + recommend(rows) + ["",
            "![speed against accuracy](accuracy_pareto.png)", ""]
    path.write_text("\n".join(out))
    return path
