"""The whole of Nagy's projective shadow texture set-up in one call."""

from __future__ import annotations

from typing import Any, Literal, NamedTuple

from ._backend import (
    Array,
    Checks,
    all_finite,
    batch_shape,
    non_finite,
    prepare,
    require_last,
    require_matrix,
)
from ._frame import LightFrame, light_frame, world_to_light
from ._frustum import Frustum, adaptive_frustum, blocker_projection, receiver_projection


class ShadowSetup(NamedTuple):
    """Everything a renderer needs to draw and apply one shadow map.

    Attributes:
        frame: the :class:`LightFrame`.
        frustum: the adaptive :class:`Frustum`.
        world_to_light: ``(*batch, 4, 4)`` world to light coordinates.
        blocker_to_world: ``(*batch, 4, 4)`` the blocker's placement (identity if none).
        blocker_to_clip: ``(*batch, 4, 4)`` the article's ``M_BlockerLocalToShadowMap``:
            draw the shadow map with it (``gl_Position = blocker_to_clip * p_local``).
        world_to_texture: ``(*batch, 4, 4)`` the article's ``M_WorldToShadowMapST``:
            world points to ``(s q, t q, r q, q)``.
    """

    frame: LightFrame
    frustum: Frustum
    world_to_light: Array
    blocker_to_world: Array
    blocker_to_clip: Array
    world_to_texture: Array


def _transform_points(xp: Any, checks: Checks, M: Array, p: Array) -> Array:
    """``(*batch, N, 3)`` points through ``(*batch, 4, 4)``, with the homogeneous divide.

    The checks run before the arithmetic, so that bad input raises its own
    ``ValueError`` rather than a NumPy warning from ``inf * 0`` or ``1 / 0``.
    """
    checks.require(all_finite(xp, p, 2), non_finite("blocker_vertices"))
    w = xp.sum(p * M[..., None, 3, :3], axis=-1) + M[..., None, 3, 3]
    checks.require(
        xp.all(w > 0, axis=-1),
        "blocker_to_world: sends a blocker vertex to w <= 0 (a projective placement); "
        "use an affine placement, last row (0, 0, 0, 1)",
    )
    h = xp.matmul(p, xp.matrix_transpose(M[..., :3, :3])) + M[..., None, :3, 3]
    return h / xp.where(w > 0, w, xp.ones_like(w))[..., None]


