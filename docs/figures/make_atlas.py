"""Make the atlas figure: the demo's many-light scene and its shadow atlas, side by side.

Run from the repository root and commit the PNG (needs the ``render`` extra and an
OpenGL context; Mesa's llvmpipe is enough):

    .venv/bin/python docs/figures/make_atlas.py

Both panels come from one ``python -m shadowmath --method atlas --pcf 1
--shadow-map-output`` run at 512x400 with the default 24 lights and 4096x4096 atlas: on
the left the picture, on the right the atlas (each tile's depths from black, near, to
light grey, far; outlined in orange), scaled to the picture's height. Writes
``docs/figures/atlas.png``.
"""

from __future__ import annotations

import contextlib
import io
import sys
import tempfile
from pathlib import Path

from PIL import Image

from shadowmath.__main__ import main as demo

FIGURES = Path(__file__).resolve().parent
SIZE = ("512", "400")

sys.path.insert(0, str(FIGURES))
from make_cascades import label  # noqa: E402  (the same caption strip)


def main() -> None:
    with tempfile.TemporaryDirectory() as tmp:
        picture, atlas = Path(tmp) / "picture.png", Path(tmp) / "atlas.png"
        args = ["--method", "atlas", "--pcf", "1", "--size", *SIZE, "--output", str(picture),
                "--shadow-map-output", str(atlas)]  # fmt: skip
        with contextlib.redirect_stdout(io.StringIO()):
            demo(args)
        side = int(SIZE[1])
        tiles = Image.open(atlas).convert("RGB").resize((side, side), Image.Resampling.BOX)
        panels = [
            label(Image.open(picture).convert("RGB"), "--method atlas: 24 lights"),
            label(tiles, "their 64 tiles in one 4096^2 atlas"),
        ]
    sheet = Image.new("RGB", (sum(p.width for p in panels) + 6, panels[0].height), "white")
    sheet.paste(panels[0], (0, 0))
    sheet.paste(panels[1], (panels[0].width + 6, 0))
    out = FIGURES / "atlas.png"
    sheet.save(out, optimize=True)
    print(f"wrote {out}")


if __name__ == "__main__":
    main()
