"""Look rather than read: an animation of a dynamic state, seen from the side (z across,
y up: the head's profile, face to the right) and from the front (x across, y up, as a
viewer facing the face sees it), the head sphere drawn as its outline. Frames come from
the HDF5 file through harness.io.trajectory: the last paper frame (the rest shape, t = 0),
then every K-th simulated frame. At most `max_strands` strands are drawn, evenly picked.

Writes a GIF (matplotlib's PillowWriter) and, where ffmpeg is on PATH, an MP4 beside it.
Each file is written to a temporary name and renamed, so an error leaves none behind; an
existing file is refused unless `force`. Drawing only: the `animate` command's steps are
harness/bench/animate_dynamic.py's, the state it simulates without one studies/animate_dynamic.py's.
"""

import math
import shutil
from pathlib import Path

import numpy as np

from harness import HarnessError
from harness.core.paths import REPORT, display
from harness.io import files
from harness.io.trajectory import open_trajectory

TARGET_FRAMES = 60  # drawn frames when `every` is not given
MAX_GIF_FPS = 50  # GIF delays are whole hundredths of a second


def pick(n, most):
    """Indices of at most `most` of n items, evenly spread, first and last included."""
    if n <= most:
        return np.arange(n)
    return np.unique(np.round(np.linspace(0, n - 1, most)).astype(int))


def frames_to_draw(traj, every):
    """The position frames drawn: the last paper frame, then every `every`-th simulated one."""
    sim = traj.simulated
    return [traj.paper_frames - 1, *sim[every - 1 :: every]]


def outputs(out, force):
    """The animation's paths (the .gif, and an .mp4 beside it where ffmpeg is on PATH); refused in one line
    when one exists without `force` or is a directory."""
    gif = Path(out) if out else REPORT / "dynamic.gif"
    if gif.suffix.lower() != ".gif":
        raise HarnessError(f"animate: --out must name a .gif file (got {out})")
    paths = [gif]
    if shutil.which("ffmpeg"):
        paths.append(gif.with_suffix(".mp4"))
    for p in paths:
        if p.exists() and not force:
            raise HarnessError(f"animate: {display(p)} exists (use --force to replace it)")
        if p.is_dir():
            raise HarnessError(f"animate: {display(p)} is a directory")
    return paths


def render(traj, paths, max_strands=150, every=None, fps=None, log=print):
    """Draw the animation of an open trajectory into `paths` (a .gif, optionally a .mp4)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.animation import FFMpegWriter, FuncAnimation, PillowWriter
    from matplotlib.collections import LineCollection
    from matplotlib.patches import Circle

    sim = traj.simulated
    if not sim:
        raise HarnessError(f"animate: {display(traj.path)} has no simulated frame to animate")
    every = every or max(1, math.ceil(len(sim) / TARGET_FRAMES))
    drawn = frames_to_draw(traj, every)
    strands = pick(traj.n_strands, max_strands)
    pos = np.stack([traj.frame(f)[strands].astype(np.float64) for f in drawn])  # [D][n][P][3]
    if not np.all(np.isfinite(pos)):
        log("animate: the state holds NaN or Inf positions; those strands are drawn where finite")
    dt = float(traj.dynamic_params.get("frame_dt", 1 / 60))
    fps = fps or max(1, min(MAX_GIF_FPS, round(1.0 / (every * dt))))
    radius = float(traj.params["head_radius"])
    # (title, column across, depth column, sign of depth toward the viewer, x label); the
    # side view's viewer stands at +x, the front view's at +z
    views = (("side (from +x)", 2, 0, 1.0, "z (cm), face →"), ("front (facing the face)", 0, 2, 1.0, "x (cm)"))

    fig, axes = plt.subplots(1, 2, figsize=(8, 4.4), dpi=80)
    panels = []
    y_all = pos[..., 1][np.isfinite(pos[..., 1])]
    y_lim = (min(float(y_all.min(initial=-radius)), -radius) - 2, max(float(y_all.max(initial=radius)), radius) + 2)
    for ax, (title, col, depth, toward, xlabel) in zip(axes, views):
        across = pos[..., col][np.isfinite(pos[..., col])]
        lo = min(float(across.min(initial=-radius)), -radius) - 2
        hi = max(float(across.max(initial=radius)), radius) + 2
        ax.set_xlim((hi, lo) if col == 0 else (lo, hi))  # the front view mirrors x: the viewer faces the face
        ax.set_ylim(*y_lim)
        ax.set_aspect("equal")
        ax.add_patch(Circle((0, 0), radius, facecolor="#f1d9c0", edgecolor="#8a6a50", lw=1.0, zorder=1))
        behind = LineCollection([], colors="#3b2a1a", linewidths=0.6, alpha=0.7, zorder=0.5)  # under the head
        front = LineCollection([], colors="#3b2a1a", linewidths=0.6, alpha=0.7, zorder=2)
        ax.add_collection(behind)
        ax.add_collection(front)
        panels.append((behind, front, col, depth, toward))
        ax.set_title(title, fontsize=9)
        ax.set_xlabel(xlabel, fontsize=8)
        ax.set_ylabel("y (cm), up", fontsize=8)
        ax.tick_params(labelsize=7)
    label = fig.suptitle("", fontsize=9)
    fig.tight_layout()
    params = traj.dynamic_params
    caption = (
        f"{traj.n_strands} strands ({len(strands)} drawn) × {traj.points} points, {traj.solver} "
        f"S = {params.get('substeps')}, I = {params.get('iterations')}, {traj.precision}, {traj.head_motion}"
    )

    def draw(d):
        artists: list = [label]
        for behind, front, col, depth, toward in panels:
            x = pos[d]
            seg = np.stack([x[:, :-1][..., [col, 1]], x[:, 1:][..., [col, 1]]], axis=2).reshape(-1, 2, 2)
            # a segment whose middle is on the viewer's side of the head's centre plane is drawn over
            # the head, the others under it (the opaque head hides what lies behind it)
            near = (toward * (x[:, :-1, depth] + x[:, 1:, depth]) >= 0).reshape(-1)
            behind.set_segments(seg[~near])
            front.set_segments(seg[near])
            artists += [behind, front]
        label.set_text(f"t = {traj.time[drawn[d]]:.3f} s    {caption}")
        return artists

    anim = FuncAnimation(fig, draw, frames=len(drawn), blit=False)
    written = []
    try:
        for path in paths:
            path.parent.mkdir(parents=True, exist_ok=True)
            writer = PillowWriter(fps=fps) if path.suffix.lower() == ".gif" else FFMpegWriter(fps=fps, bitrate=800)
            with files.writing(path) as tmp:
                anim.save(tmp, writer=writer)
            written.append(path)
            log(f"animate: {display(path)}: {len(drawn)} frames at {fps} fps, {path.stat().st_size / 1e6:.2f} MB")
    finally:
        plt.close(fig)
    return written


def dynamic_trajectory(state):
    """The open trajectory of a dynamic-model state; HarnessError for any other file."""
    traj = open_trajectory(state)
    if not traj.is_dynamic:
        traj.close()
        raise HarnessError(f"animate: {display(state)} is a paper-model state (no simulated frames)")
    return traj
