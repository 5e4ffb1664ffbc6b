"""Soft shadows from a parallelogram area light: the average of the hard shadows of
``area_light_samples`` point samples, two ways.

* ``method="soft"`` (seed 003): per sample, Williams' depth map from the sample, its hard
  shadow added into the light's mask with weight ``1 / count`` (ADD blending).
* ``method="radiance"`` (Heckbert and Herf): per planar receiver, a radiance texture over
  a parallelogram around it: per sample, the blockers drawn through
  ``pyramid_to_unit_cube(sample, corner, edge_u, edge_v)`` (black where they hide the
  sample), accumulated with weights ``1 / count``; the receiver is then drawn with it.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import moderngl
import numpy as np
from numpy.typing import NDArray

from shadowmath import ShadowSetup, area_light_samples, pyramid_to_unit_cube

from ._context import image_size, program, resolve_context, set_matrix, set_uniform
from ._pass_depth import (
    DepthPass,
    depth_map_texture,
    draw_depths,
    draw_receiving,
    world_to_light_clip,
)
from ._resources import (
    Bodies,
    Body,
    GpuMesh,
    GpuScene,
    Light,
    Prepared,
    PreparedLight,
    ShadowPass,
    float_texture,
    prepare_bodies,
    prepare_light,
)

#: The radiance pass keeps blockers from ``z = -RADIANCE_EPSILON`` (just behind the
#: receiver's plane, in the unit-cube depth ``z = 1/λ - 1``) to ``z = RADIANCE_Z_MAX``
#: (``λ ≈ 1e-4``: a hair's breadth from the light sample).
RADIANCE_EPSILON = 1e-5
RADIANCE_Z_MAX = 1e4

_QUAD = np.array([-1, -1, 1, -1, -1, 1, 1, 1], dtype=np.float32)


def check_samples(samples: Any) -> int:
    if not isinstance(samples, int | np.integer) or isinstance(samples, bool) or samples < 1:
        raise ValueError(f"samples: expected an int >= 1, got {samples!r}")
    return int(samples)


def light_samples(
    name: str, light: PreparedLight, samples: int, seed: int | None
) -> NDArray[np.float64]:
    """``(samples, 3)`` stratified jittered points of an area light (:func:`area_light_samples`)."""
    if light.edges is None:
        raise ValueError(
            f"{name}: soft shadows need an area light, Light(position, edge_u=..., edge_v=...)"
        )
    eu, ev = light.edges
    return np.asarray(area_light_samples(light.corner, eu, ev, samples, seed=seed), np.float64)


def receiver_parallelogram(
    name: str, receiver: Prepared
) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]:
    """``(corner, edge_u, edge_v)``: the rectangle around a planar receiver, in its plane.

    ``edge_u`` runs along the world axis least aligned with the plane's normal, made
    orthogonal to it (the floor ``z = 0`` gets ``u`` along ``x``, ``v`` along ``y``).
    """
    if receiver.plane is None:
        raise ValueError(f"{name}: method='radiance' needs a plane on every receiver")
    normal = receiver.plane[:3] / np.linalg.norm(receiver.plane[:3])
    axis = np.eye(3)[np.argmin(np.abs(normal))]
    e1 = axis - (axis @ normal) * normal
    e1 /= np.linalg.norm(e1)
    e2 = np.cross(normal, e1)
    v = receiver.world_vertices()
    centre = v.mean(axis=0)
    origin = centre - (normal @ centre + receiver.plane[3] / np.linalg.norm(receiver.plane[:3])) * (
        normal
    )
    u, w = (v - origin) @ e1, (v - origin) @ e2
    pad = 1e-6 * max(float(np.ptp(u)), float(np.ptp(w)), 1e-300)
    u0, u1, w0, w1 = u.min() - pad, u.max() + pad, w.min() - pad, w.max() + pad
    return origin + u0 * e1 + w0 * e2, (u1 - u0) * e1, (w1 - w0) * e2


def world_to_parallelogram(
    corner: NDArray[np.float64], edge_u: NDArray[np.float64], edge_v: NDArray[np.float64]
) -> NDArray[np.float64]:
    """``(4, 4)`` world point ``corner + u edge_u + v edge_v (+ normal offset)`` to
    ``(u, v, 0, 1)``: the dual basis of the edges."""
    dual = np.linalg.pinv(np.stack([edge_u, edge_v], axis=1))  # (2, 3)
    m = np.zeros((4, 4))
    m[:2, :3] = dual
    m[:2, 3] = -dual @ corner
    m[3, 3] = 1.0
    return m


def unit_cube_to_clip() -> NDArray[np.float64]:
    """``(4, 4)``: Heckbert and Herf's unit box to OpenGL clip space: ``x, y`` from
    ``[0, 1]`` to ``[-1, 1]``, unit-cube depth ``z`` from ``[-ε, z_max]`` to ``[-1, 1]``
    (points behind the receiver and beyond the light are clipped)."""
    eps, top = RADIANCE_EPSILON, RADIANCE_Z_MAX
    return np.array(
        [
            [2.0, 0.0, 0.0, -1.0],
            [0.0, 2.0, 0.0, -1.0],
            [0.0, 0.0, 2.0 / (top + eps), 2.0 * eps / (top + eps) - 1.0],
            [0.0, 0.0, 0.0, 1.0],
        ]
    )


def draw_radiance(
    ctx: moderngl.Context,
    blockers: Sequence[tuple[GpuMesh, NDArray[np.float64]]],
    samples: NDArray[np.float64],
    parallelogram: tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]],
    size: tuple[int, int],
) -> tuple[moderngl.Texture, NDArray[np.float32]]:
    """Heckbert and Herf's radiance texture (visibility only) of one receiver parallelogram.

    Per sample ``a``: the blockers (mesh, ``to_world``) drawn with
    ``unit_cube_to_clip() @ pyramid_to_unit_cube(a, corner, edge_u, edge_v) @ to_world``
    as flat 1 on a cleared 0 (no depth test: a texel is hidden once however many
    triangles cover it), then added with weight ``1 / count`` into the blocked
    fraction (the accumulation buffer). The returned texture (clamp to edge, linear,
    the caller releases it) and ``(h, w)`` array hold the visibility ``1 - blocked``;
    row ``i``, column ``j`` is the texel centred on
    ``corner + (j + 1/2)/w edge_u + (i + 1/2)/h edge_v``.
    """
    corner, edge_u, edge_v = parallelogram
    cube = np.asarray(pyramid_to_unit_cube(samples, corner, edge_u, edge_v), dtype=np.float64)
    to_clip = unit_cube_to_clip() @ cube  # (count, 4, 4)
    weight = 1.0 / len(samples)
    coverage = float_texture(ctx, size, 1)
    blocked = float_texture(ctx, size, 1)
    cover_fbo = ctx.framebuffer([coverage])
    sum_fbo = ctx.framebuffer([blocked])
    quad = ctx.buffer(_QUAD.tobytes())
    silhouette = program(ctx, "shadow_map.vert", "shadow_map.frag")
    accumulate = program(ctx, "fullscreen.vert", "radiance_accumulate.frag")
    quad_vao = ctx.vertex_array(accumulate, [(quad, "2f", "corner")])
    try:
        sum_fbo.use()
        sum_fbo.viewport = (0, 0, *size)
        sum_fbo.clear(0.0, 0.0, 0.0, 0.0)
        set_uniform(accumulate, "coverage", 0)
        set_uniform(accumulate, "weight", weight)
        for sample_to_clip in to_clip:
            cover_fbo.use()
            cover_fbo.viewport = (0, 0, *size)
            ctx.disable(moderngl.DEPTH_TEST | moderngl.CULL_FACE | moderngl.BLEND)
            cover_fbo.clear(0.0, 0.0, 0.0, 0.0)
            for mesh, to_world in blockers:
                set_matrix(silhouette, "blocker_to_clip", sample_to_clip @ to_world)
                mesh.render(silhouette)
            sum_fbo.use()
            sum_fbo.viewport = (0, 0, *size)
            ctx.enable(moderngl.BLEND)
            ctx.blend_equation = (moderngl.FUNC_ADD, moderngl.FUNC_ADD)
            ctx.blend_func = moderngl.ONE, moderngl.ONE
            coverage.use(location=0)
            quad_vao.render(moderngl.TRIANGLE_STRIP)
        w, h = size
        total = np.frombuffer(blocked.read(), dtype=np.float32).reshape(h, w)
        visibility = np.clip(1.0 - total, 0.0, 1.0).astype(np.float32)
        result = ctx.texture(size, 1, visibility.tobytes(), dtype="f4")
        result.repeat_x = False
        result.repeat_y = False
        result.filter = (moderngl.LINEAR, moderngl.LINEAR)
    finally:
        ctx.disable(moderngl.BLEND)
        for obj in (quad_vao, quad, cover_fbo, sum_fbo, coverage, blocked):
            obj.release()
    return result, visibility


def radiance_texture(
    corner: Any,
    edge_u: Any,
    edge_v: Any,
    blockers: Sequence[Body],
    light: Light,
    *,
    samples: int = 16,
    size: int | tuple[int, int] = 256,
    seed: int | None = 0,
    ctx: moderngl.Context | None = None,
) -> NDArray[np.float32]:
    r"""Heckbert and Herf's radiance texture: how much of an area light each texel sees.

    The receiver is the parallelogram ``corner + u edge_u + v edge_v``
    (``0 <= u, v <= 1``; fit it around a planar receiver polygon). For each of
    ``samples`` stratified jittered points ``a`` of the light
    (:func:`shadowmath.area_light_samples`), the blockers are drawn through
    ``pyramid_to_unit_cube(a, corner, edge_u, edge_v)`` (mapped from the unit box to
    clip space, keeping what lies between the receiver's plane and the sample) as 1 on
    a cleared 0, and added into an accumulator with weight ``1 / samples``. The
    result is the visibility ``1 - blocked``: the fraction of the samples the texel
    sees (the light's irradiance factors ``cos θ cos θ' / r^2`` are left out).

    Arguments:
        corner, edge_u, edge_v: ``(3,)`` the receiver's parallelogram in world
            coordinates.
        blockers: the bodies that cast shadows on it.
        light: an area light (``Light(centre, edge_u=..., edge_v=...)``).
        samples: light samples ``>= 1``.
        size: ``size`` or ``(width, height)`` of the texture in texels.
        seed: the jitter's seed (:func:`shadowmath.area_light_samples`); None: fresh.
        ctx: a moderngl context; default the shared EGL :func:`standalone_context`.

    Returns:
        ``(height, width)`` float32 visibility in ``[0, 1]``, in steps of ``1 / samples``;
        row ``i``, column ``j`` is the texel centred on
        ``corner + (j + 1/2)/width edge_u + (i + 1/2)/height edge_v`` (row 0 is
        ``v = 0``: flip it, ``[::-1]``, to show it with ``v`` upward).

    Raises:
        ValueError: bad corner or edges (non-finite, zero or parallel edges), a light
            sample in the receiver's plane, bad blockers, a point light, a bad
            ``samples`` or ``size``.
        GLUnavailableError: no OpenGL context could be created.

    Example:
        >>> from shadowmath.meshes import grid
        >>> from shadowmath.render import Body, Light
        >>> at_height_1 = [[1, 0, 0, 0], [0, 1, 0, 0], [0, 0, 1, 1.0], [0, 0, 0, 1]]
        >>> square = Body(*grid((1.0, 1.0)), to_world=at_height_1)
        >>> light = Light([0.0, 0.0, 3.0], edge_u=[0.5, 0, 0], edge_v=[0, 0.5, 0])
        >>> vis = radiance_texture([-2, -2, 0], [4, 0, 0], [0, 4, 0], [square], light,
        ...                        samples=4, size=16)
        >>> float(vis[8, 8]), float(vis[0, 0])  # under the square, and far off
        (0.0, 1.0)
    """
    count = check_samples(samples)
    texels = image_size("size", size)
    para = []
    for field, value in (("corner", corner), ("edge_u", edge_u), ("edge_v", edge_v)):
        arr = np.asarray(value, dtype=np.float64)
        if arr.shape != (3,) or not np.all(np.isfinite(arr)):
            raise ValueError(f"{field}: expected finite (x, y, z), got {value!r}")
        para.append(arr)
    prepared = prepare_light("light", light)
    points = light_samples("light", prepared, count, seed)
    bodies = prepare_bodies("blockers", blockers)
    gl = resolve_context(ctx)
    meshes = [GpuMesh(gl, b.vertices, b.triangles) for b in bodies]
    try:
        tex, visibility = draw_radiance(
            gl,
            [(m, b.to_world) for m, b in zip(meshes, bodies, strict=True)],
            points,
            (para[0], para[1], para[2]),
            texels,
        )
        tex.release()
    finally:
        for m in meshes:
            m.release()
    return visibility


class SoftPass(DepthPass):
    """``method="soft"``: seed 003's averaged hard shadows, one depth map per light sample.

    Every body casts and receives, as with ``method="depth"``: per sample ``a`` of the
    area light, :func:`fit_depth` from ``a``, every body drawn into a depth map with
    ``glPolygonOffset(*bias)``, and every visible point's comparison (PCF of radius
    ``k``) added into the mask with weight ``1 / samples``. ``setups[l]`` are the
    samples' setups; ``shadow_maps[l]`` is empty (one map per sample would be many).
    """

    def __init__(
        self,
        samples: int,
        seed: int | None,
        pcf_radius: int = 0,
        bias: tuple[float, float] | None = None,
    ) -> None:
        self.samples = check_samples(samples)
        self.seed = seed
        super().__init__(pcf_radius, bias)

    def setup_count(self, blockers: Bodies) -> int:
        return self.samples

    def light_points(self, light: PreparedLight) -> NDArray[np.float64]:
        """The area light's samples (:func:`light_samples`)."""
        return light_samples("lights", light, self.samples, self.seed)

    def draw_mask(
        self, scene: GpuScene, light: PreparedLight, setups: tuple[ShadowSetup, ...]
    ) -> tuple[NDArray[np.float32], ...]:
        gl = scene.ctx
        depth = depth_map_texture(gl, scene.map_size)
        fbo = gl.framebuffer(depth_attachment=depth)
        prog = program(gl, "surface.vert", "soft_mask.frag")
        set_matrix(prog, "world_to_clip", scene.world_to_clip)
        set_uniform(prog, "depth_map", 0)
        set_uniform(prog, "light_centre", tuple(light.position))
        set_uniform(prog, "pcf_radius", self.pcf_radius)
        set_uniform(prog, "weight", 1.0 / len(setups))
        try:
            for setup in setups:
                depth.compare_func = ""
                draw_depths(scene, fbo, world_to_light_clip(setup), self.bias)
                depth.compare_func = "<="
                scene.bind_mask()
                scene.blend(moderngl.FUNC_ADD)
                depth.use(location=0)
                sample = np.linalg.inv(np.asarray(setup.world_to_light, np.float64))[:3, 3]
                set_uniform(prog, "light_position", tuple(sample))
                draw_receiving(scene, prog, np.asarray(setup.world_to_texture, dtype=np.float64))
        finally:
            fbo.release()
            depth.release()
        return ()


