"""Which form of a fit's driver runs, and what a loop's status words say: once for every fit.

Each fit's driver has a loop form (compiled by Numba, or the same loop on Python floats)
and an array form (NumPy or JAX, whole arrays at once). :func:`form` makes the choice
every fit makes (``fit_shadow``, the atlas's 2D lights, ``fit_cascades``, the PCSS maps):

* ``"compiled"``: NumPy input with the compiled loops available (the ``fast`` extra,
  not disabled by ``SHADOWMATH_NUMBA=0``);
* ``"python"``: small NumPy input without them, the same loop on Python floats (where
  the caller has such a loop, and not inside :func:`shadowmath._backends._kernels.array_path`);
* ``"arrays"``: anything else (JAX input, large NumPy batches without Numba).

:func:`raise_fit_status` and :func:`first_failure` read ``fit_shadow``'s loop status words (bits of
:data:`shadowmath._boundary._status.FIT_CHECKS`) into the failed checks and their
messages in report order, for the callers that raise (``fit_shadow``, ``ShadowFitter``)
and the one that reports per light (``fit_atlas``).
"""

from __future__ import annotations

from typing import Literal

import numpy as np

from shadowmath._backends import _kernels
from shadowmath._boundary import _messages as msg
from shadowmath._boundary._status import WIDE_WARNING, fit_messages
from shadowmath._boundary._validate import Array, raise_status

Form = Literal["compiled", "python", "arrays"]


def form(numpy: bool, *, small: bool = False) -> Form:
    """The driver's form for NumPy input (``numpy``) or not, ``small`` enough for the
    loop on Python floats.

    >>> form(False)
    'arrays'
    """
    if not numpy:
        return "arrays"
    if _kernels.available():
        return "compiled"
    if small and _kernels.python_loop():
        return "python"
    return "arrays"


Messages = tuple[tuple[int, str], ...]


def failures(status: Array) -> Array:
    """The failed checks of ``fit_shadow``'s loop status words: the wide warning (not a
    failure) cleared."""
    return status & ~WIDE_WARNING


def failure_messages(verts: Array | None) -> Messages:
    """The checks' ``(bit, message)`` in report order: a non-finite sum of finite vertices
    ``verts`` is reported as an overflow (``None``: the vertices' check is exact)."""
    return fit_messages(verts is not None and bool(np.isfinite(verts).all()))


def first_failure(word: int, messages: Messages) -> str:
    """The message of the first failed check of one entry's status word."""
    return next(m for bit, m in messages if word & bit)


def raise_fit_status(status: Array, shape: tuple[int, ...], verts: Array | None) -> None:
    """Raise the first failed check of the status words ``(count,)`` (batch ``shape``),
    else warn when a map is wide (see :func:`failure_messages` for ``verts``)."""
    one = len(status) == 1
    if status[0] if one else status.any():
        errors = failures(status)
        if errors[0] if one else errors.any():
            raise_status(errors.reshape(shape), failure_messages(verts))
        msg.warn_wide()
