"""The scene on the GPU: bodies checked and uploaded once, the frame's render targets.

Every pass draws from the same :class:`GpuScene`: one vertex buffer per body
(un-indexed triangles, 9 floats per vertex: position, smooth normal, face
normal), with its vertex arrays cached per program; the picture's textures
and framebuffers; and the checked lights. A pass module needs nothing else.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any, NamedTuple

import moderngl
import numpy as np
from numpy.typing import NDArray

from shadowmath import ShadowSetup

from ._context import check_matrix, check_mesh, set_uniform


class Body(NamedTuple):
    """A triangle mesh placed in the world.

    Attributes:
        vertices: ``(N, 3)`` in the body's local coordinates.
        triangles: ``(M, 3)`` integer indices, counter-clockwise seen from outside.
        to_world: ``(4, 4)`` local-to-world placement (``None``: identity).
        color: RGB albedo in ``[0, 1]``.
        plane: ``(4,)`` world plane ``(a, b, c, d)`` of a flat receiver, needed by
            Blinn's method (``method="planar"``); ignored otherwise.
    """

    vertices: Any
    triangles: Any
    to_world: Any = None
    color: tuple[float, float, float] = (0.8, 0.8, 0.8)
    plane: Any = None


class Light(NamedTuple):
    """A point light, a directional light, or a parallelogram area light.

    Give ``position`` (a point light, or an area light's centre) or ``direction``
    (a directional light: parallel rays, the light infinitely far away), not both.

    Attributes:
        position: ``(3,)`` in world coordinates (an area light's centre).
        color: RGB intensity of its diffuse light.
        edge_u, edge_v: ``(3,)`` the edges of an area light, the parallelogram
            ``position + u edge_u + v edge_v`` for ``-1/2 <= u, v <= 1/2``; both or
            neither. Only the soft-shadow methods (``method="soft"``, ``"radiance"``)
            sample the area; the lit pass and the other methods light from ``position``.
        direction: ``(3,)`` a directional light's direction **toward the light**
            (the homogeneous light ``(x, y, z, 0)`` of :func:`planar_projection` and
            :func:`fit_shadow`; its length does not matter). Drawn by
            ``method="planar"`` and ``method="depth"`` only.

    Example:
        >>> sun = Light(direction=(1.0, 0.5, 2.0))  # from above, toward +x
    """

    position: Any = None
    color: tuple[float, float, float] = (1.0, 1.0, 1.0)
    edge_u: Any = None
    edge_v: Any = None
    direction: Any = None


class Prepared(NamedTuple):
    """A checked :class:`Body` as float64/int64 arrays."""

    vertices: NDArray[np.float64]
    triangles: NDArray[np.int64]
    to_world: NDArray[np.float64]
    color: NDArray[np.float64]
    plane: NDArray[np.float64] | None

    def world_vertices(self) -> NDArray[np.float64]:
        h = self.vertices @ self.to_world[:3, :3].T + self.to_world[:3, 3]
        w = self.vertices @ self.to_world[3, :3] + self.to_world[3, 3]
        return np.asarray(h / w[:, None], dtype=np.float64)


class PreparedLight(NamedTuple):
    #: A point light's position, or a directional light's unit direction toward it.
    position: NDArray[np.float64]
    color: NDArray[np.float64]
    #: An area light's ``(edge_u, edge_v)``; None for a point light.
    edges: tuple[NDArray[np.float64], NDArray[np.float64]] | None = None
    directional: bool = False

    @property
    def homogeneous(self) -> NDArray[np.float64]:
        """``(x, y, z, 1)`` a point light, ``(x, y, z, 0)`` a directional light (the
        shaders' ``vec4 light``: the vector toward the light is ``xyz - w p``)."""
        return np.append(self.position, 0.0 if self.directional else 1.0)

    @property
    def corner(self) -> NDArray[np.float64]:
        """An area light's corner ``position - (edge_u + edge_v) / 2`` (a point light's
        position)."""
        if self.edges is None:
            return self.position
        return np.asarray(self.position - 0.5 * (self.edges[0] + self.edges[1]), np.float64)


def prepare_body(name: str, body: Body) -> Prepared:
    v, t = check_mesh(name, body.vertices, body.triangles)
    to_world = (
        np.eye(4) if body.to_world is None else check_matrix(f"{name}.to_world", body.to_world)
    )
    color = np.asarray(body.color, dtype=np.float64)
    if color.shape != (3,) or not np.all(np.isfinite(color)):
        raise ValueError(f"{name}.color: expected three finite RGB values, got {body.color!r}")
    plane = None
    if body.plane is not None:
        plane = np.asarray(body.plane, dtype=np.float64)
        if plane.shape != (4,) or not np.all(np.isfinite(plane)):
            raise ValueError(f"{name}.plane: expected finite (a, b, c, d), got {body.plane!r}")
    return Prepared(v, t, to_world, color, plane)


def prepare_bodies(name: str, bodies: Sequence[Body]) -> list[Prepared]:
    """Each body checked (:func:`prepare_body`), named ``name[i]`` in errors."""
    return [prepare_body(f"{name}[{i}]", b) for i, b in enumerate(bodies)]


def prepare_light(name: str, light: Light) -> PreparedLight:
    c = np.asarray(light.color, dtype=np.float64)
    if c.shape != (3,) or not np.all(np.isfinite(c)):
        raise ValueError(f"{name}.color: expected three finite values")
    if light.direction is not None:
        if light.position is not None:
            raise ValueError(f"{name}: give position (a point light) or direction, not both")
        if light.edge_u is not None or light.edge_v is not None:
            raise ValueError(f"{name}: a directional light has no area (edge_u, edge_v)")
        d = np.asarray(light.direction, dtype=np.float64)
        if d.shape != (3,) or not np.all(np.isfinite(d)) or not np.any(d):
            raise ValueError(
                f"{name}.direction: expected finite non-zero (x, y, z), got {light.direction!r}"
            )
        return PreparedLight(d / np.linalg.norm(d), c, directional=True)
    if light.position is None:
        raise ValueError(f"{name}: expected a position (point light) or a direction")
    p = np.asarray(light.position, dtype=np.float64)
    if p.shape != (3,) or not np.all(np.isfinite(p)):
        raise ValueError(f"{name}.position: expected finite (x, y, z), got {light.position!r}")
    if light.edge_u is None and light.edge_v is None:
        return PreparedLight(p, c)
    if light.edge_u is None or light.edge_v is None:
        raise ValueError(f"{name}: an area light needs both edge_u and edge_v")
    edges = []
    for field in ("edge_u", "edge_v"):
        e = np.asarray(getattr(light, field), dtype=np.float64)
        if e.shape != (3,) or not np.all(np.isfinite(e)):
            raise ValueError(f"{name}.{field}: expected finite (x, y, z), got {e!r}")
        edges.append(e)
    eu, ev = edges
    if np.linalg.norm(np.cross(eu, ev)) <= 1e-12 * np.linalg.norm(eu) * np.linalg.norm(ev) or (
        not np.any(eu) or not np.any(ev)
    ):
        raise ValueError(f"{name}: edge_u and edge_v must be non-zero and not parallel")
    return PreparedLight(p, c, (eu, ev))


def vertex_data(vertices: NDArray[np.float64], triangles: NDArray[np.int64]) -> bytes:
    """Un-indexed triangles, 9 float32 per vertex: position, smooth normal, face normal."""
    corners = vertices[triangles]  # (M, 3, 3)
    face = np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0])
    # Area-weighted vertex normals: sum the (length 2 area) face normals at each vertex.
    smooth = np.zeros_like(vertices)
    np.add.at(smooth, triangles.reshape(-1), np.repeat(face, 3, axis=0))
    smooth = smooth / np.maximum(np.linalg.norm(smooth, axis=1, keepdims=True), 1e-300)
    face_unit = face / np.maximum(np.linalg.norm(face, axis=1, keepdims=True), 1e-300)
    data = np.concatenate(
        [corners, smooth[triangles], np.repeat(face_unit[:, None, :], 3, axis=1)], axis=-1
    )
    return data.astype(np.float32).tobytes()


class GpuMesh:
    """One mesh's vertex buffer, uploaded once, and its vertex arrays per program.

    Every program reads the same buffer: those that take only ``position``
    skip the normals (``3f 24x``), the others bind what their shaders use.
    """

    def __init__(
        self, ctx: moderngl.Context, vertices: NDArray[np.float64], triangles: NDArray[np.int64]
    ) -> None:
        self.ctx = ctx
        self.vbo = ctx.buffer(vertex_data(vertices, triangles))
        self._vaos: dict[int, moderngl.VertexArray] = {}

    def vao(self, prog: moderngl.Program) -> moderngl.VertexArray:
        key = prog.glo
        if key not in self._vaos:
            names = ("position", "normal", "face_normal")
            if any(n in prog and not isinstance(prog[n], moderngl.Attribute) for n in names):
                raise TypeError("position, normal, face_normal must be vertex attributes")
            if "normal" in prog or "face_normal" in prog:
                # skip_errors: an attribute the linker dropped keeps the buffer layout.
                content = [(self.vbo, "3f 3f 3f", *names)]
                self._vaos[key] = self.ctx.vertex_array(prog, content, skip_errors=True)
            else:
                self._vaos[key] = self.ctx.vertex_array(prog, [(self.vbo, "3f 24x", "position")])
        return self._vaos[key]

    def render(self, prog: moderngl.Program) -> None:
        self.vao(prog).render(moderngl.TRIANGLES)

    def release(self) -> None:
        for vao in self._vaos.values():
            vao.release()
        self._vaos.clear()
        self.vbo.release()


def float_texture(
    ctx: moderngl.Context, size: tuple[int, int], components: int
) -> moderngl.Texture:
    tex = ctx.texture(size, components, dtype="f4")
    tex.filter = (moderngl.NEAREST, moderngl.NEAREST)
    return tex


def read_texture(tex: moderngl.Texture, components: int) -> NDArray[np.float32]:
    """A float texture as ``(height, width, components)`` with row 0 at the *top*."""
    w, h = tex.size
    data = np.frombuffer(tex.read(), dtype=np.float32).reshape(h, w, components)
    return np.ascontiguousarray(data[::-1])  # GL's first row is the bottom one


class GpuScene:
    """The bodies, lights, camera and render targets of one :func:`render_scene` call.

    Bodies ``0 .. R-1`` are the receivers, ``R ..`` the blockers, in the order
    of the per-pixel body id. Targets share one depth buffer: ``main_fbo`` (the
    lit pass: colour, position + id, face normal), ``mask_fbo`` (one light's
    shadow mask), ``color_fbo`` (the subtractive pass). Use as a context
    manager: leaving it releases everything, including objects given to
    :meth:`keep`.
    """

    def __init__(
        self,
        ctx: moderngl.Context,
        receivers: Sequence[Prepared],
        blockers: Sequence[Prepared],
        lights: Sequence[PreparedLight],
        world_to_clip: NDArray[np.float64],
        *,
        size: tuple[int, int],
        map_size: tuple[int, int],
    ) -> None:
        self.ctx = ctx
        self.receivers = tuple(receivers)
        self.blockers = tuple(blockers)
        self.lights = tuple(lights)
        self.world_to_clip = world_to_clip
        self.size = size
        self.map_size = map_size
        self._released: list[Any] = []
        self.meshes = tuple(self.keep(GpuMesh(ctx, b.vertices, b.triangles)) for b in self.bodies)
        self.color_tex = self.keep(float_texture(ctx, size, 4))
        self.surface_tex = self.keep(float_texture(ctx, size, 4))
        self.normal_tex = self.keep(float_texture(ctx, size, 4))
        self.mask_tex = self.keep(float_texture(ctx, size, 1))
        depth = self.keep(ctx.depth_renderbuffer(size))
        self.main_fbo = self.keep(
            ctx.framebuffer([self.color_tex, self.surface_tex, self.normal_tex], depth)
        )
        self.mask_fbo = self.keep(ctx.framebuffer([self.mask_tex], depth))
        self.color_fbo = self.keep(ctx.framebuffer([self.color_tex], depth))
        # A point on the camera's near plane: which side of a plane the viewer is on.
        self.eye = np.linalg.inv(world_to_clip) @ np.array([0.0, 0.0, -1.0, 1.0])

    @property
    def bodies(self) -> tuple[Prepared, ...]:
        return self.receivers + self.blockers

    def keep(self, obj: Any) -> Any:
        """Release ``obj`` with the scene."""
        self._released.append(obj)
        return obj

    def use(self, fbo: moderngl.Framebuffer) -> None:
        fbo.use()
        fbo.viewport = (0, 0, *self.size)

    def bind_record(self, prog: moderngl.Program, body_id: int) -> None:
        """The stencil test moderngl lacks: shade only pixels where ``body_id`` is visible."""
        set_uniform(prog, "surface", 1)
        set_uniform(prog, "body_id", float(body_id))

    def read_record(
        self,
    ) -> tuple[NDArray[np.float32], NDArray[np.float32], NDArray[np.int32]]:
        """The lit pass's per-pixel record, row 0 at the top: ``(H, W, 3)`` world position and
        unit face normal (NaN on the background) and ``(H, W)`` body id (``-1`` there)."""
        surface = read_texture(self.surface_tex, 4)
        normal = read_texture(self.normal_tex, 4)[..., :3]
        body = np.rint(surface[..., 3]).astype(np.int32) - 1
        empty = (body < 0)[..., None]
        position = np.where(empty, np.float32(np.nan), surface[..., :3]).astype(np.float32)
        return position, np.where(empty, np.float32(np.nan), normal).astype(np.float32), body

    def clear_mask(self) -> None:
        """Clear the mask target for the next light (the shared depth stays)."""
        self.use(self.mask_fbo)
        self.mask_fbo.depth_mask = False
        self.mask_fbo.clear(0.0, 0.0, 0.0, 0.0)  # depth_mask False: keeps the shared depth

    def bind_mask(self) -> None:
        """Draw into the mask target: MAX blending (a pixel is marked once however many
        triangles or blockers cover it), LEQUAL against the lit pass's depth, no depth
        writes; the lit pass's record on texture unit 1."""
        self.use(self.mask_fbo)
        self.mask_fbo.depth_mask = False
        self.surface_tex.use(location=1)
        self.blend(moderngl.MAX)

    def blend(self, equation: int) -> None:
        """Additive-style blending ``(ONE, ONE)`` with ``equation``, depth test LEQUAL."""
        self.ctx.enable(moderngl.BLEND | moderngl.DEPTH_TEST)
        self.ctx.blend_equation = (equation, equation)
        self.ctx.blend_func = moderngl.ONE, moderngl.ONE
        self.ctx.depth_func = "<="

    def __enter__(self) -> GpuScene:
        return self

    def __exit__(self, *exc: object) -> None:
        for obj in reversed(self._released):
            obj.release()
        self._released.clear()


class PassOptions(NamedTuple):
    """The options of :func:`render_scene` that a shadow pass may take."""

    pcf_radius: int = 0
    depth_bias: tuple[float, float] | None = None
    samples: int = 16
    seed: int | None = 0
    light_size: float = 0.0


#: A shadow pass's checked receivers or blockers.
Bodies = Sequence[Prepared]


class ShadowPass:
    """One shadow system: its setups per light, and the light's shadow mask.

    A new system is a new module with one subclass of this; :func:`render_scene`
    picks it by its ``method`` name and touches nothing else. The defaults here are
    a system that takes any receivers, shadows every body and draws without setups;
    a subclass overrides what differs, and always :meth:`draw_mask`.
    """

    def check(self, receivers: Bodies) -> None:
        """Raise ``ValueError`` for receivers this system cannot shadow (default: none)."""

    def setup_count(self, blockers: Bodies) -> int:
        """How many ShadowSetups this system draws one light with (default 0)."""
        return 0

    def fit(
        self, receivers: Bodies, blockers: Bodies, light: PreparedLight, map_size: tuple[int, int]
    ) -> tuple[ShadowSetup, ...]:
        """The ShadowSetups this system draws one light with (default: none, after
        :meth:`check_light`)."""
        self.check_light(light, map_size)
        return ()

    def check_light(self, light: PreparedLight, map_size: tuple[int, int]) -> None:
        """Raise ``ValueError`` for a light or map size this system cannot draw (default:
        none); the default :meth:`fit` calls it."""

    def shadowed(self, scene: GpuScene) -> tuple[int, ...]:
        """The ids of the bodies that receive this system's shadows (default: every body)."""
        return tuple(range(len(scene.bodies)))

    def draw_mask(
        self, scene: GpuScene, light: PreparedLight, setups: tuple[ShadowSetup, ...]
    ) -> tuple[NDArray[np.float32], ...]:
        """Draw the light's shadow into the cleared mask target (:meth:`GpuScene.bind_mask`
        after any off-screen map); return the maps it drew, as NumPy arrays."""
        raise NotImplementedError(type(self).__name__)
