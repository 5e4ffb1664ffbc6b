"""Nagy's projective shadow texture: per blocker, draw its silhouette map (pass 1) and
apply it to the receivers (pass 2) with back-face and ``q <= 0`` elimination."""

from __future__ import annotations

from collections.abc import Sequence

import moderngl
import numpy as np
from numpy.typing import NDArray

from shadowmath import ShadowSetup, fit_shadow, receiver_texture_matrix

from ._context import program, set_matrix, set_uniform
from ._resources import Bodies, GpuMesh, GpuScene, Prepared, PreparedLight, ShadowPass


def draw_shadow_map(
    ctx: moderngl.Context,
    mesh: GpuMesh,
    blocker_to_clip: NDArray[np.float64],
    size: tuple[int, int],
) -> moderngl.Texture:
    """Pass 1: the blocker's flat-colour silhouette into a new one-channel 8-bit texture.

    No depth test, no culling, no blending: Nagy's Optimization Tip #3.
    """
    tex = ctx.texture(size, 1, dtype="f1")
    # Clamp to edge: receiver points outside the frustum read the untouched border.
    tex.repeat_x = False
    tex.repeat_y = False
    tex.filter = (moderngl.NEAREST, moderngl.NEAREST)
    fbo = ctx.framebuffer(color_attachments=[tex])
    prog = program(ctx, "shadow_map.vert", "shadow_map.frag")
    set_matrix(prog, "blocker_to_clip", blocker_to_clip)
    try:
        fbo.use()
        fbo.viewport = (0, 0, *size)
        ctx.disable(moderngl.DEPTH_TEST | moderngl.CULL_FACE | moderngl.BLEND)
        fbo.clear(0.0, 0.0, 0.0, 0.0)
        mesh.render(prog)
    finally:
        fbo.release()
    return tex


def read_mask(tex: moderngl.Texture) -> NDArray[np.float32]:
    """A one-channel 8-bit texture as a ``(height, width)`` float32 array in ``[0, 1]``."""
    w, h = tex.size
    data = np.frombuffer(tex.read(alignment=1), dtype=np.uint8).reshape(h, w)
    return (data / np.float32(255.0)).astype(np.float32)


def fit_per_blocker(
    blockers: Sequence[Prepared], light: PreparedLight, map_size: tuple[int, int]
) -> tuple[ShadowSetup, ...]:
    """One ``fit_shadow`` per blocker, in its local coordinates (the article's set-up);
    a directional light through its homogeneous ``(x, y, z, 0)`` (an orthographic map)."""
    position = light.homogeneous if light.directional else light.position
    return tuple(
        fit_shadow(position, b.vertices, map_size, blocker_to_world=b.to_world) for b in blockers
    )


def blocker_maps(
    scene: GpuScene, setups: tuple[ShadowSetup, ...]
) -> list[tuple[moderngl.Texture, NDArray[np.float32]]]:
    """Pass 1 for each blocker: the map texture (released with the scene) and its array."""
    maps = []
    offset = len(scene.receivers)
    for bi, setup in enumerate(setups):
        m = np.asarray(setup.blocker_to_clip, dtype=np.float64)
        tex = scene.keep(draw_shadow_map(scene.ctx, scene.meshes[offset + bi], m, scene.map_size))
        maps.append((tex, read_mask(tex)))
    return maps


class TexturePass(ShadowPass):
    """``method="texture"``: each blocker's map projected onto every receiver.

    The receiver is drawn with ``receiver_texture_matrix(setup, to_world)`` to
    ``(s q, t q, r q, q)``, divided per fragment (``textureProj``); no shadow where
    ``q <= 0`` (behind the light) or on faces with ``N . (L - P) <= 0``.
    """

    def setup_count(self, blockers: Bodies) -> int:
        return len(blockers)

    def fit(
        self, receivers: Bodies, blockers: Bodies, light: PreparedLight, map_size: tuple[int, int]
    ) -> tuple[ShadowSetup, ...]:
        return fit_per_blocker(blockers, light, map_size)

    def shadowed(self, scene: GpuScene) -> tuple[int, ...]:
        return tuple(range(len(scene.receivers)))

    def draw_mask(
        self, scene: GpuScene, light: PreparedLight, setups: tuple[ShadowSetup, ...]
    ) -> tuple[NDArray[np.float32], ...]:
        prog = program(scene.ctx, "surface.vert", "receiver_mask.frag")
        set_matrix(prog, "world_to_clip", scene.world_to_clip)
        set_uniform(prog, "shadow_map", 0)
        set_uniform(prog, "light_position", tuple(light.position))
        maps = blocker_maps(scene, setups)
        scene.bind_mask()
        for setup, (tex, _) in zip(setups, maps, strict=True):
            tex.use(location=0)
            for ri, receiver in enumerate(scene.receivers):
                set_matrix(prog, "body_to_world", receiver.to_world)
                set_matrix(
                    prog, "body_to_texture", receiver_texture_matrix(setup, receiver.to_world)
                )
                scene.bind_record(prog, ri)
                scene.meshes[ri].render(prog)
        return tuple(array for _, array in maps)
