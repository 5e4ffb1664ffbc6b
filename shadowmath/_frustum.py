"""The adaptive perspective frustum of the shadow map, and its two projections.

Light coordinates (see :mod:`shadowmath._frame`) have the light at the origin
and ``+Z`` toward the blocker. A light-space point ``(x, y, z)`` with ``z > 0``
projects to the ratios ``x / z`` and ``y / z``; the frustum scales the largest
of them to the border margin, so the blocker's silhouette fills the map up to a
border of untouched texels.
"""

from __future__ import annotations

import operator
from typing import Any, NamedTuple

import numpy as np

from ._backend import (
    Array,
    Checks,
    Context,
    all_finite,
    batch_shape,
    eps,
    non_finite,
    prepare,
    require_last,
)
from ._frame import LightFrame, _frame_arrays
from ._vector import norm

#: Relative slack of the default near and far planes around the blocker:
#: ``near = z_min * (1 - NEAR_FAR_SLACK)``, ``far = z_max * (1 + NEAR_FAR_SLACK)``.
NEAR_FAR_SLACK = 1.0 / 64.0


class Frustum(NamedTuple):
    """A perspective frustum in light coordinates, symmetric unless offset.

    Attributes (each ``(*batch,)``):
        rx_max: half-width of the frustum at ``z = 1`` about its centre: for the
            article's symmetric frustum, the largest ``|x / z|`` of the blocker.
        ry_max: the same along light ``Y``.
        near: distance of the near plane from the light (``z``), ``> 0``.
        far: distance of the far plane, ``> near``.
        margin_x: fraction of the map's half-width the silhouette may fill
            (``(width - 2 border) / width``; the article's 0.98).
        margin_y: the same along light ``Y`` (the map's height).
        x_offset: the ratio ``x / z`` at the map's centre (default 0: symmetric).
            An off-centre frustum spans ``x / z`` in
            ``[x_offset - rx_max, x_offset + rx_max]`` (before the margin).
        y_offset: the same along light ``Y``.
    """

    rx_max: Array
    ry_max: Array
    near: Array
    far: Array
    margin_x: Array
    margin_y: Array
    x_offset: Array = 0.0
    y_offset: Array = 0.0


def _texels(name: str, value: Any) -> tuple[int, int]:
    """``map_size`` as ``(width, height)`` of positive Python ints."""
    is_pair = isinstance(value, tuple | list) or (isinstance(value, np.ndarray) and value.ndim == 1)
    values = tuple(value) if is_pair else (value, value)
    if len(values) != 2:
        raise ValueError(f"{name}: expected an int or (width, height), got {value!r}")
    if any(isinstance(v, bool | np.bool_) for v in values):
        raise ValueError(f"{name}: texel counts must be integers, not booleans, got {value!r}")
    try:
        w, h = (operator.index(v) for v in values)
    except TypeError:
        raise ValueError(f"{name}: texel counts must be integers, got {value!r}") from None
    if w <= 0 or h <= 0:
        raise ValueError(f"{name}: texel counts must be positive, got {value!r}")
    return w, h


def border_margin(
    map_size: int | tuple[int, int], *, border_texels: int = 1
) -> tuple[float, float]:
    r"""The fraction of a shadow map's half-extent left inside its border.

    .. math:: m = \frac{\mathrm{size} - 2\,b}{\mathrm{size}}

    With ``b`` border texels on each side the silhouette must stay within
    ``|x_ndc| <= m``: NDC spans ``[-1, 1]`` over ``size`` texels, so one texel
    is ``2 / size`` wide. The map is sampled with clamp-to-edge, which repeats
    the edge texels over every receiver point outside the frustum; a single
    drawn border texel would smear a streak of false shadow across the
    receiver ("shadow leaking"). For a 100-texel map ``m = 0.98``, the
    article's constant (and ``m / 2 = 0.49`` in texture space). The constant
    0.98 stops guaranteeing an empty border below 100 texels, and below 50
    texels it lets the silhouette cover border-texel *centres*, so even
    point-sampled rasterization draws into the border.

    Arguments:
        map_size: ``size`` for a square map or ``(width, height)`` in texels.
        border_texels: untouched texels on each side (``>= 0``).

    Returns:
        ``(margin_x, margin_y)`` as Python floats.

    Raises:
        ValueError: non-integer or non-positive sizes, a negative border, or a
            map no larger than its two borders.

    Example:
        >>> border_margin(100)
        (0.98, 0.98)
        >>> border_margin((512, 256), border_texels=2)
        (0.9921875, 0.984375)
    """
    w, h = _texels("map_size", map_size)
    try:
        b = operator.index(border_texels)
    except TypeError:
        raise ValueError(f"border_texels: expected an int, got {border_texels!r}") from None
    if b < 0:
        raise ValueError(f"border_texels: must be >= 0, got {b}")
    if min(w, h) <= 2 * b:
        raise ValueError(
            f"map_size: {w}x{h} texels leave no room inside a border of {b} texel(s) on each "
            f"side; use at least {2 * b + 1} texels per axis"
        )
    return (w - 2 * b) / w, (h - 2 * b) / h


