"""A gradient-based fit of the light frame and an off-centre frustum to a blocker.

The article aims the light frame along the mean direction vector (MDV), picks
its roll by a helper axis, and centres the frustum. None of the three looks at
how well the blocker's silhouette fills the map: an elongated blocker seen
diagonally fills a thin band along the map's diagonal, and a blocker whose
vertices crowd on one side leaves the other side of the map empty.
:func:`optimize_frustum` turns the frame (direction and roll) to minimise the
frustum's cross-section (:func:`cross_section_area`), with an off-centre frustum
so the silhouette touches all four margins, starting from the MDV frame.

The loss is built from the library's own cores: the rolled frame of
:func:`rolled_light_frame` (``_formulas.rolled_axes``), the light-space pass of
the frustum (``_passes.extent``) and the soft bounds of :func:`smooth_frustum`.
Adam is five lines here (optax would add a dependency for them).

Large blockers: the ratios ``x / z``, ``y / z`` in any frame turned about the
light are linear-fractional functions of the ratios in the MDV frame, so over
a vertex set their extremes lie on the 2D convex hull of the vertices' MDV
ratios. The optimizer sees only those vertices (exact, not an approximation,
for every frame that keeps the blocker in front); the returned frustum is
fitted to the full set.
"""

from __future__ import annotations

import functools
import math
from typing import Any, NamedTuple

import numpy as np

from shadowmath._boundary._shapes import ArrayLike, BoolLike, Float, Real
from shadowmath._boundary._validate import (
    Array,
    Checks,
    Context,
    all_finite,
    convert,
    non_finite,
    require_last,
)
from shadowmath._geometry._adaptive_frustum import bounded_frustum, check_blocker, margins
from shadowmath._geometry._light_frame import frame_along
from shadowmath._geometry._smooth_frustum import rolled_frame
from shadowmath._math._frame import LightFrame, zero_direction_noise
from shadowmath._math._frustum import Frustum, blocker_reach
from shadowmath._math._passes import extent, spread
from shadowmath._math._smooth import soft_bounds
from shadowmath._math._specialize import formulas

from ._result import ShadowSetup, setup_from


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
    direction: Float[Array, "*batch 3"]
    roll: Float[Array, "*batch"]
    losses: Float[Array, "*batch {steps}"]


def _pad_size(n: int) -> int:
    """Vertex counts are padded to powers of two (>= 64) so jit compiles once per bucket."""
    return max(64, 1 << (n - 1).bit_length())


def _import_jax() -> Any:
    try:
        import jax
    except ImportError:
        raise ImportError(
            "optimize_frustum and fit_shadow(method='optimized') need JAX: "
            "pip install 'shadowmath[jax]'"
        ) from None
    return jax


@functools.lru_cache(maxsize=8)
def _loss(symmetric: bool) -> Any:
    """The optimiser's loss: the log cross-section of the frustum turned by ``p``
    (exact: ``hard``; or with soft bounds at temperature ``T``)."""
    import jax.numpy as jnp

    F = formulas(jnp)

    def loss(p: Any, T: Any, data: tuple[Any, ...], hard: bool) -> Any:
        offsets, w, x0, y0, z0, sx, sy = data
        d = z0 + p[0] * sx * x0 + p[1] * sy * y0
        # The frame of rolled_light_frame with up = Y0: the MDV frame itself at p = 0.
        ax = F.rolled_axes(tuple(d), tuple(y0), jnp.cos(p[2]), jnp.sin(p[2]))
        X, Y, Z = jnp.stack(ax[0:3]), jnp.stack(ax[3:6]), jnp.stack(ax[6:9])
        ext = extent(jnp, jnp.zeros_like(d), offsets, (X, Y, Z))
        valid = jnp.all(ext.z > 0)
        if hard:  # padding repeats a real vertex: the hard bounds are unchanged
            hx, lx, hy, ly = jnp.max(ext.rx), jnp.min(ext.rx), jnp.max(ext.ry), jnp.min(ext.ry)
            if symmetric:
                hx, hy = jnp.maximum(hx, -lx), jnp.maximum(hy, -ly)
                lx, ly = -hx, -hy
        else:
            hx, lx, hy, ly = soft_bounds(
                jnp, ext.rx, ext.ry, T * jnp.sqrt(sx * sy), symmetric=symmetric, weights=w
            )
        value = jnp.log((hx - lx) / (2 * sx)) + jnp.log((hy - ly) / (2 * sy))
        return jnp.where(valid, value, jnp.inf) if hard else value

    return loss


