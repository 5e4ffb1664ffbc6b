"""Pass 1: the shadow map, the blocker's silhouette as seen from the light."""

from __future__ import annotations

from typing import Any

import moderngl
import numpy as np
from numpy.typing import NDArray

from ._context import check_matrix, check_mesh, image_size, program, resolve_context, set_matrix


def draw_shadow_map(
    ctx: moderngl.Context,
    vertices: NDArray[np.float64],
    triangles: NDArray[np.int64],
    blocker_to_clip: NDArray[np.float64],
    size: tuple[int, int],
) -> moderngl.Texture:
    """Draw the mask into a new one-channel 8-bit texture (already-checked inputs)."""
    tex = ctx.texture(size, 1, dtype="f1")
    # Clamp to edge: receiver points outside the frustum read the untouched border.
    tex.repeat_x = False
    tex.repeat_y = False
    tex.filter = (moderngl.NEAREST, moderngl.NEAREST)
    fbo = ctx.framebuffer(color_attachments=[tex])
    prog = program(ctx, "shadow_map.vert", "shadow_map.frag")
    set_matrix(prog, "blocker_to_clip", blocker_to_clip)
    vbo = ctx.buffer(vertices.astype(np.float32).tobytes())
    ibo = ctx.buffer(triangles.astype(np.int32).tobytes())
    vao = ctx.vertex_array(prog, [(vbo, "3f", "position")], index_buffer=ibo, index_element_size=4)
    try:
        fbo.use()
        fbo.viewport = (0, 0, *size)
        ctx.disable(moderngl.DEPTH_TEST | moderngl.CULL_FACE | moderngl.BLEND)
        fbo.clear(0.0, 0.0, 0.0, 0.0)
        vao.render(moderngl.TRIANGLES)
    finally:
        for obj in (vao, ibo, vbo, fbo):
            obj.release()
    return tex


def read_mask(tex: moderngl.Texture) -> NDArray[np.float32]:
    """A one-channel 8-bit texture as a ``(height, width)`` float32 array in ``[0, 1]``."""
    w, h = tex.size
    data = np.frombuffer(tex.read(alignment=1), dtype=np.uint8).reshape(h, w)
    return (data / np.float32(255.0)).astype(np.float32)


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
    tex = draw_shadow_map(gl, v, t, m, size)
    try:
        return read_mask(tex)
    finally:
        tex.release()
