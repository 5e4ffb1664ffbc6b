r"""Conservative culling rules: what each light's fit reads, and what each map draws.

Each object is read through its world-space bounding sphere (centre ``c``, radius
``r``; :func:`world_spheres`), which holds every point of it. Two kinds of rules:

**What a map draws** (:func:`clip_visible`, one rule for every map: a sun's or a spot's,
a cube face, a cascade, an atlas tile). A map's texels are what its ``world_to_clip``
rasterizes inside the clip volume; its four side planes are the rows
``P_3 + P_0, P_3 - P_0, P_3 + P_1, P_3 - P_1`` (``|x| <= w``, ``|y| <= w``, the same in
every graphics API), and ``P_3`` (``w >= 0``: in front of a perspective map's eye). A
sphere wholly outside one of them (signed distance ``pi . (c, 1) / |pi_xyz| < -r``) puts
no fragment in the map, so leaving it out of the draw list changes no texel: the map,
and every lookup of it (any filter, any offset), is the one drawn with every caster.
Depth is not tested: what the near and far planes clip is drawn by neither.

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
* **A sun's box** (:func:`sun_candidates`, :func:`inside_box`): in the fit's frame
  (whose rotation depends on the light's direction and ``up`` only), each object's light
  coordinates lie in an interval (:func:`light_intervals`); the objects whose intervals
  may hold an extreme are read first, every other one is then checked against the fitted
  box (and, where its interval sticks out, by its summary's corners), and the fit is
  repeated with those that stick out, so the box is the one of every caster.
"""

from __future__ import annotations

from types import ModuleType

import numpy as np

from shadowmath._boundary._shapes import Bool, Float, Scalar
from shadowmath._boundary._validate import Array
from shadowmath._math._frustum import Frustum, OrthographicBox


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
    angle: Scalar,
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
    not wholly outside one of the four side planes of ``world_to_clip``, nor behind its
    eye (``w >= 0``, the row ``P_3``: it has no normal for an orthographic map, where it
    holds everywhere)."""
    P = world_to_clip
    planes = xp.stack(
        [P[..., 3, :] + P[..., 0, :], P[..., 3, :] - P[..., 0, :],
         P[..., 3, :] + P[..., 1, :], P[..., 3, :] - P[..., 1, :], P[..., 3, :]],
        axis=-2,
    )  # fmt: skip
    norm = xp.sqrt(xp.sum(planes[..., :3] ** 2, axis=-1))
    value = xp.matmul(planes[..., :3], xp.matrix_transpose(center)) + planes[..., 3:4]
    value = value / xp.where(norm > 0, norm, 1.0)[..., None]  # (*maps, 5, N): distances
    return xp.all(value >= -radius, axis=-2)


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


def light_intervals(
    world_to_light: Float[Array, "4 4"],
    center: Float[Array, "N 3"],
    radius: Float[Array, " N"],
    bounds: Float[Array, "N 2 3"],
) -> tuple[Float[Array, "N 3"], Float[Array, "N 3"]]:
    """``(lo, hi)`` ``(N, 3)`` bounds of each object's light coordinates under the rigid
    ``world_to_light``, twice bounded, by its sphere and by its world box ``bounds``
    (``[min, max]``: along a unit axis ``u`` its points lie within ``|u| . h`` of the box's
    centre, ``h`` the half-extents); the tighter of the two intervals."""
    R, t = world_to_light[:3, :3], world_to_light[:3, 3]
    p = center @ R.T + t
    mid = 0.5 * (bounds[:, 0] + bounds[:, 1])
    q, half = mid @ R.T + t, 0.5 * (bounds[:, 1] - bounds[:, 0]) @ np.abs(R).T
    return np.maximum(p - radius[:, None], q - half), np.minimum(p + radius[:, None], q + half)


def sun_candidates(
    lo: Float[Array, "N 3"],
    hi: Float[Array, "N 3"],
    casts: Bool[Array, " N"],
    receives: Bool[Array, " N"],
) -> tuple[Bool[Array, " N"], Bool[Array, " N"]]:
    """``(casters, receivers)`` the objects that may bound a sun's map, from their light
    coordinates' intervals (:func:`light_intervals`, in the fit's frame): along each axis
    the casters whose interval reaches past the least far end of every caster's (an
    interval wholly inside another's extreme cannot hold the extreme), both ways; for
    receivers the far end of ``z`` only."""
    top = np.max(np.where(casts[:, None], lo, -np.inf), axis=0)
    bottom = np.min(np.where(casts[:, None], hi, np.inf), axis=0)
    cand_c = casts & np.any((hi >= top) | (lo <= bottom), axis=1)
    cand_r = receives & (hi[:, 2] >= np.max(np.where(receives, lo[:, 2], -np.inf)))
    return cand_c, cand_r


def inside_box(
    lo: Float[Array, "N 3"],
    hi: Float[Array, "N 3"],
    box: Frustum | OrthographicBox,
    *,
    receiver: bool,
) -> Bool[Array, " N"]:
    """``(N,)`` the objects that leave an orthographic fit unchanged, from their light
    coordinates' intervals (:func:`light_intervals`): a caster's inside the box
    ``|x - c_x| <= R_x``, ``|y - c_y| <= R_y``, ``near <= z <= far``; a receiver's
    outside the window or on the light's side of ``far`` (receivers only push ``far``,
    and only where the map covers them). ``box``: a directional light's fit, a box."""
    assert isinstance(box, OrthographicBox), "a sun's fit is an orthographic box"
    cx, cy, Rx, Ry = (float(v) for v in (box.center_x, box.center_y, box.half_width,
                                          box.half_height))  # fmt: skip
    before_far = hi[:, 2] <= float(box.far)
    if receiver:
        hx, hy = Rx / float(box.margin_x), Ry / float(box.margin_y)
        outside = (lo[:, 0] > cx + hx) | (hi[:, 0] < cx - hx)
        outside |= (lo[:, 1] > cy + hy) | (hi[:, 1] < cy - hy)
        return outside | before_far
    inside = (lo[:, 0] >= cx - Rx) & (hi[:, 0] <= cx + Rx)
    inside &= (lo[:, 1] >= cy - Ry) & (hi[:, 1] <= cy + Ry)
    return inside & (lo[:, 2] >= float(box.near)) & before_far
