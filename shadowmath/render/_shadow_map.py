"""The public pass 1: the blocker's silhouette as seen from the light, as a NumPy mask."""

from __future__ import annotations

from typing import Any

import moderngl
import numpy as np
from numpy.typing import NDArray

from ._context import check_matrix, check_mesh, image_size, resolve_context
from ._pass_texture import draw_shadow_map, read_mask
from ._resources import GpuMesh


def render_shadow_map(
    vertices: Any,
    triangles: Any,
    blocker_to_clip: Any,
    map_size: int | tuple[int, int],
    *,
    ctx: moderngl.Context | None = None,
) -> NDArray[np.float32]:
    """Pass 1 of Nagy's method: draw the blocker's silhouette into a shadow map.

    The blocker is drawn exactly as the article's pass 1: in its local
    coordinates through ``blocker_to_clip`` (``gl_Position = M p``, the
    article's ``M_BlockerLocalToShadowMap``, e.g. :attr:`ShadowSetup.blocker_to_clip`),
    flat colour 1 on a cleared 0, no lighting, no depth test, no face culling,
    no multisampling: a texel is 1 exactly when the silhouette covers its centre
    (OpenGL's rasterization rule).

    Arguments:
        vertices: ``(N, 3)`` the blocker's vertices in its local coordinates.
        triangles: ``(M, 3)`` integer vertex indices.
        blocker_to_clip: ``(4, 4)`` column-vector matrix to OpenGL clip space
            (NumPy or JAX; uploaded with :func:`column_major_bytes`).
        map_size: ``size`` of a square map or ``(width, height)`` in texels.
        ctx: a moderngl context; default the shared EGL :func:`standalone_context`.

    Returns:
        ``(height, width)`` float32 mask, 1.0 under the silhouette and 0.0 elsewhere.
        Row ``i`` holds texture ``t`` in ``[i / height, (i + 1) / height]``: row 0 is
        ``t = 0``, the bottom row in OpenGL's convention (``y_ndc = -1``), and
        column ``j`` is ``s`` in ``[j / width, (j + 1) / width]``. Flip it
        vertically (``mask[::-1]``) to show it as an image with ``t`` upward.

    Raises:
        ValueError: badly shaped or non-finite inputs, out-of-range triangle
            indices, a bad map size.
        GLUnavailableError: no OpenGL context could be created.

    Example:
        >>> box = np.array([[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (4, 6)])
        >>> s = fit_shadow([0, 0, 0], box, 16)
        >>> tri = [[0, 4, 6], [0, 6, 2]]  # the near face z = 4, seen from the light
        >>> mask = render_shadow_map(box, tri, s.blocker_to_clip, 16)
        >>> # row 0 is the empty border, row 1 the first drawn one
        >>> float(mask[0].max()), float(mask[1].max())
        (0.0, 1.0)
    """
    v, t = check_mesh("blocker", vertices, triangles)
    m = check_matrix("blocker_to_clip", blocker_to_clip)
    size = image_size("map_size", map_size)
    gl = resolve_context(ctx)
    mesh = GpuMesh(gl, v, t)
    try:
        tex = draw_shadow_map(gl, mesh, m, size)
    finally:
        mesh.release()
    try:
        return read_mask(tex)
    finally:
        tex.release()
