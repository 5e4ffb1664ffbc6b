"""Seeded inputs for the speed benchmarks, and the PyGLM baseline as a user writes it."""

from __future__ import annotations

import math
from typing import Any

import numpy as np

MAP_SIZE = 256


def _rotations(rng: np.random.Generator, n: int) -> np.ndarray:
    """``(n, 3, 3)`` uniformly random rotations (from unit quaternions)."""
    q = rng.standard_normal((n, 4))
    q /= np.linalg.norm(q, axis=1, keepdims=True)
    w, x, y, z = q.T
    return np.stack(
        [
            np.stack([1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)], -1),
            np.stack([2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)], -1),
            np.stack([2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)], -1),
        ],
        -2,
    )


def boxes(n: int, seed: int, dtype: Any = np.float64) -> tuple[np.ndarray, np.ndarray]:
    """``n`` light/blocker pairs: lights ``(n, 3)`` and box corners ``(n, 8, 3)``.

    Boxes of log-uniform side lengths (0.2 to 2) in random orientations around
    random centres; each light in a random direction at 3 to 20 bounding radii.
    """
    rng = np.random.default_rng(seed)
    signs = np.array([[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)], float)
    half = np.exp(rng.uniform(np.log(0.1), 0.0, size=(n, 1, 3)))
    corners = (signs * half) @ np.swapaxes(_rotations(rng, n), -1, -2)
    centres = rng.uniform(-2.0, 2.0, size=(n, 3))
    radius = np.linalg.norm(half[:, 0], axis=-1)
    d = rng.standard_normal((n, 3))
    d /= np.linalg.norm(d, axis=-1, keepdims=True)
    lights = centres + d * (radius * rng.uniform(3.0, 20.0, size=n))[:, None]
    return lights.astype(dtype), (corners + centres[:, None]).astype(dtype)


def blob(n: int, seed: int, dtype: Any = np.float64) -> tuple[np.ndarray, np.ndarray]:
    """A light at the origin and ``n`` vertices on a tilted ellipsoid 10 units away.

    Generated in ``dtype`` directly, so that 4M float32 vertices cost 48 MB only.
    """
    rng = np.random.default_rng(seed)
    v = rng.standard_normal((n, 3), dtype=np.float32 if dtype == np.float32 else np.float64)
    v /= np.linalg.norm(v, axis=1, keepdims=True)
    v *= np.asarray([2.0, 1.0, 0.5], v.dtype)
    rot = _rotations(np.random.default_rng(seed + 1), 1)[0].astype(v.dtype)
    v = v @ rot.T
    v += np.asarray([1.0, 0.5, 10.0], v.dtype)
    return np.zeros(3, dtype), np.ascontiguousarray(v, dtype=dtype)


# ---------------------------------------------------------------------------
# The PyGLM baseline
# ---------------------------------------------------------------------------


def to_glm(light: np.ndarray, vertices: np.ndarray) -> tuple[Any, list[Any]]:
    """The scene as a PyGLM user holds it: a ``vec3`` light and a list of ``vec3`` (not timed)."""
    import glm

    return glm.vec3(*map(float, light)), [glm.vec3(*map(float, v)) for v in vertices]


def glm_fit(light: Any, vertices: list[Any], aspect: float = 1.0) -> Any:
    """What a user writes instead: ``lookAt`` + ``perspective`` on the bounding sphere.

    The sphere is centred on the bounding box (one Python loop), its radius the
    largest distance from that centre (a second loop); the camera at the light
    looks at the centre with the field of view that just contains the sphere.
    """
    import glm

    lo = glm.vec3(vertices[0])
    hi = glm.vec3(vertices[0])
    for v in vertices:
        lo = glm.min(lo, v)
        hi = glm.max(hi, v)
    centre = (lo + hi) * 0.5
    radius = 0.0
    for v in vertices:
        radius = max(radius, glm.distance(v, centre))
    dist = glm.distance(light, centre)
    up = glm.vec3(0.0, 1.0, 0.0)
    if abs(centre.y - light.y) > 0.99 * dist:
        up = glm.vec3(1.0, 0.0, 0.0)
    view = glm.lookAt(light, centre, up)
    fov = 2.0 * math.asin(min(radius / dist, 1.0))
    proj = glm.perspective(fov, aspect, max(dist - radius, 1e-3 * dist), dist + radius)
    return proj * view


