"""The loops over the batch: the fits' steps per entry, for Numba or plain Python.

Every function here is plain Python over scalars, written in the subset that
Numba compiles (tuples, ``len``, ``a[i][j]`` indexing, ``math``). Like the
formulas, they are specialized (:func:`._specialize.specialize`): compiled by
Numba through :func:`shadowmath._backends._kernels.loops` (whose cache folder is keyed on every
source of the package, so the machine code on disk can never be older than the
formulas it inlines), or bound to Python floats for one small NumPy fit without
Numba (:func:`._specialize.scalar_formulas`), where a Python loop over a few
vertices beats hundreds of NumPy calls.

:func:`fit_loop` reads each batch entry's operands and runs :func:`._fit_entry.fit_entry`,
the one driver of the fit that the array path runs on whole arrays too, with the
vertex passes of :mod:`._vertex_passes`; it stores the frame, the frustum's fields
and the matrices. Validity is reported per entry as the bits of :mod:`shadowmath._boundary._status`;
the boundary raises the message of the first failing one.
"""

from __future__ import annotations

import math
from typing import Any, NamedTuple

import numpy as np

from shadowmath._boundary._shapes import Array, ArrayLike, Float, Int, Options, Real, Row, Scalar

from ._fit_entry import Entry, fit_entry
from ._formulas import compose_rows, planar_entries
from ._rows import row16
from ._vertex_passes import enclosing_support


class FitRow(NamedTuple):
    """Where each part of :func:`fit_loop`'s output row starts (:data:`FIT_ROW_AT`)."""

    origin: int  # 3
    axes: int  # 9: X, Y, Z
    frustum: int  # 8: R_x, R_y, near, far, m_x, m_y, c_x, c_y (volume's order)


#: The parts of :func:`fit_loop`'s output row.
FIT_ROW_AT = FitRow(0, 3, 12)
#: The entries of one output row.
FIT_ROW = 12 + 8


class FitMatrices(NamedTuple):
    """Which matrix of :func:`fit_loop`'s ``(4, 4, 4)`` block is which (:data:`FIT_MATRIX`)."""

    world_to_light: int
    blocker_to_clip: int
    world_to_texture: int
    placement: int


#: The matrices' places in the block.
FIT_MATRIX = FitMatrices(0, 1, 2, 3)


def planar_loop(
    plane: Real[ArrayLike, "_ 4"],
    light: Real[ArrayLike, "_ 4"],
    eps: float,
    out: Float[Array, "n 16"],
    status: Int[Array, " n"],
) -> None:
    splitter = 134217729.0  # 2^27 + 1: the loop computes in float64
    for i in range(len(out)):
        P, L = plane[i % len(plane)], light[i % len(light)]
        pi = (float(P[0]), float(P[1]), float(P[2]), float(P[3]))
        li = (float(L[0]), float(L[1]), float(L[2]), float(L[3]))
        st = 0
        for v in pi:
            if not math.isfinite(v):
                st |= 1
        for v in li:
            if not math.isfinite(v):
                st |= 2
        e = planar_entries(pi, li, splitter)
        if not e[18] > 0:
            st |= 4
        if li[0] == 0 and li[1] == 0 and li[2] == 0 and li[3] == 0:
            st |= 8
        if not abs(e[16]) > 16 * eps * e[17]:
            st |= 16
        status[i] = st
        for j in range(16):
            out[i, j] = e[j]


def support_loop(verts: Real[ArrayLike, "n _"], out: Int[Array, "n 5"]) -> None:
    """The enclosing sphere's support of every entry of ``(count, 3 N)`` world vertices
    (flat rows ``x0, y0, z0, x1, ...``): ``out[i] = (i_0, i_1, i_2, i_3, k)``."""
    none = (0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0)
    for e in range(len(out)):
        sup, k = enclosing_support(verts[e], none, False)
        out[e, 0], out[e, 1], out[e, 2], out[e, 3], out[e, 4] = sup[0], sup[1], sup[2], sup[3], k


def _row(V: Real[ArrayLike, "n ..."], i: int) -> Real[ArrayLike, "..."]:
    return V[i % len(V)]


