"""The vertex passes' array forms (NumPy or JAX): each pass once, as reductions over the last axis.

A fit reads the vertices in passes: the **spread** (sums and bounds of the points about a
point: the viewing direction, the reach and the coordinates' size), the **bounds in light
coordinates**, the **receivers' farthest depth** and the **minimal enclosing sphere**. Each
has a loop form, one entry at a time (:mod:`._vertex_passes`, the compiled path), and the
array form here, which every other caller reaches:

* :class:`ArrayPasses`: the four passes with the loop forms' signatures, bound by
  ``specialize`` in place of the loops when :func:`._fit_entry.fit_entry` runs on whole
  arrays (:mod:`shadowmath._fits.shadow._arrays`);
* :func:`spread` and :func:`extent`: the first two passes for the doors of
  :mod:`shadowmath._geometry` (``light_frame``, ``adaptive_frustum``, ``smooth_frustum``)
  and ``optimize_frustum``, written over the same reductions (:func:`sums_and_bounds`,
  :func:`in_light`, :func:`projected`).

Each pass is one expression over ``(*batch, N)`` component arrays: under ``jax.jit`` XLA
fuses it into one loop; with NumPy the intermediate arrays are allocated, which is why
large NumPy blockers go through the compiled loop when Numba is installed. Both forms call
the per-vertex formulas of :mod:`._fit_formulas`. Trusted inputs only.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from types import ModuleType, SimpleNamespace
from typing import Any, NamedTuple

import numpy as np

from shadowmath._boundary._shapes import Float, Int, Scalar
from shadowmath._boundary._status import OVERFLOW
from shadowmath._boundary._validate import Array

from ._ball_support import support_arrays
from ._fit_formulas import to_light
from ._specialize import formulas, scalar_formulas


class Spread(NamedTuple):
    """Pass 1: where the blocker lies from the light, and the scales of the thresholds."""

    direction: Array  # (*batch, 3) the MDV (mean of V - L) or the bounding box's centre - L
    coords: Array  # (*batch,) max |coordinate| of the vertices and the light
    reach: Array  # (*batch,) max |V - L| component over the vertices


class Extent(NamedTuple):
    """Pass 2: the blocker in light coordinates."""

    x: Array  # (*batch, N) light coordinates of each vertex
    y: Array
    z: Array
    rx: Array  # (*batch, N) the ratios x / z and y / z (z replaced by 1 where z <= 0)
    ry: Array


def sums_and_bounds(
    xp: ModuleType,
    world: tuple[Float[Array, "*#batch N"], Float[Array, "*#batch N"], Float[Array, "*#batch N"]],
    o: tuple[Scalar, Scalar, Scalar],
) -> tuple[
    tuple[Float[Array, "*#batch"], Float[Array, "*#batch"], Float[Array, "*#batch"]],
    tuple[Float[Array, "*#batch"], Float[Array, "*#batch"], Float[Array, "*#batch"]],
    tuple[Float[Array, "*#batch"], Float[Array, "*#batch"], Float[Array, "*#batch"]],
]:
    """The spread's reductions: the sums of ``p - o`` and the bounds ``lo, hi`` of ``p``
    (three each, over the last axis of the ``(*batch, N)`` components ``world``; ``o``
    broadcasts against them). The differences before the sum: full precision far from
    the origin; :func:`._fit_formulas.bounds_about` gives the bounds about any point."""
    sums = tuple(xp.sum(p - q, axis=-1) for p, q in zip(world, o, strict=True))
    lo = tuple(xp.min(p, axis=-1) for p in world)
    hi = tuple(xp.max(p, axis=-1) for p in world)
    return sums, lo, hi


def in_light(
    o: tuple[Scalar, Scalar, Scalar],
    world: tuple[Float[Array, "*#batch N"], Float[Array, "*#batch N"], Float[Array, "*#batch N"]],
    a: tuple[Scalar, ...],
) -> tuple[Float[Array, "*#batch N"], Float[Array, "*#batch N"], Float[Array, "*#batch N"]]:
    """Light coordinates ``(x, y, z)`` of every point of ``world`` in the frame ``a``
    (its 9 axis components) about ``o``.

    Per component (three products and two sums), not a reduction over a last axis of
    length 3: XLA fuses the whole pass into one loop this way, while a size-3 reduction
    per vertex ran 60x slower than a read on the CPU.
    """
    c = tuple(p - q for p, q in zip(world, o, strict=True))
    x, y, z = to_light(c[0], c[1], c[2], a)
    return x, y, z


def projected(
    xp: ModuleType,
    x: Float[Array, "*#batch N"],
    y: Float[Array, "*#batch N"],
    z: Float[Array, "*#batch N"],
) -> tuple[Float[Array, "*#batch N"], Float[Array, "*#batch N"]]:
    """``x / z, y / z`` with one reciprocal per vertex, as the loop form computes them.

    A safe ``z`` (1 where ``z <= 0``), so that invalid entries never produce inf/NaN
    derivatives that leak into valid ones; the checks mark them invalid.
    """
    inv_z = 1 / xp.where(z > 0, z, xp.ones_like(z))
    return x * inv_z, y * inv_z


def _world(
    light: Float[Array, "*#batch 3"], verts: Float[Array, "*#batch N 3"]
) -> tuple[
    tuple[Float[Array, "*#batch N"], Float[Array, "*#batch N"], Float[Array, "*#batch N"]],
    tuple[Float[Array, "*#batch 1"], Float[Array, "*#batch 1"], Float[Array, "*#batch 1"]],
]:
    """The vertices' components ``(*batch, N)`` and the light's, broadcast against them."""
    world = (verts[..., 0], verts[..., 1], verts[..., 2])
    return world, (light[..., None, 0], light[..., None, 1], light[..., None, 2])


def spread(
    xp: ModuleType,
    light: Float[Array, "*#batch 3"],
    verts: Float[Array, "*#batch N 3"],
    *,
    aim: str,
) -> Spread:
    """Pass 1 over ``verts`` ``(*batch, N, 3)`` seen from ``light`` ``(*batch, 3)``:
    :func:`sums_and_bounds` and :func:`._fit_formulas.bounds_about`, as the fit reads them."""
    world, o = _world(light, verts)
    sums, lo, hi = sums_and_bounds(xp, world, o)
    L = (light[..., 0], light[..., 1], light[..., 2])
    lo_o, hi_o, reach, coords = formulas(xp).bounds_about(lo, hi, L)
    if aim == "mean":
        n = verts.shape[-2]
        direction = xp.stack([s / n for s in sums], axis=-1)
    else:
        direction = xp.stack([0.5 * (h + g) for h, g in zip(hi_o, lo_o, strict=True)], axis=-1)
    coords = xp.maximum(coords, xp.max(xp.abs(light), axis=-1))
    return Spread(direction, coords, reach)


def extent(
    xp: ModuleType,
    light: Float[Array, "*#batch 3"],
    verts: Float[Array, "*#batch N 3"],
    axes: tuple[Float[Array, "*#batch 3"], Float[Array, "*#batch 3"], Float[Array, "*#batch 3"]],
) -> Extent:
    """Pass 2: light coordinates and projection ratios of every vertex.

    ``axes = (X, Y, Z)``: the light frame's ``(*batch, 3)`` axes.
    """
    world, o = _world(light, verts)
    a = tuple(axis[..., None, j] for axis in axes for j in range(3))
    x, y, z = in_light(o, world, a)
    rx, ry = projected(xp, x, y, z)
    return Extent(x, y, z, rx, ry)


#: The minimal enclosing sphere's support of ``(*batch, N, 3)`` float64 points:
#: ``(*batch, 5)`` int32 rows ``(i_0, i_1, i_2, i_3, k)``.
Support = Callable[[Any], Any]


def array_support(points: Float[Array, "*batch N 3"]) -> Int[Array, "*batch 5"]:
    """:data:`Support` by :func:`._ball_support.support_arrays` (every entry at once)."""
    p = np.asarray(points, dtype=np.float64)
    flat = np.ascontiguousarray(p.reshape(-1, *p.shape[-2:]))
    return support_arrays(flat).reshape(*p.shape[:-2], 5)


class ArrayPasses:
    """The passes of :mod:`._vertex_passes` as reductions over the last axis (NumPy or JAX).

    The vertex source is ``(world, status)``: the world components ``(*batch, N)``
    and the per-entry bits of non-finite and projectively placed vertices. ``scalar``:
    one NumPy entry, its per-entry values Python floats; ``flag`` the driver's status
    primitive; ``support`` the enclosing sphere's support (on the host: the compiled
    Welzl loop where the caller has it, else :func:`array_support`).
    """

    def __init__(
        self, xp: ModuleType, scalar: bool, flag: Any, support: Support = array_support
    ) -> None:
        self.xp, self.scalar, self.flag, self.support = xp, scalar, flag, support

    @property
    def Fv(self) -> SimpleNamespace:
        return formulas(self.xp)

    def _e(self, v: Array) -> Array:
        return float(v) if self.scalar else v

    def _x(self, values: tuple[Array, ...]) -> tuple[Array, ...]:
        """Per-entry values broadcast against ``(*batch, N)`` vertex components."""
        return values if self.scalar else tuple(v[..., None] for v in values)

    def _bounds(self, x: Array) -> tuple[Array, Array]:
        xp = self.xp
        return self._e(xp.max(x, axis=-1)), self._e(xp.min(x, axis=-1))

    def spread(self, vs: Any, o: tuple[Array, ...]) -> tuple[Any, ...]:
        """:func:`._vertex_passes.spread`: sums about ``o``, bounds, status, count."""
        world, st = vs
        sums, lo, hi = sums_and_bounds(self.xp, world, self._x(o))
        sums, lo, hi = (tuple(self._e(v) for v in t) for t in (sums, lo, hi))
        ok = self.Fv.isfinite(sums[0]) & self.Fv.isfinite(sums[1]) & self.Fv.isfinite(sums[2])
        st = st | self.flag(ok, OVERFLOW)
        return sums, lo, hi, st, world[0].shape[-1]

    def light_pass(self, vs: Any, o: tuple[Array, ...], a: tuple[Array, ...], ratios: bool) -> Any:
        """:func:`._vertex_passes.light_pass`: the bounds of :func:`in_light`."""
        x, y, z = in_light(self._x(o), vs[0], self._x(a))
        if ratios:
            x, y = projected(self.xp, x, y, z)
        (hx, lx), (hy, ly), (hz, lz) = self._bounds(x), self._bounds(y), self._bounds(z)
        return hx, lx, hy, ly, hz, lz

    def receiver_far(
        self, R: Array, o: tuple[Array, ...], a: tuple[Array, ...], sides: Any, opts: Any
    ) -> tuple[Array, Array, Array]:
        """:func:`._vertex_passes.receiver_far`: the farthest depth, finite flag, link."""
        xp, count = self.xp, R.shape[-2]
        # NumPy: blocks of receivers whose (batch, block) temporaries hold at most _BLOCK
        # numbers (a larger one alive beside another is a fresh mapping of the allocator
        # each time: its page faults cost ten times the arithmetic). JAX: one block.
        step = count if xp is not np else max(1, _BLOCK // max(1, np.size(a[0])))
        far = self._receivers_z(R[..., :step, :], o, a, sides, opts)
        for m in range(step, count, step):
            far = xp.maximum(far, self._receivers_z(R[..., m : m + step, :], o, a, sides, opts))
        finite = xp.all(xp.isfinite(R), axis=(-2, -1))
        return self._e(far), self._e(finite), self._link(R)

    def _receivers_z(
        self, R: Array, o: tuple[Array, ...], a: tuple[Array, ...], sides: Any, opts: Any
    ) -> Array:
        """The farthest depth of the receivers ``R`` inside the sides (``-inf`` if none)."""
        xp, F = self.xp, self.Fv
        s, org, ax = self._x(sides), self._x(o), self._x(a)
        corners: list[Array] = []
        for j in range(0, R.shape[-1], 3):  # one point, or a triangle's three corners
            corners.extend(in_light(org, (R[..., j], R[..., j + 1], R[..., j + 2]), ax))
        if opts.triangles:
            z = F.triangle_far(tuple(corners), s, opts.directional, opts.eps)
        else:
            z = F.where(F.receiver_counted(*corners, s, opts.directional), corners[2], -math.inf)
        return xp.max(z, axis=-1)

    def _link(self, R: Array) -> Array:
        """0, or under JAX 0 times the receivers' non-finite entries (NaN exactly there):
        the link of :func:`._fit_entry.receivers_far` (NumPy raises instead)."""
        xp = self.xp
        if xp is np:
            return 0.0
        return 0.0 * xp.sum(xp.where(xp.isfinite(R), 0.0, R), axis=(-2, -1))

    def enclosing_ball(self, vs: Any) -> tuple[Array, Array, Array, Array]:
        """The vertices' minimal enclosing sphere: centre (3) and ``r^2``, per entry.

        Its support points (2 to 4 vertices) come from :attr:`support` on the host
        (under JAX through ``pure_callback``: they are piecewise constant), the sphere
        from :func:`._fit_formulas.sphere_through` on them, so values and derivatives
        follow the support points.
        """
        xp, world = self.xp, vs[0]
        points = xp.stack(world, axis=-1)
        if xp is np:
            support = self.support(points)
        else:
            import jax

            shape = jax.ShapeDtypeStruct((*points.shape[:-2], 5), np.int32)  # type: ignore[no-untyped-call]
            support = jax.pure_callback(
                self.support, shape, jax.lax.stop_gradient(points), vmap_method="expand_dims"
            )
        on = [xp.take_along_axis(w, support[..., :4], axis=-1) for w in world]  # (*batch, 4)
        q = tuple(on[c][..., j] for j in range(4) for c in range(3))
        k = support[..., 4]
        if self.scalar:
            q, k = tuple(float(v) for v in q), int(k)
        F = scalar_formulas() if self.scalar else self.Fv
        cx, cy, cz, r2 = F.sphere_through(q, k)
        return cx, cy, cz, r2


#: The most numbers in one NumPy temporary of the receivers' pass (64 kB of float64: fastest
#: of 4,096 to 32,768 on the 2-core benchmark machine, 25 % faster than unblocked).
_BLOCK = 8192
