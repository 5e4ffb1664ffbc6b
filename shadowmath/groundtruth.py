"""An independent ground truth for shadows: segments to the light against blocker triangles.

Pure NumPy and deliberately unrelated to the shadow matrices: no light frame,
no frustum, no projection, no texture. A receiver point ``P`` is in a
blocker's shadow when the open segment from ``P`` to the point light ``L``
crosses one of the blocker's triangles, found with the Möller–Trumbore
ray-triangle test, vectorized over points and triangles. A directional light
``(x, y, z, 0)`` (the direction toward the light) casts the ray from ``P``
along that direction instead, unbounded.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import NDArray

from ._boundary._shapes import ArrayLike, Bool, Integer, Real, shapes_checked

#: Pairs of (point, triangle) tested per chunk: bounds the temporary arrays (~100 MB).
_CHUNK_PAIRS = 1 << 20


def _points(name: str, value: Any) -> NDArray[np.float64]:
    arr = np.asarray(value, dtype=np.float64)
    if arr.ndim < 1 or arr.shape[-1] != 3:
        raise ValueError(f"{name}: expected (..., 3) coordinates, got shape {arr.shape}")
    if not np.all(np.isfinite(arr)):
        raise ValueError(f"{name}: contains non-finite values (NaN or inf); pass finite numbers")
    return arr


@shapes_checked
def _light(light_position: Any) -> tuple[NDArray[np.float64], bool]:
    """The light's point (or direction toward it) and whether it is directional (checked)."""
    light = np.asarray(light_position, dtype=np.float64)
    if light.shape not in ((3,), (4,)):
        raise ValueError(f"light_position: expected shape (3,) or (4,), got {light.shape}")
    if not np.all(np.isfinite(light)):
        raise ValueError("light_position: contains non-finite values (NaN or inf)")
    directional = bool(light.shape == (4,) and light[3] == 0)
    if directional:
        if not np.any(light[:3]):
            raise ValueError("light_position: a directional light (w = 0) needs a direction")
        return light[:3], True
    return (light[:3] / light[3] if light.shape == (4,) else light), False


def _mesh(vertices: Any, triangles: Any) -> tuple[NDArray[np.float64], NDArray[np.integer]]:
    """``(N, 3)`` vertices and ``(M, 3)`` integer indices into them (checked)."""
    v = _points("vertices", vertices)
    if v.ndim != 2:
        raise ValueError(f"vertices: expected shape (N, 3), got {v.shape}")
    t = np.asarray(triangles)
    if t.ndim != 2 or t.shape[1] != 3 or t.dtype.kind not in "iu":
        raise ValueError(f"triangles: expected (M, 3) integer indices, got {t.dtype} {t.shape}")
    if t.size and (t.min() < 0 or t.max() >= len(v)):
        raise ValueError(f"triangles: indices must lie in [0, {len(v)})")
    return v, t


