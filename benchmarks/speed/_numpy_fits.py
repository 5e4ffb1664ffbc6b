"""The NumPy-alone baseline: a shadow map's fit written by hand in NumPy, one per light kind.

What a user writes instead of ``fit_shadow`` when NumPy is all they have: an OpenGL look-at,
a projection fitted to the blocker's vertices, the options of ``fit_shadow`` they need, and
the graphics API's convention as one constant matrix product. Each returns ``(world_to_clip,
world_to_texture)``: the two matrices a renderer uploads. :func:`check` asserts (once per
benchmark case, not timed) that the matrices are right: every vertex lands inside the NDC
cube, every receiver inside the map inside the depth range, every texture coordinate in
``[0, 1]``.
"""

from __future__ import annotations

import functools
from typing import Any

import numpy as np

AXES = np.eye(3)


@functools.cache
def api_matrices(api: str, reversed_z: bool) -> tuple[np.ndarray, np.ndarray]:
    """The constants a user hard-codes: OpenGL clip to ``api``'s clip, and OpenGL clip to texture.

    Vulkan flips ``y``; every API but OpenGL stores depth in ``[0, 1]``; Direct3D, Metal and
    WebGPU put ``t = 0`` at the top; reversed Z stores ``1`` at near.
    """
    flip = -1.0 if api == "vulkan" else 1.0
    a, b = (1.0, 0.0) if api == "opengl" else (0.5, 0.5)
    a = -a if reversed_z else a
    clip = np.array([[1, 0, 0, 0], [0, flip, 0, 0], [0, 0, a, b], [0, 0, 0, 1]])
    t = -0.5 if api in ("direct3d", "metal", "webgpu") else 0.5
    c, d = (0.5, 0.5) if api == "opengl" else (1.0, 0.0)
    texture = np.array([[0.5, 0, 0, 0.5], [0, t, 0, 0.5], [0, 0, c, d], [0, 0, 0, 1]])
    return clip, texture @ clip


def look_at(forward: np.ndarray, up: Any) -> np.ndarray:
    """OpenGL's look-at rotation (rows ``s, u, -f``): the camera looks down its ``-z``."""
    s = np.cross(forward, up)
    s /= np.linalg.norm(s)
    return np.stack([s, np.cross(s, forward), -forward])


def _api(clip: np.ndarray, api: str, reversed_z: bool) -> tuple[np.ndarray, np.ndarray]:
    to_clip, to_texture = api_matrices(api, reversed_z)
    if api != "opengl" or reversed_z:
        return to_clip @ clip, to_texture @ clip
    return clip, to_texture @ clip


def point_fit(
    light: np.ndarray,
    verts: np.ndarray,
    map_size: int,
    *,
    up: Any = None,
    api: str = "opengl",
    reversed_z: bool = False,
) -> tuple[np.ndarray, np.ndarray]:
    """A point light: look-at the vertices' mean, perspective on the largest ``|x/z|``, ``|y/z|``.

    ``light`` is ``(x, y, z)`` or ``(x, y, z, w)``; without ``up`` the helper axis is the world
    axis least parallel to the viewing direction (Nagy's). One texel of border on each side.
    """
    position = light[:3] / light[3] if light.shape[-1] == 4 else light
    rel = verts - position
    forward = rel.mean(axis=0)
    forward /= np.linalg.norm(forward)
    if up is None:
        up = AXES[np.argmin(np.abs(forward))]
    R = look_at(forward, up)
    p = rel @ R.T
    depth = -p[:, 2]
    k = (map_size - 2) / map_size
    sx = k / np.max(np.abs(p[:, 0]) / depth)
    sy = k / np.max(np.abs(p[:, 1]) / depth)
    n, f = depth.min(), depth.max()
    a, b = (f + n) / (n - f), 2 * f * n / (n - f)
    proj = np.array([[sx, 0, 0, 0], [0, sy, 0, 0], [0, 0, a, b], [0, 0, -1, 0]])
    view = np.eye(4)
    view[:3, :3] = R
    view[:3, 3] = -R @ position
    return _api(proj @ view, api, reversed_z)