def _optimizer(steps: int, starts: int, symmetric: bool) -> Any:
    """The jitted, batched optimiser for one configuration (compiled once per vertex bucket)."""
    jax = _import_jax()
    import jax.numpy as jnp

    loss = _loss(symmetric)
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


def _hull_candidates(rx: np.ndarray, ry: np.ndarray) -> list[np.ndarray]:
    """Per blocker, the indices of the vertices on the 2D convex hull of their MDV ratios."""
    from scipy.spatial import ConvexHull, QhullError

    out = []
    for x, y in zip(rx.reshape(-1, rx.shape[-1]), ry.reshape(-1, ry.shape[-1]), strict=True):
        if x.shape[0] <= 64:
            out.append(np.arange(x.shape[0]))
            continue
        try:
            out.append(np.sort(ConvexHull(np.stack([x, y], axis=-1)).vertices))
        except QhullError:  # degenerate (collinear) projections: keep everything
            out.append(np.arange(x.shape[0]))
    return out


def _candidates(
    ctx: Context, offsets: Array, ext: Any, shape: tuple[int, ...], jdtype: Any
) -> tuple[Any, Any]:
    """The vertices the optimiser reads (``(flat, size, 3)`` offsets from the light, JAX)
    and their weights: those on the hull of their MDV ratios, padded to a bucket size."""
    import jax.numpy as jnp

    flat, n = int(np.prod(shape, dtype=np.int64)), int(offsets.shape[-2])
    offsets = ctx.xp.broadcast_to(offsets, (*shape, n, 3))
    offsets = jnp.reshape(jnp.asarray(offsets, dtype=jdtype), (flat, n, 3))
    if ctx.lazy:
        keep = [np.arange(n)] * flat
    else:
        rx = np.broadcast_to(np.asarray(ext.rx), (*shape, n))
        keep = _hull_candidates(rx, np.broadcast_to(np.asarray(ext.ry), (*shape, n)))
    size = _pad_size(max(len(k) for k in keep))
    # Padding repeats the first candidate with weight 0: the hard bounds see a
    # duplicate, the soft ones drop it.
    index = np.stack([np.concatenate([k, np.full(size - len(k), k[0])]) for k in keep])
    weights = np.stack([np.arange(size) < len(k) for k in keep]).astype(jdtype)
    return jnp.take_along_axis(offsets, jnp.asarray(index)[..., None], axis=1), jnp.asarray(weights)


