"""`harness calibrate`: measure the errors that tolerances.py is set from.

Runs the paper scene (w = 0.5) and a gale (w = 1) on the cpu binary in fp64 (the
reference) and fp32 for a few seeds and points per strand, and prints per precision pair
the distribution of the per-point distance relative to L (p99, p99.99, max), its max in
the tolerance's per-point unit u (tolerances.point_unit; a pair passes while this stays
below point_k), and how many points are farther than 1e-3·L (strands that took the other
side of a discrete decision of the model); and per file the invariant residuals in their
units: segment-length error over ε·E and depth inside the shell over ε·rc.

With --other BINARY a second build is compared with the cpu reference at each precision
(e.g. build/hairsim-cuda-strict on a GPU node, or c_ref rebuilt with FMA contraction).
"""

import json
import tempfile
from pathlib import Path

import numpy as np

from harness.check import diff, invariants
from harness.core.paths import binary_path
from harness.core.runner import run_binary
from harness.io.states import open_state

SCENES = {"paper": 0.5, "gale": 1.0}
FLIP = 1e-3  # a point farther than this · L took the other side of a decision


def point_errors(path_a, path_b):
    """Per-point distances relative to L, over every frame, as one array."""
    out = []
    with open_state(path_a) as a, open_state(path_b) as b:
        for f in range(a.n_frames):
            xa = a.frame(f).astype(np.float64)
            xb = b.frame(f).astype(np.float64)
            out.append(np.sqrt(np.sum((xa - xb) ** 2, axis=2)).ravel() / a.hair_length)
    return np.concatenate(out)


def invariant_residuals(path):
    with open_state(path) as s:
        rep = invariants.check(s)
    return {"segment_k": rep.worst_segment_k, "shell_k": rep.worst_shell_k}


def produce(binary, tmp, name, strands, points, seed, wind, precision):
    path = Path(tmp) / f"{name}-{precision}-P{points}-s{seed}.h5"
    run_binary(
        binary,
        [
            "--strands",
            strands,
            "--points",
            points,
            "--seed",
            seed,
            "--wind-strength",
            wind,
            "--precision",
            precision,
            "--output",
            path,
            "--force",
        ],
    )
    return path


def measure(strands, points_list, seeds, other=None, on_row=None):
    """Every measurement row; `on_row(row)` is called as each is made (progress)."""
    on_row = on_row or (lambda row: None)
    ref = binary_path("cpu")
    rows = []
    with tempfile.TemporaryDirectory(prefix="hb-calibrate-") as tmp:
        for scene, wind in SCENES.items():
            for points in points_list:
                for seed in seeds:
                    files = {
                        p: produce(ref, tmp, "cpu-" + scene, strands, points, seed, wind, p) for p in ("fp32", "fp64")
                    }
                    pairs = [("fp32↔fp64 (cpu)", files["fp32"], files["fp64"])]
                    if other:
                        o = {
                            p: produce(Path(other), tmp, "other-" + scene, strands, points, seed, wind, p)
                            for p in ("fp32", "fp64")
                        }
                        pairs += [
                            ("fp64↔fp64 (other vs cpu)", o["fp64"], files["fp64"]),
                            ("fp32↔fp32 (other vs cpu)", o["fp32"], files["fp32"]),
                            ("fp32↔fp64 (other vs cpu)", o["fp32"], files["fp64"]),
                        ]
                        files.update({"other-" + k: v for k, v in o.items()})
                    for label, a, b in pairs:
                        e = point_errors(a, b)
                        d = diff.compare(a, b)
                        rows.append(
                            {
                                "kind": "pair",
                                "pair": label,
                                "scene": scene,
                                "points": points,
                                "seed": seed,
                                "strands": strands,
                                "p99_rel_L": float(np.percentile(e, 99)),
                                "p9999_rel_L": float(np.percentile(e, 99.99)),
                                "max_rel_L": float(e.max()),
                                "max_k": max(f.max_k for f in d.frames),
                                "flipped_points": int((e > FLIP).sum()),
                                "points_total": e.size,
                            }
                        )
                        on_row(rows[-1])
                    for label, path in files.items():
                        rows.append(
                            {
                                "kind": "invariants",
                                "file": label,
                                "scene": scene,
                                "points": points,
                                "seed": seed,
                                **invariant_residuals(path),
                            }
                        )
                        on_row(rows[-1])
    return rows


def summarize(rows):
    pairs, files = {}, {}
    for r in rows:
        if r["kind"] == "pair":
            p = pairs.setdefault(r["pair"], {"max_rel_L": 0, "p9999_rel_L": 0, "max_k": 0, "flipped": 0, "total": 0})
            p["max_rel_L"] = max(p["max_rel_L"], r["max_rel_L"])
            p["p9999_rel_L"] = max(p["p9999_rel_L"], r["p9999_rel_L"])
            p["max_k"] = max(p["max_k"], r["max_k"])
            p["flipped"] += r["flipped_points"]
            p["total"] += r["points_total"]
        else:
            k = files.setdefault(r["file"], {"segment_k": 0.0, "shell_k": float("-inf")})
            k["segment_k"] = max(k["segment_k"], r["segment_k"])
            k["shell_k"] = max(k["shell_k"], r["shell_k"])
    return pairs, files


def format_row(r):
    if r["kind"] == "pair":
        return (
            f"{r['pair']:26} {r['scene']:6} P={r['points']:<4d} seed={r['seed']:<3d} "
            f"p99 {r['p99_rel_L']:8.2e}·L  p99.99 {r['p9999_rel_L']:8.2e}·L  max {r['max_rel_L']:8.2e}·L "
            f"= {r['max_k']:6.3f}·u  beyond 1e-3·L: {r['flipped_points']}"
        )
    return (
        f"{r['file']:26} {r['scene']:6} P={r['points']:<4d} seed={r['seed']:<3d} "
        f"segment {r['segment_k']:6.3f}·ε·E  shell {r['shell_k']:7.2f}·ε·rc"
    )


def run(strands=20000, points=(8, 32, 128), seeds=(1, 2, 3), other=None, as_json=False):
    show = None if as_json else (lambda r: print(format_row(r), flush=True))
    rows = measure(strands, points, seeds, other, on_row=show)
    pairs, files = summarize(rows)
    if as_json:
        print(json.dumps({"rows": rows, "pairs": pairs, "files": files}, indent=1))
        return 0
    print("\nworst over all runs:")
    for label, p in pairs.items():
        print(
            f"  {label}: max {p['max_rel_L']:.2e}·L = {p['max_k']:.3f}·u, p99.99 {p['p9999_rel_L']:.2e}·L, "
            f"{p['flipped']} of {p['total']} points beyond {FLIP:g}·L"
        )
    for label, k in files.items():
        print(f"  {label}: segment error up to {k['segment_k']:.3f}·ε·E, shell depth up to {k['shell_k']:.2f}·ε·rc")
    return 0
