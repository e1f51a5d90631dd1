"""The states the report's renders are drawn from (harness/render/hair_report.py draws them):
simulated on the C reference into ROOT/renders/, listed in ROOT/renders/renders.json.

  dynamic.h5           the default dynamic scene at ANIMATION_STRANDS strands for
                       ANIMATION_FRAMES frames, every ANIMATION_EVERY-th written: the
                       rendered animation and the hero frame
  mode-<use>-<k>.h5    each mode the dynamic accuracy study recommends for a use (preview,
                       game, offline: accuracy_verdicts_dynamic.recommended_modes), the same
                       settings run once where the CPU and GPU picks share them, at
                       MODE_STRANDS strands up to the study's horizon
  reference.h5         the study's converged reference (xpbd fp64 I = 1 at its S), the same
                       strands and frames, so each mode's last frame is seen beside it
  world-<k>.h5         the default scene, with the hair-hair grid, and on the body with the
                       grid (docs/model.md §3.16, §3.17): the grid's and the body's effect

A GPU pick's settings run on the CPU oracle: the model is the same (docs/model.md §1.3) and
the picture cannot show a build's arithmetic. `simulate` makes the scene's and the world's
states; `simulate_modes`, once the accuracy study has run, its modes' (none where it has no
results)."""

import json
import time
from dataclasses import replace
from pathlib import Path

from harness import HarnessError
from harness.core import runner, scenes
from harness.core.paths import binary_path, display
from harness.io.files import write_json
from harness.render.gl import context
from harness.studies.accuracy import results_name
from harness.studies.accuracy_dynamic import configured
from harness.studies.accuracy_verdicts_dynamic import recommended_modes

ANIMATION_STRANDS = 3000
ANIMATION_FRAMES = 120  # 2 s of the default scene
ANIMATION_EVERY = 2  # frames written: the animation draws 60 (30 fps)
MODE_STRANDS = 800
FOLDER = "renders"
RECORD = "renders.json"


def _simulate(scene, path, extra=()):
    flags = runner.run_flags(scene, "cpu", output=path, force=True)
    runner.run_binary(binary_path("cpu"), [*flags, *extra], timeout=1800)
    return path.name


def mode_states(root, out, say):
    """(modes, reference) entries of renders.json for the default scene's accuracy study, or
    ([], None) where it has no results."""
    acc = Path(root) / results_name("dynamic")
    try:
        picks, study = recommended_modes(acc)
    except HarnessError as e:
        say(f"harness: renders: no accuracy modes to draw ({e})")
        return [], None
    scene = scenes.load_scene(study.get("scene", "dynamic"))
    frames = int(study["horizon_frames"])
    ref = study["reference"]
    settings = {}
    for p in picks:
        key = (p["solver"], p["ftl_damping"], p["substeps"], p["iterations"], p["precision"])
        settings.setdefault(key, []).append(p)
    modes = []
    for k, (key, same) in enumerate(settings.items()):
        solver, damping, substeps, iterations, precision = key
        sc = configured(
            scene, solver=solver, substeps=substeps, iterations=iterations, precision=precision,
            frames=frames, strands=MODE_STRANDS, ftl_damping=damping,
        )  # fmt: skip
        name = _simulate(sc, out / f"mode-{same[0]['use']}-{k}.h5")
        modes.append({"state": name, "picks": same})
    sc = configured(
        scene, solver=ref["solver"], substeps=ref["substeps"], iterations=ref["iterations"],
        precision=ref["precision"], frames=frames, strands=MODE_STRANDS,
    )  # fmt: skip
    what = f"{ref['solver']} {ref['precision']} S = {ref['substeps']}"
    say(f"harness: renders: the reference ({what}) at {MODE_STRANDS} strands")
    reference = {
        "state": _simulate(sc, out / "reference.h5"),
        **{k: ref[k] for k in ("solver", "precision", "substeps", "iterations", "label")},
    }
    return modes, {**reference, "horizon_frames": frames, "converged": bool(ref.get("converged"))}


WORLD_STRANDS = 1000
WORLD_FRAMES = 120  # 2 s: the body rises into place in the first 0.5 s


def world_states(out):
    """The default scene, with the grid, and on the body with the grid (configs/scenes/body.toml):
    the same strands and frames, for the report's picture and table of their effect
    (docs/model.md §3.16, §3.17). [(label, state file)]."""
    base = scenes.with_frames(scenes.load_scene("dynamic").with_overrides(strands=WORLD_STRANDS), WORLD_FRAMES)
    body = scenes.with_frames(scenes.load_scene("body").with_overrides(strands=WORLD_STRANDS), WORLD_FRAMES)
    grid = {k: v for k, v in body.dynamic.items() if k.startswith("--grid")}
    every = {"--output-every": WORLD_FRAMES // 4}
    runs = [
        ("default scene", replace(base, dynamic={**base.dynamic, **every})),
        ("+ hair-hair grid", replace(base, dynamic={**base.dynamic, **grid, **every})),
        ("+ grid + body", replace(body, dynamic={**body.dynamic, **every})),
    ]
    return [(label, _simulate(sc, out / f"world-{k}.h5")) for k, (label, sc) in enumerate(runs)]


def simulate(root, say):
    """Make ROOT/renders/ (the scene's and the world's states, and renders.json, its modes empty
    until simulate_modes adds the accuracy study's); the record's path, or None (nothing made)
    where no OpenGL context can be made to draw them (one line says why)."""
    why = context.unavailable()
    if why:
        say(f"harness: renders: skipped: {why}")
        return None
    start = time.perf_counter()
    out = Path(root) / FOLDER
    out.mkdir(parents=True, exist_ok=True)
    say(f"harness: renders: the dynamic scene at {ANIMATION_STRANDS} strands, {ANIMATION_FRAMES} frames")
    scene = scenes.with_frames(scenes.load_scene("dynamic").with_overrides(strands=ANIMATION_STRANDS), ANIMATION_FRAMES)
    scene = replace(scene, dynamic={**scene.dynamic, "--output-every": ANIMATION_EVERY})
    dynamic = _simulate(scene, out / "dynamic.h5")
    say(f"harness: renders: the grid and the body's effect at {WORLD_STRANDS} strands, {WORLD_FRAMES} frames")
    world = world_states(out)
    record = {
        "dynamic": dynamic,
        "world": world,
        "modes": [],
        "reference": None,
        "mode_strands": MODE_STRANDS,
        "simulate_s": round(time.perf_counter() - start, 1),
    }
    path = out / RECORD
    write_json(path, record)
    say(f"harness: renders: states in {display(out)} ({record['simulate_s']} s)")
    return path


def simulate_modes(root, say):
    """Add the accuracy study's modes and its reference to ROOT/renders/renders.json, which
    simulate made; the record's path, or None where it made none."""
    path = Path(root) / FOLDER / RECORD
    if not path.is_file():
        return None
    start = time.perf_counter()
    record = json.loads(path.read_text())
    record["modes"], record["reference"] = mode_states(root, path.parent, say)
    record["simulate_s"] = round(record["simulate_s"] + time.perf_counter() - start, 1)
    write_json(path, record)
    return path
