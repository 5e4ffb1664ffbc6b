"""Passes 2 to 4: receivers with projective shadow textures or Blinn's planar shadows,
several lights and several blockers, composed as Nagy's article says."""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any, Literal, NamedTuple

import moderngl
import numpy as np
from numpy.typing import NDArray

from shadowmath._planar import planar_projection
from shadowmath._setup import ShadowSetup, fit_shadow, receiver_texture_matrix

from ._context import (
    check_matrix,
    check_mesh,
    program,
    resolve_context,
    set_matrix,
    set_uniform,
    uniform,
)
from ._context import image_size as _image_size
from ._shadow_map import draw_shadow_map, read_mask

#: The most lights one :func:`render_scene` call lights with (a shader array size).
MAX_LIGHTS = 8

#: Polygon offset ``(factor, units)`` pulling Blinn's flattened blocker toward the
#: camera, so that it wins the LEQUAL depth test against its coplanar receiver.
PLANAR_POLYGON_OFFSET = (-1.0, -4.0)


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
    """A point light.

    Attributes:
        position: ``(3,)`` in world coordinates.
        color: RGB intensity of its diffuse light.
    """

    position: Any
    color: tuple[float, float, float] = (1.0, 1.0, 1.0)


class Frame(NamedTuple):
    """What :func:`render_scene` returns; images have row 0 at the *top* (as saved).

    Attributes:
        color: ``(H, W, 3)`` float32 in ``[0, 1]``, the final picture.
        shadow: ``(H, W, L)`` float32, light ``l``'s combined shadow mask on the visible
            receivers (1 shadowed, 0 lit; 0 on blockers and background).
        position: ``(H, W, 3)`` float32 world position of the visible surface (NaN on
            the background).
        normal: ``(H, W, 3)`` float32 unit face normal of the visible surface (NaN on
            the background).
        body: ``(H, W)`` int32, which body is visible: ``0 .. R-1`` the receivers,
            ``R .. R+B-1`` the blockers, ``-1`` the background.
        setups: ``setups[l][b]`` the :class:`ShadowSetup` of light ``l`` and blocker ``b``.
        shadow_maps: ``shadow_maps[l][b]`` the ``(h, w)`` pass-1 mask, as
            :func:`render_shadow_map` returns it (row 0 is ``t = 0``).
    """

    color: NDArray[np.float32]
    shadow: NDArray[np.float32]
    position: NDArray[np.float32]
    normal: NDArray[np.float32]
    body: NDArray[np.int32]
    setups: tuple[tuple[ShadowSetup, ...], ...]
    shadow_maps: tuple[tuple[NDArray[np.float32], ...], ...]


class _Prepared(NamedTuple):
    vertices: NDArray[np.float64]
    triangles: NDArray[np.int64]
    to_world: NDArray[np.float64]
    color: NDArray[np.float64]
    plane: NDArray[np.float64] | None


def _prepare(name: str, body: Body) -> _Prepared:
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
    return _Prepared(v, t, to_world, color, plane)


def _vertex_data(body: _Prepared) -> bytes:
    """Un-indexed triangles, 9 floats per vertex: position, smooth normal, face normal."""
    v, t = body.vertices, body.triangles
    corners = v[t]  # (M, 3, 3)
    face = np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0])
    # Area-weighted vertex normals: sum the (length 2 area) face normals at each vertex.
    smooth = np.zeros_like(v)
    np.add.at(smooth, t.reshape(-1), np.repeat(face, 3, axis=0))
    smooth = smooth / np.maximum(np.linalg.norm(smooth, axis=1, keepdims=True), 1e-300)
    face_unit = face / np.maximum(np.linalg.norm(face, axis=1, keepdims=True), 1e-300)
    data = np.concatenate(
        [corners, smooth[t], np.repeat(face_unit[:, None, :], 3, axis=1)], axis=-1
    )
    return data.astype(np.float32).tobytes()


def _texture(ctx: moderngl.Context, size: tuple[int, int], components: int) -> moderngl.Texture:
    tex = ctx.texture(size, components, dtype="f4")
    tex.filter = (moderngl.NEAREST, moderngl.NEAREST)
    return tex


