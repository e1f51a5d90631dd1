"""Images out: PNG frames (Pillow) and animations, a GIF always and an MP4 beside it where
ffmpeg is on PATH (harness/core/encode.py). Each file is written through harness/io/files.py,
so an error leaves nothing behind; `refuse_existing` is called before any drawing, so a run
that would replace a file without --force writes nothing at all."""

import shutil
from pathlib import Path

import numpy as np

from harness import HarnessError
from harness.core import encode
from harness.core.paths import display
from harness.io import files

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
    """write(tmp) fills a temporary beside `path` (harness/io/files.py), moved over it after."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    with files.writing(path) as tmp:
        write(tmp)
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
    """H.264 through ffmpeg (harness/core/encode.py), whole or not at all."""
    return _atomic(path, lambda tmp: encode.mp4(frames, tmp, fps, name=display(path)))


def write_animation(frames, gif, fps):
    """The GIF and, where ffmpeg is on PATH, the MP4 beside it; the paths written."""
    out = [write_gif(frames, gif, fps)]
    if len(animation_paths(gif)) > 1:
        out.append(write_mp4(frames, Path(gif).with_suffix(".mp4"), fps))
    return out
