"""Omnidirectional point lights (method="omni"): a real GL cube depth map, drawn face by face
with cube_face_projection @ cube_face_views[i] and sampled with samplerCubeShadow.

The cube map's convention is checked on the hardware: the six faces drawn around the light
hold every direction exactly once, where cube_face says, and samplerCube returns for a
direction d the texel drawn for d. The shadows of blockers on all six sides of the light,
in a room, agree with the ray caster except in the edge band of test_render_depth."""

from __future__ import annotations

import numpy as np
import pytest

import shadowmath as sm
from shadowmath.meshes import box, sphere
from shadowmath.render import Body, Light, look_at, perspective, render_scene
from shadowmath.render._pass_omni import face_to_clip

from .depth_scenes import DepthScene, compare, ray_cast
from .scenes import place

SIZE = (128, 96)
LIGHT = np.array([0.3, -0.2, 0.1])
MAX_ALL = 0.01  # edges included, at most 1 % of the visible pixels differ


def _room_scene(eye, target) -> DepthScene:
    """A closed room (a box turned inside out) with a box on each side of the light."""
    v, t = box((8.0, 7.0, 6.0))
    room = Body(v, t[:, ::-1], color=(0.8, 0.8, 0.8))  # reversed winding: faces inward
    blockers = []
    for axis in range(3):
        for sign in (1.0, -1.0):
            centre = LIGHT.copy()
            centre[axis] += sign * (1.0 + 0.2 * axis)
            size = [0.7, 0.5, 0.6]
            size[axis] = 0.3
            blockers.append(
                Body(*box(tuple(size)), to_world=place(translation=centre), color=(0.9, 0.4, 0.2))
            )
    camera = perspective(100.0, SIZE[0] / SIZE[1], 0.05, 30.0) @ look_at(eye, target, (0, 0, 1))
    return DepthScene([room, *blockers], 6, Light(LIGHT), camera)


# Two views from opposite corners: together they see the shadows on all six walls.
SCENES = {
    "low corner": _room_scene((-3.6, -3.1, -2.6), (1.0, 1.0, 1.0)),
    "high corner": _room_scene((3.6, 3.1, 2.6), (-1.0, -1.0, -1.0)),
}


@pytest.mark.parametrize("name", list(SCENES))
def test_omni_shadows_agree_with_ray_caster(gl, name):
    scene = SCENES[name]
    room, *blockers = scene.bodies
    frame = render_scene(
        [room], blockers, [scene.light], scene.world_to_clip, image_size=SIZE,
        map_size=256, method="omni", ctx=gl,
    )  # fmt: skip
    truth = ray_cast(frame.body, frame.position, frame.normal, scene)
    count = compare(frame.shadow[..., 0] > 0.5, truth)
    print(f"omni {name}: {count}, visible {int(truth.on.sum())}")
    walls = (frame.body == 0) & truth.shadow
    assert walls.sum() > 500, "the walls must show sizeable shadows"
    assert count.differ_off_band == 0, count
    assert count.differ <= MAX_ALL * truth.on.sum(), count


def test_omni_shadows_fall_on_every_wall(gl):
    """Each blocker's shadow lands on the wall behind it: all six walls get one."""
    shadowed_walls = set()
    for scene in SCENES.values():
        room, *blockers = scene.bodies
        frame = render_scene(
            [room], blockers, [scene.light], scene.world_to_clip, image_size=SIZE,
            map_size=128, method="omni", ctx=gl,
        )  # fmt: skip
        on_wall = (frame.body == 0) & (frame.shadow[..., 0] > 0.5)
        n = frame.normal[on_wall]
        for axis in range(3):
            for sign in (1, -1):
                if np.sum(n[:, axis] * -sign > 0.99) > 20:  # a wall's inward normal is -sign
                    shadowed_walls.add((axis, sign))
    assert len(shadowed_walls) == 6, shadowed_walls


def test_omni_frame_holds_six_faces(gl):
    scene = SCENES["low corner"]
    room, *blockers = scene.bodies
    frame = render_scene(
        [room], blockers, [scene.light], scene.world_to_clip, image_size=32, map_size=64,
        method="omni", ctx=gl,
    )  # fmt: skip
    assert frame.setups == ((),)
    faces = np.stack(frame.shadow_maps[0])
    assert faces.shape == (6, 64, 64)
    # the closed room fills every face (its far corners at most at the far plane, where
    # the polygon offset may reach the clamp at 1); each face's blocker is nearer than
    # the wall behind it
    assert faces.min() > 0.9 and faces.max() <= 1.0
    assert (np.median(faces, axis=(1, 2)) < 1.0).all()
    assert (faces.max(axis=(1, 2)) - faces.min(axis=(1, 2)) > 1e-4).all()


def test_omni_bad_options(gl):
    scene = SCENES["low corner"]
    room, *blockers = scene.bodies
    with pytest.raises(ValueError, match="square"):
        render_scene([room], blockers, [scene.light], scene.world_to_clip, image_size=16,
                     map_size=(64, 32), method="omni", ctx=gl)  # fmt: skip
    with pytest.raises(ValueError, match="depth_bias"):
        render_scene([room], blockers, [scene.light], scene.world_to_clip, image_size=16,
                     method="omni", depth_bias=(float("inf"), 1.0), ctx=gl)  # fmt: skip


