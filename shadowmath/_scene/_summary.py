r"""What the scene's fits read of one geometry, computed once and shared by its instances.

A geometry's **summary** is a small triangle set ``S`` whose solid contains the
geometry's: the geometry's own triangles when they are few, else the surface of its
**26-DOP**, the convex polytope

.. math:: P = \{x : d_i \cdot x \le h_i,\ i = 1 \dots 26\}, \qquad
          h_i = \max_v d_i \cdot v,

with ``d_i`` the 26 directions ``(a, b, c) / |(a, b, c)|``, ``a, b, c`` in
``{-1, 0, 1}`` not all zero (the faces of a cube, its edges' and corners' directions).
Every vertex ``v`` satisfies every inequality, so ``P`` contains the geometry's convex
hull and so every triangle. Its corners are the points where three of the planes
meet and every inequality holds (all triples are tried: 2,600 3 x 3 solves, once per
geometry); each plane's face is the convex polygon of the corners on it, ordered by
angle about their mean and cut into a fan.

Why a polytope and not the hull's vertices: a smooth mesh of a million triangles has
most of its vertices on its hull, while ``P`` has at most a few dozen corners, so a fit
from summaries costs the same whatever the geometry's resolution. What the fits read of
a convex solid are extremes of functions that are linear (``z``, a box's sides) or
linear-fractional (``x/z``, ``y/z`` where ``z > 0``) over it, attained at its corners,
or, clipped by a spot's pyramid, at the corners of the clipped polytope; the nearest
point to a point light lies on its surface. So a fit that reads ``S`` in place of the
geometry's triangles keeps every caster (the map may be larger, never smaller). How
much larger is measured in ``docs/scenes.md``.

The **bounding sphere** (centre ``c``, radius ``r``) encloses the summary's corners
(so it encloses the geometry too): the culling rules read it.
"""

from __future__ import annotations

import itertools
from typing import NamedTuple

import numpy as np

from shadowmath._boundary._shapes import Float
from shadowmath._boundary._validate import Array


class GeometrySummary(NamedTuple):
    """One geometry's summary, in its local coordinates (float64 NumPy): what
    :meth:`ShadowScene.add_geometry` computes, or takes from :func:`summarize_geometry`
    to share one summary between scenes.

    Attributes:
        triangles: ``(T, 3, 3)`` the summary's triangles (see the module).
        points: ``(P, 3)`` their distinct corners.
        center: ``(3,)`` the bounding sphere's centre.
        radius: ``()`` its radius: every corner within it.
        bounds: ``(2, 3)`` ``[min, max]`` of the geometry's own vertices.
        exact: the summary is the geometry's own triangles (not its 26-DOP).
        own: ``(F, 3, 3)`` the geometry's own triangles (read in place of the summary
            by a light inside the bounding sphere, where a polytope around the light
            would hold the light itself: a torus around a point light).
    """

    triangles: Float[Array, "T 3 3"]
    points: Float[Array, "P 3"]
    center: Float[Array, "3"]
    radius: float
    bounds: Float[Array, "2 3"]
    exact: bool
    own: Float[Array, "F 3 3"]


def _directions() -> np.ndarray:
    """``(26, 3)`` the unit directions of the 26-DOP."""
    d = np.array([v for v in itertools.product((-1.0, 0.0, 1.0), repeat=3) if any(v)])
    unit: np.ndarray = d / np.linalg.norm(d, axis=1, keepdims=True)
    return unit


DIRECTIONS = _directions()
_TRIPLES = np.array(list(itertools.combinations(range(len(DIRECTIONS)), 3)))


def summarize(vertices: np.ndarray, triangles: np.ndarray) -> GeometrySummary:
    """The :class:`GeometrySummary` of a trusted geometry: finite float64 ``vertices`` ``(V, 3)``
    (``V >= 1``) and its ``triangles`` ``(F, 3, 3)`` (``F = 0`` for a point set, whose
    summary triangles are then degenerate ``(p, p, p)``)."""
    scale = float(np.max(np.abs(vertices))) or 1.0
    if len(triangles) == 0:
        triangles = np.repeat(vertices[:, None, :], 3, axis=1)
    corners, faces = dop(vertices, scale)
    exact = len(triangles) <= len(faces)
    tris = triangles if exact else faces
    points = vertices if exact else corners
    center, radius = _sphere(points)
    bounds = np.stack([vertices.min(axis=0), vertices.max(axis=0)])
    return GeometrySummary(tris, points, center, radius, bounds, exact, triangles)


def dop(vertices: np.ndarray, scale: float) -> tuple[np.ndarray, np.ndarray]:
    """The 26-DOP of ``vertices``: its corners ``(K, 3)`` and surface triangles ``(T, 3, 3)``.

    The offsets ``h_i`` are raised by ``64 eps`` of the coordinates' ``scale`` so that the
    corners, rounded by the solves, still hold every vertex.
    """
    eps = 64 * np.finfo(np.float64).eps * scale
    h = np.max(vertices @ DIRECTIONS.T, axis=0) + eps
    A, b = DIRECTIONS[_TRIPLES], h[_TRIPLES]
    det = np.linalg.det(A)
    ok = np.abs(det) > 1e-6
    x = np.linalg.solve(A[ok], b[ok][..., None])[..., 0]
    feasible = np.all(x @ DIRECTIONS.T <= h + 4 * eps, axis=1)
    corners = _distinct(x[feasible], 4 * eps)
    return corners, _faces(corners, h, 8 * eps)


def _distinct(x: np.ndarray, tol: float) -> np.ndarray:
    """The rows of ``x`` with duplicates within ``tol`` (max norm) removed."""
    keep: list[np.ndarray] = []
    for p in x[np.lexsort(x.T[::-1])]:
        if not any(np.max(np.abs(p - q)) <= tol for q in keep[-64:]):
            keep.append(p)
    return np.array(keep).reshape(-1, 3)


def _faces(corners: np.ndarray, h: np.ndarray, tol: float) -> np.ndarray:
    """``(T, 3, 3)`` each plane's corners ordered by angle about their mean, as a fan."""
    on = np.abs(corners @ DIRECTIONS.T - h) <= tol  # (K, 26)
    out: list[np.ndarray] = []
    for i, d in enumerate(DIRECTIONS):
        face = corners[on[:, i]]
        if len(face) < 3:
            continue
        u = np.cross(d, [1.0, 0.0, 0.0] if abs(d[0]) < 0.9 else [0.0, 1.0, 0.0])
        u /= np.linalg.norm(u)
        w = np.cross(d, u)
        rel = face - face.mean(axis=0)
        ring = face[np.argsort(np.arctan2(rel @ w, rel @ u))]
        out.extend(np.stack([ring[0], ring[k], ring[k + 1]]) for k in range(1, len(ring) - 1))
    return np.array(out).reshape(-1, 3, 3)


def _sphere(points: np.ndarray) -> tuple[np.ndarray, float]:
    """A sphere holding every point: the bounding box's centre and the farthest point's
    distance from it, raised by rounding."""
    center = 0.5 * (points.min(axis=0) + points.max(axis=0))
    radius = float(np.max(np.linalg.norm(points - center, axis=1)))
    scale = float(np.max(np.abs(points))) + radius
    return center, radius + 64 * np.finfo(np.float64).eps * scale
