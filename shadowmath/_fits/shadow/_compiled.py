""":func:`fit_shadow` through the compiled loop (NumPy input, Numba installed).

Packs the trusted arrays as the loop (:func:`shadowmath._math._loops.fit_loop`) reads
them (batch entry ``i`` of an operand at ``i % len``), runs it, raises the first failed
check in the order of :mod:`shadowmath._boundary._status`
(:func:`shadowmath._fits._backend.raise_fit_status`), and returns views of the loop's two
output blocks.
"""

from __future__ import annotations

import functools
import math
import typing
from types import SimpleNamespace
from typing import Any, NamedTuple

import numpy as np

from shadowmath._backends import _kernels
from shadowmath._boundary._validate import Array, Context, flat_batch
from shadowmath._fits._backend import raise_fit_status
from shadowmath._fits._spec import FitKey, fit_options
from shadowmath._math._fit_entry import FitOptions
from shadowmath._math._frame import LightFrame
from shadowmath._math._frustum import volume
from shadowmath._math._loops import FIT_MATRIX, FIT_ROW, FIT_ROW_AT
from shadowmath._math._specialize import scalar_formulas

from ._arrays import Inputs
from ._result import ShadowSetup

_FIELDS = tuple(typing.get_type_hints(FitOptions).items())

#: One output row: origin, X, Y, Z (3 each), then the eight numeric frustum fields (parts at
#: ``FIT_ROW_AT``); one matrix block (4, 4, 4): world_to_light, blocker_to_clip,
#: world_to_texture, placement (at ``FIT_MATRIX``).
ROW = FIT_ROW

_IDENTITY = np.eye(4).reshape(1, 4, 4)
_NONE = np.zeros(1)
_NO_POINTS = np.zeros((1, 1, 3))
_NO_VECTOR = np.zeros((1, 3))


#: The most vertices plus receiver points of one fit that the Python loop runs
#: (without Numba; beyond it the array path is faster).
PYTHON_LOOP_POINTS = 128


class Buffers(NamedTuple):
    """The compiled loop's output blocks for ``count`` batch entries (caller-owned for
    :class:`shadowmath.ShadowFitter`): rows of :data:`ROW` numbers (frame and frustum
    fields), four matrices per entry (world_to_light, blocker_to_clip, world_to_texture,
    placement) and the status words."""

    rows: Array  # (count, ROW)
    mats: Array  # (count, 4, 4, 4)
    status: Array  # (count,) int32


def buffers(count: int, dtype: Any) -> Buffers:
    """Empty :class:`Buffers` for ``count`` entries of ``dtype``."""
    return Buffers(
        np.empty((count, ROW), dtype), np.empty((count, 4, 4, 4), dtype), np.empty(count, np.int32)
    )


def fit(
    ctx: Context, key: FitKey, shape: tuple[int, ...], a: Inputs, *, used: Array,
    python: bool = False,
) -> ShadowSetup:  # fmt: skip
    """The fit of ``key`` for every batch entry, from the compiled loop (or, ``python``,
    the same loop run by Python on lists: one small fit without Numba), with
    ``casters_used``."""
    out = buffers(math.prod(shape), ctx.dtype)
    run(ctx, key, shape, a, out, python=python)
    return views(key, shape, out, used)


def run(
    ctx: Context, key: FitKey, shape: tuple[int, ...], a: Inputs, out: Buffers, *,
    python: bool = False, record: Array | None = None,
) -> None:  # fmt: skip
    """Fill ``out`` with every entry's fit; raise the first failed check (warn if wide).

    ``record``: :func:`options`' record of ``key`` and the dtype, if known.
    """
    status = out.status
    arrays = operands(shape, a)
    if python:
        lists = tuple(v.tolist() for v in arrays)
        python_record = options(key, ctx.dtype)[1]
        scalar_formulas().fit_loop(lists, [python_record], out)
    else:
        record = options(key, ctx.dtype)[0] if record is None else record
        # (a plain tuple: Numba dispatches it about 0.6 us faster than the NamedTuple)
        _kernels.loops().fit_loop(arrays, record, (out.rows, out.mats, status))
    raise_fit_status(status, shape, a.verts)


def operands(shape: tuple[int, ...], a: Inputs) -> tuple[Array, ...]:
    """The loop's array operands, ``(count or 1, ...)`` each (the vertices ``(count or 1,
    3 N)``)."""
    if not shape:  # one entry: no batch axes to flatten
        light, verts = a.light[None], a.verts[None]
    else:
        light = flat_batch(a.light, shape, a.light.shape[-1:])
        verts = flat_batch(a.verts, shape, a.verts.shape[-2:])
    # Each entry's vertices as one flat row x0, y0, z0, x1, ... (a view of a C-contiguous
    # array): the loops read them at a stride the compiler knows (_math/_vertex_passes.py).
    verts = verts.reshape(len(verts), verts.shape[-2] * verts.shape[-1])  # (-1: not for 0 entries)
    return (
        light,
        verts,
        _IDENTITY if a.B is None else flat_batch(a.B, shape, (4, 4)),
        _NO_POINTS if a.R is None else flat_batch(a.R, shape, a.R.shape[-2:]),
        _NO_VECTOR if a.U is None else flat_batch(a.U, shape, (3,)),
        _NONE if a.near is None else flat_batch(a.near, shape, ()),
        _NONE if a.far is None else flat_batch(a.far, shape, ()),
    )


def views(key: FitKey, shape: tuple[int, ...], out: Buffers, used: Array) -> ShadowSetup:
    """The setup as views of the output blocks, with ``casters_used`` (first-axis
    indexing: the cheapest views; one entry's frustum fields are NumPy scalars)."""
    rows, mats = out.rows, out.mats
    starts = (FIT_ROW_AT.origin, *(FIT_ROW_AT.axes + 3 * k for k in range(3)))
    f = FIT_ROW_AT.frustum
    if shape:
        v = np.moveaxis(rows.reshape(*shape, ROW), -1, 0)
        M = np.moveaxis(mats.reshape(*shape, 4, 4, 4), -3, 0)
        frame = LightFrame(*(np.moveaxis(v[i : i + 3], 0, -1) for i in starts))
        fields: Any = v[f : f + 8]
    else:
        v, M = rows[0], mats[0]
        frame = LightFrame._make(v[i : i + 3] for i in starts)
        fields = v[f : f + 8]
    frustum = volume(fields, key.directional)
    m = FIT_MATRIX
    return ShadowSetup._make((frame, frustum, M[m.world_to_light], M[m.placement],
                              M[m.blocker_to_clip], M[m.world_to_texture], used,
                              key.texels))  # fmt: skip


#: The compiled loop's options record: :class:`FitOptions`' fields by name, then the
#: API's rows (``C`` and ``T C`` of :func:`api_convention`, 16 row-major floats each).
OPTIONS = np.dtype(
    [(name, np.bool_ if kind is bool else np.float64) for name, kind in _FIELDS]
    + [("api_clip", np.float64, (16,)), ("api_texture", np.float64, (16,))]
)


@functools.lru_cache(maxsize=64)
def options(key: FitKey, dtype: Any) -> tuple[Array, Any]:
    """The loop's options: a read-only one-row :data:`OPTIONS` array (for Numba: one
    array is the cheapest operand to dispatch) and the same as a Python record."""
    single = np.dtype(dtype) == np.float32
    values = (*fit_options(key, float(np.finfo(dtype).eps), single), *key.api)
    opts = np.array([values], dtype=OPTIONS)
    opts.flags.writeable = False
    return opts, SimpleNamespace(**dict(zip(OPTIONS.fields or (), values, strict=True)))
