"""Bind the per-entry formulas to a backend: NumPy or JAX arrays, Python or Numba scalars.

The formulas of :mod:`._formulas` and :mod:`._fit_formulas` (and the loops of
:mod:`._loops` that drive them per entry, and fit_cascades' steps, :mod:`._cascade_steps`)
are written with five primitives (``where``, ``sqrt``, ``fabs``, ``rint``, ``isfinite``;
the cascades' steps also ``log2``, ``alloc``, ``flag`` and ``take_last``). :func:`specialize`
copies every one of them (and a spot light's triangle clipping, :mod:`._spot_loop`) into
one namespace where those names mean one backend's functions, so a specialized formula
calls specialized formulas: the frame, the frustum, the fits and the matrices are written
once and the backends cannot drift.
"""

from __future__ import annotations

import functools
import math
import operator
import types
from collections.abc import Callable
from types import ModuleType
from typing import Any

import numpy as np

from shadowmath._boundary._shapes import Array, Float, Real, Row, Scalar, Truth

from . import (
    _cascade_bounds,
    _cascade_formulas,
    _cascade_steps,
    _fit_entry,
    _fit_formulas,
    _formulas,
    _loops,
    _pcss,
    _rectangle_loop,
    _rows,
    _spot_loop,
    _vertex_passes,
    _warp_loop,
)

_MODULES = (
    (_formulas, _formulas.FUNCTIONS),
    (_fit_formulas, _fit_formulas.FUNCTIONS),
    (_vertex_passes, _vertex_passes.FUNCTIONS),
    (_fit_entry, _fit_entry.FUNCTIONS),
    (_loops, _loops.FUNCTIONS),
    (_cascade_formulas, _cascade_formulas.FUNCTIONS),
    (_rows, _rows.FUNCTIONS),
    (_rectangle_loop, _rectangle_loop.FUNCTIONS),
    (_warp_loop, _warp_loop.FUNCTIONS),
    (_cascade_steps, _cascade_steps.FUNCTIONS),
    (_cascade_bounds, _cascade_bounds.FUNCTIONS),
    (_pcss, _pcss.FUNCTIONS),
    (_spot_loop, _spot_loop.FUNCTIONS),
)


def _forms() -> dict[str, tuple[str, str]]:
    """Names with a loop form and an array form (the modules' ``FORMS``, each name once)."""
    pairs = [kv for module, _ in _MODULES for kv in getattr(module, "FORMS", {}).items()]
    forms = dict(pairs)
    if len(forms) != len(pairs):
        raise RuntimeError(f"a name with two forms in two modules: {sorted(forms)}")
    return forms


def specialize(
    primitives: dict[str, Any], wrap: Callable[[Any], Any] | None = None, *, loop: bool = True
) -> types.SimpleNamespace:
    """Copies of the formulas with the primitives bound to one backend.

    ``wrap`` (e.g. ``numba.njit``) is applied to each copy; the copies call one
    another through the same namespace, so a compiled formula calls compiled ones.
    A primitive named like a function replaces it (the array backends' vertex passes
    replace the loops of :mod:`._vertex_passes`). ``loop``: per-entry scalars (Python
    or Numba floats), else whole arrays: a name of a module's ``FORMS`` is bound to its
    loop form or its array form.
    """
    namespace: dict[str, Any] = {}
    for module, _ in _MODULES:
        namespace.update(vars(module))
    namespace.update(primitives)
    names = [name for _, functions in _MODULES for name in functions]
    if len(set(names)) != len(names):  # one namespace: a repeated name would replace a formula
        raise RuntimeError(
            f"formulas defined twice: {sorted(n for n in set(names) if names.count(n) > 1)}"
        )
    for name in names:
        if name in primitives:
            continue
        func = namespace[name]
        copy = types.FunctionType(func.__code__, namespace, name, func.__defaults__)
        namespace[name] = wrap(copy) if wrap is not None else copy
    forms = _forms()
    for name, (loop_form, array_form) in forms.items():
        namespace[name] = namespace[loop_form if loop else array_form]
    exported = [*names, *forms, *_PRIMITIVES]
    return types.SimpleNamespace(**{name: namespace[name] for name in exported})


