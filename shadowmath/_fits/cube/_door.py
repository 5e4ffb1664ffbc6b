"""``cube_depth_range``'s door: the casters and receivers read, converted and checked once.

The public function: it reads the operands' kinds (points, :class:`Triangles`, a
:class:`Mesh`), converts and checks them, runs the driver (:func:`._driver.cube_depth_core`)
and returns the result (:class:`._result.CubeDepthRange`).
"""

from __future__ import annotations

from shadowmath._boundary._shapes import ArrayLike, Real
from shadowmath._boundary._validate import (
    Checks,
    batch_shape,
    convert,
    integer,
    non_finite,
    require_last,
    require_no_new_batch,
    require_vertices,
)
from shadowmath._fits.shadow._door import _receiver_kind, _receiver_rows, caster_triangles
from shadowmath._geometry._cube_faces import face_scale
from shadowmath.receivers import Mesh, Triangles

from ._driver import AT_LIGHT, cube_depth_core
from ._result import CubeDepthRange


def border_scale(map_size: int | None, border_texels: int) -> float:
    """``k`` of :func:`face_scale`; 1 without a ring, where ``map_size`` may be None."""
    if map_size is None:
        if integer("border_texels", border_texels, 0) == 0:
            return 1.0
        raise ValueError("map_size: a border ring of border_texels > 0 needs the face's map_size")
    return face_scale(map_size, border_texels)


def cube_depth_range(
    light_position: Real[ArrayLike, "*#batch 3"],
    casters: Real[ArrayLike, "*#batch N 3"] | Real[ArrayLike, "*#batch N 3 3"] | Triangles | Mesh,
    *,
    receivers: Real[ArrayLike, "*#batch M 3"] | Triangles | Mesh | None = None,
    map_size: int | None = None,
    border_texels: int = 0,
) -> CubeDepthRange:
    r"""Fit ``near`` and ``far`` of a point light's cube shadow map to its casters.

    With ``D(p) = max(|p_x - L_x|, |p_y - L_y|, |p_z - L_z|)``, the depth of ``p`` along
    the axis of the face that sees it, and ``k = (N - 2b) / N`` for a border ring of
    ``b`` texels (:func:`cube_face_projection`; ``k = 1`` without one):

    .. math::

        n = k \min_{\text{casters}} D \,(1 - s), \qquad
        f = \max_{\text{casters, receivers}} D \,(1 + s), \qquad s = 1/64
        \ (\texttt{NEAR\_FAR\_SLACK}).

    A face's ring shows its neighbours' directions, where a caster's depth along this
    face's axis can drop to ``k D``: ``k`` keeps those casters too. ``D`` is convex, so
    its largest value over a triangle is at a corner but its smallest may lie inside
    (a wall beside the light): casters given as :class:`Triangles` or a :class:`Mesh`
    count their whole surface (exactly: the minimum lies at a corner, where an edge
    crosses a plane ``r_i = +-r_j``, or where the triangle crosses a diagonal
    ``r = t (+-1, +-1, +-1)``); casters given as points count those points. Receivers only
    push ``far``: a receiver nearer the light than every caster is never in shadow. Every
    caster drawn then lies in ``[near, far]`` with room for float32 rounding.

    Arguments:
        light_position: ``(*batch, 3)`` the point light.
        casters: ``(*batch, N, 3)`` points (a mesh's vertices: exact unless a triangle
            passes nearer the light than its corners), :class:`Triangles`
            ``(*batch, M, 3, 3)`` or a :class:`Mesh`.
        receivers: what the shadows fall on: ``(*batch, M, 3)`` points,
            :class:`Triangles` ``(*batch, M, 3, 3)`` or a :class:`Mesh`; None: the
            casters only. They add no batch dimension (a raw ``(M, 3, 3)`` array is
            ``M`` point sets, refused beside one light: wrap it in :class:`Triangles`).
        map_size: texels per face side; needed with ``border_texels``.
        border_texels: the border ring of :func:`cube_face_projection`.

    Returns:
        :class:`CubeDepthRange` ``(near, far)``, each ``(*batch,)``.

    Raises:
        ValueError: wrong shapes (receivers with batch dimensions that neither
            ``light_position`` nor ``casters`` has); non-finite values; a caster at the
            light's position
            (within rounding: no near plane keeps it); a border that leaves no inner
            texel. Under JAX transformations the affected entries (and their gradients)
            are NaN.

    Example:
        >>> import numpy as np, shadowmath as sm
        >>> box = np.array([[x, y, z] for x in (1, 2) for y in (-1, 1) for z in (-1, 1)], float)
        >>> near, far = cube_depth_range([0.0, 0.0, 0.0], box)
        >>> float(near), float(far)  # D from 1 to 2, with 1/64 of slack
        (0.984375, 2.03125)
        >>> float(cube_depth_range([0.0, 0.0, 0.0], box, map_size=64, border_texels=2).near)
        0.9228515625
        >>> wall = sm.Triangles(np.array([[[1.0, -5, -5], [1, 5, -5], [1, 0, 5]]]))
        >>> float(cube_depth_range([0.0, 0.0, 0.0], wall).near)  # its corners are 5 away
        0.984375
    """
    k = border_scale(map_size, border_texels)
    c_kind, c_name, c_array = _receiver_kind(casters, "casters")
    r_kind, r_name, r_array = _receiver_kind(receivers)
    ctx, (light, C, R) = convert(
        light_position=light_position, **{c_name: c_array}, **{r_name: r_array}
    )
    xp = ctx.xp
    require_last("light_position", light, 3, hint="a point light is (x, y, z)")
    triangles = None
    if c_kind == "points":
        require_vertices("casters", C)
    else:
        triangles = caster_triangles(ctx, c_kind, C, casters, "casters")
    points = C if triangles is None else xp.reshape(triangles, (*triangles.shape[:-3], -1, 3))
    shapes = (tuple(light.shape[:-1]), tuple(points.shape[:-2]))
    shape = batch_shape(*shapes, names=("light_position", "casters"))
    corners = None
    if R is not None:
        R = _receiver_rows(ctx, r_kind, R, receivers)
        corners = xp.reshape(R, (*R.shape[:-2], -1, 3))  # triangles' rows of 9: 3 corners
        require_no_new_batch("receivers", R.shape[:-2], shape)
    checks = Checks(ctx)
    checks.require(xp.all(xp.isfinite(light), axis=-1), non_finite("light_position"))
    checks.require(xp.all(xp.isfinite(points), axis=(-2, -1)), non_finite("casters"))
    if corners is not None:
        checks.require(xp.all(xp.isfinite(corners), axis=(-2, -1)), non_finite("receivers"))
    near, far, ok = cube_depth_core(
        xp, light, xp.matrix_transpose(points), corners, k=k, eps=ctx.eps, triangles=triangles
    )
    checks.require(ok, f"casters: {AT_LIGHT}")
    near, far = xp.broadcast_to(near, shape), xp.broadcast_to(far, shape)
    return CubeDepthRange(checks.poison(near, 0), checks.poison(far, 0))
