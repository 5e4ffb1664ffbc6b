"""Memory layout for uploading matrices to OpenGL: separate from the vector convention."""

from __future__ import annotations

import numpy as np

from shadowmath._boundary._shapes import ArrayLike, Real
from shadowmath._boundary._validate import require_matrix


def column_major_bytes(matrix: Real[ArrayLike, "*batch 4 4"]) -> bytes:
    """The float32 bytes an OpenGL / moderngl ``mat4`` uniform expects.

    shadowmath's matrices are column-vector matrices indexed ``M[row, col]``
    and stored row-major by NumPy. GLSL's ``mat4`` is also a column-vector
    matrix (``gl_Position = M * p``) but is filled column by column, so the
    bytes are those of ``M.T`` in C order. This is a memory-layout change only:
    the matrix itself is not transposed in meaning (``transpose=False`` in
    ``glUniformMatrix4fv``). A batch ``(*batch, 4, 4)`` gives the matrices one
    after another, as a ``mat4[]`` array uniform expects.

    Arguments:
        matrix: ``(4, 4)`` or ``(*batch, 4, 4)``, NumPy or JAX.

    Returns:
        ``16 * 4 * prod(batch)`` bytes.

    Raises:
        ValueError: wrong shape or non-finite entries (a NaN-poisoned matrix from a
            JAX transformation must not reach the GPU silently).

    Example:
        >>> import numpy as np
        >>> M = np.arange(16.0).reshape(4, 4)
        >>> np.frombuffer(column_major_bytes(M), np.float32)[:4]  # the first column
        array([ 0.,  4.,  8., 12.], dtype=float32)
    """
    m = np.asarray(matrix)
    if m.dtype.kind not in "biuf":
        raise ValueError(f"matrix: expected real numbers, got dtype {m.dtype}")
    require_matrix("matrix", m)
    if not np.all(np.isfinite(m)):
        raise ValueError("matrix: contains non-finite entries (NaN marks invalid input upstream)")
    return np.ascontiguousarray(np.swapaxes(m, -1, -2), dtype=np.float32).tobytes()