def directional_fit(
    light: np.ndarray,
    verts: np.ndarray,
    map_size: int,
    *,
    up: Any = None,
    receivers: np.ndarray | None = None,
    stable: bool = False,
    api: str = "opengl",
    reversed_z: bool = False,
) -> tuple[np.ndarray, np.ndarray]:
    """A directional light ``(x, y, z, 0)``: look-at along ``-xyz``, ortho box of the vertices.

    ``receivers`` inside the box widen the depth range; ``stable`` sizes the box from the
    bounding sphere about the vertices' mean (plus half a texel) and snaps its centre to whole
    texels of a grid fixed in world space. One texel of border on each side.
    """
    forward = -light[:3] / np.linalg.norm(light[:3])
    if up is None:
        up = AXES[np.argmin(np.abs(forward))]
    R = look_at(forward, up)
    p = verts @ R.T
    if stable:
        mean = p.mean(axis=0)
        half = np.sqrt(np.max(np.sum((p - mean) ** 2, axis=1))) * map_size / (map_size - 3)
        texel = 2.0 * half / map_size
        centre = np.round(mean[:2] / texel) * texel
        half = np.array([half, half])
    else:
        lo, hi = p[:, :2].min(axis=0), p[:, :2].max(axis=0)
        centre, half = 0.5 * (lo + hi), 0.5 * (hi - lo) * map_size / (map_size - 2)
    depth = -p[:, 2]
    n, f = depth.min(), depth.max()
    if receivers is not None:
        q = receivers @ R.T
        inside = np.all(np.abs(q[:, :2] - centre) <= half, axis=1)
        if inside.any():
            n, f = min(n, -q[inside, 2].max()), max(f, -q[inside, 2].min())
    proj = np.array(
        [
            [1 / half[0], 0, 0, -centre[0] / half[0]],
            [0, 1 / half[1], 0, -centre[1] / half[1]],
            [0, 0, 2 / (n - f), (f + n) / (n - f)],
            [0, 0, 0, 1],
        ]
    )
    view = np.eye(4)
    view[:3, :3] = R
    return _api(proj @ view, api, reversed_z)


def project(matrix: np.ndarray, points: np.ndarray) -> np.ndarray:
    """``(N, 3)`` points through a ``4 x 4`` matrix, divided by ``w``."""
    h = np.c_[points, np.ones(len(points))] @ np.asarray(matrix).T
    return h[:, :3] / h[:, 3:]


def check(
    fit: tuple[np.ndarray, np.ndarray],
    verts: np.ndarray,
    *,
    api: str = "opengl",
    receivers: np.ndarray | None = None,
    **_: Any,
) -> None:
    """Assert that a fit is right (not timed): vertices inside NDC, texture coordinates in [0, 1].

    ``x, y`` in ``[-1, 1]`` and depth in ``[-1, 1]`` (OpenGL) or ``[0, 1]`` for every vertex;
    the same depth range for every receiver inside the map; ``(s, t, r)`` in ``[0, 1]`` there.
    """
    to_clip, to_texture = fit
    tol = 1e-9
    lo = -1.0 if api == "opengl" else 0.0
    points = verts if receivers is None else np.concatenate([verts, receivers])
    ndc, tex = project(to_clip, points), project(to_texture, points)
    inside = np.all(np.abs(ndc[:, :2]) <= 1 + tol, axis=1)
    assert inside[: len(verts)].all(), f"vertices outside NDC x, y: {ndc[: len(verts)]}"
    depth = ndc[inside, 2]
    assert np.all((depth >= lo - tol) & (depth <= 1 + tol)), f"depth outside range: {depth}"
    assert np.all((tex[inside] >= -tol) & (tex[inside] <= 1 + tol)), f"texture: {tex[inside]}"
