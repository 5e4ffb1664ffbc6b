"""Make the pictures of the cube-map and soft-shadow pages with the reference renderer.

Run from the repository root and commit the PNGs (needs the ``render`` extra and an
OpenGL context; Mesa's llvmpipe through EGL is enough):

    .venv/bin/python docs/figures/make_omni_soft.py

The scenes are those of ``tests/render/test_render_omni.py`` and
``tests/render/test_render_soft.py``, drawn larger.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
from PIL import Image, ImageDraw

from shadowmath.meshes import box, grid, sphere, torus
from shadowmath.render import Body, Light, look_at, perspective, radiance_texture, render_scene

IMAGES = Path(__file__).resolve().parent.parent / "images"
SIZE = (384, 288)
FACES = ("+X", "-X", "+Y", "-Y", "+Z", "-Z")


def place(translation: Any, rotation: Any = None) -> np.ndarray:
    m = np.eye(4)
    if rotation is not None:
        m[:3, :3] = rotation
    m[:3, 3] = translation
    return m


def picture(color: np.ndarray) -> Image.Image:
    return Image.fromarray(np.round(np.clip(color, 0, 1) * 255).astype(np.uint8))


def gray(values: np.ndarray) -> Image.Image:
    return Image.fromarray(np.round(np.clip(values, 0, 1) * 255).astype(np.uint8)).convert("RGB")


def label(image: Image.Image, text: str) -> Image.Image:
    """The image under a caption strip: the caption covers none of its pixels."""
    strip = 20
    labelled = Image.new("RGB", (image.width, image.height + strip), (255, 255, 255))
    labelled.paste(image, (0, strip))
    ImageDraw.Draw(labelled).text((5, 4), text, fill=(0, 0, 0))
    return labelled


def sheet(rows: list[list[Image.Image]]) -> Image.Image:
    w = max(im.width for row in rows for im in row)
    h = max(im.height for row in rows for im in row)
    out = Image.new("RGB", (w * max(len(r) for r in rows), h * len(rows)), (255, 255, 255))
    for i, row in enumerate(rows):
        for j, im in enumerate(row):
            out.paste(im, (j * w, i * h))
    return out


def save(image: Image.Image, name: str) -> None:
    path = IMAGES / name
    image.save(path, optimize=True)  # full RGB: a palette would band the gradients
    print(path)


def omni() -> None:
    """A point light in a room with bodies on all six sides: two views, and the cube map."""
    light = np.array([0.3, -0.2, 0.1])
    X, Y, Z = np.eye(3)
    v, t = box((8.0, 7.0, 6.0))
    room = Body(v, t[:, ::-1], color=(0.85, 0.85, 0.85))  # turned inside out: faces inward
    blockers = [
        Body(*box((0.3, 0.7, 0.6)), to_world=place(light + X), color=(0.9, 0.4, 0.2)),
        Body(*sphere(0.35), to_world=place(light - X), color=(0.3, 0.6, 0.9)),
        Body(*torus(0.4, 0.12), to_world=place(light + 1.2 * Y, np.eye(3)[[0, 2, 1]]),
             color=(0.4, 0.8, 0.4)),
        Body(*box((0.7, 0.3, 0.6)), to_world=place(light - 1.2 * Y), color=(0.9, 0.8, 0.3)),
        Body(*torus(0.45, 0.1), to_world=place(light + 1.4 * Z), color=(0.8, 0.4, 0.8)),
        Body(*box((0.7, 0.5, 0.3)), to_world=place(light - 1.4 * Z), color=(0.9, 0.4, 0.2)),
    ]  # fmt: skip
    views = []
    for eye, target, caption in (
        ((-3.6, -3.1, -2.6), (1.0, 1.0, 1.0), "toward +X, +Y, +Z"),
        ((3.6, 3.1, 2.6), (-1.0, -1.0, -1.0), "toward -X, -Y, -Z"),
    ):
        camera = perspective(100.0, SIZE[0] / SIZE[1], 0.05, 30.0) @ look_at(eye, target, (0, 0, 1))
        frame = render_scene(
            [room], blockers, [Light(light)], camera, image_size=SIZE, map_size=512,
            method="omni", ambient=0.2,
        )  # fmt: skip
        views.append(label(picture(frame.color), f"method='omni', view {caption}"))
    save(sheet([views]), "omni_room.png")
    # The six faces as drawn (row 0, t = 0, on top: as each face's camera sees it), their
    # window depths turned back into distances along the face axis and shaded near = dark.
    faces = np.stack(frame.shadow_maps[0])
    # the pass's depth range: far just beyond the farthest vertex (the room's corners)
    far = float(np.abs(v - light).max()) * 1.001
    near = 1e-3 * far
    distance = far * near / (far - faces * (far - near))
    tiles = [
        label(gray(d / far).resize((192, 192), Image.Resampling.NEAREST), f"face {i} ({name})")
        for i, (name, d) in enumerate(zip(FACES, distance, strict=True))
    ]
    save(sheet([tiles[:3], tiles[3:]]), "omni_faces.png")


def soft() -> None:
    """The soft-shadow test scene: 4 to 256 samples, both methods, and the radiance texture."""
    floor = Body(*grid((8.0, 8.0)), plane=(0.0, 0.0, 1.0, 0.0), color=(0.8, 0.8, 0.8))
    occluder = Body(*grid((1.2, 1.2)), to_world=place((0.2, 0.0, 1.5)), color=(0.9, 0.4, 0.2))
    light = Light((0.0, 0.0, 4.0), edge_u=(1.6, 0.0, 0.0), edge_v=(0.0, 1.0, 0.0))
    camera = perspective(50.0, SIZE[0] / SIZE[1], 0.1, 50.0) @ look_at((0, -5, 6), (0, 0, 0),
                                                                      (0, 0, 1))  # fmt: skip
    rows = []
    for method, name in (("soft", "depth maps"), ("radiance", "radiance texture")):
        row = []
        for n in (4, 16, 64, 256):
            frame = render_scene(
                [floor], [occluder], [light], camera, image_size=SIZE, map_size=512,
                method=method, samples=n,
            )  # fmt: skip
            row.append(label(picture(frame.color), f"method='{method}' ({name}), {n} samples"))
        rows.append(row)
    save(sheet(rows), "soft_samples.png")
    # The floor's radiance texture (v upward), and the exact visibility of the light.
    texels = (256, 256)
    vis = radiance_texture((-4, -4, 0), (8, 0, 0), (0, 8, 0), [occluder], light,
                           samples=256, size=texels)  # fmt: skip
    u = (np.arange(256) + 0.5) / 256
    x, y = np.meshgrid(-4 + 8 * u, -4 + 8 * u)
    k = 4.0 / 1.5
    lo_x, hi_x = x + (0.2 - 0.6 - x) * k, x + (0.2 + 0.6 - x) * k
    lo_y, hi_y = y + (-0.6 - y) * k, y + (0.6 - y) * k
    overlap = np.clip(np.minimum(hi_x, 0.8) - np.maximum(lo_x, -0.8), 0, None) * np.clip(
        np.minimum(hi_y, 0.5) - np.maximum(lo_y, -0.5), 0, None
    )
    exact = 1 - overlap / 1.6
    diff = np.abs(vis - exact)
    save(
        sheet([[
            label(gray(vis[::-1]), "radiance_texture, 256 samples"),
            label(gray(exact[::-1]), "exact visibility of the light"),
            label(gray(diff[::-1] * 10), f"|difference| x 10 (max {diff.max():.3f})"),
        ]]),
        "soft_radiance_texture.png",
    )  # fmt: skip


def main() -> None:
    omni()
    soft()


if __name__ == "__main__":
    main()
