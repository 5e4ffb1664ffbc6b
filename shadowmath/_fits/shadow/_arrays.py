"""The fits on whole arrays (NumPy or JAX): the vertex passes of :func:`._fit_entry.fit_entry`.

:func:`fit_arrays` runs the one per-entry driver of the fit,
:func:`shadowmath._math._fit_entry.fit_entry`, once on whole arrays: each per-entry
value is an array of the batch shape, and the passes over the vertices are the
reductions of :class:`ArrayPasses` over the last axis of ``(*batch, N)`` component
arrays (under ``jax.jit`` XLA fuses each into one loop over the vertices). The kind
of light is static (``key.directional``), so only its fit is traced or run. The
status bits it returns are the compiled loop's: NumPy raises the message of the
first failing one, JAX hands each to ``Checks`` (NaN outputs under a transformation).
"""

from __future__ import annotations

import functools
import math
from types import ModuleType, SimpleNamespace
from typing import Any, NamedTuple

import numpy as np

from shadowmath._backends import _kernels
from shadowmath._boundary import _messages as msg
from shadowmath._boundary._status import (
    OVERFLOW,
    PROJECTIVE,
    VERTICES,
    WIDE_WARNING,
    fit_messages,
)
from shadowmath._boundary._validate import Array, Checks, Context, all_finite, raise_status
from shadowmath._fits._spec import FitKey, fit_options
from shadowmath._math._fit_entry import Entry
from shadowmath._math._specialize import (
    array_primitives,
    formulas,
    scalar_formulas,
    scalar_primitives,
    specialize,
)

Components = tuple[Array, Array, Array]


#: A fit's per-entry results (the status, then component arrays of the batch shape, or
#: scalars): the :class:`Entry` of the per-entry code, which every driver reads.
FitEntries = Entry


class Inputs(NamedTuple):
    """The trusted arrays of one fit (``None`` where not given)."""

    light: Array  # (*batch, 3): a position or a direction toward the light
    verts: Array  # (*batch, N, 3)
    B: Array | None
    R: Array | None
    U: Array | None
    near: Array | None
    far: Array | None


class Driver(NamedTuple):
    """How one call runs the fit: its namespace, and :func:`fit_entry` with its passes.

    On whole arrays per-entry values are ``(*batch,)`` arrays. For one NumPy entry
    (batch shape ``()``, ``scalar``) they are Python floats, which costs microseconds
    instead of the 0-d array overhead of hundreds of NumPy calls; the vertex passes
    stay NumPy.
    """

    xp: ModuleType
    F: SimpleNamespace  # the formulas and fit_entry, with this backend's passes
    eps: float
    scalar: bool

    def entry(self, v: Array) -> Array:
        """A per-entry value (a Python float for one NumPy entry)."""
        return float(v) if self.scalar else v


def driver(ctx: Context, scalar: bool) -> Driver:
    """The driver of one call; ``scalar`` for one NumPy entry."""
    return Driver(ctx.xp, _namespace(ctx.xp, scalar), ctx.eps, scalar)


@functools.cache
def _namespace(xp: ModuleType, scalar: bool) -> SimpleNamespace:
    primitives = scalar_primitives() if scalar else {**array_primitives(xp), "flag": Flags.of}
    passes = ArrayPasses(xp, scalar, primitives["flag"])
    names = ("spread", "light_pass", "receiver_far", "enclosing_ball")
    return specialize({**primitives, **{n: getattr(passes, n) for n in names}}, loop=scalar)


class Flags:
    """A fit's status on arrays: each status bit's check (True: passed), by bit.

    ``flag(ok, bit)`` on arrays is ``Flags({bit: ok})`` and ``|`` merges them (a bit
    set twice fails where either fails), so the driver hands each check to ``Checks``
    as it is, instead of building and decoding integer words: the traced fit stays small.
    """

    __slots__ = ("checks",)

    def __init__(self, checks: dict[int, Any]) -> None:
        self.checks = checks

    @staticmethod
    def of(ok: Any, bit: int) -> Flags:
        return Flags({bit: ok})

    def __or__(self, other: Flags | int) -> Flags:
        if isinstance(other, int):  # the 0 a status starts from
            return self
        merged = dict(self.checks)
        for bit, ok in other.checks.items():
            merged[bit] = merged[bit] & ok if bit in merged else ok
        return Flags(merged)

    __ror__ = __or__


