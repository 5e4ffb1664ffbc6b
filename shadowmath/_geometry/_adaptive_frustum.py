"""The adaptive frustum at the door: map margins, the fit to a blocker, its two projections.

Each public function converts and checks its arguments here, then calls the trusted
cores of :mod:`shadowmath._math._frustum` (the projection entries) and
:mod:`shadowmath._math._passes` (the blocker's extent in light coordinates).
"""

from __future__ import annotations

import functools
from typing import Any

import numpy as np

from shadowmath._boundary import _messages as msg
from shadowmath._boundary._shapes import ArrayLike, Float, IntLike, MapSize, Real
from shadowmath._boundary._validate import (
    Array,
    Checks,
    Context,
    all_finite,
    batch_shape,
    convert,
    integer,
    non_finite,
    require_vertices,
)
from shadowmath._math._frame import LightFrame, stack_matrix
from shadowmath._math._frustum import (
    NEAR_FAR_SLACK,
    Frustum,
    OrthographicBox,
    blocker_reach,
    projection_entries,
)
from shadowmath._math._passes import Extent, extent
from shadowmath._math._specialize import formulas

from ._light_frame import frame_arrays


def texel_counts(name: str, value: Any) -> tuple[int, int]:
    """``map_size`` as ``(width, height)`` of positive Python ints."""
    is_pair = isinstance(value, tuple | list) or (isinstance(value, np.ndarray) and value.ndim == 1)
    values = tuple(value) if is_pair else (value, value)
    if len(values) != 2:
        raise ValueError(f"{name}: expected an int or (width, height), got {value!r}")
    w, h = (integer(name, v) for v in values)
    if w <= 0 or h <= 0:
        raise ValueError(f"{name}: texel counts must be positive, got {value!r}")
    return w, h


def border_margin(map_size: MapSize, *, border_texels: IntLike = 1) -> tuple[float, float]:
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
    w, h = texel_counts("map_size", map_size)
    b = integer("border_texels", border_texels, 0)
    if min(w, h) <= 2 * b:
        raise ValueError(
            f"map_size: {w}x{h} texels leave no room inside a border of {b} texel(s) on each "
            f"side; use at least {2 * b + 1} texels per axis"
        )
    return (w - 2 * b) / w, (h - 2 * b) / h


def margins(map_size: Any, border_texels: int, margin: Any) -> tuple[float, float]:
    """The margins of a map: given, or derived from its size (cached for hashable input)."""
    plain = (type(map_size) is int or (type(map_size) is tuple and _ints(map_size))) and (
        type(border_texels) is int and (margin is None or type(margin) is float)
    )
    if plain:  # exactly typed Python values: safe to cache (True is not 1 here)
        return _margins_cached(map_size, border_texels, margin)
    return derived_margins(map_size, border_texels, margin)


def _ints(values: tuple[Any, ...]) -> bool:
    return all(type(v) is int for v in values)


@functools.lru_cache(maxsize=256)
def _margins_cached(map_size: Any, border_texels: int, margin: Any) -> tuple[float, float]:
    return derived_margins(map_size, border_texels, margin)


def derived_margins(map_size: Any, border_texels: int, margin: Any) -> tuple[float, float]:
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
    vertices: Real[ArrayLike, "*#batch N 3"],
    map_size: MapSize,
    *,
    border_texels: IntLike = 1,
    margin: float | tuple[float, float] | None = None,
    near: Real[ArrayLike, "*#batch"] | None = None,
    far: Real[ArrayLike, "*#batch"] | None = None,
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
    m = margins(map_size, border_texels, margin)
    ctx, checks, f, (verts, n, fa) = frame_arrays(frame, vertices=vertices, near=near, far=far)
    check_blocker(checks, verts, n, fa)
    ext = extent(ctx.xp, f.origin, verts, (f.x_axis, f.y_axis, f.z_axis))
    reach = blocker_reach(ctx.xp, f.origin, verts)
    return bounded_frustum(ctx, checks, ext, reach, m, near=n, far=fa)


