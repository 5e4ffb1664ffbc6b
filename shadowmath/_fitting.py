"""What a shadow-map user wants from a frustum, and a gradient-based fitter for it.

The article aims the light frame along the mean direction vector (MDV), picks
its roll by a helper axis, and centres the frustum. None of the three looks at
how well the blocker's silhouette fills the map: an elongated blocker seen
diagonally fills a thin band along the map's diagonal, and a blocker whose
vertices crowd on one side leaves the other side of the map empty.
:func:`optimize_frustum` turns the frame (direction and roll) to minimise the
frustum's cross-section, with an off-centre frustum so the silhouette touches
all four margins, starting from the MDV frame.

Measures:

* :func:`silhouette_coverage`: the fraction of the usable map (inside the
  border) the rendered silhouette covers, from a rendered mask;
* :func:`cross_section_area`: its differentiable proxy, the area of the
  frustum's usable cross-section at unit distance (coverage is the
  silhouette's area in that plane divided by this);
* :func:`receiver_texel_size`: the world-space size of one shadow-map texel
  where it lands on a receiver.
"""

from __future__ import annotations

import functools
import math
import operator
from typing import Any, NamedTuple

import numpy as np

from ._backend import (
    Array,
    Checks,
    all_finite,
    batch_shape,
    non_finite,
    prepare,
    require_last,
    require_matrix,
)
from ._frame import LightFrame, light_frame
from ._frustum import Frustum, _frustum_arrays, _texels, adaptive_frustum
from ._smooth import _ratio_frustum, _rolled_frame
from ._vector import cross, dot


class FrustumFit(NamedTuple):
    """The result of :func:`optimize_frustum`.

    Attributes:
        frame: the fitted :class:`LightFrame` (``(*batch, 3)`` fields).
        frustum: the exact (hard-bound) :class:`Frustum` for it, off-centre
            unless ``symmetric``: the blocker is never clipped.
        direction: ``(*batch, 3)`` the fitted viewing direction (unnormalised).
        roll: ``(*batch,)`` the roll about it, relative to the MDV frame's ``X``.
        losses: ``(*batch, steps)`` the exact loss at each step of the best
            start: ``log`` of the cross-section area over the MDV frustum's
            (0 at the article's setup; lower is better).
    """

    frame: LightFrame
    frustum: Frustum
    direction: Array
    roll: Array
    losses: Array


def cross_section_area(frustum: Frustum) -> Array:
    r"""The usable cross-section of the frustum at unit distance from the light.

    .. math:: A = (2 R_x)(2 R_y)

    in ratio units (``x / z``, ``y / z``): the part of the plane ``z = 1`` that
    maps inside the margins. A silhouette of area ``S`` in that plane covers
    ``S / A`` of the usable map, so at a fixed frame a smaller ``A`` means a
    proportionally larger coverage: the differentiable proxy the fitter minimises.

    Arguments:
        frustum: a :class:`Frustum` with ``(*batch,)`` fields.

    Returns:
        ``(*batch,)``.

    Example:
        >>> float(cross_section_area(Frustum(0.5, 0.25, 1.0, 2.0, 0.98, 0.98)))
        0.5
    """
    ctx, a, shape = _frustum_arrays(frustum)
    xp = ctx.xp
    return xp.broadcast_to(4 * a["rx_max"] * a["ry_max"], shape)


def silhouette_coverage(mask: Any, *, border_texels: int = 1) -> Array:
    """The fraction of the usable shadow map that the silhouette covers.

    The mean of ``mask`` over the texels inside the border (the border itself
    must stay empty; it is not counted). Pass a mask rendered by
    :func:`shadowmath.render.render_shadow_map` (1 under the silhouette).

    Arguments:
        mask: ``(*batch, height, width)`` values in ``[0, 1]``.
        border_texels: the border width on each side.

    Returns:
        ``(*batch,)`` coverage in ``[0, 1]``.

    Raises:
        ValueError: fewer than 2 dimensions, or a map no larger than its borders.

    Example:
        >>> m = np.zeros((6, 6)); m[1:3, 1:5] = 1  # half of the 4x4 interior
        >>> float(silhouette_coverage(m))
        0.5
    """
    ctx, a = prepare(mask=mask)
    m = a["mask"]
    if m.ndim < 2:
        raise ValueError(f"mask: expected shape (*batch, height, width), got {tuple(m.shape)}")
    try:
        b = operator.index(border_texels)
    except TypeError:
        raise ValueError(f"border_texels: expected an int, got {border_texels!r}") from None
    h, w = int(m.shape[-2]), int(m.shape[-1])
    if b < 0 or min(h, w) <= 2 * b:
        raise ValueError(f"border_texels: {b} leaves no interior in a {w}x{h} mask")
    inner = m[..., b : h - b, b : w - b]
    return ctx.xp.mean(ctx.xp.mean(inner, axis=-1), axis=-1)


