"""The report's rendered hair (harness/render/gl): the paper's two figures redrawn as
renders, the default dynamic scene's animation and the hero frame, and each accuracy
recommendation's mode beside the converged reference at the same time. Drawn from states
on disk (the paper sweep's figure state; ROOT/renders/renders.json, made by
harness/bench/renders.py); where no OpenGL context can be made, the sections say why.

  fig1_rendered.png, fig2_rendered.png     side (the paper's view) and three-quarter
  dynamic_render.gif (and .mp4)            the default scene, three-quarter view
  hair.png                                 the hero frame (1280×720)
  dynamic_accuracy_render_<use>.png        a use's modes and the reference, side view
  dynamic_world_render.png                 the default scene, with the grid, on the body
"""

import json
from pathlib import Path

import numpy as np

from harness.core.paths import display
from harness.io.trajectory import open_trajectory
from harness.render.gl import command, context, output
from harness.render.gl.renderer import Renderer

FIG_SIZE = (560, 560)
ANIMATION_SIZE = (640, 480)
HERO_SIZE = (1280, 720)
HERO_TIME = 1.25  # s: the frame the hero image shows (mid-gust in the default scene)
MODE_SIZE = (420, 480)
HERO = "hair.png"
ANIMATION = "dynamic_render.gif"

# the paper's own words on its two figures, restated (Dandashli and Mneimneh, see docs/model.md)
PAPER_FIGURES = (
    (
        "fig1_rendered.png",
        "Fig. 1, hair initialized",
        "the paper's Fig. 1 shows, from the side, strands started on the back three quarters of the head, "
        "bent back and down over it 0.1 above its surface (the drape), and then hanging; a collision pass "
        "puts back what went inside",
    ),
    (
        "fig2_rendered.png",
        "Fig. 2, hair after wind",
        "its Fig. 2 shows the same hair after the wind, which blows from the face (+z): each strand turned "
        "toward the back and up, the tip most, then the collision pass again",
    ),
)


def _image_line(path, out_dir, alt):
    return f"![{alt}]({Path(path).relative_to(out_dir)})"


def paper_lines(state, out_dir):
    """Fig. 1 (after init + collide) and Fig. 2 (the last frame, after wind + collide) of a
    paper-scene state, drawn from the side and three-quarters, beside the paper's words."""
    lines = ["## The paper's Fig. 1 and Fig. 2, rendered", ""]
    why = context.unavailable()
    if why or state is None or not Path(state).exists():
        return lines + [f"Not rendered: {why or 'no figure state (the paper sweep makes it)'}.", ""]
    out_dir = Path(out_dir)
    with open_trajectory(state) as traj, Renderer(*FIG_SIZE) as r:
        every = np.arange(traj.n_strands)
        frames = {
            "fig1_rendered.png": traj.stages.index("collide") if "collide" in traj.stages else 0,
            "fig2_rendered.png": traj.n_frames - 1,
        }
        for name, title, words in PAPER_FIGURES:
            f = frames[name]
            images = [command.draw_frames(traj, r, [f], v, every)[0] for v in ("side", "three-quarter")]
            sheet = output.side_by_side(images, ("side, the face to the right", "three-quarter"))
            output.write_png(sheet, out_dir / name)
            done = " + ".join(traj.stages[: f + 1])
            lines += [
                f"**{title}** ({words}). Ours: frame {f} of `{display(state)}` ({traj.n_strands:,} strands, "
                f"after {done}):",
                "",
                _image_line(out_dir / name, out_dir, title),
                "",
            ]
    lines += [f"Drawn on {context.describe()} (`python -m harness render`).", ""]
    return lines


def _record(root):
    path = Path(root) / "renders" / "renders.json"
    return (json.loads(path.read_text()), path.parent) if path.exists() else (None, path.parent)


def _frame_at(traj, t):
    sim = traj.simulated
    return sim[int(np.argmin(np.abs(traj.time[sim] - t)))]


def motion_lines(traj, out_dir):
    """The animation and the hero frame of the default scene's state."""
    every = np.arange(traj.n_strands)
    with Renderer(*ANIMATION_SIZE) as r:
        frames = command.animation_frames(traj)
        images = command.draw_frames(traj, r, frames, "three-quarter", every, captions=True)
        movies = output.write_animation(images, out_dir / ANIMATION, command.frame_rate(traj, frames))
    with Renderer(*HERO_SIZE) as r:
        hero = _frame_at(traj, HERO_TIME)
        output.write_png(command.draw_frames(traj, r, [hero], "three-quarter", every)[0], out_dir / HERO)
    return [
        f"{traj.n_strands:,} strands × {traj.points} points of the default scene, {len(frames)} frames of "
        f"{traj.time[traj.simulated[-1]]:.2f} s, from three-quarters"
        + (f" (also as [MP4]({movies[1].name}))" if len(movies) > 1 else "")
        + ":",
        "",
        _image_line(out_dir / ANIMATION, out_dir, "the default dynamic scene, rendered"),
        "",
        f"The frame at t = {traj.time[hero]:.3f} s ([{HERO}]({HERO})):",
        "",
        _image_line(out_dir / HERO, out_dir, "hair"),
        "",
    ]