def _read(tex: moderngl.Texture, components: int) -> NDArray[np.float32]:
    w, h = tex.size
    data = np.frombuffer(tex.read(), dtype=np.float32).reshape(h, w, components)
    return np.ascontiguousarray(data[::-1])  # GL's first row is the bottom one


def render_scene(
    receivers: Sequence[Body],
    blockers: Sequence[Body],
    lights: Sequence[Light],
    world_to_clip: Any,
    *,
    image_size: int | tuple[int, int] = (512, 384),
    map_size: int | tuple[int, int] = 256,
    method: Literal["texture", "planar"] = "texture",
    ambient: float = 0.15,
    background: tuple[float, float, float] = (0.06, 0.07, 0.09),
    setups: Sequence[Sequence[ShadowSetup]] | None = None,
    ctx: moderngl.Context | None = None,
) -> Frame:
    r"""Render receivers in the shadows of blockers, the article's passes on the GPU.

    1. **Lit pass**: every body with ambient plus Lambert diffuse from each light
       (``albedo (a + sum_l c_l max(0, n . l))``), depth-tested; it also records the
       visible body's id, world position and face normal per pixel.
    2. Per light, per blocker: the **shadow map** (:func:`render_shadow_map`'s pass,
       with ``setup.blocker_to_clip``), then the **shadow mask**: with
       ``method="texture"`` each receiver is drawn again with the map as a
       projective texture through ``receiver_texture_matrix(setup, to_world)``
       (``textureProj``, clamp to edge, no shadow where ``q <= 0`` or on faces with
       ``N . (L - P) <= 0``); with ``method="planar"`` (pass 3) the blocker is
       flattened onto each receiver's plane with :func:`planar_projection`, drawn with
       a polygon offset of :data:`PLANAR_POLYGON_OFFSET` against z-fighting, and
       skipped for a light on the other side of the plane than the camera (the
       visible face is unlit: Blinn's back-face case).
    3. **Subtractive pass** per light (pass 4): each receiver drawn again with
       ``FUNC_REVERSE_SUBTRACT`` blending removes that light's diffuse term where its
       mask is set, so the shadows of several lights compose correctly.

    **No stencil in moderngl 5**: the seeds use the stencil buffer twice, to confine
    planar shadows to the receiver and to darken overlapping shadows once. Here the
    lit pass writes each pixel's body id into a float attachment, and the mask
    passes discard fragments whose pixel shows another body (the stencil test);
    the mask passes blend with ``MAX`` into a one-channel float texture, so a pixel
    covered by several flattened triangles, or by the shadows of several blockers
    of the same light, is marked once, and the subtractive pass then darkens it
    once. The mask and subtractive passes share the lit pass's depth buffer and
    vertex shader (``invariant gl_Position``) and test ``LEQUAL`` without writing
    depth, the article's advice for multipass rendering.

    Arguments:
        receivers: the bodies that receive shadows.
        blockers: the bodies that cast them (drawn lit, not shadowed).
        lights: up to :data:`MAX_LIGHTS` point lights.
        world_to_clip: ``(4, 4)`` the camera, e.g. ``perspective(...) @ look_at(...)``.
        image_size: ``size`` or ``(width, height)`` of the picture in pixels.
        map_size: ``size`` or ``(width, height)`` of each shadow map in texels.
        method: ``"texture"`` (Nagy's projective shadow texture) or ``"planar"``
            (Blinn's planar projection: every receiver needs a ``plane``).
        ambient: the ambient term ``a``.
        background: RGB of empty pixels.
        setups: ``setups[l][b]`` to use instead of ``fit_shadow(light, blocker, map_size,
            blocker_to_world=to_world)`` (e.g. matrices computed with JAX).
        ctx: a moderngl context; default the shared EGL :func:`standalone_context`.

    Returns:
        :class:`Frame`.

    Raises:
        ValueError: bad meshes, matrices, sizes, colours; no lights or too many; a
            receiver without a plane under ``method="planar"``; ``setups`` of the wrong
            shape; and whatever :func:`fit_shadow` raises for a light and a blocker.
        GLUnavailableError: no OpenGL context could be created.

    Example:
        >>> from shadowmath.meshes import grid, sphere
        >>> from shadowmath.render import Body, Light, look_at, perspective, render_scene
        >>> floor = Body(*grid((6.0, 6.0)), plane=(0, 0, 1, 0))
        >>> ball = Body(*sphere(0.5), to_world=np.array(
        ...     [[1, 0, 0, 0], [0, 1, 0, 0], [0, 0, 1, 1.5], [0, 0, 0, 1.0]]))
        >>> camera = perspective(50.0, 1.0, 0.1, 50.0) @ look_at([0, -6, 5], [0, 0, 0], [0, 0, 1])
        >>> frame = render_scene([floor], [ball], [Light([0, 0, 5])], camera,
        ...                      image_size=64)
        >>> frame.color.shape, frame.shadow.shape
        ((64, 64, 3), (64, 64, 1))
    """
    if method not in ("texture", "planar"):
        raise ValueError(f"method: expected 'texture' or 'planar', got {method!r}")
    if not 1 <= len(lights) <= MAX_LIGHTS:
        raise ValueError(f"lights: expected 1 to {MAX_LIGHTS} lights, got {len(lights)}")
    if not (np.isfinite(ambient) and ambient >= 0):
        raise ValueError(f"ambient: must be finite and >= 0, got {ambient!r}")
    camera = check_matrix("world_to_clip", world_to_clip)
    size = _image_size("image_size", image_size)
    _image_size("map_size", map_size)
    recv = [_prepare(f"receivers[{i}]", b) for i, b in enumerate(receivers)]
    block = [_prepare(f"blockers[{i}]", b) for i, b in enumerate(blockers)]
    if method == "planar":
        for i, r in enumerate(recv):
            if r.plane is None:
                raise ValueError(
                    f"receivers[{i}].plane: method='planar' needs each receiver's plane"
                )
    light_pos = []
    for i, light in enumerate(lights):
        p = np.asarray(light.position, dtype=np.float64)
        if p.shape != (3,) or not np.all(np.isfinite(p)):
            raise ValueError(
                f"lights[{i}].position: expected finite (x, y, z), got {light.position!r}"
            )
        light_pos.append(p)
    light_col = [np.asarray(light.color, dtype=np.float64) for light in lights]
    for i, c in enumerate(light_col):
        if c.shape != (3,) or not np.all(np.isfinite(c)):
            raise ValueError(f"lights[{i}].color: expected three finite values")

    if setups is None:
        all_setups = tuple(
            tuple(fit_shadow(p, b.vertices, map_size, blocker_to_world=b.to_world) for b in block)
            for p in light_pos
        )
    else:
        all_setups = tuple(tuple(per_light) for per_light in setups)
        if len(all_setups) != len(lights) or any(len(s) != len(block) for s in all_setups):
            raise ValueError(
                f"setups: expected {len(lights)} lists (one per light) of {len(block)} "
                "ShadowSetups (one per blocker)"
            )

    gl = resolve_context(ctx)
    return _draw(
        gl, camera, size, map_size, method, ambient, background, recv, block,
        light_pos, light_col, all_setups,
    )  # fmt: skip


