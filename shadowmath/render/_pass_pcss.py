"""Percentage-closer soft shadows (Fernando 2005): one depth map per light, a blocker
search and a filter of the width the light's size, the blockers' and the receiver's
depths give, with the quantities of :func:`shadowmath.pcss_parameters`."""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np
from numpy.typing import NDArray

from shadowmath import PcssParameters, ShadowSetup, pcss_border_texels, pcss_parameters

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


def map_parameters(
    setup: ShadowSetup, light: PreparedLight, light_size: float, map_size: tuple[int, int]
) -> PcssParameters:
    """One map's :func:`shadowmath.pcss_parameters`, with the light's radius (a point
    light) or angular radius in radians (a directional light)."""
    if light.directional:
        return pcss_parameters(setup, angular_radius=light_size, map_size=map_size)
    return pcss_parameters(setup, light_radius=light_size, map_size=map_size)


def pcss_uniforms(parameters: PcssParameters) -> PcssUniforms:
    """The shader's ``k`` and ``d_near`` from one map's parameters."""
    k = np.asarray(parameters.texels_per_depth, dtype=np.float64)
    return PcssUniforms((float(k[0]), float(k[1])), float(parameters.near_depth))


class PcssPass(DepthPass):
    """``method="pcss"``: percentage-closer soft shadows from one depth map per light.

    The map holds every body's faces turned from the light (:func:`draw_depths`'s
    ``back_faces``), with a border that holds the widest search region
    (:func:`shadowmath.pcss_border_texels`; the fit is drawn again with it); the mask
    pass searches for blockers over ``k |d_R - d_near|`` texels and filters over
    ``k (d_R - d_B)`` (``pcss_mask.frag``).
    """

    def __init__(self, light_size: float, bias: tuple[float, float] | None = None) -> None:
        self.light_size = light_size_option(light_size)
        self.pcf_radius = 0
        self.bias = PCSS_POLYGON_OFFSET if bias is None else depth_bias_option(bias, 0)

    def fit(
        self, receivers: Bodies, blockers: Bodies, light: PreparedLight, map_size: tuple[int, int]
    ) -> tuple[ShadowSetup, ...]:
        """:func:`fit_depth` refitted with :func:`shadowmath.pcss_border_texels` of the
        first fit's parameters (the border narrows ``k``: it still holds), at most a
        quarter of the map."""
        (point,) = self.light_points(light)
        first = fit_depth(receivers, blockers, point, map_size)
        border = pcss_border_texels(map_parameters(first, light, self.light_size, map_size))
        border = min(border, min(map_size) // 4)
        return (fit_depth(receivers, blockers, point, map_size, border),)

    def draw_mask(
        self, scene: GpuScene, light: PreparedLight, setups: tuple[ShadowSetup, ...]
    ) -> tuple[NDArray[np.float32], ...]:
        (setup,) = setups
        depth = draw_depth_map(scene, world_to_light_clip(setup), self.bias, back_faces=True)
        depth.compare_func = ""  # plain depths: the search averages them
        uniforms = pcss_uniforms(map_parameters(setup, light, self.light_size, scene.map_size))
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