_FACE_VERT = """
#version 330
uniform mat4 world_to_clip;
uniform vec3 light;
in vec3 position;
out vec3 v_dir;
void main() {
    v_dir = position - light;
    gl_Position = world_to_clip * vec4(position, 1.0);
}
"""
_FACE_FRAG = """
#version 330
uniform float face;
in vec3 v_dir;
out vec4 color;
void main() { color = vec4(normalize(v_dir), face); }
"""
_QUAD_VERT = """
#version 330
in vec2 corner;
void main() { gl_Position = vec4(corner, 0.0, 1.0); }
"""
_LOOKUP_FRAG = """
#version 330
uniform samplerCube cube;
uniform sampler2D directions;
out vec4 color;
void main() { color = texture(cube, texelFetch(directions, ivec2(gl_FragCoord.xy), 0).xyz); }
"""


def _face_id_cube(gl, n):
    """The six faces of a unit sphere around LIGHT, each texel holding (its direction, face)."""
    v, t = sphere(1.0, segments=96, rings=48)
    vbo = gl.buffer((v[t] + LIGHT).astype("f4").tobytes())
    prog = gl.program(vertex_shader=_FACE_VERT, fragment_shader=_FACE_FRAG)
    vao = gl.vertex_array(prog, [(vbo, "3f", "position")])
    tex = gl.texture((n, n), 4, dtype="f4")
    fbo = gl.framebuffer([tex])
    matrices = face_to_clip(LIGHT, 0.1, 10.0, n)
    faces = []
    fbo.use()
    gl.disable(gl.DEPTH_TEST | gl.CULL_FACE | gl.BLEND)
    prog["light"].value = tuple(LIGHT)
    for i in range(6):
        fbo.clear(0.0, 0.0, 0.0, -1.0)
        prog["world_to_clip"].write(sm.column_major_bytes(matrices[i]))
        prog["face"].value = float(i)
        vao.render()
        faces.append(np.frombuffer(tex.read(), dtype="f4").reshape(n, n, 4))
    for obj in (fbo, tex, vao, vbo, prog):
        obj.release()
    return np.stack(faces)


def test_cube_faces_hold_every_direction_exactly_once(gl):
    """Texel (row, col) of face i holds the direction whose cube_face is (i, s, t) at the
    texel's centre: the six faces tile the sphere with no gap and no double coverage."""
    n = 32
    faces = _face_id_cube(gl, n)
    assert (faces[..., 3] == np.arange(6)[:, None, None]).all(), "every texel is drawn"
    face, s, t = sm.cube_face(faces[..., :3].astype(np.float64))
    assert (face == np.arange(6)[:, None, None]).all()
    centre = np.arange(n) + 0.5
    np.testing.assert_allclose(s * n, np.broadcast_to(centre[None, None, :], s.shape), atol=2e-3)
    np.testing.assert_allclose(t * n, np.broadcast_to(centre[None, :, None], t.shape), atol=2e-3)


def test_sampler_cube_returns_the_texel_drawn_for_each_direction(gl):
    """The hardware's samplerCube, given d, returns the texel whose direction is d's (within
    half a texel's diagonal) on the face cube_face selects (ties: any face of the edge)."""
    n, m = 32, 64
    faces = _face_id_cube(gl, n)
    cube = gl.texture_cube((n, n), 4, dtype="f4")
    for i in range(6):
        cube.write(i, faces[i].tobytes())
    cube.filter = (gl.NEAREST, gl.NEAREST)
    d = np.random.default_rng(0).normal(size=(m, m, 3))
    directions = gl.texture((m, m), 3, d.astype("f4").tobytes(), dtype="f4")
    directions.filter = (gl.NEAREST, gl.NEAREST)
    out = gl.texture((m, m), 4, dtype="f4")
    fbo = gl.framebuffer([out])
    prog = gl.program(vertex_shader=_QUAD_VERT, fragment_shader=_LOOKUP_FRAG)
    quad = gl.buffer(np.array([-1, -1, 1, -1, -1, 1, 1, 1], "f4").tobytes())
    vao = gl.vertex_array(prog, [(quad, "2f", "corner")])
    fbo.use()
    cube.use(location=0)
    directions.use(location=1)
    prog["cube"].value = 0
    prog["directions"].value = 1
    vao.render(gl.TRIANGLE_STRIP)
    got = np.frombuffer(out.read(), dtype="f4").reshape(m, m, 4)
    for obj in (vao, quad, prog, fbo, out, directions, cube):
        obj.release()
    expect = sm.cube_face(d)
    unit = d / np.linalg.norm(d, axis=-1, keepdims=True)
    angle = np.arccos(np.clip(np.sum(got[..., :3] * unit, axis=-1), -1, 1))
    # a texel spans at most 2 / n radians across (at the face centre): half its diagonal
    assert angle.max() < np.sqrt(2) / n, angle.max()
    near_edge = np.minimum.reduce([expect.s, 1 - expect.s, expect.t, 1 - expect.t]) < 1 / n
    assert ((got[..., 3] == expect.face) | near_edge).all()
    assert (got[..., 3] == expect.face).mean() > 0.9
