"""``fit_shadow``'s driver on whole arrays (NumPy or JAX): ``fit_entry`` run once.

:func:`fit_arrays` runs the one per-entry driver of the fit,
:func:`shadowmath._math._fit_entry.fit_entry`, once on whole arrays: each per-entry
value is an array of the batch shape, and the passes over the vertices are the
reductions of :class:`shadowmath._math._passes.ArrayPasses` over the last axis of
``(*batch, N)`` component arrays (under ``jax.jit`` XLA fuses each into one loop over
the vertices; the enclosing sphere's support from
:func:`shadowmath._backends._kernels.sphere_support`). The kind of light is static
(``key.directional``), so only its fit is traced or run. The status bits it returns
are the compiled loop's: NumPy raises the message of the first failing one, JAX hands
each to ``Checks`` (NaN outputs under a transformation).
"""

from __future__ import annotations

import functools
from types import ModuleType, SimpleNamespace
from typing import Any, NamedTuple

import numpy as np

from shadowmath._backends import _kernels
from shadowmath._boundary import _messages as msg
from shadowmath._boundary._shapes import Float, Scalar, Vertices
from shadowmath._boundary._status import (
    PROJECTIVE,
    VERTICES,
    WIDE_WARNING,
)
from shadowmath._boundary._validate import Array, Checks, Context, all_finite
from shadowmath._fits._backend import failure_messages, raise_fit_status
from shadowmath._fits._spec import FitKey, fit_options
from shadowmath._math._fit_entry import Entry
from shadowmath._math._passes import ArrayPasses
from shadowmath._math._specialize import (
    array_primitives,
    formulas,
    scalar_primitives,
    specialize,
)

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
    passes = ArrayPasses(xp, scalar, primitives["flag"], _kernels.sphere_support)
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
_MESSAGES = failure_messages(None)


def _report(ctx: Context, checks: Checks, status: Flags | int) -> None:
    """The failed checks, in report order: raised (NumPy) or recorded (JAX: NaN outputs)."""
    xp = ctx.xp
    if isinstance(status, int):  # one NumPy entry on Python floats: the loop's status word
        raise_fit_status(np.asarray([status]), (), None)
        return
    ok = status.checks
    for bit, message in _MESSAGES:
        if bit in ok and ok[bit] is not True:
            checks.require(ok[bit], message)
    calm = ok.get(WIDE_WARNING, True)
    if xp is np and calm is not True and not np.all(calm):  # (JAX: no warnings)
        msg.warn_wide()


def _components(d: Driver, v: Float[Array, "*batch k"], n: int) -> tuple[Scalar, ...]:
    return tuple(d.entry(v[..., i]) for i in range(n))


def _vertex_source(
    d: Driver, verts: Float[Array, "*#batch N 3"], B: Float[Array, "*#batch 4 4"] | None
) -> Vertices:
    """The vertices' world components (through the placement) and their status bits."""
    xp, F = d.xp, d.F
    px, py, pz = verts[..., 0], verts[..., 1], verts[..., 2]
    st = F.flag(d.entry(all_finite(xp, verts, 2)), VERTICES)
    if B is None:
        return (px, py, pz), st
    b = tuple(B[..., None, i // 4, i % 4] for i in range(16))
    x, y, z, w = formulas(xp).place(b, px, py, pz)
    return (x, y, z), st | F.flag(d.entry(xp.all(w > 0, axis=-1)), PROJECTIVE)
