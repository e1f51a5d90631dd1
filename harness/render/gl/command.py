"""`python -m harness render STATE`: PNG frames of a state file (paper or dynamic) from the
named views, and with --animate an animation of its simulated frames from each view. The
head is the state's sphere (bodies.head), turned with the head motion. Everything that
would be refused (a bad file, a view, an output that exists without --force, no EGL) is
refused in one line before anything is drawn or written."""

import math
import time
from pathlib import Path

import numpy as np

from harness import HarnessError
from harness.core.paths import display
from harness.io.trajectory import open_trajectory
from harness.render.gl import bodies, output
from harness.render.gl.camera import fitted
from harness.render.gl.context import context, describe
from harness.render.gl.renderer import Renderer, scene_points
from harness.render.gl.shadows import ShadowSettings

ANIMATION_FRAMES = 60  # frames an animation holds at most, evenly picked
FIT_SAMPLE = 20_000  # points per frame the animation's camera is fitted to


def pick(n, most):
    """Indices of at most `most` of n items, evenly spread, first and last included."""
    if n <= most:
        return np.arange(n)
    return np.unique(np.round(np.linspace(0, n - 1, most)).astype(int))


def chosen_frames(traj, frames):
    """Frame indices from the --frame values (negative counts from the end; default: the last)."""
    out = []
    for k in frames or [-1]:
        if not -traj.n_frames <= k < traj.n_frames:
            raise HarnessError(f"render: {display(traj.path)} has no frame {k} (it has {traj.n_frames})")
        out.append(k % traj.n_frames)
    return out


def animation_frames(traj, most=ANIMATION_FRAMES):
    """The rest shape (the last paper frame), then at most `most` simulated frames, every
    K-th written one."""
    sim = traj.simulated
    if not sim:
        raise HarnessError(f"render: {display(traj.path)} has no simulated frame to animate (a paper-model state)")
    every = max(1, math.ceil(len(sim) / most))
    return [traj.paper_frames - 1, *sim[every - 1 :: every]]


def frame_rate(traj, frames):
    """Frames a second that play the drawn frames in real time (from their times; 1 to 50)."""
    sim = [f for f in frames if f >= traj.paper_frames]
    span = traj.time[sim[-1]] - traj.time[sim[0]] if len(sim) > 1 else 0.0
    rate = (len(sim) - 1) / span if span > 0 else 1.0 / float(traj.dynamic_params.get("frame_dt", 1 / 60))
    return int(min(output.MAX_GIF_FPS, max(1, round(rate))))


def strands_at(traj, frame, strands):
    """Frame `frame`'s strands [n][P][3] (double), only those indexed by `strands`."""
    return traj.frame(frame).reshape(traj.n_strands, traj.points, 3)[strands].astype(np.float64)


def caption(traj, frame):
    if traj.is_dynamic and frame >= traj.paper_frames:
        return f"t = {traj.time[frame]:.3f} s"
    return f"frame {frame}: {traj.stages[frame]}"


def frame_cloud(traj, frame, strands):
    """Points a camera is fitted to: a sample of the frame's strand points and its head."""
    points = strands_at(traj, frame, strands).reshape(-1, 3)
    return scene_points(points[pick(len(points), FIT_SAMPLE)][:, None], bodies.of_frame(traj, frame))


def camera_for(renderer, view, clouds):
    """The named view fitted to every cloud (one camera for several frames or states)."""
    return fitted(view, np.concatenate(clouds), renderer.size[0] / renderer.size[1])


def draw(traj, renderer, frame, strands, cam):
    """The image of one frame: its strands and its head, turned by Q(t)."""
    return renderer.draw(strands_at(traj, frame, strands), bodies.of_frame(traj, frame), cam)


def draw_frames(traj, renderer, frames, view, strands, captions=False):
    """Images of `frames` from `view`, the camera fitted once to all of them, so that the
    head stays in place from one image to the next."""
    cam = camera_for(renderer, view, [frame_cloud(traj, f, strands) for f in frames])
    images = [draw(traj, renderer, f, strands, cam) for f in frames]
    return [output.captioned(img, caption(traj, f)) for img, f in zip(images, frames)] if captions else images


def run(
    state,
    out_dir,
    views=("front", "side", "three-quarter"),
    frames=None,
    size=(960, 720),
    animate=False,
    force=False,
    shadows=True,
    max_strands=None,
    log=print,
):
    """The `render` command; returns the paths written."""
    out_dir = Path(out_dir)
    with open_trajectory(state) as traj:
        picked = chosen_frames(traj, frames)
        stem = Path(state).stem
        pngs = {(f, v): out_dir / f"{stem}-frame{f}-{v}.png" for f in picked for v in views}
        movies = {v: out_dir / f"{stem}-{v}.gif" for v in views} if animate else {}
        anim = animation_frames(traj) if animate else None
        output.refuse_existing(
            [*pngs.values(), *(p for g in movies.values() for p in output.animation_paths(g))], force
        )
        context()  # no EGL: one line, nothing written
        strands = pick(traj.n_strands, max_strands or traj.n_strands)
        written = []
        start = time.perf_counter()
        try:
            with Renderer(*size, shadows=ShadowSettings(enabled=shadows)) as renderer:
                for v in views:
                    for f in picked:
                        img = draw_frames(traj, renderer, [f], v, strands)[0]
                        written.append(output.write_png(img, pngs[(f, v)]))
                    if anim:
                        images = draw_frames(traj, renderer, anim, v, strands, captions=True)
                        written += output.write_animation(images, movies[v], frame_rate(traj, anim))
        except BaseException:  # an error or Ctrl-C part way: what this run wrote goes too
            for path in written:
                path.unlink(missing_ok=True)
            raise
        log(
            f"render: {len(written)} files from {display(state)} ({len(strands)} of {traj.n_strands} strands) "
            f"in {time.perf_counter() - start:.1f} s on {describe()}"
        )
    return written