class RadiancePass(ShadowPass):
    """``method="radiance"``: Heckbert and Herf's radiance texture on each planar receiver.

    Per receiver (each needs a ``plane``): the rectangle around it in its plane
    (:func:`receiver_parallelogram`), its radiance texture of ``map_size`` texels from
    the blockers (:func:`draw_radiance`), then the receiver drawn with it: the mask is
    one minus the visibility. Receivers do not shadow each other, blockers receive
    nothing (as with ``method="texture"``). No :class:`ShadowSetup`;
    ``shadow_maps[l][r]`` is receiver ``r``'s visibility texture.
    """

    def __init__(self, samples: int, seed: int | None) -> None:
        self.samples = check_samples(samples)
        self.seed = seed

    def check(self, receivers: Bodies) -> None:
        for i, r in enumerate(receivers):
            receiver_parallelogram(f"receivers[{i}]", r)

    def check_light(self, light: PreparedLight, map_size: tuple[int, int]) -> None:
        light_samples("lights", light, 1, 0)  # an area light, or a clear error now

    def shadowed(self, scene: GpuScene) -> tuple[int, ...]:
        return tuple(range(len(scene.receivers)))

    def draw_mask(
        self, scene: GpuScene, light: PreparedLight, setups: tuple[ShadowSetup, ...]
    ) -> tuple[NDArray[np.float32], ...]:
        points = light_samples("lights", light, self.samples, self.seed)
        offset = len(scene.receivers)
        blockers = [(scene.meshes[offset + i], b.to_world) for i, b in enumerate(scene.blockers)]
        textures = []
        for ri, receiver in enumerate(scene.receivers):
            para = receiver_parallelogram(f"receivers[{ri}]", receiver)
            tex, visibility = draw_radiance(scene.ctx, blockers, points, para, scene.map_size)
            textures.append((scene.keep(tex), world_to_parallelogram(*para), visibility))
        prog = program(scene.ctx, "surface.vert", "radiance_mask.frag")
        set_matrix(prog, "world_to_clip", scene.world_to_clip)
        set_uniform(prog, "radiance", 0)
        set_uniform(prog, "light_position", tuple(light.position))
        scene.bind_mask()
        for ri, (receiver, (tex, to_uv, _)) in enumerate(
            zip(scene.receivers, textures, strict=True)
        ):
            tex.use(location=0)
            set_matrix(prog, "body_to_world", receiver.to_world)
            set_matrix(prog, "body_to_texture", to_uv @ receiver.to_world)
            scene.bind_record(prog, ri)
            scene.meshes[ri].render(prog)
        return tuple(v for _, _, v in textures)
