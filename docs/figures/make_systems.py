"""Make the "Which system when" comparison: the demo's scene under each shadow system.

Run from the repository root and commit the PNG (needs the ``render`` extra, an
OpenGL context and, for the WebGPU panel, a WebGPU adapter; Mesa's llvmpipe is
enough for both):

    .venv/bin/python docs/figures/make_systems.py

Each panel is ``python -m shadowmath --method ...`` at 384x288 with the default
256x256 maps; the script also prints each run's median wall time over three runs
(the whole demo call: fitting, drawing and reading back; llvmpipe, so a rough
relative cost only).
"""

from __future__ import annotations

import contextlib
import io
import statistics
import tempfile
import time
from pathlib import Path

from PIL import Image, ImageDraw

from shadowmath.__main__ import main as demo

IMAGES = Path(__file__).resolve().parent.parent / "images"
SIZE = ("384", "288")

#: (caption, demo options) per panel, in the order of docs/systems.md.
PANELS = [
    ("planar (Blinn)", ["--method", "planar"]),
    ("texture (Nagy)", ["--method", "texture"]),
    ("depth (Williams)", ["--method", "depth"]),
    ("depth, --pcf 2", ["--method", "depth", "--pcf", "2"]),
    ("omni (cube map)", ["--method", "omni"]),
    ("depth, --api webgpu", ["--method", "depth", "--api", "webgpu"]),
    ("soft, 1x1 light, 64 samples", ["--method", "soft", "--samples", "64"]),
    ("radiance, 1x1 light, 64 samples", ["--method", "radiance", "--samples", "64"]),
]


def label(image: Image.Image, text: str) -> Image.Image:
    """The image under a caption strip: the caption covers none of its pixels."""
    strip = 20
    labelled = Image.new("RGB", (image.width, image.height + strip), (255, 255, 255))
    labelled.paste(image, (0, strip))
    ImageDraw.Draw(labelled).text((5, 4), text, fill=(0, 0, 0))
    return labelled


def grid(images: list[Image.Image], columns: int) -> Image.Image:
    w, h = images[0].width, images[0].height
    rows = -(-len(images) // columns)
    sheet = Image.new("RGB", (w * columns, h * rows), (255, 255, 255))
    for i, im in enumerate(images):
        sheet.paste(im, ((i % columns) * w, (i // columns) * h))
    return sheet


def main() -> None:
    panels = []
    with tempfile.TemporaryDirectory() as tmp_name:
        out = Path(tmp_name) / "panel.png"
        for caption, args in PANELS:
            seconds = []
            for _ in range(3):
                start = time.perf_counter()
                with contextlib.redirect_stdout(io.StringIO()):
                    demo(["--size", *SIZE, "--output", str(out), *args])
                seconds.append(time.perf_counter() - start)
            print(f"{caption}: {1000 * statistics.median(seconds):.0f} ms")
            panels.append(label(Image.open(out).convert("RGB"), caption))
    path = IMAGES / "systems.png"
    grid(panels, 4).save(path, optimize=True)  # full RGB: a palette would band the gradients
    print(path)


if __name__ == "__main__":
    main()
