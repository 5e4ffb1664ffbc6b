"""The vertex passes' reduction steps for Numba (imported by :func:`._kernels.loops` only).

``lower``, ``upper`` and ``accumulate`` of :mod:`shadowmath._math._vertex_passes`
(Python's ``min``, ``max`` and ``+`` on Python floats) as LLVM's ``minimum`` and
``maximum`` (IEEE 754-2019: a NaN propagates; the sign of a zero result is left
free, ``nsz``) and an addition that may be reassociated (``reassoc``: a sum in any
order). A loop's running minimum written as a comparison and a select, or its sum
as a strict addition, is a chain the compiler must run one vertex after the other;
these it keeps in vector lanes and combines at the end, so a pass over the vertices
runs at vector speed. Module-level intrinsics: the loops that inline them are cached
on disk.
"""

from __future__ import annotations

from typing import Any

from llvmlite import ir
from numba import types
from numba.core import cgutils
from numba.extending import intrinsic

_DOUBLE = ir.DoubleType()
_SIGNATURE = types.float64(types.float64, types.float64)


def _call(name: str, builder: Any, args: Any) -> Any:
    kind = ir.FunctionType(_DOUBLE, [_DOUBLE, _DOUBLE])
    fn = cgutils.get_or_insert_function(builder.module, kind, f"llvm.{name}.f64")  # type: ignore[no-untyped-call]
    return builder.call(fn, args, fastmath=("nsz",))


@intrinsic
def lower(typingctx: Any, a: Any, b: Any) -> Any:
    """``minimum(a, b)``: NaN if either is NaN."""

    def codegen(context: Any, builder: Any, sig: Any, args: Any) -> Any:
        return _call("minimum", builder, args)

    return _SIGNATURE, codegen


@intrinsic
def upper(typingctx: Any, a: Any, b: Any) -> Any:
    """``maximum(a, b)``: NaN if either is NaN."""

    def codegen(context: Any, builder: Any, sig: Any, args: Any) -> Any:
        return _call("maximum", builder, args)

    return _SIGNATURE, codegen


@intrinsic
def accumulate(typingctx: Any, a: Any, b: Any) -> Any:
    """``a + b``, which the compiler may reassociate with the other terms of a sum."""

    def codegen(context: Any, builder: Any, sig: Any, args: Any) -> Any:
        return builder.fadd(args[0], args[1], flags=("reassoc", "nsz"))

    return _SIGNATURE, codegen


def primitives() -> dict[str, Any]:
    """The steps by the names the vertex passes call."""
    return {"lower": lower, "upper": upper, "accumulate": accumulate}
