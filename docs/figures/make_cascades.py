"""Make the cascades figure: the demo's large scene, shadowed and with its cascades coloured.

Run from the repository root and commit the PNG (needs the ``render`` extra and an
OpenGL context; Mesa's llvmpipe is enough):

    .venv/bin/python docs/figures/make_cascades.py

Both panels come from one ``python -m shadowmath --method cascades --cascade-colors``
run at 512x320 with the default four 1024x1024 cascades: on the left the shadowed view,
on the right the same view multiplied by each cascade's colour (red, green, blue,
yellow from near to far, mixed across the blend bands). Writes
``docs/figures/cascades.png``.
"""

from __future__ import annotations

import contextlib
import io
import tempfile
from pathlib import Path

from PIL import Image, ImageDraw

from shadowmath.__main__ import main as demo

FIGURES = Path(__file__).resolve().parent
SIZE = ("512", "320")


def label(image: Image.Image, text: str) -> Image.Image:
    """The image under a caption strip: the caption covers none of its pixels."""
    strip = 20
    labelled = Image.new("RGB", (image.width, image.height + strip), (255, 255, 255))
    labelled.paste(image, (0, strip))
    ImageDraw.Draw(labelled).text((5, 4), text, fill=(0, 0, 0))
    return labelled


def main() -> None:
    with tempfile.TemporaryDirectory() as tmp:
        shadowed, colored = Path(tmp) / "shadowed.png", Path(tmp) / "colored.png"
        args = ["--method", "cascades", "--size", *SIZE, "--output", str(shadowed),
                "--cascade-colors", str(colored)]  # fmt: skip
        with contextlib.redirect_stdout(io.StringIO()):
            demo(args)
        panels = [
            label(Image.open(shadowed).convert("RGB"), "--method cascades (4 x 1024^2)"),
            label(Image.open(colored).convert("RGB"), "the cascades: red, green, blue, yellow"),
        ]
    sheet = Image.new("RGB", (sum(p.width for p in panels), panels[0].height), (255, 255, 255))
    for i, panel in enumerate(panels):
        sheet.paste(panel, (i * panels[0].width, 0))
    out = FIGURES / "cascades.png"
    sheet.save(out, optimize=True)
    print(f"wrote {out}")


if __name__ == "__main__":
    main()
