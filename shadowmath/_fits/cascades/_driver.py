"""``fit_cascades``' driver: the steps of the cascades in their two forms.

The door (:mod:`._door`) converts and checks the arguments once; the driver runs the steps of
:mod:`shadowmath._math._cascade_steps` (written once) in one of two modes:

* the loop mode, NumPy input: :func:`~shadowmath._math._cascade_steps.cascade_loop` over
  cameras and cascades, compiled by Numba (the ``fast`` extra), or run by Python on lists
  for one to :data:`PYTHON_LOOP_CAMERAS` cameras without Numba;
* the array mode, JAX input (and NumPy batches without Numba): the same steps once on
  whole arrays (the cascades on the last axis); values and gradients follow the same
  expressions. ``orientation="fitted"`` and ``warp="lispsm"`` have both forms
  (:mod:`._orientation` and :mod:`._lispsm` here,
  :func:`~shadowmath._math._cascade_steps.fitted_fit` and
  :func:`~shadowmath._math._cascade_steps.warp_fit` in the loop); without Numba the warp
  takes this mode (its Python loop is slower).

Both return a status word of :data:`shadowmath._boundary._status.CASCADE_CHECKS`; the
driver raises the first failing check's message (NumPy) or makes the entry NaN (JAX).
"""

from __future__ import annotations

import math
from typing import Any, NamedTuple, TypeAlias

import numpy as np

from shadowmath._backends import _kernels
from shadowmath._boundary._shapes import Float, Scalar
from shadowmath._boundary._status import cascade_messages
from shadowmath._boundary._validate import Array, Checks, Context, flat_batch, raise_status
from shadowmath._fits._spec import ShadowMapSpec
from shadowmath._math._cascade_steps import (
    ROW,
    ROW_AT,
    CascadeEntry,
    CascadeInputs,
    CascadeOptions,
    CascadeScalars,
    CascadeSlice,
    row_part,
)
from shadowmath._math._frustum import OrthographicBox
from shadowmath._math._rows import MatrixEntries
from shadowmath._math._specialize import formulas, scalar_formulas
from shadowmath._math._vector import matmul

from ._lispsm import warp_cascades
from ._orientation import fitted_cascade
from ._result import Cascades, CascadeState, _texture, _tiles

#: The door's arrays: light, view, projection, scene bounds, up, splits, max distance, lam,
#: overlap, the measured and previous ranges' ends (or None), the previous half-widths.
CascadeArrays: TypeAlias = """tuple[
    Float[Array, "*#batch 3"],
    Float[Array, "*#batch 4 4"],
    Float[Array, "*#batch 4 4"],
    Float[Array, "*#batch 2 3"],
    Float[Array, "*#batch 3"] | None,
    Float[Array, "*#batch m"] | None,
    Scalar | None,
    Scalar,
    Scalar,
    tuple[Scalar, Scalar, Scalar, Scalar] | None,
    Float[Array, "*#batch n"] | None,
]"""


class _Call(NamedTuple):
    """One call's context: backend, map, layout, batch shape and options record."""

    ctx: Context
    spec: ShadowMapSpec
    layout: str
    shape: tuple[int, ...]
    o: CascadeOptions