def _entries(M: Real[ArrayLike, "n 4 4"], i: int) -> tuple[float, ...]:
    """Batch entry ``i`` of ``(count or 1, 4, 4)`` matrices as 16 floats."""
    m = M[i % len(M)]
    return (
        float(m[0][0]), float(m[0][1]), float(m[0][2]), float(m[0][3]),
        float(m[1][0]), float(m[1][1]), float(m[1][2]), float(m[1][3]),
        float(m[2][0]), float(m[2][1]), float(m[2][2]), float(m[2][3]),
        float(m[3][0]), float(m[3][1]), float(m[3][2]), float(m[3][3]),
    )  # fmt: skip


def _spot(Lr: Row, spot: bool) -> tuple[float, float, float, float, float]:
    """A spot light's axis, ``tan(angle)`` and angle (columns 3 to 7 of its row), or zeros."""
    if spot:
        return (float(Lr[3]), float(Lr[4]), float(Lr[5]), float(Lr[6]), float(Lr[7]))
    return (0.0, 0.0, 0.0, 0.0, 0.0)


def fit_loop(
    operands: tuple[Real[ArrayLike, "..."], ...],
    opts: list[Options] | np.ndarray[Any, np.dtype[np.void]],
    out: tuple[Float[Array, "n r"], Float[Array, "n 4 4 4"], Int[Array, " n"]],
) -> None:
    """Every batch entry's :func:`fit_entry`.

    ``operands = (light, verts, placement, recv, ups, near, far)``, each
    ``(count or 1, ...)`` and read at ``i % len`` (``verts``: flat rows of ``3 N``
    numbers; ``near``, ``far``: ``(count or 1,)``, ignored unless given); ``opts``: the
    options record (one row of :data:`shadowmath._fits.shadow._compiled.OPTIONS`: the fields of
    :class:`._fit_entry.FitOptions`, then the API's rows ``C`` and ``T C``);
    ``out = (rows, mats, status)``: the output blocks.
    """
    light, verts, placement, recv, ups, near, far = operands
    rows, mats, status = out
    o = opts[0]
    api = (row16(o.api_clip, 0), row16(o.api_texture, 0))
    for i in range(len(rows)):
        Lr, Ur = _row(light, i), _row(ups, i)
        L = (float(Lr[0]), float(Lr[1]), float(Lr[2]))
        U = (float(Ur[0]), float(Ur[1]), float(Ur[2]))
        b = _entries(placement, i)
        nf = (float(_row(near, i)), float(_row(far, i)))
        given = (L, _spot(Lr, o.spot), U, b, nf)
        e = fit_entry(given, (_row(verts, i), b, o.has_placement), _row(recv, i), o, api)
        status[i] = e.status
        clip = compose_rows(e.clip, b) if o.has_placement else e.clip
        _store(rows[i], mats[i], e, (e.W, clip, e.tex, b), (o.margin_x, o.margin_y))


def _store(
    row: Float[Array, " r"],
    mat: Float[Array, "4 4 4"],
    e: Entry,
    matrices: tuple[tuple[Scalar, ...], ...],
    margins: tuple[float, float],
) -> None:
    """One entry's output row (frame, frustum: parts at :data:`FIT_ROW_AT`) and its four
    matrices (at :data:`FIT_MATRIX`)."""
    W, clip, tex, b = matrices
    for j in range(3):
        row[FIT_ROW_AT.origin + j] = e.origin[j]
    for j in range(9):
        row[FIT_ROW_AT.axes + j] = e.axes[j]
    f = FIT_ROW_AT.frustum
    for j in range(4):
        row[f + j] = e.box[j]
    row[f + 4], row[f + 5], row[f + 6], row[f + 7] = margins[0], margins[1], e.box[4], e.box[5]
    w, c, t, p = FIT_MATRIX
    for j in range(12):
        mat[w, j // 4, j % 4] = W[j]
    mat[w, 3, 0], mat[w, 3, 1], mat[w, 3, 2], mat[w, 3, 3] = 0.0, 0.0, 0.0, 1.0
    for j in range(16):
        mat[c, j // 4, j % 4] = clip[j]
        mat[t, j // 4, j % 4] = tex[j]
        mat[p, j // 4, j % 4] = b[j]


FUNCTIONS = (
    "planar_loop",
    "support_loop",
    "_row",
    "_entries",
    "_spot",
    "fit_loop",
    "_store",
)
