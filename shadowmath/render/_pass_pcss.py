"""Percentage-closer soft shadows (Fernando 2005): one depth map per light, a blocker
search and a filter of the width the light's size, the blockers' and the receiver's
depths give, with the quantities of :func:`shadowmath.pcss_parameters`."""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np
from numpy.typing import NDArray

from shadowmath import OrthographicBox, ShadowSetup

from ._context import program, set_matrix, set_uniform
from ._pass_depth import (
    DepthPass,
    depth_bias_option,
    draw_depth_map,
    draw_receiving,
    fit_depth,
    read_depth,
    world_to_light_clip,
)
from ._resources import Bodies, GpuScene, PreparedLight

#: The default ``glPolygonOffset(factor, units)`` of a PCSS map: one depth step. The map
#: holds faces turned from the light, so a lit face is compared with its caster's far
#: side and needs no slope bias; a larger one lifts the shadow off the contact line (a
#: floor point beside a caster's foot lies a hair behind the face the map holds).
PCSS_POLYGON_OFFSET = (0.0, 1.0)


class PcssUniforms(NamedTuple):
    """What the PCSS shader takes from one map's quantities.

    Attributes:
        k: ``(2,)`` texels per unit of stored window depth, along ``s`` and ``t``.
        d_near: the window depth of the near plane (where the search region is widest).
    """

    k: tuple[float, float]
    d_near: float


def light_size_option(light_size: object) -> float:
    """The ``light_size`` option, checked: a finite float ``>= 0``."""
    try:
        size = float(light_size)  # type: ignore[arg-type]
    except (TypeError, ValueError):
        size = math.nan
    if isinstance(light_size, bool) or not (math.isfinite(size) and size >= 0):
        raise ValueError(f"light_size: expected a finite number >= 0, got {light_size!r}")
    return size


def pcss_uniforms(
    setup: ShadowSetup, light: PreparedLight, light_size: float, map_size: tuple[int, int]
) -> PcssUniforms:
    """The shader's ``k`` and ``d_near`` for one map: :func:`shadowmath.pcss_parameters`
    with the light's radius (a point light) or angular radius in radians (a directional
    light)."""
    return _provisional_parameters(setup, light, light_size, map_size)


def _provisional_parameters(
    setup: ShadowSetup, light: PreparedLight, size: float, map_size: tuple[int, int]
) -> PcssUniforms:
    # PROVISIONAL until shadowmath.pcss_parameters lands (branch h-pcss).
    fr = setup.frustum
    n, f = float(fr.near), float(fr.far)
    texels = np.array(map_size, float) * np.array([float(fr.margin_x), float(fr.margin_y)]) / 2
    if isinstance(fr, OrthographicBox):
        per = texels / np.array([float(fr.half_width), float(fr.half_height)])
        k = math.tan(size) * (f - n) * per
    else:
        per = texels / np.array([float(fr.rx_max), float(fr.ry_max)])
        k = size * (f - n) / (f * n) * per
    return PcssUniforms((float(k[0]), float(k[1])), 0.0)


class PcssPass(DepthPass):
    """``method="pcss"``: percentage-closer soft shadows from one depth map per light.

    The map holds every body's faces turned from the light (:func:`draw_depths`'s
    ``back_faces``), with a border that holds the widest search region (the fit is
    drawn again with it); the mask pass searches for blockers over
    ``k |d_R - d_near|`` texels and filters over ``k (d_R - d_B)``
    (``pcss_mask.frag``).
    """

    def __init__(self, light_size: float, bias: tuple[float, float] | None = None) -> None:
        self.light_size = light_size_option(light_size)
        self.pcf_radius = 0
        self.bias = PCSS_POLYGON_OFFSET if bias is None else depth_bias_option(bias, 0)

    def fit(
        self, receivers: Bodies, blockers: Bodies, light: PreparedLight, map_size: tuple[int, int]
    ) -> tuple[ShadowSetup, ...]:
        """:func:`fit_depth` with a border of the widest search region over the bodies'
        depths in the first fit (the border narrows ``k``: the region only shrinks)."""
        (point,) = self.light_points(light)
        first = fit_depth(receivers, blockers, point, map_size)
        border = search_border(first, light, self.light_size, map_size, [*receivers, *blockers])
        return (fit_depth(receivers, blockers, point, map_size, border),)

    def draw_mask(
        self, scene: GpuScene, light: PreparedLight, setups: tuple[ShadowSetup, ...]
    ) -> tuple[NDArray[np.float32], ...]:
        (setup,) = setups
        depth = draw_depth_map(scene, world_to_light_clip(setup), self.bias, back_faces=True)
        depth.compare_func = ""  # plain depths: the search averages them
        uniforms = pcss_uniforms(setup, light, self.light_size, scene.map_size)
        prog = program(scene.ctx, "surface.vert", "pcss_mask.frag")
        set_matrix(prog, "world_to_clip", scene.world_to_clip)
        set_uniform(prog, "depth_map", 0)
        set_uniform(prog, "light", tuple(light.homogeneous))
        set_uniform(prog, "k", uniforms.k)
        set_uniform(prog, "d_near", uniforms.d_near)
        scene.bind_mask()
        depth.use(location=0)
        draw_receiving(scene, prog, np.asarray(setup.world_to_texture, dtype=np.float64))
        return (read_depth(depth),)


def search_border(
    setup: ShadowSetup,
    light: PreparedLight,
    light_size: float,
    map_size: tuple[int, int],
    bodies: Bodies,
) -> int:
    """The widest search region ``k |d_R - d_near|`` in texels (rounded up) over the
    bodies' vertices inside the map's depth range, at most a quarter of the map."""
    world = np.concatenate([b.world_vertices() for b in bodies])
    stq = np.c_[world, np.ones(len(world))] @ np.asarray(setup.world_to_texture, np.float64).T
    ahead = stq[:, 3] > 0  # behind a point light: not in its map
    depth = np.clip(stq[ahead, 2] / stq[ahead, 3], 0.0, 1.0)
    uniforms = pcss_uniforms(setup, light, light_size, map_size)
    widest = max(uniforms.k) * float(np.max(np.abs(depth - uniforms.d_near), initial=0.0))
    return int(min(math.ceil(widest) + 1, min(map_size) // 4))
