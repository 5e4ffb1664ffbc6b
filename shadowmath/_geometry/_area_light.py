"""Soft shadows of a parallelogram area light at the door (checks; cores in
:mod:`shadowmath._math._soft`): the pyramid-to-cube map and the light's samples."""

from __future__ import annotations

from typing import Any

import numpy as np

from shadowmath._boundary._renamed import warn_renamed
from shadowmath._boundary._shapes import ArrayLike, Float, IntLike, Real
from shadowmath._boundary._validate import (
    Array,
    Checks,
    Context,
    all_finite,
    batch_shape,
    convert,
    is_jax,
    non_finite,
    require_last,
)
from shadowmath._math import _soft
from shadowmath._math._vector import cross, dot, norm


def pyramid_to_unit_cube(
    apex: Real[ArrayLike, "*#batch 3"],
    corner: Real[ArrayLike, "*#batch 3"],
    edge_u: Real[ArrayLike, "*#batch 3"],
    edge_v: Real[ArrayLike, "*#batch 3"],
) -> Float[Array, "*batch 4 4"]:
    r"""Heckbert and Herf's matrix: the pyramid from a light sample onto the unit box.

    The pyramid has its apex ``a`` at a light sample and, as its base, the
    parallelogram ``b + u e_u + v e_v`` (``0 <= u, v <= 1``) fitted around a
    receiver polygon. With ``e_w = b - a`` and the normals

    .. math::

        n_x = e_w \times e_v, \quad n_y = e_u \times e_w, \quad n_w = e_v \times e_u,

    (of the side planes through ``a, b, b + e_v`` and ``a, b, b + e_u``, and of
    the base), the rows of ``M`` are

    .. math::

        X = \frac{n_x \cdot (p - b)}{n_x \cdot e_u}, \quad
        Y = \frac{n_y \cdot (p - b)}{n_y \cdot e_v}, \quad
        W = \frac{n_w \cdot (p - a)}{n_w \cdot e_w}, \quad
        Z = 1 - W .

    After division ``x = X/W``, ``y = Y/W``, ``z = 1/W - 1``: a base point
    ``b + u e_u + v e_v`` goes to ``(u, v, 0)``; every point
    ``a + λ (q - a)`` of the ray from the apex through a base point ``q`` to
    the same ``(u, v)`` (``X`` and ``W`` both scale by ``λ``); the sides to
    ``x = 0``, ``x = 1``, ``y = 0``, ``y = 1``; the plane through the apex
    parallel to the base to ``W = 0`` (``z -> +inf``). Between that plane and
    the base ``W = λ in (0, 1]``: positive, so clipping keeps it, and ``z > 0``
    grows toward the light. Points beyond the base (behind the receiver) have
    ``-1 < z < 0``: clip them with a near plane at ``z = -ε``.

    The three denominators are the same triple product ``e_u · (e_w × e_v)``,
    kept per row as the paper prints them. Seed 004 prints this matrix without
    defining ``e_w`` and with a ``z`` row that contradicts its text: see the
    errata (``docs/errata.md``).

    Arguments:
        apex: ``(*batch, 3)`` the light sample.
        corner: ``(*batch, 3)`` the base corner ``b``.
        edge_u, edge_v: ``(*batch, 3)`` the base's edges (``x`` runs along ``edge_u``).

    Returns:
        ``(*batch, 4, 4)`` column-vector matrix (``p' = M @ p``).

    Raises:
        ValueError: wrong shapes; non-finite values; a degenerate parallelogram
            (a zero edge or parallel edges, relative to their lengths); the apex
            in the base plane (its height below ``64 eps`` times the pyramid's size
            ``|edge_u| + |edge_v| + |corner - apex|``). Under JAX
            transformations the affected matrices are NaN instead.

    Example:
        >>> import numpy as np
        >>> M = pyramid_to_unit_cube([0.0, 0.0, 2.0], [-1.0, -1.0, 0.0], [2.0, 0, 0], [0, 2.0, 0])
        >>> q = M @ np.array([1.0, 1.0, 0.0, 1.0])  # the base's far corner
        >>> q[:3] / q[3]
        array([1., 1., 0.])
        >>> q = M @ np.array([0.5, 0.5, 1.0, 1.0])  # halfway up the same ray
        >>> q[:3] / q[3]
        array([1., 1., 1.])
    """
    ctx, (a, b, eu, ev) = convert(apex=apex, corner=corner, edge_u=edge_u, edge_v=edge_v)
    xp = ctx.xp
    for name, value in (("apex", a), ("corner", b), ("edge_u", eu), ("edge_v", ev)):
        require_last(name, value, 3, hint="points and edges are (*batch, 3)")
    shape = batch_shape(
        *(tuple(v.shape[:-1]) for v in (a, b, eu, ev)),
        names=("apex", "corner", "edge_u", "edge_v"),
    )
    checks = Checks(ctx)
    for name, value in (("apex", a), ("corner", b), ("edge_u", eu), ("edge_v", ev)):
        checks.require(all_finite(xp, value, 1), non_finite(name))
    _require_parallelogram(ctx, checks, eu, ev)
    normal = cross(xp, ev, eu)
    size = norm(xp, eu) + norm(xp, ev) + norm(xp, b - a)
    # |n . (b - a)| = area * height of the apex above the base plane.
    checks.require(
        xp.abs(dot(xp, normal, b - a)) > 64 * ctx.eps * norm(xp, normal) * size,
        "apex: lies in the base plane of the parallelogram (relative to the pyramid's "
        "size); the pyramid needs its apex off that plane",
    )
    if checks.invalid is not None:
        checks.invalid = xp.broadcast_to(checks.invalid, shape)
    M = xp.broadcast_to(_soft.pyramid_to_unit_cube(xp, a, b, eu, ev), (*shape, 4, 4))
    return checks.poison(M, 2)


