r"""Row-major 4x4 matrices as 16 entries: a row of a buffer, a tile, a product, an inverse.

Plain arithmetic on Python or Numba scalars or on arrays (specialized like every formula,
:mod:`._specialize`), so the compiled loops and the array drivers share them.
"""

from __future__ import annotations

from shadowmath._boundary._shapes import Row, Scalar

from ._formulas import where


class MatrixEntries(tuple):  # type: ignore[type-arg]
    """The 16 row-major entries of an array ``matrix`` ``(*b, 4, 4)`` (the array forms'
    products), which :func:`._frame.stack_matrix` returns whole instead of restacking."""

    matrix: Scalar

    def __new__(cls, matrix: Scalar) -> MatrixEntries:
        entries = super().__new__(cls, (matrix[..., i // 4, i % 4] for i in range(16)))
        entries.matrix = matrix
        return entries


def row16(v: Row, k: int) -> tuple[Scalar, ...]:
    """The 16 entries ``v[k], ..., v[k + 15]`` as a tuple."""
    return (
        v[k], v[k + 1], v[k + 2], v[k + 3], v[k + 4], v[k + 5], v[k + 6], v[k + 7],
        v[k + 8], v[k + 9], v[k + 10], v[k + 11], v[k + 12], v[k + 13], v[k + 14], v[k + 15],
    )  # fmt: skip


def tile_rows(
    m: Row, rect: tuple[Scalar, Scalar, Scalar, Scalar], total: tuple[Scalar, Scalar]
) -> tuple[Scalar, ...]:
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


def inverse4(m: tuple[Scalar, ...]) -> tuple[tuple[Scalar, ...], Scalar]:
    """The inverse of a 4x4 matrix (16 row-major entries) by 2x2 minors, and its determinant."""
    s0 = m[0] * m[5] - m[4] * m[1]
    s1 = m[0] * m[6] - m[4] * m[2]
    s2 = m[0] * m[7] - m[4] * m[3]
    s3 = m[1] * m[6] - m[5] * m[2]
    s4 = m[1] * m[7] - m[5] * m[3]
    s5 = m[2] * m[7] - m[6] * m[3]
    c5 = m[10] * m[15] - m[14] * m[11]
    c4 = m[9] * m[15] - m[13] * m[11]
    c3 = m[9] * m[14] - m[13] * m[10]
    c2 = m[8] * m[15] - m[12] * m[11]
    c1 = m[8] * m[14] - m[12] * m[10]
    c0 = m[8] * m[13] - m[12] * m[9]
    det = s0 * c5 - s1 * c4 + s2 * c3 + s3 * c2 - s4 * c1 + s5 * c0
    k = 1.0 / where(det != 0, det, 1.0)
    inv = (
        (m[5] * c5 - m[6] * c4 + m[7] * c3) * k,
        (-m[1] * c5 + m[2] * c4 - m[3] * c3) * k,
        (m[13] * s5 - m[14] * s4 + m[15] * s3) * k,
        (-m[9] * s5 + m[10] * s4 - m[11] * s3) * k,
        (-m[4] * c5 + m[6] * c2 - m[7] * c1) * k,
        (m[0] * c5 - m[2] * c2 + m[3] * c1) * k,
        (-m[12] * s5 + m[14] * s2 - m[15] * s1) * k,
        (m[8] * s5 - m[10] * s2 + m[11] * s1) * k,
        (m[4] * c4 - m[5] * c2 + m[7] * c0) * k,
        (-m[0] * c4 + m[1] * c2 - m[3] * c0) * k,
        (m[12] * s4 - m[13] * s2 + m[15] * s0) * k,
        (-m[8] * s4 + m[9] * s2 - m[11] * s0) * k,
        (-m[4] * c3 + m[5] * c1 - m[6] * c0) * k,
        (m[0] * c3 - m[1] * c1 + m[2] * c0) * k,
        (-m[12] * s3 + m[13] * s1 - m[14] * s0) * k,
        (m[8] * s3 - m[9] * s1 + m[10] * s0) * k,
    )
    return inv, det


def _mul16(a: Row, b: Row) -> tuple[Scalar, ...]:
    """``a @ b`` for 16 row-major entries each."""
    return (
        a[0] * b[0] + a[1] * b[4] + a[2] * b[8] + a[3] * b[12],
        a[0] * b[1] + a[1] * b[5] + a[2] * b[9] + a[3] * b[13],
        a[0] * b[2] + a[1] * b[6] + a[2] * b[10] + a[3] * b[14],
        a[0] * b[3] + a[1] * b[7] + a[2] * b[11] + a[3] * b[15],
        a[4] * b[0] + a[5] * b[4] + a[6] * b[8] + a[7] * b[12],
        a[4] * b[1] + a[5] * b[5] + a[6] * b[9] + a[7] * b[13],
        a[4] * b[2] + a[5] * b[6] + a[6] * b[10] + a[7] * b[14],
        a[4] * b[3] + a[5] * b[7] + a[6] * b[11] + a[7] * b[15],
        a[8] * b[0] + a[9] * b[4] + a[10] * b[8] + a[11] * b[12],
        a[8] * b[1] + a[9] * b[5] + a[10] * b[9] + a[11] * b[13],
        a[8] * b[2] + a[9] * b[6] + a[10] * b[10] + a[11] * b[14],
        a[8] * b[3] + a[9] * b[7] + a[10] * b[11] + a[11] * b[15],
        a[12] * b[0] + a[13] * b[4] + a[14] * b[8] + a[15] * b[12],
        a[12] * b[1] + a[13] * b[5] + a[14] * b[9] + a[15] * b[13],
        a[12] * b[2] + a[13] * b[6] + a[14] * b[10] + a[15] * b[14],
        a[12] * b[3] + a[13] * b[7] + a[14] * b[11] + a[15] * b[15],
    )


FUNCTIONS = ("row16", "tile_rows", "inverse4", "_mul16")
