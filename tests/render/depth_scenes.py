"""The depth-map scenes (every body casts and receives) and their ray-cast ground truth,
shared by the moderngl and the wgpu tests."""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from shadowmath.groundtruth import segment_hits_triangles
from shadowmath.meshes import box, grid, torus
from shadowmath.render import Body, Light, look_at, perspective

from .scenes import edge_band, place, rotation, world_mesh

SIZE = (192, 144)
#: Pixels excluded on each side of an edge of the region the light reaches.
BAND = 2
#: The ray caster's segment starts this far (world units) off the surface along its
#: normal: the record's float32 positions lie up to ~1e-6 inside their own triangle.
LIFT = 1e-4


class DepthScene(NamedTuple):
    bodies: list[Body]  # every body casts and receives; the last ones are the blockers
    blockers: int  # how many of the last bodies the map's frustum is fitted to
    light: Light
    world_to_clip: np.ndarray


def _camera(eye, target, up=(0.0, 0.0, 1.0)):
    return perspective(45.0, SIZE[0] / SIZE[1], 0.1, 60.0) @ look_at(eye, target, up)


FLOOR = Body(*grid((10.0, 10.0), segments=(4, 4)), color=(0.7, 0.8, 0.9))
SCENES = {
    # an upright torus above a floor, lit from low on the side: it shadows the floor and
    # the far side of its own ring
    "torus": DepthScene(
        [
            FLOOR,
            Body(
                *torus(1.0, 0.35, segments=48, sides=24),
                to_world=place(rotation((1.0, 0.5, 0.0), 80.0), (0.0, 0.0, 1.6)),
                color=(0.9, 0.4, 0.2),
            ),
        ],
        1,
        Light((5.0, 1.0, 2.5)),
        _camera((2.0, -5.0, 4.0), (0.0, 0.0, 1.0)),
    ),
    # a box standing on the floor: contact edges, where a large bias would lift the shadow
    "box": DepthScene(
        [FLOOR, Body(*box((1.2, 1.2, 1.2)), to_world=place(rotation((0, 0, 1), 30), (0, 0, 0.6)))],
        1,
        Light((-3.0, -1.5, 3.5)),
        _camera((3.0, -5.0, 5.0), (0.0, 0.0, 0.5)),
    ),
}


def homogeneous(light: Light) -> np.ndarray:
    """``(x, y, z, 1)`` a point light, ``(x, y, z, 0)`` a directional one."""
    if light.direction is not None:
        return np.append(np.asarray(light.direction, dtype=np.float64), 0.0)
    return np.append(np.asarray(light.position, dtype=np.float64), 1.0)


class Truth(NamedTuple):
    on: np.ndarray  # pixels showing a body
    shadow: np.ndarray  # facing the light and blocked
    band: np.ndarray  # within BAND pixels of an edge of the shadow or of the lit region


def ray_cast(body: np.ndarray, position: np.ndarray, normal: np.ndarray, scene: DepthScene):
    """The ground truth of a frame's per-pixel record (body id, position, face normal)."""
    on = body >= 0
    p = position[on].astype(np.float64)
    n = normal[on].astype(np.float64)
    light = homogeneous(scene.light)
    facing = np.sum(n * (light[:3] - light[3] * p), axis=1) > 0
    blocked = np.zeros(len(p), dtype=bool)
    for b in scene.bodies:
        blocked |= segment_hits_triangles(p + LIFT * n, light, *world_mesh(b))
    shadow = np.zeros(on.shape, dtype=bool)
    shadow[on] = blocked & facing
    dark = np.zeros(on.shape, dtype=bool)
    dark[on] = blocked | ~facing  # where the light does not reach: its edges are shadow edges
    band = edge_band(shadow, BAND) | edge_band(dark, BAND) | edge_band(on, BAND)
    return Truth(on, shadow, band)


class Count(NamedTuple):
    shadowed: int  # ground-truth shadow pixels
    differ: int  # pixels that disagree
    differ_off_band: int  # of them outside the band
    acne: int  # lit in truth, shadowed in the picture, outside the band
    band: int  # pixels in the band


def compare(shadowed: np.ndarray, truth: Truth) -> Count:
    wrong = (shadowed != truth.shadow) & truth.on
    off = wrong & ~truth.band
    return Count(
        shadowed=int(truth.shadow.sum()),
        differ=int(wrong.sum()),
        differ_off_band=int(off.sum()),
        acne=int((off & shadowed).sum()),
        band=int((truth.band & truth.on).sum()),
    )