def _require_parallelogram(ctx: Context, checks: Checks, eu: Array, ev: Array) -> None:
    xp = ctx.xp
    area = norm(xp, cross(xp, eu, ev))
    checks.require(area > 16 * ctx.eps * norm(xp, eu) * norm(xp, ev), _soft.DEGENERATE)


def _checked_light(
    corner: Any, edge_u: Any, edge_v: Any, count: int
) -> tuple[Context, Checks, Array, Array, Array, tuple[int, ...], tuple[int, int]]:
    if isinstance(count, bool) or not isinstance(count, int | np.integer):
        raise ValueError(f"count: expected a positive integer, got {count!r}")
    if count < 1:
        raise ValueError(f"count: must be at least 1, got {count}")
    ctx, (c, eu, ev) = convert(corner=corner, edge_u=edge_u, edge_v=edge_v)
    xp = ctx.xp
    for name, value in (("corner", c), ("edge_u", eu), ("edge_v", ev)):
        require_last(name, value, 3, hint="points and edges are (*batch, 3)")
    shape = batch_shape(
        *(tuple(v.shape[:-1]) for v in (c, eu, ev)), names=("corner", "edge_u", "edge_v")
    )
    checks = Checks(ctx)
    for name, value in (("corner", c), ("edge_u", eu), ("edge_v", ev)):
        checks.require(all_finite(xp, value, 1), non_finite(name))
    _require_parallelogram(ctx, checks, eu, ev)
    if checks.invalid is not None:
        checks.invalid = xp.broadcast_to(checks.invalid, shape)
    return ctx, checks, c, eu, ev, shape, _soft.grid(int(count))


