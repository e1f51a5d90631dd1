"""What each feature of the dynamic model costs (docs/model.md §3.9): time per frame of one
scene with every feature undeclared, each alone, each removed from the full scene, and
the full scene, on one binary and variant, and the full scene with the hair–hair grid and a
body to collide with (§3.16, §3.17) where the variant runs them. Measures and writes CSV; the Markdown table is
harness/render/featurecost_dynamic_report.py.

A feature is taken out by removing its flags from the scene's command line (so the binary
compiles it out), never by setting it to zero:

    bend     --bend-compliance            shape   --shape-compliance, --shape-range
    wind     --wind-speed (and its gusts) gust    --gust-amplitude
    motion   --head-motion, amplitude, frequency
    collide  --no-collider added          drag    --drag, --damping (the wind's drag too)
"""

import shutil

from harness import HarnessError
from harness.core import load, runner, scenes, timing, variants
from harness.core.paths import binary_path
from harness.core.progress import Progress
from harness.core.scenes_dynamic import BODY_FLAGS, DECLARING, FEATURES, GRID_FLAGS, NEEDS
from harness.io.files import write_csv

FIELDS = (
    "row",
    "features",
    "solver",
    "substeps",
    "iterations",
    "strands",
    "points",
    "precision",
    "backend",
    "variant",
    "threads",
    "block_size",
    "median_ms",
    "min_ms",
    "max_ms",
    "point_substeps_per_s",
    "device",
    "instructions_per_point_substep",
    *timing.Figure().columns(),  # the frame times' spread and the host's load (core/timing.py)
)


def without(flags, features):
    """The command line with `features` undeclared."""
    drop = {f for feat in features for f in DECLARING.get(feat, ())}
    out, i = [], 0
    while i < len(flags):
        if flags[i] in drop:
            i += 2
            continue
        out.append(flags[i])
        i += 1
    if "collide" in features and "--no-collider" not in out:
        out.append("--no-collider")
    return out


def declared(record):
    """The features the binary compiled in for a run (its JSON record)."""
    sim = [s for s in record["stages"] if s["stage"] == "simulate"]
    if not sim:
        raise HarnessError("featurecost: the binary's record has no simulate stage")
    return sim[0]


# The rows beyond the full scene (docs/model.md §3.16, §3.17): the grid and the body of
# configs/scenes/body.toml added to it, each declared by its own flags (their cost beside it).
WORLD_SCENE = "body"


def world_rows(flags):
    """(row name, flags): the full scene with the grid once a frame, every substep, the body
    (colliders and friction), and both, from WORLD_SCENE's [grid] and [body] tables."""
    extra = scenes.load_scene(WORLD_SCENE).flags()
    grid = _pick(extra, lambda f: f in GRID_FLAGS)
    body = _pick(extra, lambda f: f in BODY_FLAGS)
    substep = _set(grid, "--grid-rebuild", "substep")
    return [
        ("full + grid (once a frame)", [*flags, *grid]),
        ("full + grid (every substep)", [*flags, *substep]),
        ("full + body", [*flags, *body]),
        ("full + body + grid", [*flags, *body, *grid]),
    ]


def _pick(flags, keep):
    """The `flag value` pairs of a flag list whose flag `keep` accepts."""
    return [a for i in range(0, len(flags) - 1, 2) if keep(flags[i]) for a in (flags[i], flags[i + 1])]


def cases(flags, world=True):
    """(row name, flags) for the table: none, each alone, full minus each, full (and with
    `world` the full scene with the grid and the body)."""
    rows = [("none (gravity, stretch)", without(flags, FEATURES))]
    for feat in FEATURES:
        keep = {feat, *NEEDS.get(feat, ())}
        rows.append((f"only {'+'.join(sorted(keep))}", without(flags, [f for f in FEATURES if f not in keep])))
    for feat in FEATURES:
        rows.append((f"full − {feat}", without(flags, [feat])))
    rows.append(("full", list(flags)))
    return rows + (world_rows(flags) if world else [])


