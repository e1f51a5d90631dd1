"""The state an animation is drawn from when none is given: the default dynamic scene
(configs/scenes/dynamic.toml) run on hairsim-cpu into results/animation/
(harness/render/animation_dynamic.py draws it)."""

from pathlib import Path

from harness.core import runner, scenes
from harness.core.paths import RESULTS, binary_path, display


def simulate_default(strands, frames, out_dir=None, log=print):
    """Run configs/scenes/dynamic.toml (strands, frames overridden) on hairsim-cpu; the state's path."""

    scene = scenes.with_frames(scenes.load_scene("dynamic").with_overrides(strands=strands), frames)
    out_dir = Path(out_dir) if out_dir else RESULTS / "animation"
    out_dir.mkdir(parents=True, exist_ok=True)
    path = out_dir / f"dynamic-{strands}x{frames}.h5"
    flags = runner.run_flags(scene, "cpu", output=path, force=True)
    log(f"animate: running the dynamic scene ({strands} strands, {frames} frames) into {display(path)}")
    runner.run_binary(binary_path("cpu"), flags)
    return path
