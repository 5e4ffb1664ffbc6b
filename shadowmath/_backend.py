"""One implementation for NumPy and JAX: namespaces, dtypes and the eager-or-lazy error rule.

Every public function starts by calling :func:`prepare`, which

* picks the array namespace: JAX if any argument is a JAX array (the others are
  converted), NumPy otherwise. JAX is never imported here: if ``jax`` is not in
  ``sys.modules`` no argument can be a JAX array;
* picks one floating result dtype: the promoted float dtype of the float
  arguments, float64 when all are integers (float16 is promoted to float32,
  since a shadow matrix in half precision is not usable);
* refuses masked, object and complex arrays with a ``ValueError``.

Bad *values* follow SciPy's eager-or-lazy rule, implemented by :class:`Checks`:
with NumPy (or concrete JAX) inputs a failed check raises ``ValueError``; when an
argument is a JAX tracer (inside ``jit``, ``vmap``, ``grad``...) raising is
impossible, so the affected batch entries of every output become NaN.
Bad *shapes* raise in both cases, since shapes are static while tracing.
"""

from __future__ import annotations

import sys
from collections.abc import Sequence
from types import ModuleType
from typing import Any, TypeAlias

import array_api_compat.numpy as np_compat
import numpy as np

#: Any array accepted or returned by shadowmath: ``numpy.ndarray`` or ``jax.Array``
#: (nested sequences and scalars are accepted as inputs and become NumPy arrays).
Array: TypeAlias = Any


def _jax_array_type() -> type | None:
    jax = sys.modules.get("jax")
    if jax is None:
        return None
    array_type: type = jax.Array
    return array_type


def _is_tracer(x: object) -> bool:
    core = sys.modules.get("jax.core")
    return core is not None and isinstance(x, core.Tracer)


class Context:
    """The namespace, dtype and laziness shared by one call's arguments."""

    __slots__ = ("dtype", "lazy", "xp")

    def __init__(self, xp: ModuleType, dtype: Any, lazy: bool) -> None:
        self.xp = xp
        self.dtype = dtype
        self.lazy = lazy

    def asarray(self, value: Any) -> Array:
        """``value`` converted to this call's namespace and float dtype."""
        return self.xp.asarray(value, dtype=self.dtype)

    def constant(self, value: float | Sequence[Any]) -> Array:
        return self.xp.asarray(value, dtype=self.dtype)


def _as_input(name: str, value: Any) -> Any:
    """Reject what has no unambiguous meaning as an array of coordinates."""
    if isinstance(value, np.ma.MaskedArray):
        raise ValueError(f"{name}: masked arrays are not supported; pass value.filled(...)")
    if isinstance(value, np.ndarray) or _is_jax(value):
        arr = value
    else:
        try:
            arr = np.asarray(value)
        except ValueError as err:  # ragged nested sequences
            raise ValueError(f"{name}: cannot be read as an array of numbers ({err})") from None
    kind = np.dtype(arr.dtype).kind
    if kind not in "biuf":
        raise ValueError(
            f"{name}: expected real numbers, got an array of dtype {arr.dtype}; "
            "convert it to float64 or float32 first"
        )
    return arr


def _is_jax(value: object) -> bool:
    jax_array = _jax_array_type()
    return jax_array is not None and isinstance(value, jax_array)


def prepare(**arrays: Any) -> tuple[Context, dict[str, Array]]:
    """Convert the named arguments to one namespace and one float dtype.

    Returns the :class:`Context` and the converted arrays under the same names.
    ``None`` values are passed through untouched.
    """
    inputs = {name: _as_input(name, v) for name, v in arrays.items() if v is not None}
    use_jax = any(_is_jax(v) for v in inputs.values())
    lazy = any(_is_tracer(v) for v in inputs.values())
    if use_jax:
        import jax.numpy as jnp

        xp: ModuleType = jnp
        float_default = jnp.zeros(()).dtype  # float64 only when jax_enable_x64 is on
    else:
        xp = np_compat
        float_default = np.dtype(np.float64)

    float_dtypes = [np.dtype(v.dtype) for v in inputs.values() if np.dtype(v.dtype).kind == "f"]
    if float_dtypes:
        dtype = np.result_type(*float_dtypes)
        if dtype == np.float16:
            dtype = np.dtype(np.float32)
        if use_jax and dtype.itemsize > np.dtype(float_default).itemsize:
            dtype = np.dtype(float_default)
    else:
        dtype = np.dtype(float_default)

    ctx = Context(xp, dtype, lazy)
    out = {name: ctx.asarray(v) for name, v in inputs.items()}
    for name, v in arrays.items():
        if v is None:
            out[name] = None
    return ctx, out