def check_blocker(checks: Checks, verts: Array, near: Array | None, far: Array | None) -> None:
    """The boundary checks of a frustum's vertex set and its optional near and far planes."""
    require_vertices("vertices", verts)
    xp = checks.ctx.xp
    checks.require(all_finite(xp, verts, 2), non_finite("vertices"))
    if near is not None:
        checks.require(xp.isfinite(near), msg.NEAR_NOT_FINITE)
    if far is not None:
        checks.require(xp.isfinite(far), msg.FAR_NOT_FINITE)


def bounded_frustum(
    ctx: Context,
    checks: Checks,
    ext: Extent,
    reach: Array,
    margins: tuple[float, float],
    *,
    near: Array | None,
    far: Array | None,
    symmetric: bool = True,
    bounds: tuple[Array, Array, Array, Array] | None = None,
) -> Frustum:
    """The frustum around the hard bounds of the ratios (or the given ``bounds``).

    ``bounds = (hi_x, lo_x, hi_y, lo_y)`` replaces the hard maxima and minima
    of the ratios (soft bounds, for :func:`smooth_frustum`).
    """
    xp = ctx.xp
    if bounds is None:
        bounds = (
            xp.max(ext.rx, axis=-1),
            xp.min(ext.rx, axis=-1),
            xp.max(ext.ry, axis=-1),
            xp.min(ext.ry, axis=-1),
        )
    hi_x, lo_x, hi_y, lo_y = bounds
    if symmetric:
        half_x, half_y = xp.maximum(hi_x, -lo_x), xp.maximum(hi_y, -lo_y)
        cx = cy = xp.zeros_like(half_x)
    else:
        half_x, half_y = 0.5 * (hi_x - lo_x), 0.5 * (hi_y - lo_y)
        cx, cy = 0.5 * (hi_x + lo_x), 0.5 * (hi_y + lo_y)
    extents = (half_x, half_y, cx, cy)
    return assemble(ctx, checks, ext.z, reach, margins, extents=extents, near=near, far=far)


def assemble(
    ctx: Context,
    checks: Checks,
    z: Array,
    reach: Array,
    margins: tuple[float, float],
    *,
    extents: tuple[Array, Array, Array, Array],
    near: Array | None,
    far: Array | None,
) -> Frustum:
    """The Frustum of given half-extents and centre, with default or checked near/far.

    Thresholds relative to the blocker's reach from the light, never absolute:
    light coordinates carry rounding errors of a few ulps of ``|V - L|`` (the
    difference and the axes' own rounding), so a vertex is in front only when
    its ``z`` clears that noise, and a silhouette has width only when its
    ratios clear it, in any units.
    """
    xp = ctx.xp
    half_x, half_y, cx, cy = extents
    z_min, z_max = xp.min(z, axis=-1), xp.max(z, axis=-1)
    noise = 32 * ctx.eps * reach
    checks.require(z_min > noise, msg.BEHIND_LIGHT)
    ratio_noise = 2 * noise / xp.where(z_min > 0, z_min, xp.ones_like(z_min))
    checks.require((half_x > ratio_noise) & (half_y > ratio_noise), msg.ZERO_SILHOUETTE)
    given_near, given_far = near, far
    near = z_min * (1 - NEAR_FAR_SLACK) if given_near is None else given_near
    far = z_max * (1 + NEAR_FAR_SLACK) if given_far is None else given_far
    if given_near is not None:
        checks.require(near > 0, msg.NEAR_POSITIVE)
    checks.require(near < far, msg.NEAR_FAR)
    if given_near is not None:
        checks.require(near <= z_min, msg.NEAR_CLIPS)
    if given_far is not None:
        checks.require(far >= z_max, msg.FAR_CLIPS)
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
        x_offset=field(cx),
        y_offset=field(cy),
    )


