"""The public boundary: convert arguments once, check them once, decide error vs NaN once.

Every public function of shadowmath starts with :func:`convert`, which

* picks the array namespace: ``jax.numpy`` if any argument is a JAX array (the
  others are converted), NumPy otherwise. JAX is never imported here: if ``jax``
  is not in ``sys.modules`` no argument can be a JAX array. NumPy (>= 2.1) is an
  array-API namespace itself, so no compatibility wrapper sits in the hot path;
* picks one floating result dtype: the promoted float dtype of the float
  arguments, float64 when all are integers (float16 is promoted to float32,
  since a shadow matrix in half precision is not usable, with a ``ShadowFitWarning``);
* refuses what is not real numbers with a ``ValueError`` naming the argument
  (:func:`real_array`: masked, object, string, bytes, complex and boolean arrays,
  booleans hidden in sequences); scalar options go through :func:`real` and
  :func:`integer` (a bool is not a number there either).

It then checks shapes (:func:`require_last`, :func:`require_matrix`,
:func:`batch_shape`: bad shapes raise in every mode, since shapes are static
while tracing) and values through one :class:`Checks`, and hands the trusted
arrays to private cores that check nothing. Composite functions call the cores,
never other public functions, so nothing is converted or checked twice.

Bad *values* follow SciPy's eager-or-lazy rule, decided here and nowhere else:

* ``"raise"``: NumPy or concrete JAX input: a failed check raises ``ValueError``
  with the message and the first failing batch index;
* ``"poison"``: a JAX tracer (inside ``jit``, ``vmap``, ``grad``): raising is
  impossible, so the affected batch entries of every output become NaN, and so
  do their derivatives (the outputs are *multiplied* by NaN there, never replaced
  by a constant, so a gradient through them is NaN too, not a silent zero). Each
  check is also a ``jax.experimental.checkify.debug_check`` with the same message;
* ``"record"``: inside the cached jit that serves concrete JAX input: the failed
  checks are returned as boolean masks and raised after one host sync
  (:func:`raise_recorded`).
"""

from __future__ import annotations

import math
import operator
import sys
import warnings
from collections.abc import Callable, Sequence
from types import ModuleType
from typing import Any, Literal, TypeAlias

import numpy as np

from ._messages import ShadowFitWarning

#: Any array accepted or returned by shadowmath: ``numpy.ndarray`` or ``jax.Array``
#: (nested sequences and scalars are accepted as inputs and become NumPy arrays).
Array: TypeAlias = Any

Mode: TypeAlias = Literal["raise", "poison", "record"]


def is_jax(value: object) -> bool:
    """True for a JAX array (concrete or tracer); never imports JAX."""
    jax = sys.modules.get("jax")
    return jax is not None and isinstance(value, jax.Array)


def is_tracer(value: object) -> bool:
    core = sys.modules.get("jax.core")
    return core is not None and isinstance(value, core.Tracer)


class Context:
    """The namespace, dtype and error mode shared by one call's arguments."""

    __slots__ = ("dtype", "is_jax", "lazy", "xp")

    def __init__(self, xp: ModuleType, dtype: Any, lazy: bool, is_jax: bool) -> None:
        self.xp = xp
        self.dtype = dtype
        self.lazy = lazy
        self.is_jax = is_jax

    def constant(self, value: float | Sequence[Any]) -> Array:
        """A constant in this call's namespace and dtype."""
        return self.xp.asarray(value, dtype=self.dtype)

    @property
    def eps(self) -> float:
        """Machine epsilon of the working dtype."""
        return float(np.finfo(self.dtype).eps)


#: What an array of each refused dtype kind holds, in a message.
_KINDS = {"b": "booleans", "U": "text", "S": "bytes", "O": "Python objects", "c": "complex numbers"}


