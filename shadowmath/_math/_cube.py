r"""Omnidirectional point lights: the six faces of a cube shadow map.

A point light that shines in every direction renders its shadow map into a cube
map, one 90-degree view per face (seed 002). The convention that ties drawing
and sampling together is the *face-selection table* of the OpenGL 4.6 (§8.13,
Table 8.19) and Vulkan specifications, stated in face space: a direction
``r = p - light`` samples the face of its largest component ``ma`` (ties: ``z``
wins over ``y`` and ``x``, ``y`` over ``x``, as Vulkan's rule says) at

.. math::

    s = \tfrac12\left(\frac{s_c}{|m_a|} + 1\right), \qquad
    t = \tfrac12\left(\frac{t_c}{|m_a|} + 1\right),

with ``(s_c, t_c, m_a)`` from the table (face ``i`` is
``GL_TEXTURE_CUBE_MAP_POSITIVE_X + i``)::

    face  0 +X   1 -X   2 +Y   3 -Y   4 +Z   5 -Z
    s_c     -z     +z     +x     +x     +x     -x
    t_c     -y     -y     +z     -z     -y     -y
    m_a      x      x      y      y      z      z

``t = 0`` is the face image's first row in memory. The views of
:func:`cube_face_views` are look-at cameras (looking down their ``-z``) whose
view coordinates are exactly ``(s_c, t_c, -|m_a|)``, so a face drawn with them
and :func:`cube_face_projection` holds at texel ``(s, t)`` what the direction
``(s, t)`` samples. The derivation, the graphics APIs' differences and the
engines' conventions are on ``docs/cube-maps.md``.

Trusted cores only: the public functions, which check their arguments and
call these, are in :mod:`shadowmath._geometry._cube_faces`.
"""

from __future__ import annotations

import functools
from types import ModuleType
from typing import Any, NamedTuple

import numpy as np

from shadowmath._boundary._shapes import Float, Int, Scalar
from shadowmath._boundary._validate import Array

# api -> (clip depth 0..1 instead of -1..1, NDC +y is the image's first row).
# OpenGL (lower-left window origin) and Vulkan (y-down NDC, upper-left origin)
# both put NDC y = -1 at the first row in memory; Direct3D, Metal and WebGPU
# put NDC y = +1 there (the table of _conventions).
APIS: dict[str, tuple[bool, bool]] = {
    "opengl": (False, False),
    "vulkan": (True, False),
    "direct3d": (True, True),
    "metal": (True, True),
    "webgpu": (True, True),
}

# Rows (x_view, y_view, z_view) of each face's world-to-view rotation: the rows
# (s, u, -f) of an OpenGL look-at with the (target, up) pairs. Row 0 is
# s_c, row 1 is t_c and row 2 is -|m_a| of the selection table, for directions
# in the face's pyramid.
_FACE_ROTATIONS: tuple[tuple[tuple[float, ...], ...], ...] = (
    ((0, 0, -1), (0, -1, 0), (-1, 0, 0)),  # +X: target +X, up -Y
    ((0, 0, 1), (0, -1, 0), (1, 0, 0)),  # -X: target -X, up -Y
    ((1, 0, 0), (0, 0, 1), (0, -1, 0)),  # +Y: target +Y, up +Z
    ((1, 0, 0), (0, 0, -1), (0, 1, 0)),  # -Y: target -Y, up -Z
    ((1, 0, 0), (0, -1, 0), (0, 0, -1)),  # +Z: target +Z, up -Y
    ((-1, 0, 0), (0, -1, 0), (0, 0, 1)),  # -Z: target -Z, up -Y
)


class CubeFaceCoords(NamedTuple):
    """Where a direction samples a cube map (the result of :func:`cube_face`).

    Attributes:
        face: ``(*batch,)`` int32 face index ``0..5`` (``+X, -X, +Y, -Y, +Z, -Z``);
            ``-1`` where the direction was invalid under a JAX transformation.
        s: ``(*batch,)`` texture coordinate in ``[0, 1]`` across the face.
        t: ``(*batch,)`` texture coordinate in ``[0, 1]``; ``t = 0`` is the face's first row.
    """

    face: Int[Array, "*batch"]
    s: Float[Array, "*batch"]
    t: Float[Array, "*batch"]


