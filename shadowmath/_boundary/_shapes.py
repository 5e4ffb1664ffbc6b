"""Shapes in signatures: jaxtyping annotations of the public API, checked in the test suite.

A public function writes its arrays' shapes and dtypes in its signature::

    def fit_shadow(light: Real[ArrayLike, "*#batch 4"], ...) -> ShadowSetup: ...

with ``Float`` (results: float32 or float64), ``Real`` (inputs: integers or floats),
``Int`` (signed), ``Integer`` (signed or not) and ``Bool`` from jaxtyping, and two array
types:

* :data:`ArrayLike` for inputs: NumPy or JAX arrays, tracers, and nested lists or
  scalars;
* :data:`Array` for results: NumPy in gives NumPy out, JAX in gives JAX out.

and three option types: :data:`IntLike`, a count or a size that the door takes as an
integer, :data:`BoolLike`, a switch the door takes as a boolean, and :data:`MapSize`, a
map's texels (``size`` or ``(width, height)``). For mypy they are ``int``, ``bool`` and
``int | tuple[int, int]``; at run time they accept what the doors accept: NumPy's integers
and booleans too (``map_size=np.int64(64)``, ``reversed_z=np.True_``), and a map size as a
list or a NumPy array of two.

For mypy both are ``Any`` (``Float[Array, "4 4"]`` is ``Annotated[Any, ...]``): mypy checks
the rest of each signature (options, light and mesh types, results' NamedTuples) and that
the annotations are well formed; the shapes and dtypes are checked at run time, in the
tests. (``numpy.typing.ArrayLike`` for inputs would make mypy refuse the cores' use of
the arguments they receive, which are typed ``Any`` today.)

**The cores' per-entry values.** A per-entry formula (``_math/_formulas.py`` and the
other modules that :func:`shadowmath._math._specialize.specialize` binds) runs on one
batch entry (Python or Numba floats) and on whole arrays (NumPy, JAX) alike, so its
parameters are typed by what they are in both:

* :data:`Scalar`: one real component, a number per entry or an array of the batch's
  shape (components broadcast: a cascade's ``(*batch, C)`` beside a camera's
  ``(*batch, 1)``, so the shape is not held to one memo);
* :data:`Truth`: one boolean component, ``bool`` per entry or a boolean array;
* :data:`Row`: a flat row of components, a sequence of numbers per entry (a tuple, a list,
  or a 1-D NumPy buffer in the compiled loops) or a tuple of arrays of the batch's shape
  (or, for eight corners' values, ``_math._cascade_bounds.CornerRow``: one array per value
  with the corners on a last axis, read per entry as a row).
* :data:`Status`: a fit's status word, an ``int`` of bits per entry, an integer array, or
  on whole arrays a record of each check by its bit (``_fits/shadow/_arrays.Flags``);
* :data:`Options`: a fit's static options read by name, a ``NamedTuple`` on arrays, a
  NumPy record in the compiled loop, a ``SimpleNamespace`` in its Python run;
* :data:`Vertices`: the casters as a fit's vertex passes read them, per entry
  ``(flat row, placement's 16 entries, placed)``, on arrays ``(components, status)``.

For mypy they are ``Any``, as :data:`Array` is; at run time (the suite's checked cores)
each is a marker whose ``isinstance`` accepts exactly those values.

``*#batch`` marks leading batch dimensions that broadcast against the other arguments'; a
named size (``N``) is one size in every argument and result of a call, ``_`` any size (the
fields of a type that one call may hold twice, such as :class:`Mesh`).

**Cost outside the tests: none.** Every module that annotates uses ``from __future__
import annotations``, so an annotation is a string that nothing evaluates; the names
here are stand-ins that import jaxtyping only when an annotation is evaluated
(``typing.get_type_hints``), and ``import shadowmath`` never imports it (jaxtyping's own
import costs about 60 ms). :func:`shapes_checked` returns the function itself.

**In the test suite** (``SHADOWMATH_CHECK_SHAPES=1``, set by the root ``conftest.py``
before it imports shadowmath), :func:`shapes_checked` wraps each public function:
the call runs first (the door converts and checks its arguments and raises its own
messages, which the suite's tests of bad input assert), then jaxtyping with beartype
checks, in one shape memo, every argument the door accepted against its annotation
(lists converted as the door converts them), the result, and a NamedTuple result's
annotated fields. A mismatch raises :class:`jaxtyping.TypeCheckError`: either the door
accepted what the signature says it refuses, or a core returned a wrong shape or dtype.
"""