def real_array(name: str, value: Any) -> Any:
    """``value`` as an array of real numbers (integers or floats; NumPy or JAX, as given).

    The one door for numbers given as arrays: strings, bytes, objects, complex numbers,
    booleans, masked and ragged input are refused with a ``ValueError`` naming ``name``.
    """
    if type(value) is np.ndarray or is_jax(value):
        arr = value
    elif isinstance(value, np.ma.MaskedArray):
        raise ValueError(f"{name}: masked arrays are not supported; pass value.filled(...)")
    else:
        try:
            arr = np.asarray(value)
        except ValueError as err:  # ragged nested sequences
            raise ValueError(f"{name}: cannot be read as an array of numbers ({err})") from None
    kind = arr.dtype.kind
    if kind in "iuf" and isinstance(value, list | tuple) and _holds_bool(value):
        kind = "b"  # NumPy reads [0, 1, True] as integers
    if kind not in "iuf":
        what = _KINDS.get(kind, "values")
        what = what if kind == "b" else f"{what} (dtype {arr.dtype})"
        raise ValueError(
            f"{name}: expected real numbers, got {what}; convert it to float64 or float32 first"
        )
    return arr


def flags(value: Any) -> Any:
    """An argument whose booleans *are* its meaning (a mask, a per-entry switch), as 0 and
    1 for :func:`convert`, which refuses booleans where numbers are meant."""
    if isinstance(value, list | tuple) and _holds_bool(value):
        value = np.asarray(value)
    if getattr(value, "dtype", None) == np.bool_:
        return value.astype(np.uint8)
    return value


def _holds_bool(value: object) -> bool:
    """True when a (nested) sequence holds a bool anywhere."""
    if isinstance(value, list | tuple):
        return any(_holds_bool(v) for v in value)
    return isinstance(value, bool | np.bool_)


def real(name: str, value: object) -> float:
    """A real number given as a Python or NumPy scalar (not a bool, a string, an array...)."""
    if isinstance(value, bool | np.bool_) or not isinstance(value, int | float | np.integer |
                                                            np.floating):  # fmt: skip
        raise ValueError(f"{name}: expected a number, got {value!r}")
    return float(value)


def integer(name: str, value: object, minimum: int | None = None) -> int:
    """An integer given as a Python or NumPy integer (not a bool, a float, a string...)."""
    try:
        if isinstance(value, bool | np.bool_):
            raise TypeError
        number = operator.index(value)  # type: ignore[arg-type]
    except TypeError:
        raise ValueError(f"{name}: expected an integer, got {value!r}") from None
    if minimum is not None and number < minimum:
        raise ValueError(f"{name}: must be >= {minimum}, got {number}")
    return number


def _result_dtype(inputs: Sequence[Any], use_jax: bool) -> tuple[ModuleType, Any]:
    if use_jax:
        import jax.numpy as jnp

        xp: ModuleType = jnp
        float_default = jnp.zeros(()).dtype  # float64 only when jax_enable_x64 is on
    else:
        xp = np
        float_default = np.dtype(np.float64)
    float_dtypes = [v.dtype for v in inputs if v.dtype.kind == "f"]
    if not float_dtypes:
        return xp, np.dtype(float_default)
    first = float_dtypes[0]
    same = all(d == first for d in float_dtypes)
    dtype = np.dtype(first) if same else np.result_type(*float_dtypes)
    if dtype == np.float16:
        dtype = np.dtype(np.float32)
    if use_jax and dtype.itemsize > np.dtype(float_default).itemsize:
        dtype = np.dtype(float_default)
    return xp, dtype


def convert(**arrays: Any) -> tuple[Context, tuple[Array, ...]]:
    """Convert the named arguments to one namespace and one float dtype.

    Returns the :class:`Context` and the converted arrays in the order given
    (``None`` values stay ``None``). The names only label error messages.
    """
    fast = _numpy_fast_path(arrays.values())
    if fast is not None:
        return fast, tuple(arrays.values())
    mixed = _numpy_with_sequences(tuple(arrays.values()))
    if mixed is not None:
        return mixed
    inputs = [real_array(name, v) for name, v in arrays.items() if v is not None]
    use_jax = any(is_jax(v) for v in inputs)
    lazy = use_jax and any(is_tracer(v) for v in inputs)
    xp, dtype = _result_dtype(inputs, use_jax)
    if dtype == np.float32 and all(v.dtype != np.float32 for v in inputs):
        _warn_half(arrays, inputs)
    ctx = Context(xp, dtype, lazy, use_jax)
    it = iter(inputs)
    out = tuple(None if v is None else _as_dtype(xp, next(it), dtype) for v in arrays.values())
    return ctx, out


