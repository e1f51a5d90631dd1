"""The `animate` command's steps: the outputs checked before anything runs, the default dynamic
scene simulated when no state is given (harness/studies/animate_dynamic.py), the animation drawn
(harness/render/animation_dynamic.py)."""

from harness.core.progress import Progress
from harness.render import animation_dynamic as animation
from harness.studies import animate_dynamic as animate


def run(
    state=None,
    out=None,
    max_strands=150,
    every=None,
    fps=None,
    force=False,
    strands=300,
    frames=120,
    log=print,
    state_dir=None,
):
    """The `animate` command: the written paths (`state_dir`: where the simulated state goes,
    default results/animation)."""
    paths = animation.outputs(out, force)
    if state is not None:  # a bad file is refused in one line, before the progress starts
        animation.dynamic_trajectory(state).close()
    with Progress(2 if state is None else 1, "animate: simulate and draw") as bar:
        if state is None:
            state = animate.simulate_default(strands, frames, out_dir=state_dir, log=log)
            bar.update()
        with animation.dynamic_trajectory(state) as traj:
            written = animation.render(traj, paths, max_strands=max_strands, every=every, fps=fps, log=log)
        bar.update()
        return written