def receiver_texel_size(
    world_to_texture: Any, points: Any, normals: Any, map_size: int | tuple[int, int]
) -> Array:
    r"""The world-space edge length of one shadow-map texel on a receiver surface.

    With ``(s q, t q, r q, q) = M p``, the texture coordinates ``s``, ``t``
    have world gradients ``grad s = (m_0 - s m_3) / q`` and
    ``grad t = (m_1 - t m_3) / q`` (``m_i`` the first three entries of row ``i``).
    On a surface with unit normal ``n`` the map from the tangent plane to
    ``(s, t)`` has Jacobian determinant ``(grad s x grad t) . n``, so one texel
    (``1/W`` by ``1/H`` in ``(s, t)``) covers

    .. math:: a = \frac{1}{W H \, |(\nabla s \times \nabla t) \cdot n|}

    of the surface; the result is ``sqrt(a)``, the side of a square of that
    area. Smaller is sharper. Infinite where the surface is seen edge-on from
    the light.

    Arguments:
        world_to_texture: ``(*batch, 4, 4)`` e.g. :attr:`ShadowSetup.world_to_texture`.
        points: ``(*batch, 3)`` receiver points in world coordinates (in front
            of the light, ``q > 0``).
        normals: ``(*batch, 3)`` the surface normals there (need not be unit).
        map_size: ``size`` or ``(width, height)`` in texels.

    Returns:
        ``(*batch,)`` lengths in world units.

    Raises:
        ValueError: wrong shapes, non-finite values, a zero normal, a point
            behind the light (NaN under JAX transformations).

    Example:
        >>> s = fit_shadow([0, 0, 0], [[-1, -1, 4], [1, 1, 4], [1, -1, 4], [-1, 1, 4]], 100)
        >>> # The wall z = 8 is twice as far as the blocker: 2 R z / (m W) = 2 * 0.25 * 8 / 98
        >>> float(receiver_texel_size(s.world_to_texture, [0, 0, 8], [0, 0, 1], 100).round(6))
        0.040816
    """
    W, H = _texels("map_size", map_size)
    ctx, a = prepare(world_to_texture=world_to_texture, points=points, normals=normals)
    xp = ctx.xp
    M, p, n = a["world_to_texture"], a["points"], a["normals"]
    require_matrix("world_to_texture", M)
    require_last("points", p, 3)
    require_last("normals", n, 3)
    checks = Checks(ctx)
    checks.require(xp.all(xp.isfinite(M), axis=(-2, -1)), non_finite("world_to_texture"))
    checks.require(all_finite(xp, p, 1), non_finite("points"))
    checks.require(all_finite(xp, n, 1), non_finite("normals"))
    n_sq = dot(xp, n, n)
    checks.require(n_sq > 0, "normals: a normal is zero")
    shape = batch_shape(
        tuple(M.shape[:-2]),
        tuple(p.shape[:-1]),
        tuple(n.shape[:-1]),
        names=("world_to_texture", "points", "normals"),
    )
    hom = M[..., :3] @ p[..., None] + M[..., 3:]  # (*batch, 4, 1)
    q = hom[..., 3, 0]
    checks.require(q > 0, "points: a receiver point is behind the light (q <= 0)")
    safe_q = xp.where(q > 0, q, xp.ones_like(q))
    s, t = hom[..., 0, 0] / safe_q, hom[..., 1, 0] / safe_q
    m3 = M[..., 3, :3]
    grad_s = (M[..., 0, :3] - s[..., None] * m3) / safe_q[..., None]
    grad_t = (M[..., 1, :3] - t[..., None] * m3) / safe_q[..., None]
    safe_n_sq = xp.where(n_sq > 0, n_sq, xp.ones_like(n_sq))
    det = xp.abs(dot(xp, cross(xp, grad_s, grad_t), n)) / xp.sqrt(safe_n_sq)
    size = 1 / xp.sqrt(W * H * det)
    return checks.poison(xp.broadcast_to(size, shape), 0)


