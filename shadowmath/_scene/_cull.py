r"""Conservative culling rules: which objects can cast into which map.

Each object is read through its world-space bounding sphere (centre ``c``, radius
``r``; :func:`world_spheres`), which holds every point of it. A rule drops an object
only when no point of its sphere can shadow a lit point of the map, so the shadows drawn
from the draw lists equal those drawn with every caster in every map.

* **Spot light** at ``L``, unit axis ``a``, half-angle ``theta`` (:func:`spot_visible`).
  A receiver point ``P`` it lights lies in the cone, and so does the segment ``LP``
  (a cone is convex from its apex); a caster shadows ``P`` only on that segment. A
  sphere misses the cone when the angle between ``a`` and ``c - L`` exceeds
  ``theta + asin(r / |c - L|)`` (every point of the sphere is seen from ``L`` within
  ``asin(r / |c - L|)`` of ``c``'s direction), i.e. when ``theta + asin(r/|c - L|) <
  pi`` and ``cos(angle(a, c - L)) < cos(theta + asin(r / |c - L|))``. A sphere holding
  the light is always kept.
* **Cube face** of a point light at ``L`` (:func:`cube_faces_visible`): face ``+X``
  sees the directions with ``x >= |y|, x >= |z|`` (relative to ``L``): the four
  half-spaces ``x - y >= 0``, ``x + y >= 0``, ``x - z >= 0``, ``x + z >= 0`` through
  ``L``, each of normal length ``sqrt 2``. A sphere lies wholly outside one of them when
  its signed value is below ``-r sqrt 2``; such an object casts nothing a texel of that
  face samples (a lit point seen through the face lies in its pyramid, and so does its
  segment to the light). The other five faces likewise.
* **A cube map's depth range** (:func:`cube_range_candidates`): with ``D(p) =
  max_i |p_i - L_i|`` (the depth of ``p`` in the face that sees it), every point of a
  sphere has ``D(c) - r <= D <= D(c) + r`` (``D`` is 1-Lipschitz in the max norm, which is
  at most the Euclidean). The nearest caster lies in an object whose ``D(c) - r`` is at
  most the least ``D(c) + r`` of the casters; the farthest caster or receiver corner in one
  whose ``D(c) + r`` is at least the largest ``D(c) - r``. Only these are read: the range
  is the same as from every object.
* **Orthographic box** (a sun's map or a cascade, :func:`box_visible`): in the map's
  light coordinates (``Z`` along the light's travel), a lit point has ``|x - c_x| <=
  R_x``, ``|y - c_y| <= R_y`` and ``z <= far``; its segment toward the light keeps
  ``x, y`` and has smaller ``z``. A sphere whose ``x`` or ``y`` range misses the box's,
  or whose nearest ``z`` is beyond ``far``, is dropped.
"""

from __future__ import annotations

from types import ModuleType
from typing import Any

import numpy as np

from shadowmath._boundary._shapes import Bool, Float
from shadowmath._boundary._validate import Array


def world_spheres(
    transforms: Float[Array, "N 4 4"], center: Float[Array, "N 3"], radius: Float[Array, " N"]
) -> tuple[Float[Array, "N 3"], Float[Array, " N"]]:
    """The spheres of local centres ``center`` and radii ``radius`` through the affine
    ``transforms``: ``c' = A c + t``, ``r' = r sigma_max(A)`` (the largest singular value,
    the most the linear part ``A`` stretches any direction)."""
    A = transforms[:, :3, :3]
    c = np.einsum("nij,nj->ni", A, center) + transforms[:, :3, 3]
    stretch = np.sqrt(np.maximum(np.linalg.eigvalsh(np.einsum("nji,njk->nik", A, A))[:, -1], 0))
    return c, radius * stretch * (1 + 1e-12)


def spot_visible(
    position: Float[Array, "3"],
    axis: Float[Array, "3"],
    angle: Any,
    center: Float[Array, "N 3"],
    radius: Float[Array, " N"],
    *,
    xp: ModuleType = np,
) -> Bool[Array, " N"]:
    """``(N,)`` the spheres that reach into the cone (see the module): kept. ``xp`` the
    arrays' namespace (NumPy or ``jax.numpy``)."""
    rel = center - position
    dist = xp.sqrt(xp.sum(rel * rel, axis=-1))
    inside = dist <= radius
    safe = xp.where(inside, 1.0, dist)
    spread = angle + xp.arcsin(xp.clip(radius / safe, 0.0, 1.0))
    cos_angle = (rel @ axis) / xp.sqrt(xp.sum(axis * axis)) / safe
    return inside | (spread >= np.pi) | (cos_angle >= xp.cos(xp.minimum(spread, np.pi)))


#: The cube's faces as (axis, sign) in pygfx's and OpenGL's order +X, -X, +Y, -Y, +Z, -Z.
CUBE_FACES = ((0, 1.0), (0, -1.0), (1, 1.0), (1, -1.0), (2, 1.0), (2, -1.0))


