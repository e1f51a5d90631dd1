"""Images out: PNG frames (Pillow) and animations, a GIF always and an MP4 beside it where
ffmpeg is on PATH. Each file is written under a temporary name in its directory and renamed,
so an error leaves nothing behind; `refuse_existing` is called before any drawing, so a run
that would replace a file without --force writes nothing at all."""

import os
import shutil
import subprocess
from pathlib import Path

import numpy as np

from harness import HarnessError
from harness.core.paths import display

MAX_GIF_FPS = 50  # GIF delays are whole hundredths of a second


def animation_paths(gif):
    """The files an animation writes: the GIF, and an MP4 beside it where ffmpeg is on PATH."""
    gif = Path(gif)
    return [gif, gif.with_suffix(".mp4")] if shutil.which("ffmpeg") else [gif]


def refuse_existing(paths, force):
    """One line for a path that exists (without `force`) or is a directory."""
    for p in map(Path, paths):
        if p.is_dir():
            raise HarnessError(f"render: {display(p)} is a directory")
        if (p.exists() or p.is_symlink()) and not force:
            raise HarnessError(f"render: {display(p)} exists (use --force to replace it)")


def _atomic(path, write):
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_name(f".{path.stem}.tmp.{os.getpid()}{path.suffix}")
    try:
        write(tmp)
        os.replace(tmp, path)
    finally:
        if tmp.exists():
            tmp.unlink()
    return path


def write_png(image, path):
    from PIL import Image

    return _atomic(path, lambda tmp: Image.fromarray(np.asarray(image, np.uint8)).save(tmp, format="PNG"))


def captioned(image, text):
    """The image with one line of text in its top-left corner (Pillow's default font)."""
    from PIL import Image, ImageDraw

    im = Image.fromarray(np.asarray(image, np.uint8))
    ImageDraw.Draw(im).text((8, 6), text, fill=(40, 40, 40))
    return np.asarray(im)


def side_by_side(images, captions=(), gap=6, caption_px=18):
    """One image of equally tall images in a row, each captioned below (Pillow's default font)."""
    from PIL import Image, ImageDraw

    h = max(np.shape(i)[0] for i in images)
    w = sum(np.shape(i)[1] for i in images) + gap * (len(images) - 1)
    sheet = Image.new("RGB", (w, h + (caption_px if captions else 0)), (255, 255, 255))
    x = 0
    draw = ImageDraw.Draw(sheet)
    for k, img in enumerate(images):
        sheet.paste(Image.fromarray(np.asarray(img, np.uint8)), (x, 0))
        if k < len(captions):
            draw.text((x + 4, h + 3), captions[k], fill=(30, 30, 30))
        x += np.shape(img)[1] + gap
    return np.asarray(sheet)


def write_gif(frames, path, fps):
    from PIL import Image

    fps = max(1, min(MAX_GIF_FPS, int(fps)))
    images = [Image.fromarray(np.asarray(f, np.uint8)) for f in frames]
    # an adaptive palette shared by all frames: hair tones need more than the web palette
    palette = images[len(images) // 2].quantize(colors=255, method=Image.Quantize.MEDIANCUT)
    paletted = [im.quantize(palette=palette, dither=Image.Dither.NONE) for im in images]

    def save(tmp):
        paletted[0].save(
            tmp, format="GIF", save_all=True, append_images=paletted[1:], duration=round(1000 / fps), loop=0
        )

    return _atomic(path, save)


def write_mp4(frames, path, fps):
    """H.264 through ffmpeg, the frames piped as raw RGB (even sizes, as yuv420p needs)."""
    h, w = np.shape(frames[0])[:2]
    h2, w2 = h - h % 2, w - w % 2

    def encode(tmp):
        cmd = ["ffmpeg", "-loglevel", "error", "-y", "-f", "rawvideo", "-pix_fmt", "rgb24", "-s", f"{w2}x{h2}"]
        cmd += ["-r", str(fps), "-i", "-", "-pix_fmt", "yuv420p", "-c:v", "libx264", "-f", "mp4", str(tmp)]
        data = b"".join(np.ascontiguousarray(np.asarray(f, np.uint8)[:h2, :w2]).tobytes() for f in frames)
        done = subprocess.run(cmd, input=data, capture_output=True)
        if done.returncode:
            why = done.stderr.decode(errors="replace").strip().splitlines()
            raise HarnessError(
                f"render: ffmpeg could not write {display(path)} ({why[-1] if why else done.returncode})"
            )

    return _atomic(path, encode)


def write_animation(frames, gif, fps):
    """The GIF and, where ffmpeg is on PATH, the MP4 beside it; the paths written."""
    out = [write_gif(frames, gif, fps)]
    if len(animation_paths(gif)) > 1:
        out.append(write_mp4(frames, Path(gif).with_suffix(".mp4"), fps))
    return out
