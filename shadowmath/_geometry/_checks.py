"""The public checks: a camera projection read at the door, and shadowmath's NaN-marked
invalid outputs turned back into errors.

With NumPy (or concrete JAX) inputs every function raises ``ValueError`` on bad
values. Inside JAX transformations (``jit``, ``vmap``, ``grad``) raising on a
value is impossible, so the affected outputs are NaN instead. Two ways to get
an error back:

* **checkify, with the specific message.** Every value check of shadowmath
  is also a ``jax.experimental.checkify.debug_check``: wrap the transformed
  function in ``checkify.checkify`` and the returned error carries the same
  message NumPy input would have raised::

      from jax.experimental import checkify

      fitted = checkify.checkify(jax.jit(lambda L, V: fit_shadow(L, V, 256)))
      err, setup = fitted(light, vertices)
      err.throw()  # JaxRuntimeError: vertices: a blocker vertex is not strictly ...

  Without ``checkify.checkify`` those checks cost nothing and the NaNs stay.

* **check_finite on the outputs**, for any result: eagerly it raises
  ``ValueError``; under a transformation it calls ``checkify.check``, so it
  must run inside ``checkify.checkify`` (JAX refuses to trace it otherwise,
  rather than skipping it silently).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from shadowmath._boundary import _projection
from shadowmath._boundary._shapes import ArrayLike, Float, Real
from shadowmath._boundary._validate import Array, Checks, convert, is_jax, is_tracer


def _leaves(value: Any, name: str) -> list[tuple[str, Any]]:
    """``(name, array)`` pairs of an array, a NamedTuple or a tuple of them."""
    if isinstance(value, tuple):
        fields = getattr(value, "_fields", None) or [str(i) for i in range(len(value))]
        out: list[tuple[str, Any]] = []
        for field, item in zip(fields, value, strict=True):
            out += _leaves(item, f"{name}.{field}")
        return out
    return [(name, value)]


def check_finite(value: Any, *, name: str = "value") -> Any:
    """Raise where shadowmath marked an output invalid (NaN), else return it unchanged.

    Arguments:
        value: an array, or a NamedTuple of arrays such as :class:`LightFrame`,
            :class:`Frustum` or :class:`ShadowSetup`.
        name: how the error message refers to ``value``.

    Returns:
        ``value`` itself.

    Raises:
        ValueError: with NumPy or concrete JAX arrays, when any entry is NaN or
            infinite; the message names the field and the first bad index.
            Under JAX transformations the check goes through
            ``jax.experimental.checkify.check`` instead: run the function inside
            ``checkify.checkify`` and call ``err.throw()``.

    Example:
        >>> import numpy as np
        >>> M = check_finite(planar_projection([0, 1, 0, 0], [0, 10, 0, 1]), name="M")
        >>> bad = np.stack([M, np.full((4, 4), np.nan)])
        >>> check_finite(bad, name="M")
        Traceback (most recent call last):
        ...
        ValueError: M: NaN or infinite entries (first at index (1, 0, 0)): ...
    """
    for label, leaf in _leaves(value, name):
        if is_tracer(leaf):
            import jax.numpy as jnp
            from jax.experimental import checkify

            checkify.check(
                jnp.all(jnp.isfinite(leaf)),
                f"{label}: NaN or infinite entries (invalid input; see the function's errors)",
            )
            continue
        arr = np.asarray(leaf) if is_jax(leaf) or not isinstance(leaf, np.ndarray) else leaf
        if arr.dtype.kind not in "biuf":
            raise ValueError(f"{label}: expected an array of real numbers, got dtype {arr.dtype}")
        finite = np.isfinite(arr)
        if not bool(np.all(finite)):
            first = tuple(int(i) for i in np.argwhere(~finite)[0]) if arr.ndim else ()
            raise ValueError(
                f"{label}: NaN or infinite entries (first at index {first}): shadowmath marks "
                "invalid input "
                "with NaN under JAX transformations; call the function on concrete values "
                "(or inside jax.experimental.checkify.checkify) to get the specific error"
            )
    return value


def check_projection(projection: Real[ArrayLike, "*batch 4 4"]) -> Float[Array, "*batch 4 4"]:
    """A camera's projection, refused unless it is one; the check :func:`fit_cascades` makes.

    A projection maps view to clip coordinates with ``w`` the view depth
    (perspective: last row ``(0, 0, -1, 0)``, or ``(0, 0, 1, 0)`` for a camera
    looking down ``+z``) or ``1`` (orthographic: ``(0, 0, 0, 1)``); every graphics
    API writes that row so, whatever its depth range or reversed Z. The row is
    checked exactly, to rounding, not up to scale: the transpose of a perspective
    projection (a row-major matrix read as column-major) is refused, as is a scaled one.

    Arguments:
        projection: ``(*batch, 4, 4)`` column-vector projection (``clip = P @ view``).

    Returns:
        ``projection`` converted (NumPy or JAX, float32 or float64), unchanged in value.

    Raises:
        ValueError: a wrong shape; non-finite entries; a last row that is neither a
            perspective nor an orthographic projection's. Under JAX transformations
            the returned matrices are NaN instead.

    Example:
        >>> import numpy as np
        >>> P = np.array([[1.0, 0, 0, 0], [0, 1, 0, 0], [0, 0, -1, -0.2], [0, 0, -1, 0]])
        >>> check_projection(P)[3]
        array([ 0.,  0., -1.,  0.])
        >>> check_projection(P.T)
        Traceback (most recent call last):
        ...
        ValueError: projection: its last row is neither a perspective projection's ...
    """
    ctx, (P,) = convert(projection=projection)
    checks = Checks(ctx)
    _projection.check_projection(checks, P)
    return checks.poison(P, 2)