def cube_faces_visible(
    position: Float[Array, "3"],
    center: Float[Array, "N 3"],
    radius: Float[Array, " N"],
    *,
    xp: ModuleType = np,
) -> Bool[Array, "6 N"]:
    """``(6, N)`` for each cube face, the spheres that reach into its pyramid."""
    rel = center - position
    slack = np.sqrt(2.0) * radius
    rows = []
    for axis, sign in CUBE_FACES:
        main = sign * rel[:, axis]
        a, b = (rel[:, k] for k in range(3) if k != axis)
        rows.append((main - xp.abs(a) >= -slack) & (main - xp.abs(b) >= -slack))
    return xp.stack(rows)


def cube_range_candidates(
    position: Float[Array, "3"],
    center: Float[Array, "N 3"],
    radius: Float[Array, " N"],
    casts: Bool[Array, " N"],
    receives: Bool[Array, " N"],
) -> tuple[Bool[Array, " N"], Bool[Array, " N"]]:
    """``(near, far)`` the objects that may hold the nearest caster and the farthest
    caster or receiver point of a cube map at ``position`` (see the module)."""
    D = np.max(np.abs(center - position), axis=1)
    lo, hi = D - radius, D + radius
    near = casts & (lo <= np.min(hi[casts], initial=np.inf))
    either = casts | receives
    far = either & (hi >= np.max(lo[either], initial=-np.inf))
    return near, far


#: The directions across a sun's light (angles in the plane normal to it) whose extremes
#: pick the objects that may bound its map (:func:`sun_candidates`).
_SUN_DIRECTIONS = 16


def sun_candidates(
    direction: Float[Array, "3"],
    center: Float[Array, "N 3"],
    radius: Float[Array, " N"],
    casts: Bool[Array, " N"],
    receives: Bool[Array, " N"],
) -> tuple[Bool[Array, " N"], Bool[Array, " N"]]:
    """``(casters, receivers)`` a first guess of the objects that bound a sun's map: along
    each of 16 directions normal to the light and along the light, the objects whose
    sphere reaches past the least far end of every other sphere (a sphere entirely
    behind another's extreme cannot hold the extreme); for receivers, only the far end.
    A guess: :func:`inside_box` checks the rest against the fitted map."""
    Z = -direction / np.linalg.norm(direction)
    e1 = np.cross(Z, [1.0, 0.0, 0.0] if abs(Z[0]) < 0.9 else [0.0, 1.0, 0.0])
    e1 /= np.linalg.norm(e1)
    e2 = np.cross(Z, e1)
    angle = np.linspace(0.0, 2 * np.pi, _SUN_DIRECTIONS, endpoint=False)
    U = np.concatenate([np.cos(angle)[:, None] * e1 + np.sin(angle)[:, None] * e2, [Z, -Z]])
    proj = center @ U.T  # (N, 18)
    lo, hi = proj - radius[:, None], proj + radius[:, None]
    bound = np.max(np.where(casts[:, None], lo, -np.inf), axis=0)
    cand_c = casts & np.any(hi >= bound, axis=1)
    z_lo, z_hi = lo[:, -2], hi[:, -2]
    cand_r = receives & (z_hi >= np.max(np.where(receives, z_lo, -np.inf)))
    return cand_c, cand_r


def inside_box(
    world_to_light: Float[Array, "4 4"],
    box: Any,
    center: Float[Array, "N 3"],
    radius: Float[Array, " N"],
    *,
    receiver: bool,
) -> Bool[Array, " N"]:
    """``(N,)`` the spheres that leave an orthographic fit unchanged: a caster's inside the
    box ``|x - c_x| <= R_x``, ``|y - c_y| <= R_y``, ``near <= z <= far`` (in the rigid
    ``world_to_light``); a receiver's outside the window or on the light's side of ``far``
    (receivers only push ``far``, and only where the map covers them)."""
    p = center @ world_to_light[:3, :3].T + world_to_light[:3, 3]
    dx = np.abs(p[:, 0] - float(box.center_x))
    dy = np.abs(p[:, 1] - float(box.center_y))
    Rx, Ry = float(box.half_width), float(box.half_height)
    before_far = p[:, 2] + radius <= float(box.far)
    if receiver:
        hx, hy = Rx / float(box.margin_x), Ry / float(box.margin_y)
        return (dx - radius > hx) | (dy - radius > hy) | before_far
    return (
        (dx + radius <= Rx)
        & (dy + radius <= Ry)
        & (p[:, 2] - radius >= float(box.near))
        & before_far
    )


def box_visible(
    world_to_light: Float[Array, "4 4"],
    window: Float[Array, "4"],
    far: float,
    center: Float[Array, "N 3"],
    radius: Float[Array, " N"],
) -> Bool[Array, " N"]:
    """``(N,)`` the spheres that can shadow the box ``x in [window[0], window[1]]``,
    ``y in [window[2], window[3]]``, ``z <= far`` (light coordinates of the rigid
    ``world_to_light``)."""
    p = center @ world_to_light[:3, :3].T + world_to_light[:3, 3]
    return (
        (p[:, 0] + radius >= window[0])
        & (p[:, 0] - radius <= window[1])
        & (p[:, 1] + radius >= window[2])
        & (p[:, 1] - radius <= window[3])
        & (p[:, 2] - radius <= far)
    )