from __future__ import annotations

import functools
import os
from collections.abc import Callable
from typing import TYPE_CHECKING, Any, TypeAlias, TypeVar

__all__ = [
    "Array",
    "ArrayLike",
    "Bool",
    "BoolLike",
    "Float",
    "Int",
    "IntLike",
    "Integer",
    "MapSize",
    "Options",
    "Real",
    "Row",
    "Scalar",
    "Status",
    "Truth",
    "Vertices",
    "shapes_checked",
]

F = TypeVar("F", bound=Callable[..., Any])

if TYPE_CHECKING:
    from jaxtyping import Bool, Float, Int, Integer, Real

    ArrayLike: TypeAlias = Any
    Array: TypeAlias = Any
    IntLike: TypeAlias = int
    BoolLike: TypeAlias = bool
    MapSize: TypeAlias = int | tuple[int, int]
    Scalar: TypeAlias = Any
    Truth: TypeAlias = Any
    Row: TypeAlias = Any
    Status: TypeAlias = Any
    Options: TypeAlias = Any
    Vertices: TypeAlias = Any
else:
    from numbers import Integral as IntLike

    import numpy as _np

    BoolLike = bool | _np.bool_

    class _MapSizeType(type):
        def __instancecheck__(cls, value: object) -> bool:
            if hasattr(value, "shape") and hasattr(value, "dtype"):  # a NumPy array of two
                return tuple(value.shape) in ((), (2,)) and value.dtype.kind in "iu"
            if isinstance(value, tuple | list):
                return len(value) == 2 and all(isinstance(v, IntLike) for v in value)
            return isinstance(value, IntLike)

    class MapSize(metaclass=_MapSizeType):
        """Run-time marker of a map size: an integer or two (see the module's docstring)."""

    def _kind(value: object) -> str:
        """The dtype kind of a number or an array (``b``, ``i``, ``u``, ``f``...), else ``""``."""
        if isinstance(value, bool | _np.bool_):
            return "b"
        if isinstance(value, int | float):
            return "f" if isinstance(value, float) else "i"
        dtype = getattr(value, "dtype", None)
        if dtype is None or not hasattr(value, "shape"):
            return ""
        return str(_np.dtype(dtype).kind)

    class _ComponentType(type):
        kinds = ""

        def __instancecheck__(cls, value: object) -> bool:
            kind = _kind(value)
            return bool(kind) and kind in cls.kinds

    class Scalar(metaclass=_ComponentType):
        """Run-time marker of a real component: a number or a real array."""

        kinds = "iuf"

    class Truth(metaclass=_ComponentType):
        """Run-time marker of a boolean component: a ``bool`` or a boolean array."""

        kinds = "b"

    class _RowType(type):
        def __instancecheck__(cls, value: object) -> bool:
            if isinstance(value, tuple | list):
                return all(isinstance(v, Scalar | Truth) for v in value)
            if hasattr(value, "columns"):  # the array form's corner row: arrays per column
                return all(isinstance(v, Scalar) for v in value.columns)
            return getattr(value, "ndim", None) == 1 and isinstance(value, Scalar)

    class Row(metaclass=_RowType):
        """Run-time marker of a flat row of components (see the module's docstring)."""

    class _StatusType(type):
        def __instancecheck__(cls, value: object) -> bool:
            return _kind(value) in ("i", "u") or hasattr(value, "checks")

    class Status(metaclass=_StatusType):
        """Run-time marker of a status word (see the module's docstring)."""

    class _OptionsType(type):
        def __instancecheck__(cls, value: object) -> bool:
            import types

            named = isinstance(value, tuple) and hasattr(value, "_fields")
            record = isinstance(value, _np.void) and value.dtype.names is not None
            return named or record or isinstance(value, types.SimpleNamespace)

    class Options(metaclass=_OptionsType):
        """Run-time marker of options read by name (see the module's docstring)."""

    class _VerticesType(type):
        def __instancecheck__(cls, value: object) -> bool:
            if not isinstance(value, tuple):
                return False
            if len(value) == 3:  # per entry: (row, placement, placed)
                row, placement, placed = value
                return isinstance(row, Row) and isinstance(placement, Row) and placed in (0, 1)
            return len(value) == 2 and isinstance(value[0], Row) and isinstance(value[1], Status)

    class Vertices(metaclass=_VerticesType):
        """Run-time marker of a vertex source (see the module's docstring)."""

    class ArrayLike:
        """Run-time marker of an input array type (see the module's docstring)."""

    class Array:
        """Run-time marker of a result array type (see the module's docstring)."""

    class _Dtype:
        """A stand-in for jaxtyping's ``Float`` and the others: jaxtyping on first use."""

        def __init__(self, name: str) -> None:
            self.name = name

        def __getitem__(self, item: tuple[Any, str]) -> Any:
            array_type, dims = item
            return _hint(self.name, array_type, dims)

    Bool, Float, Int, Integer, Real = map(_Dtype, ("Bool", "Float", "Int", "Integer", "Real"))


