r"""Conservative culling rules: what each light's fit reads, and what each map draws.

Each object is read through its world-space bounding sphere (centre ``c``, radius
``r``; :func:`world_spheres`), which holds every point of it. Two kinds of rules:

**What a map draws** (:func:`clip_visible`, one rule for every map: a sun's or a spot's,
a cube face, a cascade, an atlas tile). A map's texels are what its ``world_to_clip``
rasterizes inside the clip volume; its four side planes are the rows
``P_3 + P_0, P_3 - P_0, P_3 + P_1, P_3 - P_1`` (``|x| <= w``, ``|y| <= w``, the same in
every graphics API; their intersection also has ``w >= 0``). A sphere wholly outside one
of them (signed distance ``pi . (c, 1) / |pi_xyz| < -r``) puts no fragment in the map, so
leaving it out of the draw list changes no texel: the map, and every lookup of it (any
filter, any offset), is the one drawn with every caster. Depth is not tested: what the
near and far planes clip is drawn by neither.

**What a fit reads**, before it has a map:

* **Spot light** at ``L``, unit axis ``a``, half-angle ``theta`` (:func:`spot_visible`).
  A receiver point ``P`` it lights lies in the cone, and so does the segment ``LP``
  (a cone is convex from its apex); a caster shadows ``P`` only on that segment. A
  sphere misses the cone when the angle between ``a`` and ``c - L`` exceeds
  ``theta + asin(r / |c - L|)`` (every point of the sphere is seen from ``L`` within
  ``asin(r / |c - L|)`` of ``c``'s direction). A sphere holding the light is kept. The
  map is fitted to the rest (clipped to the cone's square pyramid); its draw list is
  then the clip-volume rule's, which may also hold casters in the square's corners.
* **A cube map's depth range** (:func:`cube_range_candidates`): with ``D(p) =
  max_i |p_i - L_i|`` (the depth of ``p`` in the face that sees it), every point of a
  sphere has ``D(c) - r <= D <= D(c) + r`` (``D`` is 1-Lipschitz in the max norm, which is
  at most the Euclidean). The nearest caster lies in an object whose ``D(c) - r`` is at
  most the least ``D(c) + r`` of the casters; the farthest caster or receiver corner in one
  whose ``D(c) + r`` is at least the largest ``D(c) - r``. Only these are read: the range
  is the same as from every object.
* **A sun's box** (:func:`sun_candidates`, :func:`inside_box`): the objects that may
  bound it along 16 directions across the light and along it are read first; every other
  sphere is then checked against the fitted box and the fit is repeated with those that
  stick out, so the box is the one of every caster.
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


def clip_visible(
    world_to_clip: Float[Array, "*maps 4 4"],
    center: Float[Array, "N 3"],
    radius: Float[Array, " N"],
    *,
    xp: ModuleType = np,
) -> Bool[Array, "*maps N"]:
    """``(*maps, N)`` the spheres that may put a fragment in each map (see the module):
    not wholly outside one of the four side planes of ``world_to_clip``."""
    P = world_to_clip[..., None, :, :]  # (*maps, 1, 4, 4): planes (*maps, 1, 4, 4)
    planes = xp.stack(
        [P[..., 3, :] + P[..., 0, :], P[..., 3, :] - P[..., 0, :],
         P[..., 3, :] + P[..., 1, :], P[..., 3, :] - P[..., 1, :]],
        axis=-2,
    )  # fmt: skip
    value = xp.sum(planes[..., :3] * center[:, None, :], axis=-1) + planes[..., 3]
    norm = xp.sqrt(xp.sum(planes[..., :3] ** 2, axis=-1))
    return xp.all(value >= -radius[:, None] * norm, axis=-1)


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
