"""Make the cube-map seam picture: LINEAR comparison filtering, seamless or not, and NEAREST.

Run from the repository root and commit the PNG (needs the ``render`` extra and an
OpenGL context; Mesa's llvmpipe through EGL is enough):

    .venv/bin/python docs/figures/make_cube_seams.py

The room of ``make_omni_soft.py`` (a point light, bodies on its six sides), one view,
128² faces, drawn three times by ``method="omni"`` with the omni pass's ``filter`` and
``seamless`` options (``OmniPass``; ``render_scene`` does not take them, so the script
swaps the pass in). The second row marks in red the pixels whose shadow differs from
the ray caster (``shadowmath.groundtruth``) away from shadow and terminator edges, and
counts those within a texel and a half of a face edge: the seam speckles. It prints the
counts.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any
from unittest import mock

import numpy as np
from numpy.lib.stride_tricks import sliding_window_view
from PIL import Image, ImageDraw

import shadowmath as sm
from shadowmath.groundtruth import segment_hits_triangles
from shadowmath.meshes import box, sphere, torus
from shadowmath.render import Body, Frame, Light, look_at, perspective, render_scene
from shadowmath.render._pass_omni import OmniPass
from shadowmath.render._scene import PASSES

IMAGES = Path(__file__).resolve().parent.parent / "images"
SIZE = (320, 240)
MAP_SIZE = 128
LIGHT = np.array([0.3, -0.2, 0.1])
#: Pixels within this many (Chebyshev) of a shadow or terminator edge are not counted,
#: as in the render tests (``tests/render/depth_scenes.py``).
BAND = 2
#: The ray caster's segments start this far off the surface along its normal.
LIFT = 1e-4

PANELS = {
    "LINEAR, seamless (moderngl's default)": {"filter": "linear", "seamless": True},
    "LINEAR, not seamless": {"filter": "linear", "seamless": False},
    "NEAREST (the renderer's default)": {"filter": "nearest"},
}


def place(translation: Any, rotation: Any = None) -> np.ndarray:
    m = np.eye(4)
    if rotation is not None:
        m[:3, :3] = rotation
    m[:3, 3] = translation
    return m


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


def room() -> tuple[list[Body], np.ndarray]:
    """The bodies (the room first) and the camera of ``make_omni_soft.py``'s first view."""
    X, Y, Z = np.eye(3)
    v, t = box((8.0, 7.0, 6.0))
    walls = Body(v, t[:, ::-1], color=(0.85, 0.85, 0.85))  # turned inside out: faces inward
    blockers = [
        Body(*box((0.3, 0.7, 0.6)), to_world=place(LIGHT + X), color=(0.9, 0.4, 0.2)),
        Body(*sphere(0.35), to_world=place(LIGHT - X), color=(0.3, 0.6, 0.9)),
        Body(*torus(0.4, 0.12), to_world=place(LIGHT + 1.2 * Y, np.eye(3)[[0, 2, 1]]),
             color=(0.4, 0.8, 0.4)),
        Body(*box((0.7, 0.3, 0.6)), to_world=place(LIGHT - 1.2 * Y), color=(0.9, 0.8, 0.3)),
        Body(*torus(0.45, 0.1), to_world=place(LIGHT + 1.4 * Z), color=(0.8, 0.4, 0.8)),
        Body(*box((0.7, 0.5, 0.3)), to_world=place(LIGHT - 1.4 * Z), color=(0.9, 0.4, 0.2)),
    ]  # fmt: skip
    camera = perspective(100.0, SIZE[0] / SIZE[1], 0.05, 30.0) @ look_at(
        (-3.6, -3.1, -2.6), (1.0, 1.0, 1.0), (0, 0, 1)
    )
    return [walls, *blockers], camera


def edge_band(image: np.ndarray) -> np.ndarray:
    padded = np.pad(image, BAND, mode="edge")
    windows = sliding_window_view(padded, (2 * BAND + 1, 2 * BAND + 1))
    return windows.any(axis=(-2, -1)) != windows.all(axis=(-2, -1))


def speckles(frame: Frame, bodies: list[Body]) -> np.ndarray:
    """Pixels off the band around shadow and terminator edges whose mask differs from the
    ray caster at all (any shadow on a lit point, less than full shadow on a shadowed one)."""
    on = frame.body >= 0
    p = frame.position[on].astype(np.float64)
    n = frame.normal[on].astype(np.float64)
    facing = np.sum(n * (LIGHT - p), axis=1) > 0
    blocked = np.zeros(len(p), dtype=bool)
    for b in bodies:
        m = np.eye(4) if b.to_world is None else np.asarray(b.to_world)
        v = np.asarray(b.vertices, dtype=np.float64) @ m[:3, :3].T + m[:3, 3]
        blocked |= segment_hits_triangles(p + LIFT * n, LIGHT, v, b.triangles)
    shadow = np.zeros(on.shape, dtype=bool)
    shadow[on] = blocked & facing
    dark = np.zeros(on.shape, dtype=bool)
    dark[on] = blocked | ~facing
    band = edge_band(shadow) | edge_band(dark) | edge_band(on)
    mask = frame.shadow[..., 0]
    wrong = np.where(shadow, mask < 1.0, mask > 0.0)
    result: np.ndarray = on & ~band & wrong
    return result


def main() -> None:
    bodies, camera = room()
    pictures, marked = [], []
    for caption, options in PANELS.items():
        with mock.patch.dict(PASSES, {"omni": lambda o, kw=options: OmniPass(o.depth_bias, **kw)}):
            frame = render_scene(
                bodies[:1], bodies[1:], [Light(LIGHT)], camera, image_size=SIZE,
                map_size=MAP_SIZE, method="omni", ambient=0.2,
            )  # fmt: skip
        color = np.round(np.clip(frame.color, 0, 1) * 255).astype(np.uint8)
        wrong = speckles(frame, bodies)
        # Within a texel and a half of a face edge (cube_face's s, t): on a seam.
        _, s, t = sm.cube_face(frame.position[wrong].astype(np.float64) - LIGHT)
        seams = int(np.sum(np.minimum.reduce([s, 1 - s, t, 1 - t]) * MAP_SIZE < 1.5))
        visible = int((frame.body >= 0).sum())
        print(f"{caption}: {int(wrong.sum())} of {visible} pixels differ, {seams} on seams")
        pictures.append(label(Image.fromarray(color), caption))
        gray = np.repeat(np.mean(color, axis=-1, keepdims=True) * 0.5 + 96, 3, axis=-1)
        gray[wrong] = (230, 0, 0)
        marked.append(
            label(
                Image.fromarray(gray.astype(np.uint8)),
                f"differs from the ray caster: {int(wrong.sum())} px, {seams} on seams",
            )
        )
    path = IMAGES / "omni_seams.png"
    sheet([pictures, marked]).save(path, optimize=True)
    print(path, f"{path.stat().st_size / 1024:.0f} kB")


if __name__ == "__main__":
    main()