# ---------------------------------------------------------------------------
# The optimiser (plain JAX: Adam, a soft-max loss, several starting rolls).
# ---------------------------------------------------------------------------


def _pad_size(n: int) -> int:
    """Vertex counts are padded to powers of two (>= 64) so jit compiles once per bucket."""
    return max(64, 1 << (n - 1).bit_length())


@functools.lru_cache(maxsize=8)
def _optimizer(steps: int, starts: int, symmetric: bool) -> Any:
    """The jitted, batched optimiser for one configuration (compiled once per vertex bucket)."""
    import jax
    import jax.numpy as jnp

    def frame(p: Any, x0: Any, y0: Any, z0: Any, sx: Any, sy: Any) -> tuple[Any, Any, Any]:
        d = z0 + p[0] * sx * x0 + p[1] * sy * y0
        z = d / jnp.linalg.norm(d)
        # X = Z x Y0 / |.|: the MDV frame's own X at p = 0 (left-handed: Z x Y = X).
        xa = jnp.cross(z, y0)
        xa = xa / jnp.linalg.norm(xa)
        ya = jnp.cross(xa, z)
        c, s = jnp.cos(p[2]), jnp.sin(p[2])
        return c * xa + s * ya, c * ya - s * xa, z

    def bounds(r: Any, w: Any, T: Any) -> tuple[Any, Any]:
        """Soft (T > 0) upper bound of max r and lower bound of min r, padding dropped."""
        hi = T * jax.nn.logsumexp(r / T, b=w)
        lo = -T * jax.nn.logsumexp(-r / T, b=w)
        return hi, lo

    def loss(p: Any, T: Any, data: tuple[Any, ...], hard: bool) -> Any:
        offsets, w, x0, y0, z0, sx, sy = data
        X, Y, Z = frame(p, x0, y0, z0, sx, sy)
        z = offsets @ Z
        valid = jnp.all(jnp.where(w > 0, z, 1.0) > 0)
        safe_z = jnp.where(z > 0, z, 1.0)
        rx, ry = (offsets @ X) / safe_z, (offsets @ Y) / safe_z
        if hard:
            big = jnp.where(w > 0, 0.0, jnp.inf)
            hx, lx = jnp.max(rx - big), jnp.min(rx + big)
            hy, ly = jnp.max(ry - big), jnp.min(ry + big)
            if symmetric:
                hx, hy = jnp.maximum(hx, -lx), jnp.maximum(hy, -ly)
        elif symmetric:
            hx = bounds(jnp.concatenate([rx, -rx]), jnp.concatenate([w, w]), T * sx)[0]
            hy = bounds(jnp.concatenate([ry, -ry]), jnp.concatenate([w, w]), T * sy)[0]
        else:
            hx, lx = bounds(rx, w, T * sx)
            hy, ly = bounds(ry, w, T * sy)
        width, height = (2 * hx, 2 * hy) if symmetric else (hx - lx, hy - ly)
        value = jnp.log(width / (2 * sx)) + jnp.log(height / (2 * sy))
        return jnp.where(valid, value, jnp.inf) if hard else value

    grad = jax.grad(loss)

    def one_start(p0: Any, data: tuple[Any, ...], lr: Any) -> tuple[Any, Any, Any]:
        # Temperature (relative to the MDV frustum's half-extent) and step size
        # both anneal geometrically: broad moves first, a tight bound at the end.
        k = jnp.arange(steps, dtype=p0.dtype) / max(steps - 1, 1)
        temps = 0.05 * (0.002 / 0.05) ** k
        rates = lr * 0.05**k
        b1, b2 = 0.9, 0.999

        def step(carry: Any, sched: Any) -> Any:
            p, m, v, t, best_p, best = carry
            T, rate = sched
            exact = loss(p, T, data, True)
            better = exact < best
            best_p = jnp.where(better, p, best_p)
            best = jnp.where(better, exact, best)
            g = grad(p, T, data, False)
            g = jnp.where(jnp.isfinite(g), g, 0.0)
            t = t + 1
            m = b1 * m + (1 - b1) * g
            v = b2 * v + (1 - b2) * g * g
            p = p - rate * (m / (1 - b1**t)) / (jnp.sqrt(v / (1 - b2**t)) + 1e-8)
            return (p, m, v, t, best_p, best), exact

        zero = jnp.zeros_like(p0)
        init = (p0, zero, zero, jnp.zeros((), p0.dtype), p0, jnp.asarray(jnp.inf, p0.dtype))
        (p, _, _, _, best_p, best), history = jax.lax.scan(step, init, (temps, rates))
        exact = loss(p, temps[-1], data, True)
        best_p = jnp.where(exact < best, p, best_p)
        best = jnp.minimum(exact, best)
        return best_p, best, history

    def one_blocker(data: tuple[Any, ...], lr: Any) -> tuple[Any, Any, Any]:
        dtype = data[0].dtype
        # Rolls spread over a quarter turn: the cross-section's area repeats
        # every quarter turn (width and height swap), so this covers all rolls.
        rolls = jnp.arange(starts, dtype=dtype) * (0.5 * math.pi / starts)
        p0 = jnp.stack([jnp.zeros_like(rolls), jnp.zeros_like(rolls), rolls], axis=-1)
        ps, losses, history = jax.vmap(one_start, in_axes=(0, None, None))(p0, data, lr)
        best = jnp.argmin(losses)
        return ps[best], losses[best], history[best]

    return jax.jit(jax.vmap(one_blocker, in_axes=(0, None)))