def _warn_half(arrays: dict[str, Any], inputs: list[Any]) -> None:
    """Warn that float16 arguments (none float32) are computed and returned in float32."""
    names = [n for n, v in arrays.items() if v is not None]
    half = [n for n, v in zip(names, inputs, strict=True) if v.dtype == np.float16]
    if half:
        warnings.warn(
            f"{', '.join(half)}: float16 is computed and returned in float32 (a shadow "
            "matrix needs more than float16's 11 bits); pass float32 to say so",
            ShadowFitWarning,
            stacklevel=4,
        )


_NUMPY_CONTEXTS = {
    np.dtype(t): Context(np, np.dtype(t), lazy=False, is_jax=False)
    for t in (np.float32, np.float64)
}


def _numpy_fast_path(values: Any) -> Context | None:
    """The context when every array is an ndarray of one float32/float64 dtype, else None.

    The per-frame case (a renderer passing its own arrays): nothing to convert.
    """
    dtype = None
    for v in values:
        if v is None:
            continue
        if type(v) is not np.ndarray:
            return None
        if dtype is None:
            dtype = v.dtype
        elif v.dtype != dtype:
            return None
    return None if dtype is None else _NUMPY_CONTEXTS.get(dtype)


def _numpy_with_sequences(values: tuple[Any, ...]) -> tuple[Context, tuple[Array, ...]] | None:
    """Float ndarrays of one dtype beside short tuples or lists of integers (``up=(0, 1, 0)``).

    The integers take the arrays' dtype, as the general rule gives them; anything
    else (float sequences, which may promote, or what needs a check) returns None.
    """
    arrays = [v for v in values if type(v) is np.ndarray]
    if not arrays or (ctx := _numpy_fast_path(arrays)) is None:
        return None
    out = []
    for v in values:
        if type(v) in (tuple, list):
            try:
                a = np.asarray(v)
            except ValueError:
                return None
            if a.dtype.kind not in "iu" or _holds_bool(v):
                return None
            v = a.astype(ctx.dtype)
        elif v is not None and type(v) is not np.ndarray:
            return None
        out.append(v)
    return ctx, tuple(out)


def _as_dtype(xp: ModuleType, value: Any, dtype: Any) -> Array:
    # An ndarray already in the dtype is used as it is (asarray would return it too, slower).
    if type(value) is np.ndarray and value.dtype == dtype and xp is np:
        return value
    return xp.asarray(value, dtype=dtype)


def shape_error(name: str, expected: str, got: tuple[int, ...], hint: str = "") -> ValueError:
    message = f"{name}: expected shape {expected}, got {got}"
    return ValueError(f"{message}; {hint}" if hint else message)


def check_faces(name: str, faces: Any, count: int, *, concrete: bool = True) -> None:
    """A mesh's ``faces``: ``(F, 3)`` integer indices into ``count`` vertices (their range
    checked where ``concrete``; traced indices cannot raise)."""
    shape = tuple(np.shape(faces))
    if len(shape) != 2 or shape[-1] != 3:
        raise shape_error(name, "(F, 3)", shape, "three indices per triangle")
    dtype = np.dtype(faces.dtype)
    if not np.issubdtype(dtype, np.integer):
        raise TypeError(f"{name}: expected integer indices, got dtype {dtype}")
    if concrete:
        f = np.asarray(faces)
        if f.size and (f.min() < 0 or f.max() >= count):
            raise ValueError(
                f"{name}: indices must lie in [0, {count}) (the mesh has {count} "
                f"vertices); got {int(f.min())} to {int(f.max())}"
            )


def require_last(name: str, x: Array, size: int, *, min_ndim: int = 1, hint: str = "") -> None:
    """Shape check: ``x`` must be ``(*batch, size)`` (with at least ``min_ndim`` dims)."""
    if x.ndim < min_ndim or x.shape[-1] != size:
        expected = "(*batch, " + ("N, " if min_ndim == 2 else "") + f"{size})"
        raise shape_error(name, expected, tuple(x.shape), hint)


