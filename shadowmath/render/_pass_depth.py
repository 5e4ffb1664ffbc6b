"""Williams' shadow z-buffer: the depth of every caster seen from the light, compared
with each visible point's light depth, with a polygon-offset bias and PCF."""

from __future__ import annotations

from collections.abc import Sequence

import moderngl
import numpy as np
from numpy.typing import NDArray

from shadowmath import ShadowSetup, Triangles, fit_shadow

from ._context import program, set_matrix, set_uniform
from ._resources import Bodies, GpuScene, Prepared, PreparedLight, ShadowPass

#: Default ``glPolygonOffset(factor, units)`` of the depth map without PCF: ``factor``
#: times the depth slope of each caster triangle plus ``units`` times the smallest
#: resolvable depth step. :func:`depth_bias` widens the factor with the PCF radius.
DEPTH_POLYGON_OFFSET = (2.5, 4.0)


def depth_bias(pcf_radius: int) -> tuple[float, float]:
    """The default polygon offset for a PCF kernel of radius ``k``.

    A tap ``k`` texels from the centre reads the map where a sloped receiver's
    own depth differs from its ``r`` by up to ``k`` texels of slope along each
    axis, so the slope factor grows by 2 per unit of radius.
    """
    factor, units = DEPTH_POLYGON_OFFSET
    return factor + 2.0 * pcf_radius, units


def begin_depth_pass(
    gl: moderngl.Context, fbo: moderngl.Framebuffer, bias: tuple[float, float]
) -> None:
    """Draw depth only into ``fbo``: cleared to the far depth 1, test ``<``, writes on, no
    blending or culling (both faces of a caster), ``glPolygonOffset(*bias)``. The caller
    resets ``gl.polygon_offset`` to ``(0, 0)`` when done."""
    fbo.use()
    gl.disable(moderngl.BLEND | moderngl.CULL_FACE)
    gl.enable(moderngl.DEPTH_TEST)
    gl.depth_func = "<"
    fbo.depth_mask = True
    fbo.clear(depth=1.0)
    gl.polygon_offset = bias


def pcf_radius_option(pcf_radius: object) -> int:
    """A pass's ``pcf_radius`` option, checked: an int ``>= 0``."""
    if not isinstance(pcf_radius, int | np.integer) or pcf_radius < 0:
        raise ValueError(f"pcf_radius: expected an int >= 0, got {pcf_radius!r}")
    return int(pcf_radius)


def nonnegative_option(name: str, value: float) -> float:
    """A pass's finite ``>= 0`` option ``name`` (``normal_offset``, ``ambient``), checked."""
    if not (np.isfinite(value) and value >= 0):
        raise ValueError(f"{name}: must be finite and >= 0, got {value!r}")
    return float(value)


def depth_bias_option(bias: object, pcf_radius: int) -> tuple[float, float]:
    """A pass's ``depth_bias`` option, checked: finite ``(factor, units)``, or the default."""
    if bias is None:
        return depth_bias(pcf_radius)
    try:
        b = tuple(float(v) for v in bias)  # type: ignore[attr-defined]
    except (TypeError, ValueError):
        b = ()
    if len(b) != 2 or not all(np.isfinite(b)):
        raise ValueError(f"depth_bias: expected finite (factor, units), got {bias!r}")
    return b[0], b[1]


def fit_depth(
    receivers: Sequence[Prepared],
    blockers: Sequence[Prepared],
    light: NDArray[np.float64],
    map_size: tuple[int, int],
    pcf_radius: int = 0,
    *,
    stable: bool = False,
) -> ShadowSetup:
    """One setup per light: the sides fit all blockers (in world coordinates), with
    the border the shader's box kernel needs (``pcf_radius=``: :func:`pcf_border_texels`,
    ``max(1, pcf_radius)`` texels) so a kernel never reads past the silhouette, and
    the depth range holds every body's triangles where the map covers them
    (``fit_shadow(..., receivers=Triangles(...))``), as a user's renderer calls it.
    ``light`` is a point ``(x, y, z)`` or a homogeneous ``(x, y, z, w)``, ``w = 0`` a
    directional light (an orthographic map); ``stable`` as in :func:`fit_shadow`. A
    body outside the frustum's sides is lit by this map.
    """
    casters = np.concatenate([b.world_vertices() for b in blockers])
    corners = np.concatenate([b.world_vertices()[b.triangles] for b in [*receivers, *blockers]])
    return fit_shadow(
        light,
        casters,
        map_size,
        pcf_radius=pcf_radius,
        receivers=Triangles(corners),
        stable=stable,
    )


def world_to_light_clip(setup: ShadowSetup) -> NDArray[np.float64]:
    """``blocker_to_clip @ inverse(blocker_to_world)``: world to the light's OpenGL clip."""
    b2c = np.asarray(setup.blocker_to_clip, dtype=np.float64)
    b2w = np.asarray(setup.blocker_to_world, dtype=np.float64)
    return np.asarray(b2c @ np.linalg.inv(b2w), dtype=np.float64)


def depth_map_texture(gl: moderngl.Context, size: tuple[int, int]) -> moderngl.Texture:
    """A new depth texture of ``size`` for hardware comparison (``sampler2DShadow``):
    nearest, clamp to edge; the caller sets ``compare_func`` once it is drawn."""
    tex = gl.depth_texture(size)
    tex.repeat_x = False
    tex.repeat_y = False
    tex.filter = (moderngl.NEAREST, moderngl.NEAREST)
    return tex