def _margins(map_size: Any, border_texels: int, margin: Any) -> tuple[float, float]:
    derived = border_margin(map_size, border_texels=border_texels)
    if margin is None:
        return derived
    values = tuple(margin) if isinstance(margin, tuple | list) else (margin, margin)
    if len(values) != 2:
        raise ValueError(f"margin: expected a float or (margin_x, margin_y), got {margin!r}")
    mx, my = (float(v) for v in values)
    if not (0 < mx <= 1 and 0 < my <= 1):
        raise ValueError(f"margin: must lie in (0, 1], got {margin!r}")
    return mx, my


def adaptive_frustum(
    frame: LightFrame,
    vertices: Any,
    map_size: int | tuple[int, int],
    *,
    border_texels: int = 1,
    margin: float | tuple[float, float] | None = None,
    near: Any = None,
    far: Any = None,
) -> Frustum:
    r"""The article's adaptive frustum: the largest projection ratios of the blocker.

    .. math::

        R_{x,\max} = \max_i \left|\frac{x_i}{z_i}\right|, \qquad
        R_{y,\max} = \max_i \left|\frac{y_i}{z_i}\right|

    over the blocker's vertices ``(x_i, y_i, z_i)`` in light coordinates.
    Scaling ``x / z`` by ``margin_x / R_x,max`` then puts every vertex inside
    ``|x_ndc| <= margin_x`` with at least one on it (and likewise for ``y``).
    As maxima, ``R_x,max`` and ``R_y,max`` are only piecewise smooth: their
    gradient flows to the extreme vertex alone (shared among tied ones) and
    jumps when another vertex takes over. :func:`smooth_frustum` is a smooth,
    still conservative alternative, :func:`offcenter_frustum` an off-centre one.

    Arguments:
        frame: the :class:`LightFrame` (``(*batch, 3)`` fields).
        vertices: ``(*batch, N, 3)`` blocker vertices in world coordinates.
        map_size: ``size`` of a square map or ``(width, height)`` in texels;
            width runs along light ``X``, height along light ``Y``.
        border_texels: texels left empty on each side (default 1, as in the article).
        margin: force the margins instead of deriving them from the map's size,
            e.g. ``0.98`` for the article's constant (a float, or ``(mx, my)``).
        near: near-plane distance; default ``z_min * (1 - NEAR_FAR_SLACK)``.
        far: far-plane distance; default ``z_max * (1 + NEAR_FAR_SLACK)``, so
            the blocker is never clipped (``NEAR_FAR_SLACK = 1/64``).

    Returns:
        :class:`Frustum` with ``(*batch,)`` fields.

    Raises:
        ValueError: wrong shapes, an empty vertex set, non-finite values, any
            vertex not strictly in front of the light (``z <= 0``: one frustum
            cannot see it), a silhouette of zero width or height (a point or an
            edge-on blocker), a map too small for its border, ``near <= 0`` or
            ``near >= far``. Under JAX transformations the frustum's fields are
            NaN instead (except the static margins).

    Example:
        >>> f = light_frame([0, 0, 0], [[-1, -1, 4], [1, 1, 4], [1, -1, 4], [-1, 1, 4]])
        >>> fr = adaptive_frustum(f, [[-1, -1, 4], [1, 1, 4], [1, -1, 4], [-1, 1, 4]], 100)
        >>> float(fr.rx_max), float(fr.margin_x)
        (0.25, 0.98)
    """
    margins = _margins(map_size, border_texels, margin)
    ls = _light_space(frame, vertices, near=near, far=far)
    xp = ls.ctx.xp
    rx_max = xp.max(xp.abs(ls.x) / ls.safe_z, axis=-1)
    ry_max = xp.max(xp.abs(ls.y) / ls.safe_z, axis=-1)
    zero = xp.zeros_like(rx_max)
    return _assemble(ls, margins, rx_max, ry_max, zero, zero)