class CubeFaceDepth(NamedTuple):
    """What a receiver point compares against a cube shadow map (:func:`cube_face_depth`).

    Attributes:
        face: ``(*batch,)`` int32 face the point's direction samples (``-1`` where invalid
            under a JAX transformation).
        depth: ``(*batch,)`` the depth-buffer value the face's projection gives the point
            (window depth, ``0`` at near and ``1`` at far; reversed with ``reversed_z``):
            compare it with a hardware depth cube map (``samplerCubeShadow``).
        distance: ``(*batch,)`` the radial distance ``|p - light|``: compare it with a
            cube map that stores distances (seed 002's "linear distance").
    """

    face: Int[Array, "*batch"]
    depth: Float[Array, "*batch"]
    distance: Float[Array, "*batch"]


# ------------------------------------------------------------------ helpers


@functools.cache
def _view_constants(dtype: np.dtype[Any]) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``(A, index, sign)``, read-only: ``V = A + L[..., index] * sign`` for a light ``L``.

    ``A`` (``(6, 4, 4)``, in ``dtype``) is each face's ``[[R, 0], [0, 1]]``; the
    translation ``-R L`` of its last column is one signed component of ``L`` per
    row (``R`` is a signed permutation), which ``index`` picks and ``sign``
    (``-R``'s nonzero entry there, ``0`` elsewhere) scales: exact, and no matmul
    (a JAX matmul may round float32 operands on GPU and TPU).
    """
    R = np.asarray(_FACE_ROTATIONS, dtype=np.float64)  # (6, 3, 3)
    component = np.argmax(np.abs(R), axis=-1)  # (6, 3)
    A = np.zeros((6, 4, 4))
    A[:, :3, :3] = R
    A[:, 3, 3] = 1
    index = np.zeros((6, 4, 4), dtype=np.intp)
    index[:, :3, 3] = component
    sign = np.zeros((6, 4, 4))
    sign[:, :3, 3] = -np.take_along_axis(R, component[..., None], axis=-1)[..., 0]
    constants = (A.astype(dtype), index, sign.astype(dtype))
    for c in constants:
        c.flags.writeable = False
    return constants


@functools.cache
def _rotation_constant(dtype: np.dtype[Any]) -> np.ndarray:
    R = np.asarray(_FACE_ROTATIONS, dtype=dtype)
    R.flags.writeable = False
    return R


def _rotations(xp: ModuleType, dtype: np.dtype[Any]) -> Float[Array, "6 3 3"]:
    return xp.asarray(_rotation_constant(np.dtype(dtype)))  # (6, 3, 3)


@functools.lru_cache(maxsize=64)
def _projection_constants(
    dtype: np.dtype[Any], scale: float, flip_y: bool
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``(P0, at_a, at_b)``, read-only: the projection with a zero depth row, and the
    masks of that row's entries ``a`` (``[2, 2]``) and ``b`` (``[2, 3]``)."""
    P0 = np.zeros((4, 4), dtype=dtype)
    P0[0, 0] = scale
    P0[1, 1] = -scale if flip_y else scale
    P0[3, 2] = -1
    at_a = np.zeros((4, 4), dtype=bool)
    at_a[2, 2] = True
    at_b = np.zeros((4, 4), dtype=bool)
    at_b[2, 3] = True
    constants = (P0, at_a, at_b)
    for c in constants:
        c.flags.writeable = False
    return constants


def _select_face(
    xp: ModuleType, face: Int[Array, "*#batch"], candidates: Float[Array, "*#batch 6 k"]
) -> Float[Array, "*batch k"]:
    """``candidates[..., face, :]`` for ``candidates (*batch, 6, k)`` (a where, not a gather)."""
    onehot = face[..., None] == xp.arange(6, dtype=face.dtype)
    zero = xp.zeros((), dtype=candidates.dtype)
    return xp.sum(xp.where(onehot[..., None], candidates, zero), axis=-2)


def major_face(xp: ModuleType, d: Float[Array, "*batch 3"]) -> Int[Array, "*batch"]:
    """The face index (int32) of ``d``: the major axis, ties by Vulkan's rule (z, then y, then x).

    The one face selection of the package: :func:`cube_face` and
    :func:`cube_face_depth` both call it. Vulkan's "Cube Map Face Selection":
    "``r_z`` wins over ``r_y`` and ``r_x``, and [...] ``r_y`` wins over ``r_x``".
    """
    ax, ay, az = xp.abs(d[..., 0]), xp.abs(d[..., 1]), xp.abs(d[..., 2])
    use_z = (az >= ax) & (az >= ay)
    use_y = xp.logical_not(use_z) & (ay >= ax)
    axis = xp.where(use_z, 2, xp.where(use_y, 1, 0))
    ma = xp.where(use_z, d[..., 2], xp.where(use_y, d[..., 1], d[..., 0]))
    return xp.astype(2 * axis + xp.where(ma > 0, 0, 1), xp.int32)


# ------------------------------------------------------------------ cores


def cube_face_views(
    xp: ModuleType, light: Float[Array, "*batch 3"]
) -> Float[Array, "*batch 6 4 4"]:
    A, index, sign = _view_constants(light.dtype)
    if xp is not np:
        A, sign = xp.asarray(A), xp.asarray(sign)
    return A + light[..., index] * sign  # (*batch, 6, 4, 4)


def depth_row(
    near: Scalar, far: Scalar, zero_to_one: bool, reversed_z: bool
) -> tuple[Scalar, Scalar]:
    """The depth row ``(0, 0, a, b)`` of the projection: clip ``z = a z_v + b``, ``w = -z_v = D``.

    Plain arithmetic: ``near, far`` may be arrays or NumPy scalars.
    """
    n, f = near, far
    span = f - n
    if zero_to_one and reversed_z:  # depth n (f - D) / ((f - n) D): 1 at near, 0 at far
        return n / span, f * n / span
    if zero_to_one:  # depth f (D - n) / ((f - n) D): 0 at near, 1 at far
        return -f / span, -f * n / span
    if reversed_z:  # NDC +1 at near, -1 at far
        return (f + n) / span, 2 * f * n / span
    return -(f + n) / span, -2 * f * n / span  # glFrustum: NDC -1 at near, +1 at far


def cube_face_projection(
    xp: ModuleType,
    near: Float[Array, "*#batch"],
    far: Float[Array, "*#batch"],
    scale: float,
    *,
    zero_to_one: bool,
    flip_y: bool,
    reversed_z: bool,
) -> Float[Array, "*batch 4 4"]:
    """``(*batch, 4, 4)`` from ``(*batch,)`` arrays ``near, far``."""
    a, b = depth_row(near, far, zero_to_one, reversed_z)
    P0, at_a, at_b = (xp.asarray(c) for c in _projection_constants(a.dtype, scale, flip_y))
    # where, not P0 + a * mask: b overflows to inf for an extreme far * near, and inf * 0 is NaN.
    return xp.where(at_a, a[..., None, None], xp.where(at_b, b[..., None, None], P0))


def cube_face_projection_scalar(
    near: Scalar, far: Scalar, scale: float, *, zero_to_one: bool, flip_y: bool, reversed_z: bool
) -> Float[Array, "4 4"]:
    """:func:`cube_face_projection` of one light's NumPy scalars, entry by entry."""
    a, b = depth_row(near, far, zero_to_one, reversed_z)
    sy = -scale if flip_y else scale
    entries = (scale, 0, 0, 0, 0, sy, 0, 0, 0, 0, a, b, 0, 0, -1, 0)
    return np.array(entries, dtype=a.dtype).reshape(4, 4)


def cube_face(
    xp: ModuleType, d: Float[Array, "*batch 3"]
) -> tuple[Int[Array, "*batch"], Float[Array, "*batch"], Float[Array, "*batch"]]:
    face = major_face(xp, d)
    R = _rotations(xp, d.dtype)
    view = xp.sum(R * d[..., None, None, :], axis=-1)  # (*batch, 6, 3): (s_c, t_c, -|m_a|)
    sc, tc, minus_ma = xp.unstack(_select_face(xp, face, view), axis=-1)
    # |m_a| is 0 only for the zero direction, which the caller refuses or poisons.
    ma = xp.where(minus_ma == 0, xp.ones_like(minus_ma), -minus_ma)
    return face, (sc / ma + 1) / 2, (tc / ma + 1) / 2


def cube_face_direction(
    xp: ModuleType,
    face: Int[Array, "*#batch"],
    s: Float[Array, "*#batch"],
    t: Float[Array, "*#batch"],
) -> Float[Array, "*batch 3"]:
    sc, tc = 2 * s - 1, 2 * t - 1
    v = xp.stack([sc, tc, -xp.ones_like(sc)], axis=-1)  # view coordinates, |m_a| = 1
    R = _rotations(xp, v.dtype)
    # World = R^T view for each face; entries 0 and +-1 keep it exact.
    world = xp.sum(xp.matrix_transpose(R) * v[..., None, None, :], axis=-1)  # (*batch, 6, 3)
    return _select_face(xp, xp.astype(face, xp.int32), world)


def face_depth(
    xp: ModuleType,
    D: Float[Array, "*#batch"],
    near: Float[Array, "*#batch"],
    far: Float[Array, "*#batch"],
    reversed_z: bool,
) -> Float[Array, "*batch"]:
    span = far - near
    if reversed_z:
        return near * (far - D) / (span * D)
    return far * (D - near) / (span * D)