def _optimize_core(
    ctx: Context,
    checks: Checks,
    light: Array,
    verts: Array,
    *,
    m: tuple[float, float],
    near: Array | None,
    far: Array | None,
    symmetric: bool,
    steps: int,
    starts: int,
    learning_rate: float,
) -> FrustumFit:
    """:func:`optimize_frustum` on shape-checked arrays (checks the values)."""
    jax = _import_jax()
    import jax.numpy as jnp

    xp = ctx.xp
    checks.require(all_finite(xp, light, 1), non_finite("light_position"))
    checks.require(all_finite(xp, verts, 2), non_finite("vertices"))
    check_blocker(checks, verts, near, far)
    # The MDV frame and frustum: the starting point and the scale of the parameters.
    s = spread(xp, light, verts, aim="mean")
    ref = frame_along(ctx, checks, light, s.direction, zero_direction_noise(ctx, s.coords))
    ext = extent(xp, light, verts, (ref.x_axis, ref.y_axis, ref.z_axis))
    ref_frustum = bounded_frustum(ctx, checks, ext, s.reach, m, near=None, far=None)

    shape = tuple(ref.origin.shape[:-1])
    flat = int(np.prod(shape, dtype=np.int64))
    jdtype = jnp.zeros(()).dtype if ctx.dtype == np.float64 else jnp.float32
    chosen, weights = _candidates(ctx, verts - light[..., None, :], ext, shape, jdtype)

    def to_jax(v: Array, tail: tuple[int, ...]) -> Any:
        v = xp.broadcast_to(v, (*shape, *tail))
        return jnp.reshape(jnp.asarray(v, dtype=jdtype), (flat, *tail))

    data = (
        chosen,
        weights,
        to_jax(ref.x_axis, (3,)),
        to_jax(ref.y_axis, (3,)),
        to_jax(ref.z_axis, (3,)),
        to_jax(ref_frustum.rx_max, ()),
        to_jax(ref_frustum.ry_max, ()),
    )
    params, _, history = _optimizer(steps, starts, symmetric)(
        data, jnp.asarray(learning_rate, jdtype)
    )
    if ctx.is_jax:
        params, history = jnp.asarray(params, ctx.dtype), jnp.asarray(history, ctx.dtype)
    else:
        params = np.asarray(jax.device_get(params), dtype=ctx.dtype)
        history = np.asarray(jax.device_get(history), dtype=ctx.dtype)
    params = xp.reshape(params, (*shape, 3))
    history = xp.reshape(history, (*shape, steps))

    alpha, beta, roll = params[..., 0], params[..., 1], params[..., 2]
    direction = (
        ref.z_axis
        + (alpha * ref_frustum.rx_max)[..., None] * ref.x_axis
        + (beta * ref_frustum.ry_max)[..., None] * ref.y_axis
    )
    frame = rolled_frame(ctx, checks, ref.origin, direction, theta=roll, up=ref.y_axis)
    ext = extent(xp, light, verts, (frame.x_axis, frame.y_axis, frame.z_axis))
    reach = blocker_reach(xp, light, verts)
    frustum = bounded_frustum(ctx, checks, ext, reach, m, near=near, far=far, symmetric=symmetric)
    return FrustumFit(frame=frame, frustum=frustum, direction=direction, roll=roll, losses=history)


def optimize_frustum(
    light_position: Real[ArrayLike, "*#batch 3"],
    vertices: Real[ArrayLike, "*#batch N 3"],
    map_size: int | tuple[int, int],
    *,
    symmetric: BoolLike = False,
    steps: int = 80,
    starts: int = 6,
    learning_rate: float = 0.1,
    border_texels: int = 1,
    margin: float | tuple[float, float] | None = None,
    near: Real[ArrayLike, "*#batch"] | None = None,
    far: Real[ArrayLike, "*#batch"] | None = None,
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
    m = margins(map_size, border_texels, margin)
    ctx, (light, verts, n, f) = convert(
        light_position=light_position, vertices=vertices, near=near, far=far
    )
    require_last("light_position", light, 3, hint="a light position is (x, y, z)")
    require_last("vertices", verts, 3, min_ndim=2, hint="vertices are (*batch, N, 3)")
    if verts.shape[-2] == 0:
        raise ValueError("vertices: the vertex set is empty (N = 0); a blocker needs vertices")
    return _optimize_core(
        ctx,
        Checks(ctx),
        light,
        verts,
        m=m,
        near=n,
        far=f,
        symmetric=bool(symmetric),
        steps=int(steps),
        starts=int(starts),
        learning_rate=float(learning_rate),
    )


def optimized_setup(
    ctx: Context,
    checks: Checks,
    light: Array,
    world: Array,
    B: Array | None,
    *,
    m: tuple[float, float],
    near: Array | None,
    far: Array | None,
) -> ShadowSetup:
    """``fit_shadow(method="optimized")`` on shape-checked arrays (world-space vertices)."""
    fit = _optimize_core(
        ctx, checks, light, world, m=m, near=near, far=far,
        symmetric=False, steps=80, starts=6, learning_rate=0.1,
    )  # fmt: skip
    return setup_from(ctx, checks, fit.frame, fit.frustum, B)