class _LightSpace(NamedTuple):
    """A validated blocker in light coordinates, shared by every frustum builder."""

    ctx: Context
    checks: Checks
    args: dict[str, Array]  # the converted arguments (near, far and any extras)
    x: Array  # (*batch, N) light-space coordinates of the vertices
    y: Array
    z: Array
    safe_z: Array  # z, with 1 where z <= 0 (those entries are invalid anyway)
    noise: Array  # (*batch,) the rounding noise of the ratios x / z and y / z


def _light_space(frame: LightFrame, vertices: Any, **extra: Any) -> _LightSpace:
    """The blocker's vertices in light coordinates, with the in-front check done."""
    _, fchecks, f = _frame_arrays(frame)
    ctx, a = prepare(
        origin=f.origin,
        x_axis=f.x_axis,
        y_axis=f.y_axis,
        z_axis=f.z_axis,
        vertices=vertices,
        **extra,
    )
    xp = ctx.xp
    verts = a["vertices"]
    require_last("vertices", verts, 3, min_ndim=2, hint="vertices are (*batch, N, 3)")
    if verts.shape[-2] == 0:
        raise ValueError("vertices: the vertex set is empty (N = 0); a blocker needs vertices")
    checks = Checks(ctx)
    checks.invalid = fchecks.invalid
    checks.require(all_finite(xp, verts, 2), non_finite("vertices"))

    offsets = verts - a["origin"][..., None, :]
    x = xp.sum(offsets * a["x_axis"][..., None, :], axis=-1)
    y = xp.sum(offsets * a["y_axis"][..., None, :], axis=-1)
    z = xp.sum(offsets * a["z_axis"][..., None, :], axis=-1)
    # Thresholds relative to each vertex's distance, never absolute: x, y and z
    # carry rounding errors of a few ulps of |V - P| (the difference and the
    # axes' own rounding), so a vertex is in front only when z clears that
    # noise, and a silhouette has width only when its ratios clear it, in any units.
    dist = norm(xp, offsets)
    tiny = eps(ctx)
    checks.require(
        xp.all(z > 16 * tiny * dist, axis=-1),
        "vertices: a blocker vertex is not strictly in front of the light (z <= 0 in light "
        "coordinates, or within rounding of 0); one frustum cannot cover it: move the light "
        "out of the blocker, or split the blocker (or use an omnidirectional shadow map)",
    )
    # Divide by a safe z so that invalid entries (z <= 0) never produce inf/NaN
    # gradients that leak into valid ones; they are poisoned below.
    safe_z = xp.where(z > 0, z, xp.ones_like(z))
    noise = 32 * tiny * xp.max(dist / safe_z, axis=-1)
    return _LightSpace(ctx, checks, a, x, y, z, safe_z, noise)


def _assemble(
    ls: _LightSpace,
    margins: tuple[float, float],
    half_x: Array,
    half_y: Array,
    x_offset: Array,
    y_offset: Array,
) -> Frustum:
    """The Frustum of given half-extents and centre, with default or checked near/far."""
    ctx, checks, a = ls.ctx, ls.checks, ls.args
    xp = ctx.xp
    checks.require(
        (half_x > ls.noise) & (half_y > ls.noise),
        "vertices: the blocker's silhouette has zero width or height as seen from the light "
        "(a single point, or a flat blocker seen edge-on, within rounding); no frustum can "
        "be fitted",
    )
    near = a["near"] if a["near"] is not None else xp.min(ls.z, axis=-1) * (1 - NEAR_FAR_SLACK)
    far = a["far"] if a["far"] is not None else xp.max(ls.z, axis=-1) * (1 + NEAR_FAR_SLACK)
    for name in ("near", "far"):
        if a[name] is not None:
            checks.require(xp.isfinite(a[name]), f"{name}: must be finite")
    checks.require(near > 0, "near: the near plane must lie in front of the light (near > 0)")
    checks.require(near < far, "near/far: the near plane must be closer than the far plane")

    shapes = [tuple(v.shape) for v in (half_x, half_y, near, far)]
    shape = batch_shape(*shapes, names=("frame and vertices", "temperature", "near", "far"))

    def field(v: Array) -> Array:
        return checks.poison(xp.broadcast_to(v, shape), 0)

    mx, my = margins
    return Frustum(
        rx_max=field(half_x),
        ry_max=field(half_y),
        near=field(near),
        far=field(far),
        margin_x=xp.broadcast_to(ctx.constant(mx), shape),
        margin_y=xp.broadcast_to(ctx.constant(my), shape),
        x_offset=field(x_offset),
        y_offset=field(y_offset),
    )


