"""Make the gallery's pictures with the reference renderer (the demo's scene).

Run from the repository root and commit the PNGs (needs the ``render`` extra and
an OpenGL context; Mesa's llvmpipe through EGL is enough):

    .venv/bin/python docs/figures/make_gallery.py
"""

from __future__ import annotations

import contextlib
import io
import tempfile
from pathlib import Path

import numpy as np
from PIL import Image, ImageDraw

from shadowmath.__main__ import main as demo

IMAGES = Path(__file__).resolve().parent.parent / "images"
SIZE = ("384", "288")


def render(tmp: Path, name: str, *args: str) -> tuple[Image.Image, Image.Image | None]:
    """Run the demo quietly with ``args``; return its picture and its shadow map, if any.

    Planar shadows draw no map, and the demo refuses ``--shadow-map-output`` for them.
    """
    out, shadow_map = tmp / f"{name}.png", tmp / f"{name}_map.png"
    planar = "planar" in args
    map_args = [] if planar else ["--shadow-map-output", str(shadow_map)]
    with contextlib.redirect_stdout(io.StringIO()):
        demo(["--size", *SIZE, "--output", str(out), *map_args, *args])
    picture = Image.open(out).convert("RGB")
    return picture, None if planar else Image.open(shadow_map).convert("RGB")


def label(image: Image.Image, text: str) -> Image.Image:
    """The image under a caption strip: the caption covers none of its pixels."""
    strip = 20
    labelled = Image.new("RGB", (image.width, image.height + strip), (255, 255, 255))
    labelled.paste(image, (0, strip))
    ImageDraw.Draw(labelled).text((5, 4), text, fill=(0, 0, 0))
    return labelled


def grid(rows: list[list[Image.Image]]) -> Image.Image:
    w = max(im.width for row in rows for im in row)
    h = max(im.height for row in rows for im in row)
    sheet = Image.new("RGB", (w * max(len(r) for r in rows), h * len(rows)), (255, 255, 255))
    for i, row in enumerate(rows):
        for j, im in enumerate(row):
            sheet.paste(im, (j * w, i * h))
    return sheet


def save(image: Image.Image, name: str) -> None:
    path = IMAGES / name
    # Full RGB: a palette of 256 colours would band the lit gradients.
    image.save(path, optimize=True)
    print(path)


def main() -> None:
    with tempfile.TemporaryDirectory() as tmp_name:
        tmp = Path(tmp_name)
        pictures, maps = [], []
        for size in (16, 32, 64, 256):
            picture, shadow_map = render(tmp, f"size{size}", "--map-size", str(size))
            assert shadow_map is not None
            # Show every map at the same size, texels as blocks (nearest neighbour).
            big = shadow_map.resize((int(SIZE[1]), int(SIZE[1])), Image.Resampling.NEAREST)
            edge = np.asarray(shadow_map.convert("L"))
            border = np.concatenate([edge[0], edge[-1], edge[:, 0], edge[:, -1]])
            assert border.min() == border.max(), f"{size}x{size}: the border was drawn"
            maps.append(label(big, f"{size}x{size} map, border empty"))
            pictures.append(label(picture, f"map {size}x{size}"))
        save(grid([pictures[:2], pictures[2:], maps[:2], maps[2:]]), "gallery_sizes.png")
        texture, _ = render(tmp, "texture")
        planar, _ = render(tmp, "planar", "--method", "planar")
        save(
            grid([[label(texture, "projective texture (Nagy)"), label(planar, "planar (Blinn)")]]),
            "gallery_methods.png",
        )


if __name__ == "__main__":
    main()
