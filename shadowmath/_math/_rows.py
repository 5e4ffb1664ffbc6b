r"""Row-major 4x4 matrices as 16 entries: reading a row of a buffer, and moving into a tile.

Plain arithmetic on Python or Numba scalars or on arrays (specialized like every formula,
:mod:`._specialize`), so the compiled loops and the array drivers share them.
"""

from __future__ import annotations

from typing import Any


def row16(v: Any, k: int) -> Any:
    """The 16 entries ``v[k], ..., v[k + 15]`` as a tuple."""
    return (
        v[k], v[k + 1], v[k + 2], v[k + 3], v[k + 4], v[k + 5], v[k + 6], v[k + 7],
        v[k + 8], v[k + 9], v[k + 10], v[k + 11], v[k + 12], v[k + 13], v[k + 14], v[k + 15],
    )  # fmt: skip


def tile_rows(m: Any, rect: Any, total: Any) -> Any:
    r"""Texture rows ``m`` (16 entries) moved into the tile ``rect = (x, y, w, h)`` of a
    texture of ``total = (W, H)`` units.

    A tile holds its own ``s, t in [0, 1]`` at ``x + w s``, ``y + h t``; on homogeneous
    rows ``(s q, t q, r q, q)``:

    .. math:: s' = (w\,s + x\,q) / W, \qquad t' = (h\,t + y\,q) / H

    (``r`` and ``q`` unchanged). ``t`` and ``y`` count from the texture's first row in
    memory, where every API's viewport ``y = 0`` lies. A cascade in an atlas of ``cols x
    rows`` maps is ``rect = (col, row, 1, 1)``, ``total = (cols, rows)``; an atlas tile of
    ``n`` texels at ``(x, y)`` in an ``A``-texel atlas is ``(x, y, n, n)``, ``(A, A)``: on
    the identity rows the result is the tile's matrix.

    Example:
        >>> tile_rows((1.0, 0, 0, 0, 0, 1.0, 0, 0, 0, 0, 1.0, 0, 0, 0, 0, 1.0),
        ...           (1.0, 0.0, 1.0, 1.0), (2.0, 1.0))[:4]
        (0.5, 0.0, 0.0, 0.5)
    """
    x, y, w, h = rect
    return (
        (w * m[0] + x * m[12]) / total[0], (w * m[1] + x * m[13]) / total[0],
        (w * m[2] + x * m[14]) / total[0], (w * m[3] + x * m[15]) / total[0],
        (h * m[4] + y * m[12]) / total[1], (h * m[5] + y * m[13]) / total[1],
        (h * m[6] + y * m[14]) / total[1], (h * m[7] + y * m[15]) / total[1],
        m[8], m[9], m[10], m[11], m[12], m[13], m[14], m[15],
    )  # fmt: skip


FUNCTIONS = ("row16", "tile_rows")
