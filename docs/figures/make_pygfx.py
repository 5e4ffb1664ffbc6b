"""Make the pygfx figure: pygfx's default shadow cameras beside shadowmath's fits.

Run from the repository root and commit the PNG (needs the ``pygfx`` extra and a wgpu
adapter; Mesa's llvmpipe Vulkan driver is enough):

    .venv/bin/python docs/figures/make_pygfx.py

Renders the scenes of ``tests/render/test_pygfx.py`` with pygfx (offscreen, 400x300, its
default anti-aliasing), once with pygfx's own shadow cameras and once after
``shadowmath.integrations.pygfx.set_shadow_camera``, side by side, one row per scene
(a sun, a spot light, and a point light whose shadow falls toward +Y).
Prints the texel-size table of ``docs/pygfx.md`` (the median world size of a shadow-map
texel on the shadowed receiver points, measured as in the test). Writes
``docs/figures/pygfx.png``.
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
import pygfx as gfx
from PIL import Image, ImageDraw
from rendercanvas.offscreen import RenderCanvas

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT))

from tests.render.test_pygfx import FRUSTUM_SCENES, SCENES, fit, pygfx_scene, texel_sizes  # noqa: E402

FIGURE = ROOT / "docs" / "figures" / "pygfx.png"
SIZE = (400, 300)
ROWS = ["torus, sun", "box, spot", "box, point toward +y"]
COLORS = ["#b8c4d0", "#d07040"]  # floor, caster


def render(canvas: RenderCanvas, renderer: gfx.WgpuRenderer, name: str, fitted: bool) -> Image:
    world, camera, light = pygfx_scene(SCENES[name], fitted=fitted)
    light.intensity = 1.5  # the test's brighter light only serves its 8-bit comparison
    meshes = [ob for ob in world.children if isinstance(ob, gfx.Mesh)]
    for mesh, color in zip(meshes, COLORS, strict=True):
        mesh.material.color = color
    world.add(gfx.AmbientLight(intensity=0.3))
    canvas.request_draw(lambda: renderer.render(world, camera))
    return Image.fromarray(np.asarray(canvas.draw())[..., :3])


def label(image: Image.Image, text: str) -> Image.Image:
    draw = ImageDraw.Draw(image)
    draw.rectangle((0, 0, image.width, 18), fill=(255, 255, 255))
    draw.text((6, 3), text, fill=(0, 0, 0))
    return image


def main() -> None:
    canvas = RenderCanvas(size=SIZE, pixel_ratio=1)
    renderer = gfx.renderers.WgpuRenderer(canvas, pixel_scale=1)
    figure = Image.new("RGB", (2 * SIZE[0] + 6, len(ROWS) * (SIZE[1] + 6) - 6), "white")
    for row, name in enumerate(ROWS):
        if SCENES[name].kind == "point":  # the texels are pygfx's; the faces and range differ
            near = float(fit(SCENES[name]).near)
            what = [("pygfx default", "near 0.5, +Y face aimed down -Z"),
                    ("shadowmath fit", f"near {near:.3g}, +Y face turned")]  # fmt: skip
        else:
            sizes = texel_sizes(SCENES[name])
            what = [
                (w, f"texel {size:.3g}")
                for w, size in zip(("pygfx default", "shadowmath fit"), sizes, strict=True)
            ]
        panels = [
            label(render(canvas, renderer, name, fitted), f"{name}: {who}, {detail}")
            for fitted, (who, detail) in zip((False, True), what, strict=True)
        ]
        for col, panel in enumerate(panels):
            figure.paste(panel, (col * (SIZE[0] + 6), row * (SIZE[1] + 6)))
    figure.save(FIGURE, optimize=True)
    print(f"wrote {FIGURE.relative_to(ROOT)}")
    print("| scene | pygfx default | shadowmath fit | sharper |")
    print("| --- | ---: | ---: | ---: |")
    for name in FRUSTUM_SCENES:
        default, fitted = texel_sizes(SCENES[name])
        print(f"| {name} | {default:.4g} | {fitted:.4g} | {default / fitted:.1f}x |")


if __name__ == "__main__":
    main()
