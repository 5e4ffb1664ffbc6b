r"""Graphics API conventions: clip space, depth range and texture origin of each API.

shadowmath computes in OpenGL's clip space (NDC depth ``-1`` at near, ``+1`` at
far, ``y`` up, framebuffer and texture origin at the lower left). Another API
draws and samples the same shadow map with two constant matrices:

* ``gl_clip_to_clip`` (``C``): left-multiplied onto an OpenGL clip matrix, it
  gives that API's clip coordinates: ``blocker_to_clip_api = C @ blocker_to_clip``;
* ``clip_to_texture`` (``T``): from that API's clip coordinates to homogeneous
  texture coordinates ``(s q, t q, r q, q)``, ``q = w_clip``, such that a point
  samples exactly the texel the rasterizer drew it into (``t = 0`` is the first
  row of the texture in memory) and ``r`` is the depth value the API stores
  there: ``world_to_texture_api = T @ C @ P @ W``.

Derivation (``x, y, z`` are NDC, ``W x H`` the map, viewport covering it,
depth range ``[0, 1]``):

====================  ==================  ===================  ===================
API                   window ``x``        window row (memory)  depth stored
====================  ==================  ===================  ===================
opengl                ``W (x + 1) / 2``   ``H (y + 1) / 2``    ``(z + 1) / 2``
vulkan                ``W (x + 1) / 2``   ``H (y + 1) / 2``    ``z``
direct3d/metal/webgpu ``W (x + 1) / 2``   ``H (1 - y) / 2``    ``z``
====================  ==================  ===================  ===================

OpenGL counts window rows from the bottom and its texture's first row is its
bottom row: row ``H (y + 1) / 2`` in both, no flip. Vulkan's viewport maps
``y = -1`` to the framebuffer's first (top) row, and its texture ``t = 0`` is that
first row: again no flip between its own clip ``y`` and ``t``, but Vulkan's clip
``y`` points down, so ``C`` negates OpenGL's ``y``. Direct3D, Metal and WebGPU
keep ``y`` up in NDC but their viewport sends ``y = +1`` to the first (top) row,
and their texture origin is that row: ``T`` maps ``t = (1 - y) / 2``. In every
API a point drawn at OpenGL-clip ``y = +1`` (the top of the image as the light
sees it) lies in the first row in memory, except OpenGL's own, where it lies in
the last.

Depth: the non-OpenGL APIs clip ``0 <= z <= w``, so ``C`` maps
``z' = (z + w) / 2``; with ``reversed_z`` it maps ``z' = (w - z) / 2`` (near ``1``,
far ``0``). OpenGL with ``reversed_z`` keeps its ``[-1, 1]`` clip range
(``glClipControl`` untouched) and negates ``z``. In every case the viewport's depth
range is the default ``[0, 1]``, so the stored depth is ``(z + 1) / 2`` for OpenGL and
``z`` for the others (the reversal lives in ``C``, so ``T`` does not depend on it).

Trusted cores only: the public functions, which check their arguments and
call these, are in :mod:`shadowmath._geometry._api_convention`.
"""

from __future__ import annotations

from typing import Literal, NamedTuple, TypeAlias

import numpy as np

from shadowmath._boundary._shapes import Float
from shadowmath._boundary._validate import Array

GraphicsApi: TypeAlias = Literal["opengl", "vulkan", "direct3d", "metal", "webgpu"]

#: The graphics APIs whose conventions shadowmath knows, in the order of the docs' table.
GRAPHICS_APIS: tuple[GraphicsApi, ...] = ("opengl", "vulkan", "direct3d", "metal", "webgpu")

#: A constant 4x4 matrix as rows of exact floats (``ctx.constant(m)`` converts it).
Matrix4: TypeAlias = tuple[tuple[float, ...], ...]


class ApiConvention(NamedTuple):
    """The constant matrices and depth values of one graphics API's conventions.

    Attributes:
        gl_clip_to_clip: ``(4, 4)`` OpenGL clip coordinates to the API's clip
            coordinates (left-multiply ``blocker_to_clip`` by it).
        clip_to_texture: ``(4, 4)`` the API's clip coordinates to
            ``(s q, t q, r q, q)``: ``t = 0`` is the texture's first row in memory,
            ``r`` the depth the API stores.
        gl_clip_to_texture: ``(4, 4)`` the product ``clip_to_texture @ gl_clip_to_clip``
            (left-multiply OpenGL clip coordinates by it to get texture coordinates).
        near_depth: the depth stored at the near plane (``0.0``, or ``1.0`` reversed).
        far_depth: the depth stored at the far plane: clear the depth buffer to it;
            the depth test keeps the smaller depth when ``near_depth < far_depth``
            (``LESS``), the larger one otherwise (``GREATER``).
    """

    gl_clip_to_clip: Float[Array, "4 4"]
    clip_to_texture: Float[Array, "4 4"]
    gl_clip_to_texture: Float[Array, "4 4"]
    near_depth: float
    far_depth: float


def clip_from_gl(api: str, reversed_z: bool) -> Matrix4:
    """``C``: OpenGL clip coordinates to ``api``'s clip coordinates (trusted inputs).

    Nested tuples of exact floats: convert with ``ctx.constant(...)``.
    """
    y = -1.0 if api == "vulkan" else 1.0
    if api == "opengl":
        depth = (0.0, 0.0, -1.0, 0.0) if reversed_z else (0.0, 0.0, 1.0, 0.0)
    else:
        depth = (0.0, 0.0, -0.5, 0.5) if reversed_z else (0.0, 0.0, 0.5, 0.5)
    return ((1.0, 0.0, 0.0, 0.0), (0.0, y, 0.0, 0.0), depth, (0.0, 0.0, 0.0, 1.0))


def texture_from_clip(api: str, reversed_z: bool) -> Matrix4:
    """``T``: ``api``'s clip coordinates to ``(s q, t q, r q, q)`` (trusted inputs).

    ``reversed_z`` does not change ``T`` (the reversal is in :func:`clip_from_gl`);
    it is taken so that both cores have one signature.
    """
    del reversed_z
    t = -0.5 if api in ("direct3d", "metal", "webgpu") else 0.5
    depth = (0.0, 0.0, 0.5, 0.5) if api == "opengl" else (0.0, 0.0, 1.0, 0.0)
    return ((0.5, 0.0, 0.0, 0.5), (0.0, t, 0.0, 0.5), depth, (0.0, 0.0, 0.0, 1.0))


def texture_from_gl_clip(api: str, reversed_z: bool) -> Matrix4:
    """``T @ C``: OpenGL clip coordinates straight to ``api``'s texture coordinates."""
    product = np.asarray(texture_from_clip(api, reversed_z)) @ np.asarray(
        clip_from_gl(api, reversed_z)
    )
    return tuple(tuple(float(v) for v in row) for row in product)