def area_light_samples(
    corner: Real[ArrayLike, "*#batch 3"],
    edge_u: Real[ArrayLike, "*#batch 3"],
    edge_v: Real[ArrayLike, "*#batch 3"],
    count: IntLike,
    *,
    seed: int | np.random.Generator | None = None,
    key: Any = None,
) -> Float[Array, "*batch {count} 3"]:
    r"""Stratified, jittered samples of a parallelogram area light.

    The light ``corner + u edge_u + v edge_v`` (``0 <= u, v <= 1``) is cut into
    the most nearly square grid of ``rows x cols = count`` cells (``rows`` the
    largest divisor of ``count`` not above its square root, so a prime
    ``count`` gives ``1 x count``; ``cols`` runs along ``edge_u``, so pass the
    longer edge there), and each cell gets one uniformly jittered sample:

    .. math::

        u_k = \frac{j + \xi_k}{\mathrm{cols}}, \quad
        v_k = \frac{i + \eta_k}{\mathrm{rows}}, \qquad
        k = i\,\mathrm{cols} + j, \quad \xi_k, \eta_k \sim U[0, 1).

    Each sample stands for ``1 / count`` of the light's area: average the hard
    shadows with equal weights. The jitter comes from
    ``numpy.random.default_rng(seed)`` on the host, in the working dtype, and is
    then a constant: JAX inputs give JAX outputs (differentiable in the
    corner and edges), but under ``jax.jit`` it is drawn once, at trace time.
    With a JAX PRNG ``key`` instead, ``ξ, η = jax.random.uniform(key, (*batch, count,
    2))`` and the result is a JAX array: fresh jitter inside ``jit`` (``count`` fixes
    the output's shape, so it is static: ``jax.jit(area_light_samples,
    static_argnums=3)``; split the key for a new set of samples, one set per frame,
    say). ``area_light_samples_jax(key, corner, edge_u, edge_v, count)`` is the
    deprecated name of this call.

    Arguments:
        corner: ``(*batch, 3)`` one corner of the light.
        edge_u, edge_v: ``(*batch, 3)`` its edges from that corner.
        count: the number of samples (a Python integer, static), ``>= 1``.
        seed: anything ``numpy.random.default_rng`` accepts; ``None`` for fresh
            entropy, an integer for reproducible samples.
        key: a JAX PRNG key (``jax.random.key(0)`` or ``jax.random.PRNGKey(0)``) to
            draw the jitter with JAX instead (not with ``seed``).

    Returns:
        ``(*batch, count, 3)`` sample positions, row by row (``k = i cols + j``).

    Raises:
        ValueError: wrong shapes; ``count < 1`` or not an integer; non-finite
            values; a degenerate parallelogram (a zero edge or parallel edges);
            both ``seed`` and ``key``. Under JAX transformations the affected samples
            are NaN instead.

    Example:
        >>> samples = area_light_samples([0.0, 0, 5], [2.0, 0, 0], [0, 1.0, 0], 6, seed=1)
        >>> samples.shape  # a 2 x 3 grid
        (6, 3)
        >>> bool(((samples[:, 0] // (2 / 3)) == [0, 1, 2, 0, 1, 2]).all())
        True
        >>> import jax
        >>> s = area_light_samples([0.0, 0, 5], [2.0, 0, 0], [0, 1.0, 0], 4, key=jax.random.key(0))
        >>> s.shape, bool((s[:, 2] == 5).all())
        ((4, 3), True)
    """
    if key is not None:
        if seed is not None:
            raise ValueError("seed, key: give one of them (seed for NumPy, key for JAX)")
        return _jax_samples(key, corner, edge_u, edge_v, count)
    ctx, checks, c, eu, ev, shape, (rows, cols) = _checked_light(corner, edge_u, edge_v, count)
    rng = np.random.default_rng(seed)
    jitter_np = rng.random((*shape, rows * cols, 2), dtype=np.dtype(ctx.dtype).type)
    jitter = ctx.xp.asarray(jitter_np, dtype=ctx.dtype)
    return checks.poison(_soft.area_light_samples(ctx.xp, c, eu, ev, jitter, grid=(rows, cols)), 2)


def area_light_samples_jax(
    key: Any,
    corner: Real[ArrayLike, "*#batch 3"],
    edge_u: Real[ArrayLike, "*#batch 3"],
    edge_v: Real[ArrayLike, "*#batch 3"],
    count: IntLike,
) -> Float[Array, "*batch {count} 3"]:
    """Deprecated: ``area_light_samples(corner, edge_u, edge_v, count, key=key)``."""
    warn_renamed("area_light_samples_jax(key, ...)", "area_light_samples(..., key=key)")
    return area_light_samples(corner, edge_u, edge_v, count, key=key)


def _jax_samples(key: Any, corner: Any, edge_u: Any, edge_v: Any, count: int) -> Array:
    import jax
    import jax.numpy as jnp

    c, eu, ev = (v if is_jax(v) else jnp.asarray(np.asarray(v)) for v in (corner, edge_u, edge_v))
    ctx, checks, c, eu, ev, shape, (rows, cols) = _checked_light(c, eu, ev, count)
    jitter = jax.random.uniform(key, (*shape, rows * cols, 2), dtype=ctx.dtype)
    return checks.poison(_soft.area_light_samples(ctx.xp, c, eu, ev, jitter, grid=(rows, cols)), 2)