class ArrayPasses:
    """The passes over the vertices as reductions over the last axis (NumPy or JAX).

    The vertex source is ``(world, status)``: the world components ``(*batch, N)``
    and the per-entry bits of non-finite and projectively placed vertices.
    """

    def __init__(self, xp: ModuleType, scalar: bool, flag: Any) -> None:
        self.xp, self.scalar, self.flag = xp, scalar, flag

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
        world, st = vs
        xp = self.xp
        sums = tuple(
            self._e(xp.sum(p - q, axis=-1)) for p, q in zip(world, self._x(o), strict=True)
        )
        (hx, lx), (hy, ly), (hz, lz) = (self._bounds(p) for p in world)
        ok = self.Fv.isfinite(sums[0]) & self.Fv.isfinite(sums[1]) & self.Fv.isfinite(sums[2])
        st = st | self.flag(ok, OVERFLOW)
        return sums, (lx, ly, lz), (hx, hy, hz), st, world[0].shape[-1]

    def light_pass(self, vs: Any, o: tuple[Array, ...], a: tuple[Array, ...], ratios: bool) -> Any:
        xp = self.xp
        c = tuple(p - q for p, q in zip(vs[0], self._x(o), strict=True))
        x, y, z = self.Fv.to_light(*c, self._x(a))
        if ratios:  # one reciprocal per vertex, as the compiled loop computes it
            inv_z = 1 / xp.where(z > 0, z, xp.ones_like(z))
            x, y = x * inv_z, y * inv_z
        (hx, lx), (hy, ly), (hz, lz) = self._bounds(x), self._bounds(y), self._bounds(z)
        return hx, lx, hy, ly, hz, lz

    def receiver_far(
        self, R: Array, o: tuple[Array, ...], a: tuple[Array, ...], sides: Any, opts: Any
    ) -> tuple[Array, Array, Array]:
        xp, count = self.xp, R.shape[-2]
        # NumPy: blocks of receivers whose (batch, block) temporaries hold at most _BLOCK
        # numbers (a larger one alive beside another is a fresh mapping of the allocator
        # each time: its page faults cost ten times the arithmetic). JAX: one block.
        step = count if xp is not np else max(1, _BLOCK // max(1, np.size(a[0])))
        far = self._receivers_z(R[..., :step, :], o, a, sides, opts)
        for m in range(step, count, step):
            far = xp.maximum(far, self._receivers_z(R[..., m : m + step, :], o, a, sides, opts))
        return self._e(far), self._e(all_finite(xp, R, 2)), self._link(R)

    def _receivers_z(
        self, R: Array, o: tuple[Array, ...], a: tuple[Array, ...], sides: Any, opts: Any
    ) -> Array:
        """The farthest depth of the receivers ``R`` inside the sides (``-inf`` if none)."""
        xp, F = self.xp, self.Fv
        s, org, ax = self._x(sides), self._x(o), self._x(a)
        corners = []
        for j in range(0, R.shape[-1], 3):  # one point, or a triangle's three corners
            r = (R[..., j] - org[0], R[..., j + 1] - org[1], R[..., j + 2] - org[2])
            corners.extend(F.to_light(*r, ax))
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

        Its support points (2 to 4 vertices) come from Welzl's algorithm on the host
        (:func:`._kernels.sphere_support`; under JAX through ``pure_callback``: they are
        piecewise constant), the sphere from :func:`sphere_through` on them, so values
        and derivatives follow the support points.
        """
        xp, world = self.xp, vs[0]
        points = xp.stack(world, axis=-1)
        if xp is np:
            support = _kernels.sphere_support(points)
        else:
            import jax

            shape = jax.ShapeDtypeStruct((*points.shape[:-2], 5), np.int32)  # type: ignore[no-untyped-call]
            support = jax.pure_callback(
                _kernels.sphere_support, shape, jax.lax.stop_gradient(points),
                vmap_method="expand_dims",
            )  # fmt: skip
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

_IDENTITY = tuple(float(i % 5 == 0) for i in range(16))


def fit_arrays(ctx: Context, checks: Checks, key: FitKey, a: Inputs, d: Driver) -> FitEntries:
    """The fit of ``key`` on shape-checked arrays; every value check goes to ``checks``."""
    comps = _components(d, a.light, 8 if key.spot else 3)
    L, S = comps[:3], comps[3:] if key.spot else (0.0,) * 5
    U = _components(d, a.U, 3) if a.U is not None else (0.0, 0.0, 0.0)
    b = _IDENTITY if a.B is None else tuple(d.entry(a.B[..., i // 4, i % 4]) for i in range(16))
    nf = tuple(0.0 if v is None else d.entry(v) for v in (a.near, a.far))
    o = fit_options(key, d.eps)
    e = d.F.fit_entry((L, S, U, b, nf), _vertex_source(d, a.verts, a.B), a.R, o, key.api)
    _report(ctx, checks, e.status)
    entries: FitEntries = e
    return entries


#: The checks' bits and messages in report order (the vertices' check is exact here).
_MESSAGES = fit_messages(False)


def _report(ctx: Context, checks: Checks, status: Flags | int) -> None:
    """The failed checks, in report order: raised (NumPy) or recorded (JAX: NaN outputs)."""
    xp = ctx.xp
    if isinstance(status, int):  # one NumPy entry on Python floats: the loop's status word
        if status & ~WIDE_WARNING:
            raise_status(np.asarray(status), _MESSAGES)
        if status & WIDE_WARNING:
            msg.warn_wide()
        return
    ok = status.checks
    for bit, message in _MESSAGES:
        if bit in ok and ok[bit] is not True:
            checks.require(ok[bit], message)
    calm = ok.get(WIDE_WARNING, True)
    if xp is np and calm is not True and not np.all(calm):  # (JAX: no warnings)
        msg.warn_wide()


def _components(d: Driver, v: Array, n: int) -> tuple[Array, ...]:
    return tuple(d.entry(v[..., i]) for i in range(n))


def _vertex_source(d: Driver, verts: Array, B: Array | None) -> tuple[Components, Any]:
    """The vertices' world components (through the placement) and their status bits."""
    xp, F = d.xp, d.F
    px, py, pz = verts[..., 0], verts[..., 1], verts[..., 2]
    st = F.flag(d.entry(all_finite(xp, verts, 2)), VERTICES)
    if B is None:
        return (px, py, pz), st
    b = tuple(B[..., None, i // 4, i % 4] for i in range(16))
    x, y, z, w = formulas(xp).place(b, px, py, pz)
    return (x, y, z), st | F.flag(d.entry(xp.all(w > 0, axis=-1)), PROJECTIVE)