def draw_depths(
    scene: GpuScene,
    fbo: moderngl.Framebuffer,
    world_to_clip: NDArray[np.float64],
    bias: tuple[float, float],
    *,
    back_faces: bool = False,
) -> None:
    """Every body's depth through ``world_to_clip`` into the whole of ``fbo``
    (:func:`begin_depth_pass`: cleared first), the polygon offset reset after.

    ``back_faces``: draw only the faces turned from the light
    (:func:`cull_faces_toward_light`), so each texel holds the surface of a closed
    caster nearest the receivers behind it."""
    gl = scene.ctx
    prog = program(gl, "depth_map.vert", "depth_map.frag")
    fbo.viewport = (0, 0, *fbo.size)
    try:
        begin_depth_pass(gl, fbo, bias)
        for body, mesh in zip(scene.bodies, scene.meshes, strict=True):
            body_to_clip = world_to_clip @ body.to_world
            if back_faces:
                cull_faces_toward_light(gl, body_to_clip)
            set_matrix(prog, "body_to_clip", body_to_clip)
            mesh.render(prog)
    finally:
        gl.polygon_offset = (0.0, 0.0)
        gl.disable(moderngl.CULL_FACE)
        gl.cull_face = "back"


def cull_faces_toward_light(gl: moderngl.Context, body_to_clip: NDArray[np.float64]) -> None:
    """Cull the faces whose outside (counter-clockwise side) faces the light: GL's front
    faces where ``body_to_clip`` reverses orientation (``det < 0``, as a camera's
    projection does: the Jacobian of ``p -> (M p)_xyz / (M p)_w`` is ``det M / w^4``),
    its back faces where it keeps it. The caller disables ``CULL_FACE`` when done."""
    gl.enable(moderngl.CULL_FACE)
    gl.cull_face = "front" if np.linalg.det(body_to_clip) < 0 else "back"


def draw_depth_map(
    scene: GpuScene,
    world_to_clip: NDArray[np.float64],
    bias: tuple[float, float],
    *,
    back_faces: bool = False,
) -> moderngl.Texture:
    """Every body's depth from the light into a new depth texture (released with the scene),
    set up for hardware comparison (``sampler2DShadow``, ``<=``, nearest, clamp to edge);
    ``back_faces`` as in :func:`draw_depths`."""
    tex: moderngl.Texture = scene.keep(depth_map_texture(scene.ctx, scene.map_size))
    fbo = scene.ctx.framebuffer(depth_attachment=tex)
    try:
        draw_depths(scene, fbo, world_to_clip, bias, back_faces=back_faces)
    finally:
        fbo.release()
    tex.compare_func = "<="
    return tex


def draw_receiving(
    scene: GpuScene, prog: moderngl.Program, world_to_texture: NDArray[np.float64]
) -> None:
    """Every body into the bound mask target through ``prog``, with its ``body_to_world``,
    ``body_to_texture = world_to_texture @ body_to_world`` and record (:meth:`bind_record`)."""
    for i, (body, mesh) in enumerate(zip(scene.bodies, scene.meshes, strict=True)):
        set_matrix(prog, "body_to_world", body.to_world)
        set_matrix(prog, "body_to_texture", world_to_texture @ body.to_world)
        scene.bind_record(prog, i)
        mesh.render(prog)


def read_depth(tex: moderngl.Texture) -> NDArray[np.float32]:
    """A depth texture as ``(height, width)`` float32 window depths; row 0 is ``t = 0``."""
    w, h = tex.size
    tex.compare_func = ""  # reading back does not compare, but leave no doubt
    data = np.frombuffer(tex.read(alignment=1), dtype=np.float32).reshape(h, w).copy()
    tex.compare_func = "<="
    return data


class DepthPass(ShadowPass):
    """``method="depth"``: Williams' shadow z-buffer, one map per light.

    Every body casts and receives (the torus shadows itself and the floor, a box its
    floor): the map holds the depth of all bodies, drawn through one setup fitted to
    the blockers (:func:`fit_depth`) with ``glPolygonOffset(*bias)``; the mask pass
    compares each visible point's ``r`` over a ``(2k + 1)^2`` box of texels.
    """

    def __init__(self, pcf_radius: int = 0, bias: tuple[float, float] | None = None) -> None:
        self.pcf_radius = pcf_radius_option(pcf_radius)
        self.bias = depth_bias_option(bias, self.pcf_radius)

    def setup_count(self, blockers: Bodies) -> int:
        return 1

    def light_points(self, light: PreparedLight) -> NDArray[np.float64]:
        """``(count, 3 or 4)``: the points the maps are drawn from, one per setup: the
        light's own (a directional light's homogeneous ``(x, y, z, 0)``)."""
        return (light.homogeneous if light.directional else light.position)[None]

    def fit(
        self, receivers: Bodies, blockers: Bodies, light: PreparedLight, map_size: tuple[int, int]
    ) -> tuple[ShadowSetup, ...]:
        """One :func:`fit_depth` from each of :meth:`light_points`."""
        points = self.light_points(light)
        return tuple(fit_depth(receivers, blockers, a, map_size, self.pcf_radius) for a in points)

    def draw_mask(
        self, scene: GpuScene, light: PreparedLight, setups: tuple[ShadowSetup, ...]
    ) -> tuple[NDArray[np.float32], ...]:
        (setup,) = setups
        depth = draw_depth_map(scene, world_to_light_clip(setup), self.bias)
        prog = program(scene.ctx, "surface.vert", "depth_mask.frag")
        set_matrix(prog, "world_to_clip", scene.world_to_clip)
        set_uniform(prog, "depth_map", 0)
        set_uniform(prog, "light", tuple(light.homogeneous))
        set_uniform(prog, "pcf_radius", self.pcf_radius)
        scene.bind_mask()
        depth.use(location=0)
        draw_receiving(scene, prog, np.asarray(setup.world_to_texture, dtype=np.float64))
        return (read_depth(depth),)