def mode_lines(record, folder, out_dir):
    """Per use, its recommended modes' last frames beside the reference's, one camera for all."""
    ref = record.get("reference")
    if not record.get("modes") or not ref:
        return ["No accuracy modes drawn: the dynamic accuracy study has no results here.", ""]
    uses = {}
    for m in record["modes"]:
        for p in m["picks"]:
            uses.setdefault(p["use"], []).append((m["state"], p))
    ref_label = f"reference {ref['solver']} {ref['precision']} S{ref['substeps']} I{ref['iterations']}"
    lines = [
        f"Each use's mode (the cheapest that meets its budgets, as the study recommends; the most accurate where "
        f"none does) beside the {'converged ' if ref['converged'] else ''}reference at the same time, "
        f"t = {ref['horizon_frames']} frames (the study's horizon), {record['mode_strands']:,} strands on the C "
        "reference with each mode's settings, seen from the side:",
        "",
    ]
    with Renderer(*MODE_SIZE) as r:
        trajs = {s: open_trajectory(folder / s) for s in {s for v in uses.values() for s, _ in v} | {ref["state"]}}
        try:
            every = np.arange(trajs[ref["state"]].n_strands)
            last = {s: t.n_frames - 1 for s, t in trajs.items()}
            cam = command.camera_for(r, "side", [command.frame_cloud(t, last[s], every) for s, t in trajs.items()])
            for use, picks in uses.items():
                states = list(dict.fromkeys(s for s, _ in picks))
                captions = [
                    " / ".join(p["mode"] + ("" if p["meets"] else " (meets none)") for s2, p in picks if s2 == s)
                    for s in states
                ]
                images = [command.draw(trajs[s], r, last[s], every, cam) for s in [*states, ref["state"]]]
                name = f"dynamic_accuracy_render_{use}.png"
                output.write_png(output.side_by_side(images, [*captions, ref_label]), out_dir / name)
                lines += [f"**{use}**:", "", _image_line(out_dir / name, out_dir, f"{use} against the reference"), ""]
        finally:
            for t in trajs.values():
                t.close()
    return lines


WORLD_SIZE = (420, 520)


def world_lines(record, folder, out_dir):
    """The grid's and the body's effect (docs/model.md §3.16, §3.17): the same last frame with
    and without them, and the hair's volume, envelope, close pairs, stretch and penetration."""
    from harness.check.hair_volume_dynamic import frame_volume

    runs = record.get("world") or []
    if not runs:
        return ["Not drawn: these states predate the grid and the body.", ""]
    trajs = [(label, open_trajectory(folder / state)) for label, state in runs]
    try:
        rows = ["| run | hair volume (cm³) | envelope radius (cm) | close pairs | stretch max | penetration max (cm) |",
                "| --- | --- | --- | --- | --- | --- |"]  # fmt: skip
        for label, t in trajs:
            f = t.n_frames - 1
            v = frame_volume(t, f)
            obs = t.observables.iloc[-1]
            rows.append(f"| {label} | {v['hair_volume']:.0f} | {v['envelope_radius']:.2f} | {v['close_pairs']} | "
                        f"{float(obs['stretch_max']):.3g} | {float(obs['penetration_max']):.3g} |")  # fmt: skip
        with Renderer(*WORLD_SIZE) as r:
            every = np.arange(trajs[0][1].n_strands)
            last = [t.n_frames - 1 for _, t in trajs]
            cam = command.camera_for(r, "front", [command.frame_cloud(t, f, every) for (_, t), f in zip(trajs, last)])
            images = [command.draw(t, r, f, every, cam) for (_, t), f in zip(trajs, last)]
            name = "dynamic_world_render.png"
            output.write_png(output.side_by_side(images, [label for label, _ in trajs]), out_dir / name)
        t0 = trajs[0][1]
        return [
            f"The same {t0.n_strands:,} strands at t = {t0.time[t0.n_frames - 1]:.2f} s of the default scene, "
            "with the hair-hair grid (32³, friction and volume, rebuilt once a frame) and on the body of "
            "configs/scenes/body.toml with the grid, from the front; the hair's volume (distinct 1-cm cells of "
            "the head frame holding a point), its envelope (the tips' 90th-percentile distance from the head's "
            "centre) and the close pairs (segment pairs of 256 sampled strands closer than 0.05 cm) at that "
            "frame (docs/model.md §3.16; their cost is in the feature-cost table above):",
            "",
            *rows,
            "",
            _image_line(out_dir / name, out_dir, "the default scene, with the grid, on the body"),
            "",
        ]
    finally:
        for _, t in trajs:
            t.close()


def dynamic_lines(root, out_dir):
    """The dynamic report's rendered section from ROOT/renders/renders.json."""
    lines = ["## The hair, rendered", ""]
    record, folder = _record(root)
    why = context.unavailable()
    if why or record is None:
        return lines + [f"Not rendered: {why or f'no {display(folder)}/renders.json (make bench makes it)'}.", ""]
    out_dir = Path(out_dir)
    with open_trajectory(folder / record["dynamic"]) as traj:
        lines += motion_lines(traj, out_dir)
    lines += ["### The accuracy recommendations, seen", ""] + mode_lines(record, folder, out_dir)
    lines += ["### Hair that touches hair, on a body", ""] + world_lines(record, folder, out_dir)
    lines += [f"Drawn on {context.describe()} from the states in `{display(folder)}` (made by `make bench`).", ""]
    return lines
