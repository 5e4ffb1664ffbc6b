r"""The cube lights of a shadow atlas fitted: six faces per light, on whole arrays.

Face ``i``'s ``world_to_clip = P V_i`` with ``V_i`` of :func:`cube_face_views` and ``P``
of :func:`cube_face_projection` with the border ring (scale ``k = (n - 2b) / n``), and the
depth range of :func:`cube_depth_range`.
"""

from __future__ import annotations

from types import ModuleType

import numpy as np
from numpy.typing import NDArray

from shadowmath._boundary._shapes import Float
from shadowmath._boundary._validate import Array, Context, non_finite
from shadowmath._fits.cube._driver import AT_LIGHT, cube_depth_core
from shadowmath._math._conventions import texture_from_clip as _texture_from_clip
from shadowmath._math._cube import APIS as _APIS
from shadowmath._math._cube import cube_face_views as _cube_face_views
from shadowmath._math._cube import depth_row as _depth_row
from shadowmath._math._frame import stack_matrix
from shadowmath._math._vector import matmul

from ._allocate import ShadowAtlas
from ._report import AtlasInputs, Report, pick

__all__ = ["fit_cubes"]

Ints = NDArray[np.int64]


def fit_cubes(
    ctx: Context, atlas: ShadowAtlas, cubes: Ints, inputs: AtlasInputs, *, api: str, report: Report
) -> tuple[Ints, Array, Array, Array, Array]:
    """The six faces of every cube light at once: ``(tiles, clip, texture, near, far)``;
    a light with a non-finite position, a caster at it or a bad depth range is reported."""
    xp = ctx.xp
    data, verts, tris, R, n, f = inputs
    finite = np.asarray(xp.all(xp.isfinite(data[cubes, :3]), axis=1))
    P = xp.where(xp.asarray(finite)[:, None], data[cubes, :3], 0.0)
    size = atlas.light_size[cubes].astype(np.float64)
    k = xp.asarray((size - 2 * atlas.light_border[cubes]) / size, dtype=ctx.dtype)
    VT = xp.matrix_transpose(verts[None] if verts.ndim == 2 else verts[cubes])
    corners = None if R is None else xp.reshape(R, (-1, 3))[None]
    T = None if tris is None else (tris[None] if tris.ndim == 3 else tris[cubes])
    near, far, clear = cube_depth_core(xp, P, VT, corners, k=k, eps=ctx.eps, triangles=T)
    lo = near if n is None else pick(ctx, n, cubes)
    hi = far if f is None else pick(ctx, f, cubes)
    ranged = np.asarray(xp.isfinite(lo) & xp.isfinite(hi) & (lo > 0) & (hi > lo))
    failed = ~(finite & np.asarray(clear) & ranged)
    for i in np.flatnonzero(failed).tolist():
        report.fail(int(cubes[i]), _cube_message(finite[i], bool(np.asarray(clear)[i])))
    bad = xp.asarray(failed)
    lo, hi = xp.where(bad, 1.0, lo), xp.where(bad, 2.0, hi)  # safe: replaced below
    zero_to_one, flip_y = _APIS[api]
    a, b = _depth_row(lo, hi, zero_to_one, bool(report.reversed_z))
    Pm = _face_projections(xp, k, -k if flip_y else k, a, b)
    clip = matmul(xp, Pm[:, None], _cube_face_views(xp, P))  # (C, 6, 4, 4)
    T = ctx.constant(_texture_from_clip(api, bool(report.reversed_z)))
    tex = matmul(xp, T, clip)
    tile = atlas.light_tiles[cubes].reshape(-1)
    values = (clip.reshape(-1, 4, 4), tex.reshape(-1, 4, 4), xp.repeat(lo, 6), xp.repeat(hi, 6))
    return (tile, *report.replace(ctx, np.repeat(failed, 6), values))


def _cube_message(finite: bool, clear: bool) -> str:
    if not finite:
        return non_finite("light")
    if not clear:
        return f"{AT_LIGHT}, or give near="
    return "near and far must be finite with 0 < near < far"


def _face_projections(
    xp: ModuleType,
    kx: Float[Array, " C"],
    ky: Float[Array, " C"],
    a: Float[Array, " C"],
    b: Float[Array, " C"],
) -> Float[Array, "C 4 4"]:
    """``(C, 4, 4)`` :func:`cube_face_projection` matrices, one per light (written in place
    for NumPy: sixteen broadcasts cost more than the fit)."""
    if xp is not np:
        zero = xp.zeros_like(kx)
        return stack_matrix(xp, (kx, zero, zero, zero, zero, ky, zero, zero,
                                 zero, zero, a, b, zero, zero, zero - 1, zero))  # fmt: skip
    P = np.zeros((kx.shape[0], 4, 4), dtype=np.result_type(kx, a))
    P[:, 0, 0], P[:, 1, 1], P[:, 2, 2], P[:, 2, 3], P[:, 3, 2] = kx, ky, a, b, -1.0
    return P
