"""Cube shadow maps at the door: the six faces' views and projection, and the face a
direction samples (checks; the cores are :mod:`shadowmath._math._cube`'s)."""

from __future__ import annotations

import math
from types import ModuleType
from typing import Any

import numpy as np

from shadowmath._boundary._shapes import ArrayLike, BoolLike, Float, IntLike, Real
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
from shadowmath._math import _cube
from shadowmath._math._conventions import GraphicsApi
from shadowmath._math._cube import CubeFaceCoords, CubeFaceDepth
from shadowmath._math._vector import norm

from ._api_convention import check_api


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


def _check_near_far(checks: Checks, xp: ModuleType, near: Array, far: Array) -> None:
    checks.require(xp.isfinite(near), non_finite("near"))
    checks.require(xp.isfinite(far), non_finite("far"))
    checks.require(near > 0, "near: must be > 0 (the near plane lies in front of the light)")
    checks.require(far > near, "far: must be greater than near (near < far)")


def cube_face_views(light_position: Real[ArrayLike, "*batch 3"]) -> Float[Array, "*batch 6 4 4"]:
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
    return checks.poison(_cube.cube_face_views(ctx.xp, light), 3)


def cube_face_projection(
    near: Real[ArrayLike, "*#batch"],
    far: Real[ArrayLike, "*#batch"],
    *,
    map_size: IntLike,
    border_texels: IntLike = 0,
    api: GraphicsApi = "opengl",
    reversed_z: BoolLike = False,
) -> Float[Array, "*batch 4 4"]:
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
    check_api(api, reversed_z)
    zero_to_one, flip_y = _cube.APIS[api]
    conv = {"zero_to_one": zero_to_one, "flip_y": flip_y, "reversed_z": reversed_z}
    scale = face_scale(map_size, border_texels)
    n, f = _numpy_scalar(near), _numpy_scalar(far)
    if n is not None and type(n) is type(f) and math.isfinite(n) and math.isfinite(f) and 0 < n < f:
        # One light's NumPy scalars that pass the checks below: no conversion to
        # arrays, no per-check round trips. Anything else, failures included
        # (which the checks below report), takes the general path.
        return _cube.cube_face_projection_scalar(n, f, scale, **conv)
    ctx, (n, f) = convert(near=near, far=far)
    xp = ctx.xp
    shape = batch_shape(tuple(n.shape), tuple(f.shape), names=("near", "far"))
    n, f = xp.broadcast_to(n, shape), xp.broadcast_to(f, shape)
    checks = Checks(ctx)
    _check_near_far(checks, xp, n, f)
    P = _cube.cube_face_projection(xp, n, f, scale, **conv)
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


def cube_face(directions: Real[ArrayLike, "*batch 3"]) -> CubeFaceCoords:
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
    face, s, t = _cube.cube_face(xp, d)
    if checks.invalid is not None:
        face = xp.where(checks.invalid, xp.asarray(-1, dtype=face.dtype), face)
    return CubeFaceCoords(face, checks.poison(s, 0), checks.poison(t, 0))


def cube_face_direction(
    face: Real[ArrayLike, "*#batch"], s: Real[ArrayLike, "*#batch"], t: Real[ArrayLike, "*#batch"]
) -> Float[Array, "*batch 3"]:
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
    return checks.poison(_cube.cube_face_direction(xp, safe_face, s_, t_), 1)


def cube_face_depth(
    light_position: Real[ArrayLike, "*#batch 3"],
    points: Real[ArrayLike, "*#batch 3"],
    near: Real[ArrayLike, "*#batch"],
    far: Real[ArrayLike, "*#batch"],
    *,
    reversed_z: BoolLike = False,
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
    face = xp.broadcast_to(_cube.major_face(xp, r), shape)
    D = xp.max(xp.abs(r), axis=-1)
    safe_D = xp.where(D == 0, xp.ones_like(D), D)
    depth = xp.broadcast_to(_cube.face_depth(xp, safe_D, n, f, reversed_z), shape)
    distance = xp.broadcast_to(norm(xp, r), shape)
    if checks.invalid is not None:
        checks.invalid = xp.broadcast_to(checks.invalid, shape)
        face = xp.where(checks.invalid, xp.asarray(-1, dtype=face.dtype), face)
    return CubeFaceDepth(face, checks.poison(depth, 0), checks.poison(distance, 0))