def _frustum_arrays(frustum: Frustum) -> tuple[Context, dict[str, Array], tuple[int, ...]]:
    if not isinstance(frustum, tuple) or len(frustum) not in (6, 8):
        raise ValueError("frustum: expected a Frustum (rx_max, ry_max, near, far, margin_x, ...)")
    names = ("rx_max", "ry_max", "near", "far", "margin_x", "margin_y", "x_offset", "y_offset")
    values = dict(zip(names, (*frustum, 0.0, 0.0)[:8], strict=True))
    # A default (Python number) offset must not promote a float32 frustum to float64.
    defaults = {n: values.pop(n) for n in names[6:] if isinstance(values[n], int | float)}
    ctx, a = prepare(**values)
    a.update({n: ctx.constant(float(v)) for n, v in defaults.items()})
    shape = batch_shape(*(tuple(a[n].shape) for n in names), names=names)
    return ctx, a, shape


def _entries(ctx: Context, rows: list[list[Array | float]], shape: tuple[int, ...]) -> Array:
    """Stack a 4x4 of scalars and ``(*batch,)`` arrays into ``(*batch, 4, 4)``."""
    xp = ctx.xp
    flat = [xp.broadcast_to(ctx.asarray(e), shape) for row in rows for e in row]
    return xp.reshape(xp.stack(flat, axis=-1), (*shape, 4, 4))


def _projection_rows(ctx: Context, a: dict[str, Array]) -> list[list[Array | float]]:
    n, f = a["near"], a["far"]
    sx, sy = a["margin_x"] / a["rx_max"], a["margin_y"] / a["ry_max"]
    return [
        [sx, 0.0, -sx * a["x_offset"], 0.0],
        [0.0, sy, -sy * a["y_offset"], 0.0],
        # -2 n (f / (f - n)) rather than -2 f n / (f - n): no overflow of f n.
        [0.0, 0.0, (f + n) / (f - n), -2 * n * (f / (f - n))],
        [0.0, 0.0, 1.0, 0.0],
    ]


def _validated(ctx: Context, a: dict[str, Array], shape: tuple[int, ...]) -> Checks:
    """The frustum's value checks, run before any entry is computed.

    Eagerly a bad field raises here, before a division by ``rx_max = 0`` or
    ``far - near = 0`` could emit a NumPy warning; lazily the returned checks
    poison the matrix.
    """
    xp = ctx.xp
    checks = Checks(ctx)
    for name, v in a.items():
        checks.require(xp.isfinite(v), f"frustum.{name}: must be finite")
    # At least the smallest normal float, so that margin / rx_max cannot overflow.
    tiny = float(np.finfo(ctx.dtype).tiny)
    checks.require(
        (a["rx_max"] >= tiny) & (a["ry_max"] >= tiny),
        "frustum: rx_max and ry_max must be > 0 (and normal floats)",
    )
    checks.require(a["near"] > 0, "frustum.near: must be > 0")
    checks.require(a["near"] < a["far"], "frustum: near must be < far")
    if checks.invalid is not None:
        checks.invalid = xp.broadcast_to(checks.invalid, shape)
    return checks


