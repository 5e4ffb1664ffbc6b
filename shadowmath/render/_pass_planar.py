"""Blinn's planar shadows: each blocker flattened onto each receiver's plane by
:func:`planar_projection`, confined to the receiver by the lit pass's body-id record
(the seeds' stencil test)."""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from shadowmath import ShadowSetup, planar_projection

from ._context import program, set_matrix
from ._pass_texture import TexturePass, blocker_maps
from ._resources import Bodies, GpuScene, PreparedLight

#: Polygon offset ``(factor, units)`` pulling Blinn's flattened blocker toward the
#: camera, so that it wins the LEQUAL depth test against its coplanar receiver.
PLANAR_POLYGON_OFFSET = (-1.0, -4.0)


class PlanarPass(TexturePass):
    """``method="planar"``: every receiver needs its ``plane``; point and directional lights
    (``planar_projection(plane, (x, y, z, 0))`` flattens along the direction).

    Drawn with a polygon offset of :data:`PLANAR_POLYGON_OFFSET`; a receiver is
    skipped for a light on the other side of its plane than the camera (the
    visible face is unlit: Blinn's back-face case). The blockers' silhouette maps
    are drawn too, from the same set-ups, so that a :class:`Frame` of either
    method holds them. The setups are :class:`TexturePass`'s, one per blocker.
    """

    def check(self, receivers: Bodies) -> None:
        for i, r in enumerate(receivers):
            if r.plane is None:
                raise ValueError(
                    f"receivers[{i}].plane: method='planar' needs each receiver's plane"
                )

    def draw_mask(
        self, scene: GpuScene, light: PreparedLight, setups: tuple[ShadowSetup, ...]
    ) -> tuple[NDArray[np.float32], ...]:
        prog = program(scene.ctx, "planar.vert", "planar_mask.frag")
        set_matrix(prog, "world_to_clip", scene.world_to_clip)
        maps = blocker_maps(scene, setups)
        scene.bind_mask()
        scene.ctx.polygon_offset = PLANAR_POLYGON_OFFSET
        offset = len(scene.receivers)
        try:
            for bi, blocker in enumerate(scene.blockers):
                set_matrix(prog, "blocker_to_world", blocker.to_world)
                for ri, receiver in enumerate(scene.receivers):
                    plane = receiver.plane
                    assert plane is not None  # render_scene checks it for this method
                    # a directional light (x, y, z, 0) is on the side its direction points to
                    side_light = np.dot(plane, light.homogeneous)
                    side_eye = np.dot(plane, scene.eye) / scene.eye[3]
                    if side_light * side_eye <= 0:
                        continue  # the camera sees the face the light does not reach
                    flatten = planar_projection(plane, light.homogeneous)
                    set_matrix(prog, "flatten", flatten)
                    scene.bind_record(prog, ri)
                    scene.meshes[offset + bi].render(prog)
        finally:
            scene.ctx.polygon_offset = (0.0, 0.0)
        return tuple(array for _, array in maps)