def segment_hits_triangles(
    points: Real[ArrayLike, "*points 3"],
    light_position: Real[ArrayLike, " 3"] | Real[ArrayLike, " 4"],
    vertices: Real[ArrayLike, "N 3"],
    triangles: Integer[ArrayLike, "M 3"],
    *,
    eps: float = 1e-9,
) -> Bool[NDArray[np.bool_], "*points"]:
    r"""Whether the segment from each point to the light crosses any triangle.

    ``light_position`` is a point ``(x, y, z)``, or homogeneous ``(x, y, z, w)``:
    ``w != 0`` the point ``(x, y, z) / w``, ``w = 0`` a directional light whose
    ``(x, y, z)`` points toward the light: then the ray ``P + t d`` for ``t > eps``
    (``d = (x, y, z)``), no upper end.

    Möller–Trumbore: with ``d = L - P``, edges ``e1 = B - A``, ``e2 = C - A``,
    ``h = d x e2``, ``det = e1 . h``, ``s = P - A``, ``k = s x e1``:

    .. math::

        u = \frac{s \cdot h}{\det}, \quad v = \frac{d \cdot k}{\det}, \quad
        t = \frac{e_2 \cdot k}{\det}

    and the segment hits the triangle when ``det != 0``, ``u >= 0``, ``v >= 0``,
    ``u + v <= 1`` and ``eps < t < 1 - eps`` (strictly between the point and
    the light, so a receiver touching the blocker is not shadowed by the
    contact itself; a directional light: ``eps < t``). Both faces of a triangle
    block light.

    Arguments:
        points: ``(..., 3)`` receiver points in world coordinates.
        light_position: ``(3,)`` the point light, or ``(4,)`` homogeneous (``w = 0``:
            a directional light, the direction toward it).
        vertices: ``(N, 3)`` blocker vertices in world coordinates.
        triangles: ``(M, 3)`` integer indices into ``vertices``.
        eps: the fraction of the segment ignored at each end.

    Returns:
        ``(...)`` booleans: ``True`` where the point is in the blocker's shadow.

    Raises:
        ValueError: wrong shapes, non-finite values, indices out of range.

    Example:
        >>> tri = [[-1, -1, 1], [1, -1, 1], [0, 1, 1]]  # a triangle at height 1
        >>> points = [[0, 0, 0], [5, 0, 0]]  # under it, and off to the side
        >>> segment_hits_triangles(points, [0, 0, 2], tri, [[0, 1, 2]])
        array([ True, False])
        >>> segment_hits_triangles(points, [0, 0, 1, 0], tri, [[0, 1, 2]])  # from straight up
        array([ True, False])
    """
    p = _points("points", points)
    light, directional = _light(light_position)
    # A directional light's ray d = (x, y, z) has no far end: t is bounded below only.
    upper = np.inf if directional else 1 - eps
    v, t = _mesh(vertices, triangles)
    corners = v[t]  # (M, 3 corners, 3)
    flat = p.reshape(-1, 3)
    # Only segments that pass through the blocker's bounding sphere can hit it, and within
    # it only those through the sphere of a run of triangles can hit one of them: the
    # others are answered without the (points x triangles) test.
    near = _near_sphere(flat, light, directional, v)
    hits_near = np.zeros(len(near), dtype=bool)
    for first in range(0, len(t), _RUN):
        run = corners[first : first + _RUN]
        close = (
            _near_sphere(flat[near], light, directional, run.reshape(-1, 3))
            if len(t) > _RUN
            else np.arange(len(near))
        )
        step = max(1, _CHUNK_PAIRS // len(run))
        for i in range(0, len(close), step):
            rows = close[i : i + step]
            hits_near[rows] |= _crossings(flat[near[rows]], light, directional, run, (eps, upper))
    hits = np.zeros(len(flat), dtype=bool)
    hits[near[hits_near]] = True
    return hits.reshape(p.shape[:-1])


#: Triangles whose bounding sphere is tested as one (a mesh's triangles run over its surface).
_RUN = 64


def _near_sphere(
    flat: NDArray[np.float64], light: NDArray[np.float64], directional: bool, v: NDArray[np.float64]
) -> NDArray[np.intp]:
    """The points whose segment (ray) to the light passes through the bounding sphere of
    the points ``v`` (about their mean, widened by rounding's margin)."""
    centre = v.mean(axis=0)
    radius = np.linalg.norm(v - centre, axis=1).max() * (1 + 1e-9) + 1e-12
    seg = np.broadcast_to(light, flat.shape) if directional else light - flat
    along_seg = np.clip(
        np.sum((centre - flat) * seg, axis=1) / np.maximum(np.sum(seg * seg, axis=1), 1e-300),
        0,
        np.inf if directional else 1,
    )
    nearest = flat + along_seg[:, None] * seg
    return np.flatnonzero(np.linalg.norm(nearest - centre, axis=1) <= radius)


def _crossings(
    q: NDArray[np.float64],
    light: NDArray[np.float64],
    directional: bool,
    corners: NDArray[np.float64],
    bounds: tuple[float, float],
) -> NDArray[np.bool_]:
    """Whether the segment (ray) from each point ``q`` crosses one of the triangles
    ``corners`` ``(M, 3, 3)`` at ``eps < t < upper`` (``bounds``): Möller–Trumbore."""
    eps, upper = bounds
    a = corners[:, 0]
    e1, e2 = corners[:, 1] - a, corners[:, 2] - a
    # Components as separate (P, M) arrays: np.cross on (P, M, 3) is several times slower.
    if directional:
        dx, dy, dz = (np.broadcast_to(light[i], (len(q), 1)) for i in range(3))
    else:
        dx, dy, dz = (light[i] - q[:, i, None] for i in range(3))
    sx, sy, sz = (q[:, i, None] - a[None, :, i] for i in range(3))
    ax, ay, az = e1[:, 0], e1[:, 1], e1[:, 2]
    bx, by, bz = e2[:, 0], e2[:, 1], e2[:, 2]
    hx, hy, hz = dy * bz - dz * by, dz * bx - dx * bz, dx * by - dy * bx  # d x e2
    det = ax * hx + ay * hy + az * hz
    ok = np.abs(det) > 1e-300  # a segment parallel to the triangle's plane never hits it
    inv = np.where(ok, 1.0 / np.where(ok, det, 1.0), 0.0)
    u = (sx * hx + sy * hy + sz * hz) * inv
    kx, ky, kz = sy * az - sz * ay, sz * ax - sx * az, sx * ay - sy * ax  # s x e1
    w = (dx * kx + dy * ky + dz * kz) * inv
    along = (bx * kx + by * ky + bz * kz) * inv
    crossing = ok & (u >= 0) & (w >= 0) & (u + w <= 1) & (along > eps) & (along < upper)
    return np.asarray(crossing.any(axis=-1), dtype=np.bool_)