def shape_error(name: str, expected: str, got: tuple[int, ...], hint: str = "") -> ValueError:
    message = f"{name}: expected shape {expected}, got {got}"
    return ValueError(f"{message}; {hint}" if hint else message)


def require_last(name: str, x: Array, size: int, *, min_ndim: int = 1, hint: str = "") -> None:
    """Shape check: ``x`` must be ``(*batch, size)`` (with at least ``min_ndim`` dims)."""
    if x.ndim < min_ndim or x.shape[-1] != size:
        expected = "(*batch, " + ("N, " if min_ndim == 2 else "") + f"{size})"
        raise shape_error(name, expected, tuple(x.shape), hint)


def require_matrix(name: str, x: Array) -> None:
    if x.ndim < 2 or tuple(x.shape[-2:]) != (4, 4):
        raise shape_error(name, "(*batch, 4, 4)", tuple(x.shape))


def batch_shape(*shapes: tuple[int, ...], names: Sequence[str]) -> tuple[int, ...]:
    """NumPy broadcasting of batch shapes, with an error naming the arguments."""
    try:
        return tuple(np.broadcast_shapes(*shapes))
    except ValueError:
        detail = ", ".join(f"{n} {s}" for n, s in zip(names, shapes, strict=True))
        raise ValueError(f"batch dimensions do not broadcast: {detail}") from None


class Checks:
    """Collects value checks of one call: raise when eager, NaN-poison when lazy.

    ``require(ok, message)`` takes a boolean array over the batch shape that is
    True where the input is valid. Eagerly, any False raises ``ValueError`` with
    ``message`` (and the first failing batch index); lazily, the failures are
    remembered and :meth:`poison` turns the matching outputs into NaN, and
    inside ``jax.experimental.checkify.checkify`` each failed check is also
    reported as an error carrying ``message``.
    """

    def __init__(self, ctx: Context) -> None:
        self.ctx = ctx
        self.invalid: Array | None = None

    def require(self, ok: Array, message: str) -> None:
        xp = self.ctx.xp
        if not self.ctx.lazy:
            ok_np = np.asarray(ok)
            if not bool(np.all(ok_np)):
                bad = np.argwhere(~ok_np)
                where = (
                    f" (first at batch index {tuple(int(i) for i in bad[0])})" if ok_np.ndim else ""
                )
                raise ValueError(message + where)
            return
        # Under jax.experimental.checkify the failed check becomes an error with
        # this message; elsewhere debug_check is a no-op and the NaN stays.
        from jax.experimental import checkify

        checkify.debug_check(xp.all(ok), message)
        bad = xp.logical_not(ok)
        self.invalid = bad if self.invalid is None else xp.logical_or(self.invalid, bad)

    def poison(self, value: Array, trailing: int) -> Array:
        """``value`` (shape ``(*batch, *trailing_dims)``) with NaN where a check failed."""
        if self.invalid is None:
            return value
        xp = self.ctx.xp
        mask = xp.reshape(self.invalid, tuple(self.invalid.shape) + (1,) * trailing)
        return xp.where(mask, xp.asarray(float("nan"), dtype=value.dtype), value)


def non_finite(name: str) -> str:
    """The message for an argument holding NaN or infinite entries."""
    return f"{name}: contains non-finite values (NaN or inf); every entry must be a finite number"


def all_finite(xp: ModuleType, x: Array, trailing: int) -> Array:
    """True per batch entry when every one of the ``trailing`` dims' entries is finite."""
    ok = xp.isfinite(x)
    for _ in range(trailing):
        ok = xp.all(ok, axis=-1)
    return ok


def eps(ctx: Context) -> float:
    return float(np.finfo(ctx.dtype).eps)
