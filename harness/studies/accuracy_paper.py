"""`python -m harness accuracy`: speed against accuracy, the measuring part
(render/accuracy_paper_report.py renders it).

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

Writes results/accuracy/accuracy.csv and env.json (render/accuracy_paper_report.py draws
report/accuracy_pareto.png and writes report/accuracy.md from them).
"""

import numpy as np

from harness.check import invariants
from harness.core import env, runner, scenes, variants
from harness.core.paths import RESULTS, binary_path, display, output_dir
from harness.core.variants import Runner
from harness.io import files, runfolder
from harness.io.states import open_state
from harness.studies.accuracy import PAPER_MODES, PAPER_OTHER_CPU_USE, Mode, frame_errors


def modes():
    """PAPER_MODES with one "cpu fp32 <variant>" mode per cpu variant other than the default."""
    cpu = variants.declared("cpu")
    extra = tuple(
        Mode(Runner("cpu", "default", v), "fp32", label=f"cpu fp32 {v}", use=PAPER_OTHER_CPU_USE)
        for v in cpu.variants
        if v != cpu.default_variant
    )
    return PAPER_MODES[:2] + extra + PAPER_MODES[2:]


COLUMNS = (
    "study",
    "mode",
    "backend",
    "build",
    "variant",
    "precision",
    "strands",
    "points",
    "frame",
    "stage",
    "max_err_L",
    "rms_err_L",
    "seg_drift",
    "penetration",
    "time_ms",
    "device",
)


def _mode_available(mode, gpu_ok):
    if mode.runner.backend == "cuda":
        return gpu_ok and binary_path("cuda", mode.runner.build).exists()
    return binary_path("cpu").exists()


def _variant(mode):
    return mode.runner.variant or variants.declared(mode.runner.backend, mode.runner.build).default_variant


def frame_measures(test, ref, f, L):
    """The four error measures of frame f of `test` against `ref` (both [N][P][3]): the
    position errors (studies/accuracy.py) and the segment drift and penetration of `test`."""
    a = test.frame(f).astype(np.float64)
    max_err, rms_err = frame_errors(a, ref.frame(f), L)[::-1]
    if not np.isfinite(a).all():
        return dict(max_err_L=float("nan"), rms_err_L=float("nan"), seg_drift=float("nan"), penetration=float("nan"))
    ell = test.segment_length
    seg = np.linalg.norm(np.diff(a, axis=1), axis=-1)
    drift = float(np.abs(seg - ell).max() / ell) if seg.size else 0.0
    pen = 0.0
    if invariants.is_collide_frame(test, f):
        rc = np.hypot(a[:, 0, 1], a[:, 0, 2]) + float(test.params["hair_offset"])
        r = np.hypot(a[:, 1:, 1], a[:, 1:, 2])
        pen = float(max(0.0, ((rc[:, None] - r) / rc[:, None]).max())) if r.size else 0.0
    return dict(max_err_L=max_err, rms_err_L=rms_err, seg_drift=drift, penetration=pen)


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


def _fastest(gpu_ok):
    """(backend, build, variant) to time the resolution study with: the GPU's default
    variant, else the last cpu variant declared (the oracle comes first)."""
    if gpu_ok and binary_path("cuda").exists():
        return ("cuda", "default", variants.declared("cuda").default_variant)
    return ("cpu", "default", variants.declared("cpu").variants[-1])