def frustum_arrays(frustum: Any) -> tuple[Context, Checks, Frustum | OrthographicBox]:
    """A user-given frustum or box converted and checked (the frustum-taking functions' door).

    Eagerly a bad field raises here, before a division by ``rx_max = 0`` or
    ``far - near = 0`` could emit a NumPy warning; lazily the returned checks
    poison the results. The result has the type of ``frustum``: an
    :class:`OrthographicBox`, or a :class:`Frustum` (also for a plain tuple of its
    6 or 8 fields; 9 with the deprecated ``orthographic`` flag).
    """
    if not isinstance(frustum, tuple) or len(frustum) not in (6, 8, 9):
        raise ValueError(
            "frustum: expected a Frustum (rx_max, ry_max, near, far, margin_x, ...) "
            "or an OrthographicBox (half_width, half_height, near, far, margin_x, ...)"
        )
    if not isinstance(frustum, Frustum | OrthographicBox):
        frustum = Frustum(*frustum)
    names = type(frustum)._fields
    given = frustum._asdict()
    # A default (Python number) centre must not promote a float32 frustum to float64.
    defaults = {n: given.pop(n) for n in names[6:] if isinstance(given[n], int | float)}
    ctx, arrays = convert(**given)
    xp = ctx.xp
    converted = dict(zip(given, arrays, strict=True))
    converted.update({n: ctx.constant(float(v)) for n, v in defaults.items()})
    fields = [converted[n] for n in names]
    shape = batch_shape(*(tuple(a.shape) for a in fields), names=names)
    checks = Checks(ctx)
    for name, v in zip(names, fields, strict=True):
        checks.require(xp.isfinite(v), f"frustum.{name}: must be finite")
    fr = type(frustum)._make([xp.broadcast_to(v, shape) for v in fields])
    # At least the smallest normal float, so that margin / half-extent cannot overflow.
    tiny = float(np.finfo(ctx.dtype).tiny)
    checks.require(
        (fr[0] >= tiny) & (fr[1] >= tiny),
        f"frustum: {names[0]} and {names[1]} must be > 0 (and normal floats)",
    )
    if isinstance(fr, Frustum):
        checks.require(fr.near > 0, "frustum.near: must be > 0")
        checks.require(fr.near < fr.far, "frustum: near must be < far")
    else:  # a box's depth scale 2 / (far - near) must not overflow
        checks.require(fr.far - fr.near >= tiny, "frustum: near must be < far (by a normal float)")
    if checks.invalid is not None:
        checks.invalid = xp.broadcast_to(checks.invalid, shape)
    return ctx, checks, fr


def blocker_projection(
    frustum: Frustum | OrthographicBox | tuple[Any, ...],
) -> Float[Array, "*batch 4 4"]:
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

    An :class:`OrthographicBox` (a directional light's) gives the orthographic
    matrix instead: rows ``(s_x, 0, 0, -s_x c_x)``, ``(0, s_y, 0, -s_y c_y)``,
    ``(0, 0, 2 / (f - n), -(f + n) / (f - n))``, ``(0, 0, 0, 1)`` with
    ``s_x = m_x / R_x``: ``x_ndc = m_x (x - c_x) / R_x``.

    Arguments:
        frustum: a :class:`Frustum` or an :class:`OrthographicBox` (or a tuple of a
            frustum's fields) with ``(*batch,)`` fields (the matrix follows its type).

    Returns:
        ``(*batch, 4, 4)`` column-vector matrix.

    Raises:
        ValueError: non-finite fields, ``rx_max``/``ry_max <= 0``, ``near <= 0`` or
            ``near >= far`` (a box: ``half_width``/``half_height <= 0`` or ``near >=
            far``; its near plane may be behind the origin) (NaN under JAX
            transformations).

    Example:
        >>> import numpy as np
        >>> fr = Frustum(rx_max=0.5, ry_max=0.25, near=1.0, far=3.0, margin_x=0.98, margin_y=0.98)
        >>> clip = blocker_projection(fr) @ np.array([1.0, 0.5, 2.0, 1.0])
        >>> (clip[:3] / clip[3]).round(4)  # on the x and y margins, mid depth
        array([0.98, 0.98, 0.5 ])
    """
    ctx, checks, fr = frustum_arrays(frustum)
    return checks.poison(stack_matrix(ctx.xp, projection_entries(ctx.xp, fr)), 2)


def receiver_projection(
    frustum: Frustum | OrthographicBox | tuple[Any, ...],
) -> Float[Array, "*batch 4 4"]:
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
        frustum: a :class:`Frustum` or an :class:`OrthographicBox` (or a tuple of a
            frustum's fields) with ``(*batch,)`` fields (an orthographic box gives ``q = 1``).

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
    ctx, checks, fr = frustum_arrays(frustum)
    P = projection_entries(ctx.xp, fr)
    T = formulas(ctx.xp).texture_rows(P)
    return checks.poison(stack_matrix(ctx.xp, T), 2)