def _compiled(
    call: _Call, arrays: CascadeArrays, record: np.ndarray[Any, np.dtype[Any]] | None
) -> Cascades:
    """The loop mode: :func:`shadowmath._math._cascade_steps.cascade_loop` compiled by
    Numba (``fast`` extra, ``record`` its options), or, ``record`` None, run by Python on
    lists (a few cameras without Numba)."""
    ctx, shape, o = call.ctx, call.shape, call.o
    L, V, P, box, U, S, dmax, lm, ov, extra, W = arrays
    n, total = o.cascades, math.prod(shape)
    values = (
        lm,
        np.nan if dmax is None else dmax,
        ov,
        *((np.nan,) * 4 if extra is None else extra),
    )
    if all(type(v) is float or (type(v) is np.ndarray and v.ndim == 0) for v in values):
        scal = np.array([[float(v) for v in values]])  # one camera's: no broadcasting
    else:
        scal = np.stack(np.broadcast_arrays(*values), axis=-1)
    inputs = (
        flat_batch(L, shape, (3,)), flat_batch(V, shape, (4, 4)).reshape(-1, 16),
        flat_batch(P, shape, (4, 4)).reshape(-1, 16), flat_batch(box, shape, (2, 3)).reshape(-1, 6),
        _NO_UP if U is None else flat_batch(U, shape, (3,)), flat_batch(scal, shape, (_SCALARS,)),
        _NO_SPLITS if S is None else flat_batch(S, shape, (n + 1,)),
        _NO_SIZES if W is None else flat_batch(W, shape, (n,)),
    )  # fmt: skip
    if record is None:  # the same loop on Python lists and floats
        rows = [[[0.0] * ROW for _ in range(n)] for _ in range(total)]
        cuts, flags = [[0.0] * (n + 1) for _ in range(total)], [0] * total
        loop_inputs = tuple(v.tolist() for v in inputs)
        scalar_formulas().cascade_loop(loop_inputs, (o,), rows, cuts, flags)
        out = np.asarray(rows, dtype=ctx.dtype)
        splits = np.asarray(cuts, dtype=ctx.dtype)
        status = np.asarray(flags, dtype=np.int64)
    else:
        out = np.empty((total, n, ROW), dtype=ctx.dtype)
        splits = np.empty((total, n + 1), dtype=ctx.dtype)
        status = np.zeros(total, dtype=np.int64)
        _kernels.loops().cascade_loop(inputs, record, out, splits, status)
    if status[0] if total == 1 else status.any():
        raise_status(status.reshape(shape), cascade_messages())
    return _result(call, out.reshape(*shape, n, ROW), splits.reshape(*shape, n + 1))