def blocker_projection(frustum: Frustum) -> Array:
    r"""Light coordinates to OpenGL clip space, for drawing the shadow map.

    .. math::

        P = \begin{bmatrix}
            m_x / R_{x,\max} & 0 & -m_x c_x / R_{x,\max} & 0 \\
            0 & m_y / R_{y,\max} & -m_y c_y / R_{y,\max} & 0 \\
            0 & 0 & \frac{f + n}{f - n} & \frac{-2 f n}{f - n} \\
            0 & 0 & 1 & 0
        \end{bmatrix}

    Clip ``w = +z`` (positive in front of the light), so ``x_ndc = m_x (x / z
    - c_x) / R_x,max`` lies within ``[-m_x, m_x]`` for the blocker, and depth
    is ``-1`` at ``near``, ``+1`` at ``far``. The offsets ``c_x, c_y``
    (``frustum.x_offset``, ``y_offset``; 0 for the article's symmetric
    frustum) shear the frustum off-centre. **Errata:** the article's matrix
    (printed transposed, for row vectors) has ``-1`` and
    ``(f + n)/(n - f)``, ``2 f n/(n - f)``: those belong to a camera looking
    down ``-Z``, whereas the article's own light frame looks down ``+Z``; and
    its ``* SMapWidth`` factor is spurious in OpenGL, where the viewport
    transform maps NDC to texels (it would blow the image up ``width`` times).

    Arguments:
        frustum: a :class:`Frustum` with ``(*batch,)`` fields.

    Returns:
        ``(*batch, 4, 4)`` column-vector matrix.

    Raises:
        ValueError: non-finite fields, ``rx_max``/``ry_max <= 0``, ``near <= 0`` or
            ``near >= far`` (NaN under JAX transformations).

    Example:
        >>> import numpy as np
        >>> fr = Frustum(rx_max=0.5, ry_max=0.25, near=1.0, far=3.0, margin_x=0.98, margin_y=0.98)
        >>> clip = blocker_projection(fr) @ np.array([1.0, 0.5, 2.0, 1.0])
        >>> (clip[:3] / clip[3]).round(4)  # on the x and y margins, mid depth
        array([0.98, 0.98, 0.5 ])
    """
    ctx, a, shape = _frustum_arrays(frustum)
    checks = _validated(ctx, a, shape)
    return checks.poison(_entries(ctx, _projection_rows(ctx, a), shape), 2)


def receiver_projection(frustum: Frustum) -> Array:
    r"""Light coordinates to homogeneous shadow-map texture coordinates.

    The blocker projection followed by the scale-and-bias from NDC ``[-1, 1]``
    to texture ``[0, 1]``:

    .. math::

        T = \begin{bmatrix}
            \tfrac12 & 0 & 0 & \tfrac12 \\ 0 & \tfrac12 & 0 & \tfrac12 \\
            0 & 0 & \tfrac12 & \tfrac12 \\ 0 & 0 & 0 & 1
        \end{bmatrix} P

    giving ``(s q, t q, r q, q)`` with ``q = z``,
    ``s = 1/2 + (m_x / 2) (x / z - c_x) / R_x,max`` (the article's 0.49 at 100
    texels),
    and ``r`` the ``[0, 1]`` window depth a depth shadow map would hold.
    Texture ``t = 0`` is the map's first row, which is where OpenGL draws
    ``y_ndc = -1``, so no flip is needed. A receiver point with ``q <= 0``
    is behind the light: it must get no shadow (the division flips signs).

    Arguments:
        frustum: a :class:`Frustum` with ``(*batch,)`` fields.

    Returns:
        ``(*batch, 4, 4)`` column-vector matrix.

    Raises:
        ValueError: as :func:`blocker_projection`.

    Example:
        >>> import numpy as np
        >>> fr = Frustum(rx_max=0.5, ry_max=0.5, near=1.0, far=3.0, margin_x=0.98, margin_y=0.98)
        >>> stq = receiver_projection(fr) @ np.array([1.0, 0.0, 2.0, 1.0])
        >>> (stq[:2] / stq[3]).round(4)  # the right margin: s = 0.5 + 0.49
        array([0.99, 0.5 ])
    """
    ctx, a, shape = _frustum_arrays(frustum)
    checks = _validated(ctx, a, shape)
    P = _projection_rows(ctx, a)
    half = 0.5
    rows: list[list[Array | float]] = [
        [half * P[0][0], 0.0, half * P[0][2] + half, 0.0],
        [0.0, half * P[1][1], half * P[1][2] + half, 0.0],
        [0.0, 0.0, half * P[2][2] + half, half * P[2][3]],
        [0.0, 0.0, 1.0, 0.0],
    ]
    return checks.poison(_entries(ctx, rows, shape), 2)
