""":class:`ShadowSetup`, what every fit returns, and its matrices from a frame and frustum."""

from __future__ import annotations

from typing import NamedTuple

from shadowmath._boundary._shapes import Float, Int
from shadowmath._boundary._validate import Array, Checks, Context
from shadowmath._math._frame import LightFrame, light_entries, stack_matrix
from shadowmath._math._frustum import Frustum, OrthographicBox, projection_terms
from shadowmath._math._specialize import formulas


class ShadowSetup(NamedTuple):
    """Everything a renderer needs to draw and apply one shadow map.

    Attributes:
        frame: the :class:`LightFrame`.
        frustum: the fitted :class:`Frustum` of a point or spot light, or the
            :class:`OrthographicBox` of a directional light.
        world_to_light: ``(*batch, 4, 4)`` world to light coordinates.
        blocker_to_world: ``(*batch, 4, 4)`` the blocker's placement (identity if none).
        blocker_to_clip: ``(*batch, 4, 4)`` the article's ``M_BlockerLocalToShadowMap``:
            draw the shadow map with it (``gl_Position = blocker_to_clip * p_local``).
        world_to_texture: ``(*batch, 4, 4)`` the article's ``M_WorldToShadowMapST``:
            world points to ``(s q, t q, r q, q)``.
        casters_used: ``(*batch,)`` integers, set by :func:`fit_shadow`: how many casters
            the fit used (triangles when they were given as :class:`Triangles` or a
            :class:`Mesh`, points otherwise). A spot light uses those that reach into its
            cone's square pyramid (the rest cannot shadow what it lights); ``0`` marks its
            empty fit (nothing to shadow: a frustum inside the pyramid that no caster
            enters). Point and directional lights use every caster. ``None`` from the
            other fits.
        map_size: ``(width, height)`` in texels of the map the fit was made for, set by
            :func:`fit_shadow` (and :class:`ShadowFitter`), so that
            :func:`pcss_parameters` reads it; ``None`` from the other fits. Python ints
            (out of ``jax.jit`` or ``jax.vmap`` JAX makes them arrays, as it does every
            leaf of a result: ``pcss_parameters`` reads those too, outside the
            transformation).
    """

    frame: LightFrame
    frustum: Frustum | OrthographicBox
    world_to_light: Float[Array, "*batch 4 4"]
    blocker_to_world: Float[Array, "*batch 4 4"]
    blocker_to_clip: Float[Array, "*batch 4 4"]
    world_to_texture: Float[Array, "*batch 4 4"]
    casters_used: Int[Array, "*#batch"] | None = None
    map_size: tuple[int, int] | tuple[Int[Array, "*#batch"], Int[Array, "*#batch"]] | None = None


def setup_from(
    ctx: Context, checks: Checks, frame: LightFrame, frustum: Frustum, B: Array | None
) -> ShadowSetup:
    """The OpenGL matrices of a trusted frame and perspective frustum, in closed form."""
    xp = ctx.xp
    F = formulas(xp)
    W = light_entries(xp, frame)
    clip = F.clip_rows(W, projection_terms(xp, frustum))
    tex = F.texture_rows(clip)
    if B is not None:
        b = tuple(B[..., i // 4, i % 4] for i in range(16))
        clip = F.compose_rows(clip, b)
    shape = tuple(frustum.near.shape)
    placement = xp.eye(4, dtype=ctx.dtype) if B is None else B
    return ShadowSetup(
        frame=frame,
        frustum=frustum,
        world_to_light=checks.poison(stack_matrix(xp, W), 2),
        blocker_to_world=xp.broadcast_to(placement, (*shape, 4, 4)),
        blocker_to_clip=checks.poison(stack_matrix(xp, clip), 2),
        world_to_texture=checks.poison(stack_matrix(xp, tex), 2),
    )