def optimize_frustum(
    light_position: Any,
    vertices: Any,
    map_size: int | tuple[int, int],
    *,
    symmetric: bool = False,
    steps: int = 80,
    starts: int = 6,
    learning_rate: float = 0.1,
    border_texels: int = 1,
    margin: float | tuple[float, float] | None = None,
    near: Any = None,
    far: Any = None,
) -> FrustumFit:
    r"""Fit the light frame's direction and roll to the blocker by gradient descent.

    Parameters ``(alpha, beta, theta)`` give the direction
    ``d = Z_0 + alpha R_x X_0 + beta R_y Y_0`` and the roll ``theta`` about it
    (:func:`rolled_light_frame` with ``up = Y_0``), where ``(X_0, Y_0, Z_0)``
    is the article's MDV frame and ``R_x, R_y`` its frustum's half-extents (so
    the parameters are scale-free). The loss is the log of the
    :func:`cross_section_area` of the :func:`smooth_frustum` (off-centre unless
    ``symmetric``) relative to the MDV frustum's,

    .. math:: L = \log \frac{(h_x - l_x)(h_y - l_y)}{(2 R_x)(2 R_y)}

    with ``h, l`` soft upper and lower bounds of the ratios ``x / z``, ``y / z``
    at a temperature annealed from 5 % to 0.2 % of ``R``. Adam runs ``steps``
    steps from ``starts`` rolls spread over a quarter turn (one of them the MDV
    frame itself) in parallel, and keeps the parameters of lowest *exact* loss
    seen, so the result is never worse than the MDV frame with the same kind
    of frustum. The returned frustum uses the exact bounds
    (:func:`offcenter_frustum`, or :func:`adaptive_frustum` if ``symmetric``).

    Written in plain JAX (``jit``, ``vmap``, ``lax.scan``); requires JAX, and
    compiles once per configuration and vertex-count bucket (padded to a power
    of two). NumPy inputs give NumPy outputs; inside a JAX transformation the
    fit is traced like any JAX code (its gradient is that of the unrolled
    optimisation).

    Arguments:
        light_position: ``(*batch, 3)`` the point light.
        vertices: ``(*batch, N, 3)`` blocker vertices in world coordinates.
        map_size: ``size`` or ``(width, height)`` of the map in texels.
        symmetric: keep the frustum centred (the article's kind); default
            False: off-centre, which at any frame covers at least as much.
        steps: Adam steps per start.
        starts: number of starting rolls.
        learning_rate: Adam's initial step size (in units of the parameters).
        border_texels, margin, near, far: as in :func:`adaptive_frustum`.

    Returns:
        :class:`FrustumFit`.

    Raises:
        ValueError: everything :func:`light_frame` and :func:`adaptive_frustum`
            raise, and ``steps`` or ``starts`` below 1.
        ImportError: JAX is not installed.

    Example:
        >>> bar = np.array([[x, y, z] for x in (-3, 3) for y in (-0.1, 0.1) for z in (9.9, 10.1)])
        >>> bar = bar @ np.array([[0.8, 0.6, 0], [-0.6, 0.8, 0], [0, 0, 1]])  # turned 37 deg
        >>> fit = optimize_frustum([0, 0, 0], bar, 128)
        >>> bool(fit.losses[-1] < np.log(0.5))  # the cross-section shrinks more than twice
        True
    """
    if steps < 1 or starts < 1:
        raise ValueError(f"steps and starts must be >= 1, got steps={steps}, starts={starts}")
    import jax.numpy as jnp

    ctx, a = prepare(light_position=light_position, vertices=vertices)
    xp = ctx.xp
    light, verts = a["light_position"], a["vertices"]
    # The MDV frame and frustum validate the inputs and set the scale.
    ref = light_frame(light, verts)
    ref_frustum = adaptive_frustum(ref, verts, map_size, border_texels=border_texels, margin=margin)

    shape = tuple(ref.origin.shape[:-1])
    n = int(verts.shape[-2])
    flat = int(np.prod(shape, dtype=np.int64))
    offsets = xp.broadcast_to(verts - light[..., None, :], (*shape, n, 3))
    jdtype = jnp.zeros(()).dtype if ctx.dtype == np.float64 else jnp.float32

    def to_jax(v: Array, tail: tuple[int, ...]) -> Any:
        return jnp.reshape(
            jnp.asarray(xp.broadcast_to(v, (*shape, *tail)), dtype=jdtype), (flat, *tail)
        )

    j_off = to_jax(offsets, (n, 3))
    padded = _pad_size(n)
    # Padding repeats vertex 0 with weight 0: the hard bounds see a duplicate,
    # the soft ones drop it.
    j_off = jnp.concatenate([j_off, jnp.repeat(j_off[:, :1], padded - n, axis=1)], axis=1)
    weights = jnp.concatenate(
        [jnp.ones((flat, n), jdtype), jnp.zeros((flat, padded - n), jdtype)], axis=1
    )
    data = (
        j_off,
        weights,
        to_jax(ref.x_axis, (3,)),
        to_jax(ref.y_axis, (3,)),
        to_jax(ref.z_axis, (3,)),
        to_jax(ref_frustum.rx_max, ()),
        to_jax(ref_frustum.ry_max, ()),
    )
    params, _, history = _optimizer(int(steps), int(starts), bool(symmetric))(
        data, jnp.asarray(learning_rate, jdtype)
    )
    if ctx.xp is jnp or getattr(ctx.xp, "__name__", "") == "jax.numpy":
        params = jnp.asarray(params, dtype=ctx.dtype)
        history = jnp.asarray(history, dtype=ctx.dtype)
    else:
        params, history = np.asarray(params, dtype=ctx.dtype), np.asarray(history, dtype=ctx.dtype)
    params = xp.reshape(params, (*shape, 3))
    history = xp.reshape(history, (*shape, int(steps)))

    alpha, beta, roll = params[..., 0], params[..., 1], params[..., 2]
    direction = (
        ref.z_axis
        + (alpha * ref_frustum.rx_max)[..., None] * ref.x_axis
        + (beta * ref_frustum.ry_max)[..., None] * ref.y_axis
    )
    checks = Checks(ctx)
    frame = _rolled_frame(ctx, checks, ref.origin, direction, roll, ref.y_axis)
    frustum = _ratio_frustum(
        frame,
        verts,
        map_size,
        temperature=None,
        symmetric=symmetric,
        border_texels=border_texels,
        margin=margin,
        near=near,
        far=far,
    )
    return FrustumFit(frame=frame, frustum=frustum, direction=direction, roll=roll, losses=history)
