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
"""

from __future__ import annotations

import functools
import math
from types import ModuleType
from typing import Any, NamedTuple

import numpy as np

from shadowmath._boundary._validate import (
    Array,
    Checks,
    all_finite,
    batch_shape,
    convert,
    integer,
    non_finite,
    require_last,
)

from ._conventions import GraphicsApi, _check_api
from ._vector import norm

# api -> (clip depth 0..1 instead of -1..1, NDC +y is the image's first row).
# OpenGL (lower-left window origin) and Vulkan (y-down NDC, upper-left origin)
# both put NDC y = -1 at the first row in memory; Direct3D, Metal and WebGPU
# put NDC y = +1 there (the table of _conventions).
_APIS: dict[str, tuple[bool, bool]] = {
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

    face: Array
    s: Array
    t: Array


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

    face: Array
    depth: Array
    distance: Array


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


def _rotations(xp: ModuleType, dtype: Any) -> Array:
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


def _require_finite(checks: Checks, x: Array, trailing: int, name: str) -> None:
    """``checks.require(all_finite(...))``, after one whole-array test for eager NumPy.

    Only an array that fails the test pays for the per-entry check, which names
    the first bad batch index. (``count_nonzero``: ``.all()`` costs microseconds
    more on a light's three numbers.)
    """
    eager_numpy = checks.mode == "raise" and type(x) is np.ndarray
    if eager_numpy and np.count_nonzero(np.isfinite(x)) == x.size:
        return
    checks.require(all_finite(checks.ctx.xp, x, trailing), non_finite(name))


_SCALAR_TYPES: dict[type, Any] = {float: np.float64, np.float64: np.float64, np.float32: np.float32}


def _numpy_scalar(value: object) -> Any:
    """A Python float, a NumPy float32/float64 scalar or a 0-d array of one, as a
    NumPy scalar of its dtype (what :func:`convert` would make of it); else ``None``."""
    kind = _SCALAR_TYPES.get(type(value))
    if kind is not None:
        return kind(value)
    if (
        type(value) is np.ndarray
        and value.ndim == 0
        and value.dtype.type in (np.float32, np.float64)
    ):
        return value[()]
    return None


def _select_face(xp: ModuleType, face: Array, candidates: Array) -> Array:
    """``candidates[..., face, :]`` for ``candidates (*batch, 6, k)`` (a where, not a gather)."""
    onehot = face[..., None] == xp.arange(6, dtype=face.dtype)
    zero = xp.zeros((), dtype=candidates.dtype)
    return xp.sum(xp.where(onehot[..., None], candidates, zero), axis=-2)


def _major_face(xp: ModuleType, d: Array) -> Array:
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


def _check_near_far(checks: Checks, xp: ModuleType, near: Array, far: Array) -> None:
    checks.require(xp.isfinite(near), non_finite("near"))
    checks.require(xp.isfinite(far), non_finite("far"))
    checks.require(near > 0, "near: must be > 0 (the near plane lies in front of the light)")
    checks.require(far > near, "far: must be greater than near (near < far)")


# ------------------------------------------------------------------ cores


def _cube_face_views(xp: ModuleType, light: Array) -> Array:
    A, index, sign = _view_constants(light.dtype)
    if xp is not np:
        A, sign = xp.asarray(A), xp.asarray(sign)
    return A + light[..., index] * sign  # (*batch, 6, 4, 4)


def _depth_row(near: Array, far: Array, zero_to_one: bool, reversed_z: bool) -> tuple[Array, Array]:
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


def _cube_face_projection(
    xp: ModuleType,
    near: Array,
    far: Array,
    scale: float,
    zero_to_one: bool,
    flip_y: bool,
    reversed_z: bool,
) -> Array:
    """``(*batch, 4, 4)`` from ``(*batch,)`` arrays ``near, far``."""
    a, b = _depth_row(near, far, zero_to_one, reversed_z)
    P0, at_a, at_b = (xp.asarray(c) for c in _projection_constants(a.dtype, scale, flip_y))
    # where, not P0 + a * mask: b overflows to inf for an extreme far * near, and inf * 0 is NaN.
    return xp.where(at_a, a[..., None, None], xp.where(at_b, b[..., None, None], P0))


def _cube_face_projection_scalar(
    near: Any, far: Any, scale: float, zero_to_one: bool, flip_y: bool, reversed_z: bool
) -> Array:
    """:func:`_cube_face_projection` of one light's NumPy scalars, entry by entry."""
    a, b = _depth_row(near, far, zero_to_one, reversed_z)
    sy = -scale if flip_y else scale
    entries = (scale, 0, 0, 0, 0, sy, 0, 0, 0, 0, a, b, 0, 0, -1, 0)
    return np.array(entries, dtype=a.dtype).reshape(4, 4)


def _cube_face(xp: ModuleType, d: Array) -> tuple[Array, Array, Array]:
    face = _major_face(xp, d)
    R = _rotations(xp, d.dtype)
    view = xp.sum(R * d[..., None, None, :], axis=-1)  # (*batch, 6, 3): (s_c, t_c, -|m_a|)
    sc, tc, minus_ma = xp.unstack(_select_face(xp, face, view), axis=-1)
    # |m_a| is 0 only for the zero direction, which the caller refuses or poisons.
    ma = xp.where(minus_ma == 0, xp.ones_like(minus_ma), -minus_ma)
    return face, (sc / ma + 1) / 2, (tc / ma + 1) / 2


def _cube_face_direction(xp: ModuleType, face: Array, s: Array, t: Array) -> Array:
    sc, tc = 2 * s - 1, 2 * t - 1
    v = xp.stack([sc, tc, -xp.ones_like(sc)], axis=-1)  # view coordinates, |m_a| = 1
    R = _rotations(xp, v.dtype)
    # World = R^T view for each face; entries 0 and +-1 keep it exact.
    world = xp.sum(xp.matrix_transpose(R) * v[..., None, None, :], axis=-1)  # (*batch, 6, 3)
    return _select_face(xp, xp.astype(face, xp.int32), world)


def _face_depth(xp: ModuleType, D: Array, near: Array, far: Array, reversed_z: bool) -> Array:
    span = far - near
    if reversed_z:
        return near * (far - D) / (span * D)
    return far * (D - near) / (span * D)


# ------------------------------------------------------------------ public


def cube_face_views(light_position: Any) -> Array:
    r"""World-to-view matrices of the six faces of a point light's cube shadow map.

    Face ``i`` (``+X, -X, +Y, -Y, +Z, -Z``, i.e. ``GL_TEXTURE_CUBE_MAP_POSITIVE_X + i``)
    is the OpenGL look-at camera at the light with the (target, up) pairs of
    OpenGL and Vulkan: ``+X`` up ``-Y``, ``-X`` up ``-Y``, ``+Y`` up ``+Z``,
    ``-Y`` up ``-Z``, ``+Z`` up ``-Y``, ``-Z`` up ``-Y``:

    .. math::

        V_i = \begin{bmatrix} R_i & -R_i\,L \\ 0 & 1 \end{bmatrix},\qquad
        R_i = \begin{bmatrix} \mathbf s_i & \mathbf u_i & -\mathbf f_i \end{bmatrix}^{\mathsf T},
        \quad \mathbf s_i = \mathbf f_i \times \mathbf{up}_i,\;
        \mathbf u_i = \mathbf s_i \times \mathbf f_i .

    For a point ``p`` whose direction ``r = p - L`` selects face ``i``, the view
    coordinates ``V_i p`` are exactly ``(s_c, t_c, -|m_a|)`` of the
    specification's selection table, so drawing face ``i`` with
    :func:`cube_face_projection` and sampling the cube map with ``p - L``
    returns the texel drawn for ``p`` (OpenGL and Vulkan; the projection adds
    the y flip Direct3D, Metal and WebGPU need). Each ``R_i`` is a proper
    rotation with entries ``0, ±1``, so the matrices are exact and rigid and
    send the light to the origin.

    Arguments:
        light_position: ``(*batch, 3)`` the point light.

    Returns:
        ``(*batch, 6, 4, 4)`` column-vector matrices (``p_view = V[..., i, :, :] @ p``).

    Raises:
        ValueError: wrong shape; non-finite values (NaN under JAX transformations).

    Example:
        >>> import numpy as np
        >>> V = cube_face_views([1.0, 2.0, 3.0])
        >>> V.shape
        (6, 4, 4)
        >>> V[0] @ np.array([2.0, 2.0, 3.0, 1.0])  # one unit along +X: straight ahead
        array([ 0.,  0., -1.,  1.])
    """
    ctx, (light,) = convert(light_position=light_position)
    require_last("light_position", light, 3, hint="a point light is (x, y, z)")
    checks = Checks(ctx)
    _require_finite(checks, light, 1, "light_position")
    return checks.poison(_cube_face_views(ctx.xp, light), 3)


def cube_face_projection(
    near: Any,
    far: Any,
    *,
    map_size: int,
    border_texels: int = 0,
    api: GraphicsApi = "opengl",
    reversed_z: bool = False,
) -> Array:
    r"""The 90-degree projection of a cube shadow map's faces, with an optional border ring.

    With ``N = map_size`` texels per face side and ``b = border_texels``, the
    inner ``N - 2b`` texels cover the face's 90 degrees and the outer ring of
    ``b`` texels the neighbouring faces' directions, so a PCF kernel at a face
    edge reads real depths instead of clamping. The ``x`` and ``y`` scale is

    .. math::

        k = \frac{N - 2b}{N}, \qquad
        x_\mathrm{ndc} = k\,\frac{x_v}{-z_v}, \quad y_\mathrm{ndc} = \pm k\,\frac{y_v}{-z_v},

    so a direction on the face's 45-degree edge (``x_v = -z_v``) lands at window
    ``x = N - b``: the inner edge of the ring. Sampling such a map goes through
    the face explicitly (a 2D array texture, not ``samplerCube``): texel
    coordinate ``(b + s (N - 2b)) / N`` for the ``s`` of :func:`cube_face`
    (same for ``t``). With ``b = 0``, ``k = 1``: the plain cube map.

    **Depth** (``D = -z_v``, the distance along the face's axis): OpenGL's clip
    depth ``(f+n)/(f-n) - 2fn / ((f-n) D)`` runs ``-1..1``; the other APIs'
    ``f (D - n) / ((f - n) D)`` runs ``0..1``. ``reversed_z`` maps near to
    ``1`` (OpenGL: ``+1``) and far to ``0`` (``-1``). Reversed Z only gains
    precision with a ``0..1`` depth range: in OpenGL use
    ``glClipControl(GL_LOWER_LEFT, GL_ZERO_TO_ONE)`` with ``api="vulkan"``.

    **The y axis.** The selection table puts ``t = 0`` at the face's first row
    in memory. OpenGL draws NDC ``y = -1`` into the first row (lower-left
    origin), and so does Vulkan (its NDC ``y`` points down and its framebuffer
    origin is the upper left): for both, ``y_ndc = +k y_v / D``, and Vulkan must
    **not** get the usual ``y`` flip (negated ``[1, 1]`` entry or negative
    viewport height), which would mirror every face (``t -> 1 - t``).
    Direct3D, Metal and WebGPU draw NDC ``y = +1`` into the first row: their
    ``[1, 1]`` entry is ``-k``.

    Arguments:
        near: ``(*batch,)`` near plane distance along the face axis, ``> 0``.
        far: ``(*batch,)`` far plane distance, ``> near``.
        map_size: texels per side of each (square) face.
        border_texels: width of the border ring in texels, ``0 <= 2 b < N``.
        api: ``"opengl"``, ``"vulkan"``, ``"direct3d"``, ``"metal"`` or ``"webgpu"``.
        reversed_z: map near to the largest depth and far to the smallest.

    Returns:
        ``(*batch, 4, 4)`` column-vector projection (``clip = P @ V_i @ p``).

    Raises:
        ValueError: ``near <= 0``, ``near >= far`` or non-finite values (NaN under
            JAX transformations); a ``map_size`` or ``border_texels`` that is not
            an integer, or leaves no inner texel; an unknown ``api``.

    Example:
        >>> P = cube_face_projection(0.5, 10.0, map_size=256, border_texels=2)
        >>> float(P[0, 0]), float(P[1, 1])  # (256 - 4) / 256
        (0.984375, 0.984375)
        >>> cube_face_projection(0.5, 10.0, map_size=256, api="direct3d")[1, 1]
        np.float64(-1.0)
    """
    _check_api(api, reversed_z)
    zero_to_one, flip_y = _APIS[api]
    scale = face_scale(map_size, border_texels)
    n, f = _numpy_scalar(near), _numpy_scalar(far)
    if n is not None and type(n) is type(f) and math.isfinite(n) and math.isfinite(f) and 0 < n < f:
        # One light's NumPy scalars that pass the checks below: no conversion to
        # arrays, no per-check round trips. Anything else, failures included
        # (which the checks below report), takes the general path.
        return _cube_face_projection_scalar(n, f, scale, zero_to_one, flip_y, reversed_z)
    ctx, (n, f) = convert(near=near, far=far)
    xp = ctx.xp
    shape = batch_shape(tuple(n.shape), tuple(f.shape), names=("near", "far"))
    n, f = xp.broadcast_to(n, shape), xp.broadcast_to(f, shape)
    checks = Checks(ctx)
    _check_near_far(checks, xp, n, f)
    P = _cube_face_projection(xp, n, f, scale, zero_to_one, flip_y, reversed_z)
    return checks.poison(P, 2)


def face_scale(map_size: object, border_texels: object) -> float:
    """``k = (N - 2b) / N``, the window scale of a face with a border ring, both checked."""
    size = integer("map_size", map_size, 1)
    border = integer("border_texels", border_texels, 0)
    if size - 2 * border < 1:
        raise ValueError(
            f"border_texels: a border of {border} texels on each side leaves no inner "
            f"texel of a {size}-texel face (need 2 * border_texels < map_size)"
        )
    return (size - 2 * border) / size


def cube_face(directions: Any) -> CubeFaceCoords:
    r"""The cube-map face a direction samples, and where: the specification's selection.

    The face is that of the component ``m_a`` of largest magnitude, ``+`` or
    ``-`` by its sign; ``(s_c, t_c)`` come from the table of OpenGL 4.6 §8.13
    (Table 8.19), identical in Vulkan's specification:

    .. math::

        s = \tfrac12\left(\frac{s_c}{|m_a|} + 1\right), \qquad
        t = \tfrac12\left(\frac{t_c}{|m_a|} + 1\right).

    | face | ``s_c`` | ``t_c`` | ``m_a`` |
    | ---- | ------- | ------- | ------- |
    | +X   | ``-z``  | ``-y``  | ``x``   |
    | -X   | ``+z``  | ``-y``  | ``x``   |
    | +Y   | ``+x``  | ``+z``  | ``y``   |
    | -Y   | ``+x``  | ``-z``  | ``y``   |
    | +Z   | ``+x``  | ``-y``  | ``z``   |
    | -Z   | ``-x``  | ``-y``  | ``z``   |

    **Ties** (a direction with two or three equal largest magnitudes: an edge
    or a corner of the cube) follow the rule of Vulkan's "Cube Map Face
    Selection": "``r_z`` wins over ``r_y`` and ``r_x``, and [...] ``r_y`` wins
    over ``r_x``". So ``|z| >= |x|, |y|`` selects ``±Z``, else ``|y| >= |x|``
    selects ``±Y``, else ``±X`` (the sign of the winning component picks ``+``
    or ``-``). Vulkan only recommends this rule and OpenGL leaves ties to the
    implementation, so a GPU may pick another face; each candidate face
    addresses the same point of the shared edge (``s`` or ``t`` is ``0`` or
    ``1`` on each), so a map whose faces agree along their edges gives the
    same value either way.

    Arguments:
        directions: ``(*batch, 3)`` nonzero directions (from the light to the point).

    Returns:
        :class:`CubeFaceCoords` ``(face, s, t)``, each ``(*batch,)``; ``face``
        int32 in ``0..5``, ``s, t`` in ``[0, 1]``.

    Raises:
        ValueError: wrong shape; non-finite values; a zero direction. Under JAX
            transformations ``s, t`` are NaN and ``face`` is ``-1`` there.

    Example:
        >>> cube_face([1.0, 0.5, -0.25])  # +X: s = (0.25 + 1) / 2, t = (-0.5 + 1) / 2
        CubeFaceCoords(face=np.int32(0), s=np.float64(0.625), t=np.float64(0.25))
        >>> int(cube_face([1.0, -1.0, 0.5]).face)  # |x| = |y|: y wins, -Y
        3
        >>> int(cube_face([-2.0, 2.0, -2.0]).face)  # a corner: z wins, -Z
        5
    """
    ctx, (d,) = convert(directions=directions)
    xp = ctx.xp
    require_last("directions", d, 3, hint="a direction is (x, y, z)")
    checks = Checks(ctx)
    _require_finite(checks, d, 1, "directions")
    checks.require(
        xp.any(d != 0, axis=-1),
        "directions: a direction is zero (the point is at the light); it selects no face",
    )
    face, s, t = _cube_face(xp, d)
    if checks.invalid is not None:
        face = xp.where(checks.invalid, xp.asarray(-1, dtype=face.dtype), face)
    return CubeFaceCoords(face, checks.poison(s, 0), checks.poison(t, 0))


def cube_face_direction(face: Any, s: Any, t: Any) -> Array:
    r"""The inverse of :func:`cube_face`: the direction that samples ``(face, s, t)``.

    With ``s_c = 2 s - 1`` and ``t_c = 2 t - 1`` the face's view coordinates are
    ``(s_c, t_c, -1)`` and the direction is ``R_face^T (s_c, t_c, -1)`` (the
    rotation of :func:`cube_face_views`): a point on the surface of the cube
    ``[-1, 1]^3`` (``|m_a| = 1``), not a unit vector; normalize it if needed.
    ``s, t`` outside ``[0, 1]`` continue the face's plane, which is where the
    border ring of :func:`cube_face_projection` looks.

    Arguments:
        face: ``(*batch,)`` integer face index in ``0..5`` (``+X, -X, +Y, -Y, +Z, -Z``).
        s, t: ``(*batch,)`` texture coordinates on the face.

    Returns:
        ``(*batch, 3)`` direction with ``|m_a| = 1``.

    Raises:
        ValueError: ``face`` not an integer in ``0..5``; non-finite ``s`` or ``t``
            (NaN under JAX transformations).

    Example:
        >>> cube_face_direction(0, 0.625, 0.25)  # back to (1, 0.5, -0.25)
        array([ 1.  ,  0.5 , -0.25])
    """
    ctx, (f, s_, t_) = convert(face=face, s=s, t=t)
    xp = ctx.xp
    shape = batch_shape(tuple(f.shape), tuple(s_.shape), tuple(t_.shape), names=("face", "s", "t"))
    f, s_, t_ = (xp.broadcast_to(v, shape) for v in (f, s_, t_))
    checks = Checks(ctx)
    checks.require(
        xp.isfinite(f) & (f == xp.round(f)) & (f >= 0) & (f <= 5),
        "face: must be an integer from 0 to 5 (+X, -X, +Y, -Y, +Z, -Z)",
    )
    checks.require(xp.isfinite(s_), non_finite("s"))
    checks.require(xp.isfinite(t_), non_finite("t"))
    safe_face = xp.where(xp.isfinite(f), f, xp.zeros_like(f))
    return checks.poison(_cube_face_direction(xp, safe_face, s_, t_), 1)


def cube_face_depth(
    light_position: Any,
    points: Any,
    near: Any,
    far: Any,
    *,
    reversed_z: bool = False,
) -> CubeFaceDepth:
    r"""The depth a receiver point compares against its light's cube shadow map.

    The point ``p`` is seen through the face of ``r = p - L``
    (:func:`cube_face`, ties included) at the distance ``D = |m_a| = max(|r_x|, |r_y|, |r_z|)``
    along that face's axis (the view's ``-z``), not at ``|r|``. A hardware
    depth cube map holds the window depth of :func:`cube_face_projection`:

    .. math::

        d = \frac{f\,(D - n)}{(f - n)\,D}
        \quad\text{or, reversed,}\quad
        d = \frac{n\,(f - D)}{(f - n)\,D},

    the same in every API (OpenGL's ``-1..1`` NDC depth becomes ``0..1`` in
    the default depth range), so there is no ``api`` argument. A cube map that
    stores distances instead compares ``|r|``. Points with ``D`` outside
    ``[near, far]`` get depths outside ``[0, 1]`` (clipped when drawn). Apply
    your depth bias to the value compared, in the same units.

    Arguments:
        light_position: ``(*batch, 3)`` the point light.
        points: ``(*batch, 3)`` receiver points (batch dimensions broadcast; pass
            ``light[..., None, :]`` with ``(*batch, N, 3)`` points).
        near, far: ``(*batch,)`` as given to :func:`cube_face_projection`.
        reversed_z: as given to :func:`cube_face_projection`.

    Returns:
        :class:`CubeFaceDepth` ``(face, depth, distance)``, each ``(*batch,)``.

    Raises:
        ValueError: wrong shapes; non-finite values; ``near <= 0`` or
            ``near >= far``; a point at the light. Under JAX transformations the
            affected ``depth`` and ``distance`` are NaN and ``face`` is ``-1``.

    Example:
        >>> r = cube_face_depth([0.0, 0.0, 0.0], [3.0, 4.0, 0.0], 1.0, 9.0)
        >>> int(r.face), float(r.depth), float(r.distance)  # +Y, D = 4
        (2, 0.84375, 5.0)
    """
    ctx, (light, p, n, f) = convert(
        light_position=light_position, points=points, near=near, far=far
    )
    xp = ctx.xp
    require_last("light_position", light, 3, hint="a point light is (x, y, z)")
    require_last("points", p, 3, hint="points are (*batch, 3)")
    shape = batch_shape(
        tuple(light.shape[:-1]),
        tuple(p.shape[:-1]),
        tuple(n.shape),
        tuple(f.shape),
        names=("light_position", "points", "near", "far"),
    )
    checks = Checks(ctx)
    _require_finite(checks, light, 1, "light_position")
    _require_finite(checks, p, 1, "points")
    _check_near_far(checks, xp, n, f)
    r = p - light
    checks.require(
        xp.any(r != 0, axis=-1),
        "points: a point coincides with light_position; it has no direction from the light",
    )
    face = xp.broadcast_to(_major_face(xp, r), shape)
    D = xp.max(xp.abs(r), axis=-1)
    safe_D = xp.where(D == 0, xp.ones_like(D), D)
    depth = xp.broadcast_to(_face_depth(xp, safe_D, n, f, reversed_z), shape)
    distance = xp.broadcast_to(norm(xp, r), shape)
    if checks.invalid is not None:
        checks.invalid = xp.broadcast_to(checks.invalid, shape)
        face = xp.where(checks.invalid, xp.asarray(-1, dtype=face.dtype), face)
    return CubeFaceDepth(face, checks.poison(depth, 0), checks.poison(distance, 0))