def run_study(
    scene_name="paper",
    *,
    strands=100_000,
    points=32,
    repeat=9,
    resolution=(4, 8, 16, 32, 64, 128, 256),
    res_strands=20_000,
    out_dir=None,
    log=print,
):
    """Measure every mode and the model resolution; write accuracy.csv and env.json into
    out_dir (render/accuracy_paper_report.py draws them) and return the rows."""
    scene = scenes.load_scene(scene_name).with_overrides(strands=strands, points=points)
    out_dir = runfolder.claim(out_dir or RESULTS / "accuracy", "accuracy", force=True)
    scratch = output_dir(out_dir / "states")
    gpu_ok, why = env.gpu_status()
    L = scene.hair_length
    rows = []

    def state_path(tag):
        return scratch / f"{tag.replace(' ', '_')}.h5"

    # ---- precision / build modes against the fp64 reference ----
    ref_path = state_path("cpu fp64 ref")
    for mode in modes():
        if not _mode_available(mode, gpu_ok):
            log(
                f"accuracy: skipping {mode.name}: "
                + (why if mode.runner.backend == "cuda" and not gpu_ok else "not built here")
            )
            continue
        binary = binary_path(mode.runner.backend, mode.runner.build)
        sc = scene.with_overrides(precision=mode.precision)
        path = state_path(mode.name)
        variant = _variant(mode)
        flags = runner.run_flags(sc, mode.runner.backend, variant=variant, output=path, force=True)
        rec = runner.run_binary(binary, flags)
        t_ms, trec = _time(binary, runner.run_flags(sc, mode.runner.backend, variant=variant), repeat)
        log(f"accuracy: {mode.name}: {t_ms:.2f} ms")
        with open_state(path) as test, open_state(ref_path) as ref:
            for f in range(test.n_frames):
                e = frame_measures(test, ref, f, L)
                rows.append(
                    dict(
                        study="mode",
                        mode=mode.name,
                        backend=mode.runner.backend,
                        build=mode.runner.build,
                        variant=variant,
                        precision=mode.precision,
                        strands=strands,
                        points=points,
                        frame=f,
                        stage=test.stages[f],
                        time_ms=t_ms,
                        device=rec.get("device"),
                        **e,
                    )
                )

    # ---- model resolution, fp64, against the finest P ----
    fine_p = max(resolution)
    res_scene = scene.with_overrides(strands=res_strands, precision="fp64")
    fast = _fastest(gpu_ok)
    for P in sorted(resolution):
        sc = res_scene.with_overrides(points=P)
        path = state_path(f"res_P{P}")
        runner.run_binary(binary_path("cpu"), runner.run_flags(sc, "cpu", output=path, force=True))
        t_ms, trec = _time(
            binary_path(fast[0], fast[1]),
            runner.run_flags(sc.with_overrides(strands=strands, precision="fp32"), fast[0], variant=fast[2]),
            repeat,
        )
        rows.append(
            dict(
                study="resolution",
                mode=f"P={P}",
                backend=fast[0],
                build=fast[1],
                variant=fast[2],
                precision="fp32",
                strands=strands,
                points=P,
                frame=-1,
                stage="",
                time_ms=t_ms,
                device=trec.get("device"),
                max_err_L=float("nan"),
                rms_err_L=float("nan"),
                seg_drift=float("nan"),
                penetration=float("nan"),
            )
        )
    with open_state(state_path(f"res_P{fine_p}")) as fine:
        for row in rows:
            if row["study"] != "resolution":
                continue
            with open_state(state_path(f"res_P{row['points']}")) as coarse:
                for f in range(coarse.n_frames):
                    d = along_curve_error(coarse.frame(f).astype(np.float64), fine.frame(f).astype(np.float64))
                    if f == coarse.n_frames - 1:
                        row.update(
                            frame=f,
                            stage=coarse.stages[f],
                            max_err_L=float(d.max() / L),
                            rms_err_L=float(np.sqrt((d * d).mean()) / L),
                        )

    csv_path = out_dir / "accuracy.csv"
    files.write_csv(csv_path, COLUMNS, rows, extrasaction="ignore")
    meta = dict(env.collect(), resolution_strands=res_strands, gpu_absent=None if gpu_ok else why)
    files.write_json(out_dir / "env.json", meta)
    for p in scratch.glob("*.h5"):
        p.unlink()
    scratch.rmdir()
    log(f"wrote {display(csv_path)}")
    return rows
