"""The graphics APIs' conventions at the door: :func:`api_convention` and the check of ``api``.

The constant matrices are :mod:`shadowmath._math._conventions`'s.
"""

from __future__ import annotations

import numpy as np

from shadowmath._boundary._shapes import BoolLike
from shadowmath._math import _conventions
from shadowmath._math._conventions import GRAPHICS_APIS, ApiConvention


def check_api(api: object, reversed_z: object) -> None:
    """Raise ``ValueError`` for an unknown ``api`` or a non-boolean ``reversed_z``."""
    if not isinstance(api, str) or api not in GRAPHICS_APIS:
        valid = ", ".join(repr(a) for a in GRAPHICS_APIS)
        raise ValueError(f"api: unknown graphics API {api!r}; expected one of {valid}")
    if not isinstance(reversed_z, bool | np.bool_):
        raise ValueError(f"reversed_z: expected True or False, got {reversed_z!r}")


def api_convention(*, api: str = "opengl", reversed_z: BoolLike = False) -> ApiConvention:
    r"""The clip and texture conventions of a graphics API, as constant matrices.

    With ``P W`` an OpenGL clip matrix from world coordinates (e.g.
    ``setup.blocker_to_clip``), draw the shadow map in ``api`` with
    ``C @ P @ W`` and sample it with ``T @ C @ P @ W``, where ``C`` is
    ``gl_clip_to_clip`` and ``T`` is ``clip_to_texture``:

    .. math::

        C = \begin{bmatrix} 1&0&0&0\\ 0&\pm1&0&0\\ 0&0&a&b\\ 0&0&0&1 \end{bmatrix},
        \qquad
        T = \begin{bmatrix} \tfrac12&0&0&\tfrac12\\ 0&\pm\tfrac12&0&\tfrac12\\
        0&0&c&d\\ 0&0&0&1 \end{bmatrix}

    ``C``'s ``y`` is ``-1`` for Vulkan only; ``T``'s ``t`` row is ``-½`` for
    Direct3D, Metal and WebGPU (top-left texture origin, ``y`` up in NDC);
    ``(a, b)`` is ``(1, 0)`` for OpenGL (``(-1, 0)`` reversed) and ``(½, ½)``
    for the others (``(-½, ½)`` reversed); ``(c, d)`` is ``(½, ½)`` for OpenGL
    and ``(1, 0)`` for the others. The table and its derivation are in
    ``docs/conventions.md``.

    Arguments:
        api: ``"opengl"`` (default), ``"vulkan"``, ``"direct3d"``, ``"metal"``
            or ``"webgpu"``.
        reversed_z: store ``1`` at the near plane and ``0`` at the far plane
            (the reversal is in the projection, the viewport's depth range
            stays ``[0, 1]``; clear the depth buffer to ``0`` and test ``GREATER``).

    Returns:
        An :class:`ApiConvention` of float64 NumPy ``(4, 4)`` matrices and the
        near and far depths.

    Raises:
        ValueError: an unknown ``api`` (the message lists the valid ones) or a
            ``reversed_z`` that is not a boolean.

    Example:
        >>> conv = api_convention(api="webgpu")
        >>> conv.gl_clip_to_texture  # s = (x + 1)/2, t = (1 - y)/2, r = (z + 1)/2
        array([[ 0.5,  0. ,  0. ,  0.5],
               [ 0. , -0.5,  0. ,  0.5],
               [ 0. ,  0. ,  0.5,  0.5],
               [ 0. ,  0. ,  0. ,  1. ]])
        >>> api_convention(api="vulkan", reversed_z=True).near_depth
        1.0
    """
    check_api(api, reversed_z)
    rz = bool(reversed_z)
    near, far = (1.0, 0.0) if rz else (0.0, 1.0)
    return ApiConvention(
        gl_clip_to_clip=np.array(_conventions.clip_from_gl(api, rz)),
        clip_to_texture=np.array(_conventions.texture_from_clip(api, rz)),
        gl_clip_to_texture=np.array(_conventions.texture_from_gl_clip(api, rz)),
        near_depth=near,
        far_depth=far,
    )