def require_vertices(name: str, x: Array) -> None:
    """Shape check for a vertex set: ``(*batch, N, 3)`` with ``N >= 1``."""
    require_last(name, x, 3, min_ndim=2, hint="vertices are (*batch, N, 3)")
    if x.shape[-2] == 0:
        need = "; a blocker needs vertices" if "blocker" in name or name == "vertices" else ""
        raise ValueError(f"{name}: the vertex set is empty (N = 0){need}")


def require_matrix(name: str, x: Array) -> None:
    if x.ndim < 2 or tuple(x.shape[-2:]) != (4, 4):
        raise shape_error(name, "(*batch, 4, 4)", tuple(x.shape))


def batch_shape(*shapes: tuple[int, ...], names: Sequence[str]) -> tuple[int, ...]:
    """NumPy broadcasting of batch shapes, with an error naming the arguments."""
    first = shapes[0]
    if all(s == first for s in shapes):  # the common case, without NumPy's machinery
        return tuple(first)
    try:
        return tuple(np.broadcast_shapes(*shapes))
    except ValueError:
        detail = ", ".join(f"{n} {s}" for n, s in zip(names, shapes, strict=True))
        raise ValueError(f"batch dimensions do not broadcast: {detail}") from None


def require_no_new_batch(name: str, shape: tuple[int, ...], base: tuple[int, ...]) -> None:
    """Receivers never add batch dimensions: ``shape`` must broadcast into ``base``, the
    batch shape of the other arguments (the fits that were asked for).

    A raw ``(M, 3, 3)`` array of triangles passed as receivers reads as ``M`` sets of
    three points, which would make ``M`` fits no other argument asked for: refused.
    """
    full = batch_shape(base, shape, names=("the other arguments", name))
    if full != tuple(base):
        raise ValueError(
            f"{name}: its batch shape {tuple(shape)} would make a batch of fits {full} that "
            f"no other argument asks for (theirs: {tuple(base)}); receivers never add batch "
            f"dimensions. {RECEIVER_KINDS}"
        )


#: How receivers are read, for the messages about their shape.
RECEIVER_KINDS = (
    "A raw array of receivers is points (*batch, M, 3); pass triangles as "
    "sm.Triangles(corners) ((*batch, M, 3, 3)) or sm.Mesh(vertices, faces)"
)


def non_finite(name: str) -> str:
    """The message for an argument holding NaN or infinite entries."""
    return f"{name}: contains non-finite values (NaN or inf); every entry must be a finite number"


def all_finite(xp: ModuleType, x: Array, trailing: int) -> Array:
    """True per batch entry when every one of the ``trailing`` dims' entries is finite."""
    ok = xp.isfinite(x)
    return xp.all(ok, axis=tuple(range(-trailing, 0))) if trailing else ok


def _raise_first(ok: Any, message: str) -> None:
    ok_np = np.asarray(ok)
    if bool(ok_np.all()):
        return
    where = ""
    if ok_np.ndim:
        first = np.argwhere(~ok_np)[0]
        where = f" (first at batch index {tuple(int(i) for i in first)})"
    raise ValueError(message + where)