def fit_shadow(
    light_position: Any,
    blocker_vertices: Any,
    map_size: int | tuple[int, int],
    *,
    border_texels: int = 1,
    blocker_to_world: Any = None,
    margin: float | tuple[float, float] | None = None,
    near: Any = None,
    far: Any = None,
    aim: Literal["mean", "bbox"] = "mean",
    method: Literal["mdv", "optimized"] = "mdv",
) -> ShadowSetup:
    r"""Nagy's projective shadow texture for one point light and one blocker.

    .. math::

        M_\mathrm{blocker \to clip} = P \, W \, B, \qquad
        M_\mathrm{world \to texture} = T \, W

    with ``B`` the blocker's placement, ``W`` :func:`world_to_light` of the
    :func:`light_frame`, ``P`` :func:`blocker_projection` and ``T``
    :func:`receiver_projection` of the :func:`adaptive_frustum`. (The article
    writes the same products in row-vector order, ``B * W * P``.)

    Arguments:
        light_position: ``(*batch, 3)`` the point light.
        blocker_vertices: ``(*batch, N, 3)`` in the blocker's local coordinates
            (world coordinates when ``blocker_to_world`` is None).
        map_size: ``size`` or ``(width, height)`` of the shadow map in texels.
        border_texels: texels left empty on each side of the map.
        blocker_to_world: ``(*batch, 4, 4)`` the blocker's local-to-world placement.
        margin, near, far: as in :func:`adaptive_frustum`.
        aim: as in :func:`light_frame` (for ``method="mdv"``).
        method: ``"mdv"`` (default) the article's frame and symmetric frustum;
            ``"optimized"`` the frame and off-centre frustum of
            :func:`optimize_frustum` (needs JAX; the silhouette fills the map
            better, it touches the margin on all four sides). The matrices
            are used the same way either way.

    Returns:
        :class:`ShadowSetup`.

    Raises:
        ValueError: everything :func:`light_frame` and :func:`adaptive_frustum`
            raise, and a non-finite or wrongly shaped ``blocker_to_world``
            (NaN outputs under JAX transformations).

    Example:
        >>> import numpy as np
        >>> box = np.array([[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (4, 6)])
        >>> s = fit_shadow([0, 0, 0], box, 100)
        >>> clip = (s.blocker_to_clip @ np.c_[box, np.ones(8)].T).T
        >>> float(np.abs(clip[:, 0] / clip[:, 3]).max().round(6))
        0.98
    """
    ctx, a = prepare(
        light_position=light_position, vertices=blocker_vertices, blocker_to_world=blocker_to_world
    )
    xp = ctx.xp
    light, verts = a["light_position"], a["vertices"]
    require_last("light_position", light, 3, hint="a light position is (x, y, z)")
    require_last("blocker_vertices", verts, 3, min_ndim=2, hint="vertices are (*batch, N, 3)")
    checks = Checks(ctx)
    B = a["blocker_to_world"]
    if B is None:
        B = xp.eye(4, dtype=ctx.dtype)
        world_verts = verts  # no placement: the vertices exactly as given
    else:
        require_matrix("blocker_to_world", B)
        checks.require(xp.all(xp.isfinite(B), axis=(-2, -1)), non_finite("blocker_to_world"))
        world_verts = _transform_points(xp, checks, B, verts)
    options = {"border_texels": border_texels, "margin": margin, "near": near, "far": far}
    if method == "mdv":
        frame = light_frame(light, world_verts, aim=aim)
        frustum = adaptive_frustum(frame, world_verts, map_size, **options)
    elif method == "optimized":
        from ._fitting import optimize_frustum

        fit = optimize_frustum(light, world_verts, map_size, **options)
        frame, frustum = fit.frame, fit.frustum
    else:
        raise ValueError(f"method: expected 'mdv' or 'optimized', got {method!r}")
    W = world_to_light(frame)
    blocker_to_clip = xp.matmul(blocker_projection(frustum), xp.matmul(W, B))
    world_to_texture = xp.matmul(receiver_projection(frustum), W)
    shape = batch_shape(
        tuple(blocker_to_clip.shape[:-2]), tuple(B.shape[:-2]), names=("setup", "blocker_to_world")
    )
    B = xp.broadcast_to(B, (*shape, 4, 4))
    return ShadowSetup(
        frame=frame,
        frustum=frustum,
        world_to_light=checks.poison(W, 2),
        blocker_to_world=checks.poison(B, 2),
        blocker_to_clip=checks.poison(blocker_to_clip, 2),
        world_to_texture=checks.poison(world_to_texture, 2),
    )


def receiver_texture_matrix(setup: ShadowSetup, receiver_to_world: Any) -> Array:
    """Receiver local coordinates straight to homogeneous shadow-map texture coordinates.

    ``setup.world_to_texture @ receiver_to_world``: the matrix a receiver's
    vertex shader applies to its local positions to get ``(s q, t q, r q, q)``.

    Arguments:
        setup: a :class:`ShadowSetup`.
        receiver_to_world: ``(*batch, 4, 4)`` the receiver's placement.

    Returns:
        ``(*batch, 4, 4)``.

    Raises:
        ValueError: wrong shape or non-finite values (NaN under JAX transformations).

    Example:
        >>> import numpy as np
        >>> s = fit_shadow([0, 0, 0], [[-1, -1, 4], [1, 1, 4], [1, -1, 5]], 64)
        >>> bool(np.allclose(receiver_texture_matrix(s, np.eye(4)), s.world_to_texture))
        True
    """
    ctx, a = prepare(world_to_texture=setup.world_to_texture, receiver_to_world=receiver_to_world)
    xp = ctx.xp
    R = a["receiver_to_world"]
    require_matrix("receiver_to_world", R)
    checks = Checks(ctx)
    checks.require(xp.all(xp.isfinite(R), axis=(-2, -1)), non_finite("receiver_to_world"))
    return checks.poison(xp.matmul(a["world_to_texture"], R), 2)
