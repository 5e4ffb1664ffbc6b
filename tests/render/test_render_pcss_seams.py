"""No seam where PCSS changes cube face: a point light 1.5 above the floor's origin
(``SEAM_LIGHT``, radius 0.25) and a long bar at height 0.7 (``CASTERS["bar"]``) whose
shadow runs along ``x`` across the floor line ``x = 1.5``, where the face a floor point
samples (the largest component of ``r = p - light``) turns from ``-Z`` to ``+X``. The
shadow's two edges run along ``x``, so the truth barely changes from one column to the
next: what changes across the line is the face, its ``K`` and its texels.

Seen from above (96 pixels over the floor's square ``[1, 2] x [0.05, 1.05]``, the line
between columns 47 and 48), the pixels beside each other across the line are compared
in the rows where either is in the truth's penumbra (the shadow's edge away from the
light; the bar hides the other), through the cube pass
(``render_scene(method="omni")``) and the atlas's six face tiles (``render_atlas``).

The bound is the kernel's noise: 64 filter taps of a Vogel disk rotated per pixel, at
most the variance of 64 independent taps, ``v (1 - v) / 64`` at a true visibility ``v``;
two pixels differ by twice that in mean square, plus the truth's own change, its
``1/256`` samples and the disk facing each face (tests/render/pcss_scenes.py). Across
the line, PCSS's error against the truth of each face, and the visibility itself, must
change by no more in mean square than that. A renderer that gives the ``+X`` face a
``K`` 1.5 times too large (the pixels of that face taken from the render of a light
1.5 times wider) fails both by far.
"""

from __future__ import annotations

import functools

import numpy as np
import pytest

import shadowmath as sm
from shadowmath.render import Light, render_atlas, render_scene

from . import pcss_scenes as ps

VIEW = ps.View(1.5, 0.55, 0.5, 96)
LEFT = 47  # the last column on the -Z face; LEFT + 1 is the first on the +X face
AXES = {"-Z": (0.0, 0.0, -1.0), "+X": (1.0, 0.0, 0.0)}


@functools.cache
def truth() -> np.ndarray:
    """The true visibility of each pixel's floor point for the disk facing its face."""
    points = VIEW.floor_points()
    on_x = np.abs(points[..., 0] - ps.SEAM_LIGHT.where[0]) > ps.SEAM_LIGHT.where[2]
    assert not on_x[:, : LEFT + 1].any() and on_x[:, LEFT + 1 :].all()
    faces = {
        name: ps.true_visibility(points.reshape(-1, 3), "bar", ps.SEAM_LIGHT, np.array(axis))
        for name, axis in AXES.items()
    }
    return np.where(on_x, faces["+X"].reshape(on_x.shape), faces["-Z"].reshape(on_x.shape))


def render(method: str, radius: float, gl) -> np.ndarray:
    """PCSS's visible fraction per pixel, NaN where the bar hides the floor."""
    where = ps.SEAM_LIGHT.where
    if method == "omni":
        frame = render_scene(
            [ps.FLOOR], [ps.CASTERS["bar"]], [Light(where)], VIEW.world_to_clip(),
            image_size=VIEW.pixels, map_size=ps.MAP, method="omni", light_size=radius,
            ctx=gl,
        )  # fmt: skip
        shadow = frame.shadow[..., 0]
    else:
        frame = render_atlas(
            [ps.FLOOR, ps.CASTERS["bar"]], [sm.PointLight(np.array(where))], np.eye(4),
            VIEW.world_to_clip(), casters=[False, True], light_size=[radius],
            image_size=VIEW.pixels, atlas_size=4096, ctx=gl,
        )  # fmt: skip
        shadow = frame.shadow[0]
    return np.where(frame.body == 0, 1.0 - shadow.astype(np.float64), np.nan)


class Seam:
    """Mean squares over the penumbra's rows of the changes from column ``c`` to
    ``c + 1``: of PCSS's error (``error``) and its bound (``noise``: the two pixels'
    64-tap variances and the truth's samples), of the visibility (``jump``) and its bound
    (``jump_noise``: the same plus the truth's own change)."""

    def __init__(self, pcss: np.ndarray, c: int) -> None:
        t = truth()
        penumbra = ((t[:, c : c + 2] > 0.02) & (t[:, c : c + 2] < 0.98)).any(axis=1)
        rows = penumbra & ~np.isnan(pcss[:, c : c + 2]).any(axis=1)
        a, b = (slice(None), c), (slice(None), c + 1)
        self.rows = int(rows.sum())
        self.error = float(((pcss[b] - t[b] - pcss[a] + t[a])[rows] ** 2).mean())
        self.jump = float(((pcss[b] - pcss[a])[rows] ** 2).mean())
        taps = (t[a] * (1 - t[a]) + t[b] * (1 - t[b]))[rows].mean() / 64 + 2 / 256**2
        self.noise = float(taps)
        self.jump_noise = float(taps + ((t[b] - t[a])[rows] ** 2).mean())

    def __repr__(self) -> str:
        return (
            f"Seam(rows={self.rows}, error={self.error:.5f}, noise={self.noise:.5f}, "
            f"jump={self.jump:.5f}, jump_noise={self.jump_noise:.5f})"
        )


@pytest.mark.parametrize("method", ["omni", "atlas"])
def test_no_seam_where_the_face_changes(gl, method):
    pcss = render(method, ps.SEAM_LIGHT.size, gl)
    seam = Seam(pcss, LEFT)
    assert seam.rows > 40, seam
    assert seam.error < seam.noise and seam.jump < seam.jump_noise, seam
    for c in (LEFT - 8, LEFT + 8):  # inside a face, the same statistics
        inside = Seam(pcss, c)
        assert inside.error < inside.noise and inside.jump < inside.jump_noise, (c, inside)


@pytest.mark.parametrize("method", ["omni", "atlas"])
def test_a_face_with_the_wrong_k_makes_a_seam(gl, method):
    right = render(method, ps.SEAM_LIGHT.size, gl)
    wide = render(method, 1.5 * ps.SEAM_LIGHT.size, gl)
    mixed = np.where(np.arange(VIEW.pixels) > LEFT, wide, right)
    seam = Seam(mixed, LEFT)
    assert seam.error > 3 * seam.noise and seam.jump > 3 * seam.jump_noise, seam