def glm_ortho_fit(direction: Any, vertices: list[Any]) -> Any:
    """The directional baseline: ``lookAt`` along ``-direction`` + ``ortho`` on the bounding sphere.

    ``direction`` (a ``vec3``) points toward the light. The sphere is found as in
    :func:`glm_fit` (two Python loops); the camera stands one diameter up-light
    of its centre, and the box just contains the sphere.
    """
    import glm

    lo = glm.vec3(vertices[0])
    hi = glm.vec3(vertices[0])
    for v in vertices:
        lo = glm.min(lo, v)
        hi = glm.max(hi, v)
    centre = (lo + hi) * 0.5
    radius = 0.0
    for v in vertices:
        radius = max(radius, glm.distance(v, centre))
    d = glm.normalize(direction)
    up = glm.vec3(0.0, 1.0, 0.0)
    if abs(d.y) > 0.99:
        up = glm.vec3(1.0, 0.0, 0.0)
    view = glm.lookAt(centre + d * (2.0 * radius), centre, up)
    proj = glm.ortho(-radius, radius, -radius, radius, radius, 3.0 * radius)
    return proj * view


# (direction, up) of the six cube-map faces, +X, -X, +Y, -Y, +Z, -Z (OpenGL's table).
CUBE_FACES = (
    ((1.0, 0.0, 0.0), (0.0, -1.0, 0.0)),
    ((-1.0, 0.0, 0.0), (0.0, -1.0, 0.0)),
    ((0.0, 1.0, 0.0), (0.0, 0.0, 1.0)),
    ((0.0, -1.0, 0.0), (0.0, 0.0, -1.0)),
    ((0.0, 0.0, 1.0), (0.0, -1.0, 0.0)),
    ((0.0, 0.0, -1.0), (0.0, -1.0, 0.0)),
)


def glm_cube(light: Any, near: float, far: float) -> tuple[Any, list[Any]]:
    """A cube shadow map's matrices in PyGLM: one 90° ``perspective`` and six ``lookAt``."""
    import glm

    proj = glm.perspective(0.5 * math.pi, 1.0, near, far)
    views = [glm.lookAt(light, light + glm.vec3(d), glm.vec3(up)) for d, up in CUBE_FACES]
    return proj, views


# ---------------------------------------------------------------------------
# Directional lights and receivers
# ---------------------------------------------------------------------------

SUN = np.array([0.3, 1.0, -0.2, 0.0])
"""The directional light of the single-call benchmarks: ``(x, y, z, 0)``, toward the light."""


def suns(n: int, seed: int, dtype: Any = np.float64) -> np.ndarray:
    """``(n, 4)`` directional lights ``(x, y, z, 0)`` from random directions in the upper half."""
    rng = np.random.default_rng(seed)
    d = rng.standard_normal((n, 3))
    d[:, 1] = np.abs(d[:, 1]) + 0.5
    d /= np.linalg.norm(d, axis=-1, keepdims=True)
    return np.concatenate([d, np.zeros((n, 1))], axis=-1).astype(dtype)


def floor(points: int, *, y: float = -4.0, half: float = 20.0) -> np.ndarray:
    """``(4 + points**2, 3)`` receivers: a square floor's 4 corners and a grid of points on it.

    Below every blocker of :func:`boxes` (centres within ``[-2, 2]``, reach below 1.8).
    """
    corners = [[x, y, z] for x in (-half, half) for z in (-half, half)]
    g = np.linspace(-0.5 * half, 0.5 * half, points)
    gx, gz = np.meshgrid(g, g)
    grid = np.stack([gx.ravel(), np.full(gx.size, y), gz.ravel()], axis=-1)
    return np.concatenate([np.asarray(corners), grid])