def _draw(
    gl: moderngl.Context,
    camera: NDArray[np.float64],
    size: tuple[int, int],
    map_size: int | tuple[int, int],
    method: str,
    ambient: float,
    background: tuple[float, float, float],
    recv: list[_Prepared],
    block: list[_Prepared],
    light_pos: list[NDArray[np.float64]],
    light_col: list[NDArray[np.float64]],
    setups: tuple[tuple[ShadowSetup, ...], ...],
) -> Frame:
    map_texels = _image_size("map_size", map_size)
    released: list[Any] = []

    def keep(obj: Any) -> Any:
        released.append(obj)
        return obj

    try:
        color_tex = keep(_texture(gl, size, 4))
        surface_tex = keep(_texture(gl, size, 4))
        normal_tex = keep(_texture(gl, size, 4))
        mask_tex = keep(_texture(gl, size, 1))
        depth = keep(gl.depth_renderbuffer(size))
        main_fbo = keep(gl.framebuffer([color_tex, surface_tex, normal_tex], depth))
        mask_fbo = keep(gl.framebuffer([mask_tex], depth))
        color_fbo = keep(gl.framebuffer([color_tex], depth))

        surface_prog = program(gl, "surface.vert", "surface_lit.frag")
        mask_prog = program(gl, "surface.vert", "receiver_mask.frag")
        planar_prog = program(gl, "planar.vert", "planar_mask.frag")
        subtract_prog = program(gl, "surface.vert", "receiver_subtract.frag")

        def body_vao(prog: moderngl.Program, body: _Prepared) -> Any:
            vbo = keep(gl.buffer(_vertex_data(body)))
            return keep(
                # skip_errors: a pass whose shaders do not read an attribute (the
                # linker drops it) still gets the same buffer layout.
                gl.vertex_array(
                    prog,
                    [(vbo, "3f 3f 3f", "position", "normal", "face_normal")],
                    skip_errors=True,
                )
            )

        def plain_vao(prog: moderngl.Program, body: _Prepared) -> Any:
            vbo = keep(gl.buffer(body.vertices[body.triangles].astype(np.float32).tobytes()))
            return keep(gl.vertex_array(prog, [(vbo, "3f", "position")]))

        bodies = recv + block
        set_matrix(surface_prog, "world_to_clip", camera)
        for prog in (mask_prog, subtract_prog):
            set_matrix(prog, "world_to_clip", camera)
        set_matrix(planar_prog, "world_to_clip", camera)

        # Pass 0: the lit scene and the per-pixel record (position + id, face normal).
        main_fbo.use()
        main_fbo.viewport = (0, 0, *size)
        gl.disable(moderngl.BLEND | moderngl.CULL_FACE)
        gl.enable(moderngl.DEPTH_TEST)
        gl.depth_func = "<"
        gl.polygon_offset = (0.0, 0.0)
        main_fbo.depth_mask = True
        main_fbo.clear(*background, 0.0, depth=1.0)
        set_uniform(surface_prog, "light_count", len(light_pos))
        padding = [np.zeros(3)] * (MAX_LIGHTS - len(light_pos))
        uniform(surface_prog, "light_position").write(
            np.array(light_pos + padding, np.float32).tobytes()
        )
        uniform(surface_prog, "light_color").write(
            np.array(light_col + padding, np.float32).tobytes()
        )
        set_uniform(surface_prog, "ambient", float(ambient))
        for i, prepared in enumerate(bodies):
            set_matrix(surface_prog, "body_to_world", prepared.to_world)
            set_uniform(surface_prog, "albedo", tuple(prepared.color))
            set_uniform(surface_prog, "body_id", float(i))
            body_vao(surface_prog, prepared).render(moderngl.TRIANGLES)

        surface_tex.use(location=1)
        mask_tex.use(location=2)
        for prog in (mask_prog, planar_prog, subtract_prog):
            set_uniform(prog, "surface", 1)
        set_uniform(mask_prog, "shadow_map", 0)
        set_uniform(subtract_prog, "mask", 2)
        mask_vaos = [body_vao(mask_prog, r) for r in recv]
        subtract_vaos = [body_vao(subtract_prog, r) for r in recv]
        planar_vaos = [plain_vao(planar_prog, b) for b in block]
        eye = np.linalg.inv(camera) @ np.array([0.0, 0.0, -1.0, 1.0])  # on the near plane

        shadows = []
        maps = []
        for li, (light, lcolor) in enumerate(zip(light_pos, light_col, strict=True)):
            # Pass 2/3: the light's combined shadow mask, MAX-blended over its blockers.
            mask_fbo.use()
            mask_fbo.viewport = (0, 0, *size)
            mask_fbo.depth_mask = False
            mask_fbo.clear(0.0, 0.0, 0.0, 0.0)  # depth_mask False: keeps the shared depth
            gl.enable(moderngl.BLEND)
            gl.blend_equation = (moderngl.MAX, moderngl.MAX)
            gl.blend_func = moderngl.ONE, moderngl.ONE
            gl.depth_func = "<="
            light_maps = []
            for bi, blocker in enumerate(block):
                setup = setups[li][bi]
                smap = keep(
                    draw_shadow_map(
                        gl, blocker.vertices, blocker.triangles,
                        np.asarray(setup.blocker_to_clip), map_texels,
                    )
                )  # fmt: skip
                light_maps.append(read_mask(smap))
                mask_fbo.use()
                mask_fbo.viewport = (0, 0, *size)
                gl.enable(moderngl.BLEND | moderngl.DEPTH_TEST)
                if method == "texture":
                    smap.use(location=0)
                    set_uniform(mask_prog, "light_position", tuple(light))
                    for ri, receiver in enumerate(recv):
                        set_matrix(mask_prog, "body_to_world", receiver.to_world)
                        set_matrix(
                            mask_prog,
                            "body_to_texture",
                            receiver_texture_matrix(setup, receiver.to_world),
                        )
                        set_uniform(mask_prog, "body_id", float(ri))
                        mask_vaos[ri].render(moderngl.TRIANGLES)
                else:
                    gl.polygon_offset = PLANAR_POLYGON_OFFSET
                    set_matrix(planar_prog, "blocker_to_world", blocker.to_world)
                    for ri, receiver in enumerate(recv):
                        plane = receiver.plane
                        assert plane is not None
                        side_light = np.dot(plane[:3], light) + plane[3]
                        side_eye = np.dot(plane, eye) / eye[3]
                        if side_light * side_eye <= 0:
                            continue  # the camera sees the face the light does not reach
                        flatten = planar_projection(plane, np.append(light, 1.0))
                        set_matrix(planar_prog, "flatten", flatten)
                        set_uniform(planar_prog, "body_id", float(ri))
                        planar_vaos[bi].render(moderngl.TRIANGLES)
                    gl.polygon_offset = (0.0, 0.0)
            maps.append(tuple(light_maps))
            shadows.append(_read(mask_tex, 1)[..., 0])

            # Pass 4: subtract this light's diffuse term where its mask is set.
            color_fbo.use()
            color_fbo.viewport = (0, 0, *size)
            color_fbo.depth_mask = False
            gl.enable(moderngl.BLEND | moderngl.DEPTH_TEST)
            gl.blend_equation = (moderngl.FUNC_REVERSE_SUBTRACT, moderngl.FUNC_REVERSE_SUBTRACT)
            gl.blend_func = moderngl.ONE, moderngl.ONE
            set_uniform(subtract_prog, "light_position", tuple(light))
            set_uniform(subtract_prog, "light_color", tuple(lcolor))
            for ri, receiver in enumerate(recv):
                set_matrix(subtract_prog, "body_to_world", receiver.to_world)
                set_uniform(subtract_prog, "albedo", tuple(receiver.color))
                set_uniform(subtract_prog, "body_id", float(ri))
                subtract_vaos[ri].render(moderngl.TRIANGLES)

        gl.blend_equation = (moderngl.FUNC_ADD, moderngl.FUNC_ADD)
        gl.disable(moderngl.BLEND)
        color = _read(color_tex, 4)[..., :3]
        surface = _read(surface_tex, 4)
        normal = _read(normal_tex, 4)[..., :3]
    finally:
        for obj in reversed(released):
            obj.release()

    body = np.rint(surface[..., 3]).astype(np.int32) - 1
    empty = (body < 0)[..., None]
    return Frame(
        color=np.clip(color, 0.0, 1.0).astype(np.float32),
        shadow=np.stack(shadows, axis=-1).astype(np.float32),
        position=np.where(empty, np.float32(np.nan), surface[..., :3]).astype(np.float32),
        normal=np.where(empty, np.float32(np.nan), normal).astype(np.float32),
        body=body,
        setups=setups,
        shadow_maps=tuple(maps),
    )