def measure(
    scene_ref="dynamic",
    backend="cpu",
    build="default",
    variant=None,
    strands=100_000,
    points=None,
    frames=3,
    repeat=3,
    threads=None,
    block_size=None,
    out=None,
    timeout=None,
    progress=print,
    instructions=False,
):
    scene = scenes.load_scene(scene_ref).with_overrides(strands=strands, points=points)
    if scene.model != "dynamic":
        raise HarnessError(f"featurecost: scene {scene_ref} is not a dynamic scene")
    base = runner.run_flags(scene, backend, variant=variant, threads=threads, block_size=block_size, repeat=repeat)
    base = _set(base, "--frames", str(frames))
    binary = binary_path(backend, build)
    rows = []
    declared_ = variants.declared(backend, build)
    used = variant or declared_.default_variant
    todo = cases(base, world=declared_.runs_features(used, {"grid", "colliders", "friction"}))
    with Progress(len(todo), f"featurecost {backend}") as bar:
        for name, flags in todo:
            rows.append(_row(binary, name, flags, timeout, instructions, progress))
            bar.update()
    if out:
        write_csv(out, FIELDS, rows)
    return rows


def _row(binary, name, flags, timeout, instructions, progress):
    """One row of the study: the binary's record of one feature set, its frame times' spread and
    the load they ran under (its own --repeat; core/timing.py flags a noisy row)."""
    probe = load.LoadProbe(gpu=rec_backend(binary) == "cuda")
    rec = runner.run_binary(binary, flags, timeout=timeout)
    ran_under = probe.stop()
    st = declared(rec)
    fig = timing.Figure(
        st.get("times_ms") or [], stop="fixed repeats", rounds=1, load=ran_under, backend=rec["backend"]
    )
    ips = instructions_per_point_substep(binary, flags, rec, st, timeout) if instructions else None
    row = {
        "row": name,
        "features": st["features"],
        "solver": st["solver"],
        "substeps": st["substeps"],
        "iterations": st["iterations"],
        "strands": rec["strands"],
        "points": rec["points"],
        "precision": rec["precision"],
        "backend": rec["backend"],
        "variant": rec["variant"],
        "threads": rec.get("threads"),
        "block_size": rec.get("block_size"),
        "median_ms": st["median_ms"],
        "min_ms": st["min_ms"],
        "max_ms": st["max_ms"],
        "point_substeps_per_s": st["point_substeps_per_s"],
        "device": rec["device"],
        "instructions_per_point_substep": ips,
        **fig.columns(),
    }
    progress(f"featurecost: {name:28s} {st['features']:44s} {st['median_ms']:10.3f} ms/frame")
    return row


def instructions_per_point_substep(binary, flags, rec, st, timeout=None):
    """CPU oracle only: the instructions executed inside the per-strand frame function
    (hb_dyn_frame_strand_f32/_f64, the whole of a frame's model arithmetic) over the frames'
    point-substeps, counted by valgrind's callgrind: deterministic, whatever else the machine
    is doing, where wall times on a shared machine are not."""
    import re
    import tempfile

    if rec["backend"] != "cpu" or rec.get("variant") not in (None, "ref"):
        raise HarnessError("featurecost --instructions counts the CPU oracle (--backend cpu, variant ref) only")
    valgrind = shutil.which("valgrind")
    if not valgrind:
        raise HarnessError("featurecost --instructions needs valgrind (apt-get install valgrind)")
    fn = "hb_dyn_frame_strand_" + ("f64" if rec["precision"] == "fp64" else "f32")
    args = [str(a) for a in flags]
    timing = ("--repeat", "--warmup")
    args = [a for i, a in enumerate(args) if a not in timing and args[i - 1] not in timing]
    with tempfile.TemporaryDirectory() as d:
        cmd = [valgrind, "--tool=callgrind", f"--callgrind-out-file={d}/cg", f"--toggle-collect={fn}", str(binary)]
        p = runner.run_command(cmd + args + ["--threads", "1", "--quiet"], timeout=timeout)
    m = re.search(r"Collected\s*:\s*([0-9]+)", p.stderr)
    if p.returncode not in runner.COMPLETED or not m:
        raise HarnessError(f"callgrind failed on {binary.name}: {runner.last_line(p.stderr)}")
    point_substeps = rec["strands"] * rec["points"] * st["substeps"] * st["frames"]
    return int(m.group(1)) / point_substeps


def rec_backend(binary):
    return "cuda" if "cuda" in binary.name else "cpu"


def _set(flags, flag, value):
    """flags with `flag value` set (replaced when present)."""
    out = list(flags)
    if flag in out:
        out[out.index(flag) + 1] = value
    else:
        out += [flag, value]
    return out