def _arrays(call: _Call, checks: Checks, arrays: CascadeArrays, warp: str | None) -> Cascades:
    """The array mode: the same steps once on whole arrays (NumPy or JAX), per-entry
    values ``(*batch, 1)`` and the cascades on the last axis (``(*batch, n)``);
    ``warp``: the warp's name (or None); ``o.fitted``: the maps turned
    (``orientation="fitted"``)."""
    ctx, o = call.ctx, call.o
    xp, F = ctx.xp, formulas(ctx.xp)
    L, V, P, box, U, S, dmax, lm, ov, extra, W = arrays
    inputs = CascadeInputs(
        light=tuple(L[..., c, None] for c in range(3)),
        view_matrix=tuple(V[..., i // 4, i % 4, None] for i in range(16)),
        projection=tuple(P[..., i // 4, i % 4, None] for i in range(16)),
        box=tuple(box[..., i // 3, i % 3, None] for i in range(6)),
        up=(0.0, 0.0, 0.0) if U is None else tuple(U[..., c, None] for c in range(3)),
    )
    more = (math.nan,) * 4 if extra is None else extra
    sc = CascadeScalars._make(
        v if v is None or isinstance(v, float) else v[..., None] for v in (lm, dmax, ov, *more)
    )
    j = np.arange(o.cascades + 1, dtype=ctx.dtype)  # the cascades' indices, in the work dtype
    with np.errstate(all="ignore"):  # invalid entries: their status bits say so
        e = F.cascade_entry(inputs, sc, (S, W), o)
        splits = F.cascade_split(S, j, (e.lo, e.hi, e.lam, e.overlap), o)
        sl = F.cascade_slice(e, inputs.box, splits, j[:-1], o)
        row = _RowParts([0.0] * ROW)
        if o.fitted:
            fitted_cascade(xp, F, (e, sl, j[:-1], o), row)
        else:
            F.cascade_fit(e, sl, j[:-1], o, row)
        if warp is not None:
            _warp(call, (e, sl, j[:-1]), (V, P), row)
    for bit, message in cascade_messages():
        checks.require((e.status[..., 0] & bit) == 0, message)
    rows = row.assemble(xp, (*call.shape, o.cascades), ctx.dtype)
    splits = xp.broadcast_to(splits, (*call.shape, o.cascades + 1))
    return _result(call, checks.poison(rows, 2), checks.poison(splits, 1))


class _RowParts(list[Any]):
    """The array mode's row: a list of per-entry values ``(*b, n)``, which also keeps a
    matrix product's 16 entries written whole (``row[k : k + 16] = entries``, the
    :class:`~shadowmath._math._rows.MatrixEntries` of the array form of ``fit_rows``) as its
    matrix ``(*b, n, 4, 4)``, so that :meth:`assemble` does not slice it and stack it again
    (under JAX, 32 kernels fewer). Writing into such a part forgets the matrix."""

    def __init__(self, values: list[Any]) -> None:
        super().__init__(values)
        self.blocks: dict[int, Any] = {}

    def __setitem__(self, key: Any, value: Any) -> None:
        first, stop = (key.start, key.stop) if isinstance(key, slice) else (key, key + 1)
        self.blocks = {k: m for k, m in self.blocks.items() if k + 16 <= first or stop <= k}
        super().__setitem__(key, value)
        if isinstance(key, slice) and isinstance(value, MatrixEntries) and stop - first == 16:
            self.blocks[first] = value.matrix

    def assemble(self, xp: Any, full: tuple[int, ...], dtype: Any) -> Float[Array, "*b n r"]:
        """The rows ``(*full, ROW)``: each entry broadcast to ``full``, a kept matrix whole."""
        parts, k = [], 0
        while k < len(self):
            if k in self.blocks:
                m = self.blocks[k]
                parts.append(xp.broadcast_to(xp.reshape(m, (*m.shape[:-2], 16)), (*full, 16)))
                k += 16
            else:
                parts.append(xp.broadcast_to(xp.asarray(self[k], dtype=dtype), full)[..., None])
                k += 1
        return xp.concat(parts, axis=-1)


class _WarpCamera(NamedTuple):
    """What the LiSPSM hook reads of the camera (per entry, ``(*b, ...)``)."""

    sign: Array  # (*b,): view depth = sign * z_view
    view_to_world: Array  # (*b, 4, 4)
    clip_rows: Array  # (*b, 4, 4): projection @ view


def _warp(
    call: _Call,
    steps: tuple[CascadeEntry, CascadeSlice, Float[Array, " n"]],
    VP: tuple[Float[Array, "*#batch 4 4"], Float[Array, "*#batch 4 4"]],
    row: list[Scalar],
) -> None:
    """The LiSPSM hook (:mod:`._lispsm`): the warp replaces clip, texture rows and size."""
    xp, F, o = call.ctx.xp, formulas(call.ctx.xp), call.o
    e, sl, j = steps
    V, P = VP
    body = F.cascade_body(
        sl.light_corners, sl.box_values, (e.box_light, e.box_camera), (sl.s0, sl.s1)
    )
    iV = xp.stack(xp.broadcast_arrays(*e.camera.view_to_world), axis=-1)[..., 0, :]
    cam = _WarpCamera(
        e.camera.sign[..., 0], xp.reshape(iV, (*iV.shape[:-1], 4, 4)), matmul(xp, P, V)
    )
    clip_at, tex_at, size_at = (row_part(k) for k in ("world_to_clip", "world_to_texture",
                                                       "texel_size"))  # fmt: skip
    size = xp.stack(xp.broadcast_arrays(*row[size_at]), axis=-1)
    ortho = (tuple(row[clip_at]), tuple(row[tex_at]), size)
    clip, tex, size = warp_cascades(
        xp, F, body, cam, V, a=e.camera.axes, spec=call.spec, ortho=ortho,
        tile=lambda rows: F.cascade_tile(rows, j, o),
    )  # fmt: skip
    row[clip_at], row[tex_at] = clip, tex
    row[size_at] = size[..., 0], size[..., 1]


def _result(
    call: _Call, rows: Float[Array, "*batch n r"], splits: Float[Array, "*batch m"]
) -> Cascades:
    """The result from each cascade's row ``(*batch, n, ROW)`` and the splits."""
    xp, n, spec = call.ctx.xp, call.o.cascades, call.spec
    m = xp.reshape(rows[..., : ROW_AT.frustum], (*call.shape, n, 3, 4, 4))  # the three matrices
    box = OrthographicBox(*(rows[..., ROW_AT.frustum + k] for k in range(8)))
    state = CascadeState(splits[..., 0], splits[..., -1], rows[..., ROW_AT.half_width])
    texture = _texture(n, spec.size, call.layout)
    return Cascades(
        world_to_light=m[..., 0, :, :],
        frustum=box,
        world_to_clip=m[..., 1, :, :],
        world_to_texture=m[..., 2, :, :],
        splits=splits,
        band_end=rows[..., ROW_AT.band_end],
        texel_size=rows[..., row_part("texel_size")],
        viewports=_tiles(n, spec.size, call.layout),
        texture_size=texture[0],
        texture_layers=texture[1],
        state=state,
    )


#: The most cameras that NumPy without Numba fits with the loop run by Python (beyond,
#: the array driver, vectorized over the cameras, is faster).
PYTHON_LOOP_CAMERAS = 4

_NO_UP = np.zeros((1, 3))
_SCALARS = len(CascadeScalars._fields)  # the compiled loop's columns of scalars
_NO_SPLITS = np.zeros((1, 2))
_NO_SIZES = np.zeros((1, 1))