class Checks:
    """The value checks of one call, in the call's error mode (see the module docstring).

    ``require(ok, message)`` takes a boolean array over (part of) the batch shape,
    True where the input is valid. :meth:`poison` marks an output invalid where
    any check failed (NaN value and NaN derivatives).
    """

    __slots__ = ("ctx", "invalid", "mode", "recorded")

    def __init__(self, ctx: Context, mode: Mode | None = None) -> None:
        self.ctx = ctx
        self.mode: Mode = mode if mode is not None else ("poison" if ctx.lazy else "raise")
        self.invalid: Array | None = None
        self.recorded: list[tuple[str, Array]] = []

    def require(self, ok: Array, message: str) -> None:
        if self.mode == "raise":
            _raise_first(ok, message)
            return
        xp = self.ctx.xp
        bad = xp.logical_not(ok)
        if self.mode == "record":
            self.recorded.append((message, bad))
            return
        # Under jax.experimental.checkify the failed check becomes an error with
        # this message; elsewhere debug_check is a no-op and the NaN stays.
        from jax.experimental import checkify

        checkify.debug_check(xp.all(ok), message)
        self.invalid = bad if self.invalid is None else xp.logical_or(self.invalid, bad)

    def poison(self, value: Array, trailing: int) -> Array:
        """``value`` (``(*batch, *trailing_dims)``) times NaN where a check failed.

        A product, not a ``where``: where the entry is invalid its derivative
        is NaN as well, so an optimizer cannot stall on a silent zero gradient.
        """
        if self.invalid is None:
            return value
        xp = self.ctx.xp
        mask = xp.reshape(self.invalid, (*self.invalid.shape, *(1,) * trailing))
        nan, one = xp.asarray(float("nan"), dtype=value.dtype), xp.asarray(1, dtype=value.dtype)
        return value * xp.where(mask, nan, one)


def raise_recorded(messages: Sequence[str], bad: Array | None) -> None:
    """Raise the first recorded failure (``bad``: ``(checks, *batch)``) after one host sync."""
    if bad is None:
        return
    bad_np = np.asarray(bad)
    for message, b in zip(messages, bad_np, strict=True):
        _raise_first(~b, message)


def flat_batch(a: Array, shape: tuple[int, ...], tail: tuple[int, ...]) -> Array:
    """NumPy ``a`` (``(*b, *tail)``, ``b`` broadcasting to ``shape``) as ``(1 or prod, *tail)``.

    For the compiled loops, which read batch entry ``i`` of an operand at
    ``i % len``: a view when ``b`` has one entry or all of them, else a copy.
    """
    size = math.prod(a.shape[: a.ndim - len(tail)])
    if size == 1:
        return a.reshape(1, *tail)
    if size == math.prod(shape):
        return a.reshape(-1, *tail)
    return np.broadcast_to(a, (*shape, *tail)).reshape(-1, *tail)


def raise_status(status: Array, messages: Sequence[tuple[int, str]]) -> None:
    """Raise the first failed check of a compiled loop's status words (bits, in check order)."""
    for bit, message in messages:
        _raise_first((status & bit) == 0, message)


def nan_unless(xp: ModuleType, ok: Array, x: Array) -> Array:
    """``x`` where ``ok``, NaN elsewhere, and NaN *derivatives* there too.

    ``where(ok, x, 1)`` would keep the value finite but give the derivative
    with respect to ``x`` as exactly zero where ``ok`` fails: an optimizer would
    stall silently at an invalid input. A product carries the NaN into the
    derivative. Only reached lazily (eagerly the failed check has raised).
    """
    nan = xp.asarray(float("nan"), dtype=x.dtype)
    return x * xp.where(ok, xp.ones_like(x), nan)


def recorded_jit(
    core: Callable[..., Any], batch_of: Callable[[Any], tuple[int, ...]]
) -> tuple[Any, list[str]]:
    """``core(ctx, checks, *arrays)`` under ``jax.jit`` for concrete JAX input.

    The checks run in ``"record"`` mode: the jitted function returns the result
    and a ``(checks, *batch)`` mask of failures (``batch_of(result)`` is the
    batch shape), and the messages, known at trace time, fill the returned list.
    Call :func:`raise_recorded` on them: one host sync, the eager error. Cache
    one per set of static options and absent (None) arguments, so that every
    trace records the same checks in the same order.
    """
    import jax
    import jax.numpy as jnp

    messages: list[str] = []

    def run(*arrays: Any) -> tuple[Any, Any]:
        ctx = Context(jnp, arrays[0].dtype, lazy=True, is_jax=True)
        checks = Checks(ctx, mode="record")
        result = core(ctx, checks, *arrays)
        shape = batch_of(result)
        messages[:] = [message for message, _ in checks.recorded]
        bad = jnp.stack([jnp.broadcast_to(b, shape) for _, b in checks.recorded])
        return result, bad

    return jax.jit(run), messages