_PRIMITIVES = ("where", "sqrt", "fabs", "rint", "isfinite", "maximum", "log2", "flag")


@functools.cache
def formulas(xp: ModuleType) -> types.SimpleNamespace:
    """The formulas specialized to the array namespace ``xp`` (NumPy or ``jax.numpy``)."""
    return specialize(array_primitives(xp), loop=False)


def array_primitives(xp: ModuleType) -> dict[str, Any]:
    """The primitives on arrays of the namespace ``xp``."""
    where = xp.where if xp is not np else _numpy_where
    return {
        "where": where, "sqrt": xp.sqrt, "fabs": xp.abs, "rint": xp.round,
        "isfinite": xp.isfinite, "alloc": _zeros_list, "array_api": xp,
        "flag": functools.partial(_array_flag, xp), "take_last": _take_last,
        "maximum": xp.maximum, "log2": xp.log2, "to_single": _same,
    }  # fmt: skip


@functools.cache
def scalar_formulas() -> types.SimpleNamespace:
    """The formulas and loops on Python floats: one NumPy batch entry without array overhead."""
    return specialize(scalar_primitives())


def scalar_primitives() -> dict[str, Any]:
    """The primitives on Python floats (Numba compiles the same ones for its scalars)."""
    return {
        "where": _scalar_where,
        "sqrt": math.sqrt,
        "fabs": abs,
        "rint": _rint,
        "isfinite": math.isfinite,
        "maximum": max,
        "log2": math.log2,
        "to_single": _fit_entry.to_single,
        "alloc": _zeros_list,
        "flag": _scalar_flag,
        "take_last": _scalar_take,
        "lower": min,
        "upper": max,
        "accumulate": operator.add,
    }


def _same(x: Scalar) -> Scalar:
    return x


def _zeros_list(n: int) -> list[float]:
    """The compiled loops' float buffer on Python: a list (its floats stay Python floats)."""
    return [0.0] * n


def _scalar_flag(ok: Truth | float, bit: int) -> int:
    """A check's status bit on scalars: 0 where ``ok`` (a bool, or 1.0 and 0.0 from an
    array's check read per entry)."""
    return 0 if ok else bit


def _array_flag(xp: ModuleType, ok: Truth, bit: int) -> Scalar:
    """A check's status bit on arrays: 0 where ``ok``."""
    return xp.where(ok, 0, bit)


def _scalar_take(row: Row, k: int) -> Scalar:
    """Entry ``k`` of one entry's row."""
    return row[k]


def _take_last(
    row: Float[Array, "*batch m"], k: int | Real[Array, " n"]
) -> Float[Array, "*batch _"]:
    """Entry ``k`` of each entry's row ``(*batch, m)``: ``(*batch, 1)`` for an int ``k``,
    ``(*batch, n)`` for ``n`` indices (whole numbers of any dtype)."""
    if isinstance(k, int):
        return row[..., k, None]
    if isinstance(k, np.ndarray) and len(k):  # the driver's indices, on the host
        first = int(k[0])
        if np.array_equal(k, np.arange(first, first + len(k))):
            return row[..., first : first + len(k)]  # a slice, not a gather (JAX: nor a scatter)
    return row[..., k.astype(int)]


def _scalar_where(c: Truth, a: Scalar, b: Scalar) -> Scalar:
    return a if c else b


def _rint(x: float) -> float:
    return float(np.rint(x))  # half to even, as NumPy's round (and Numba's np.rint)


def _numpy_where(c: Truth, a: Scalar, b: Scalar) -> Scalar:
    """``np.where`` keeping the arrays' dtype: a Python float is weak, as in JAX.

    (``np.where`` turns a Python float into a float64 array, which would
    promote float32 work to float64.)
    """
    dtypes = [v.dtype for v in (a, b) if isinstance(v, np.ndarray | np.generic)]
    out: Scalar = np.where(c, a, b)
    return out.astype(np.result_type(*dtypes), copy=False) if dtypes else out