@functools.cache
def _hint(dtype: str, array_type: Any, dims: str) -> Any:
    """The jaxtyping hint of ``dtype[array_type, dims]``; an input also takes lists."""
    import jaxtyping

    if array_type not in (Array, ArrayLike):
        return getattr(jaxtyping, dtype)[array_type, dims]
    # Any: NumPy and JAX arrays and tracers alike (what has a shape and a dtype).
    checked = getattr(jaxtyping, dtype)[Any, dims]
    if array_type is Array:
        return checked
    from typing import Annotated

    from beartype.vale import Is

    return Annotated[object, Is[functools.partial(_array_like_is, checked)]]


def _array_like_is(checked: Any, value: Any) -> bool:
    """``value`` (an array, or lists and scalars as the door converts them) is ``checked``."""
    import numpy as np

    if not (hasattr(value, "shape") and hasattr(value, "dtype")):
        try:
            value = np.asarray(value)
        except (TypeError, ValueError):
            return False
    return isinstance(value, checked)


def shapes_checked(fn: F) -> F:
    """``fn`` itself; in the test suite, ``fn`` with its annotations checked after each call."""
    if os.environ.get("SHADOWMATH_CHECK_SHAPES") != "1":
        return fn
    return _checking(fn)  # type: ignore[return-value]


def _checking(fn: Callable[..., Any]) -> Callable[..., Any]:
    import inspect

    signature = inspect.signature(fn)
    hints: dict[str, Any] = {}

    @functools.wraps(fn)
    def checked(*args: Any, **kwargs: Any) -> Any:
        out = fn(*args, **kwargs)  # the door first, with its own messages
        if not hints:
            import typing

            hints.update(typing.get_type_hints(fn, include_extras=True))
        try:
            bound = signature.bind(*args, **kwargs)
        except TypeError:  # a renamed keyword (_renamed.py): the result is still checked
            _check(fn.__qualname__, hints, {}, out)
            return out
        bound.apply_defaults()
        _check(fn.__qualname__, hints, bound.arguments, out)
        return out

    return checked


@functools.cache
def _field_hints(cls: type) -> dict[str, Any]:
    import typing

    return typing.get_type_hints(cls, include_extras=True)


def _check(name: str, hints: dict[str, Any], arguments: dict[str, Any], out: Any) -> None:
    from beartype import BeartypeConf
    from beartype.door import die_if_unbearable
    from jaxtyping import TypeCheckError
    from jaxtyping._storage import pop_shape_memo, push_shape_memo

    values = [(f"argument {k}", v, hints[k]) for k, v in arguments.items() if k in hints]
    values.append(("result", out, hints.get("return", Any)))
    # A NamedTuple's fields too; of two of one type (last frame's atlas beside this one's)
    # only the result's, since their sizes differ.
    named = [type(v) for _, v, _ in values if isinstance(v, tuple) and hasattr(v, "_fields")]
    for what, value, _ in list(values):
        if type(value) in named and (what == "result" or named.count(type(value)) == 1):
            fields = _field_hints(value.__class__)
            values += [(f"{what}.{f}", getattr(value, f), fields[f]) for f in value._fields]
    # One memo, as jaxtyping's own decorator pushes it: a name such as N is one size in every
    # value, and a size may name an argument ("{count}+1").
    push_shape_memo(arguments)
    try:
        for what, value, hint in values:
            try:
                die_if_unbearable(value, hint, conf=BeartypeConf(is_pep484_tower=True))
            except Exception as err:
                raise TypeCheckError(f"{name}: {what} does not match {hint}: {err}") from err
    finally:
        pop_shape_memo()
