"""Omnidirectional point lights (method="omni"): a real GL cube depth map, drawn face by face
with cube_face_projection @ cube_face_views[i] and sampled with samplerCubeShadow.

The cube map's convention is checked on the hardware: the six faces drawn around the light
hold every direction exactly once, where cube_face says, and samplerCube returns for a
direction d the texel drawn for d. The shadows of blockers on all six sides of the light,
in a room, agree with the ray caster except in the edge band of test_render_depth.
The hardware breaks face ties as cube_face does (Vulkan's rule), and LINEAR comparison
filtering with seamless cube filtering speckles the seams with acne, NEAREST not; without
seamless filtering a driver may or may not filter across the faces (both allowed)."""

from __future__ import annotations

import moderngl
import numpy as np
import pytest

import shadowmath as sm
from shadowmath.meshes import box, sphere
from shadowmath.render import Body, Light, look_at, perspective, render_scene
from shadowmath.render._pass_omni import GL_TEXTURE_CUBE_MAP_SEAMLESS, OmniPass, face_to_clip
from shadowmath.render._scene import PASSES

from .depth_scenes import DepthScene, Truth, compare, ray_cast
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


_CONSTANT_FACES_FRAG = """
#version 330
uniform samplerCube cube;
uniform sampler2D directions;
out vec4 color;
void main() { color = texture(cube, texelFetch(directions, ivec2(gl_FragCoord.xy), 0).xyz); }
"""


def _sample_constant_faces(gl, d, texel_filter, n=8):
    """samplerCube at directions ``d`` on a cube whose face ``i`` holds ``i`` everywhere."""
    cube = gl.texture_cube((n, n), 1, dtype="f4")
    for i in range(6):
        cube.write(i, np.full((n, n), float(i), "f4").tobytes())
    cube.filter = (texel_filter, texel_filter)
    directions = gl.texture((len(d), 1), 3, np.asarray(d, "f4").tobytes(), dtype="f4")
    directions.filter = (gl.NEAREST, gl.NEAREST)
    out = gl.texture((len(d), 1), 4, dtype="f4")
    fbo = gl.framebuffer([out])
    prog = gl.program(vertex_shader=_QUAD_VERT, fragment_shader=_CONSTANT_FACES_FRAG)
    quad = gl.buffer(np.array([-1, -1, 1, -1, -1, 1, 1, 1], "f4").tobytes())
    vao = gl.vertex_array(prog, [(quad, "2f", "corner")])
    fbo.use()
    cube.use(location=0)
    directions.use(location=1)
    prog["cube"].value = 0
    prog["directions"].value = 1
    vao.render(gl.TRIANGLE_STRIP)
    got = np.frombuffer(out.read(), dtype="f4").reshape(len(d), 4)[:, 0]
    for obj in (vao, quad, prog, fbo, out, directions, cube):
        obj.release()
    return got


def test_sampler_cube_breaks_exact_ties_like_cube_face(gl):
    """On an edge or a corner of the cube, Mesa's samplerCube picks the face Vulkan's rule
    (z over y over x) and cube_face pick. The rule is only recommended (Vulkan) or left
    to the implementation (OpenGL), so other drivers may differ: checked on llvmpipe."""
    if "llvmpipe" not in gl.info["GL_RENDERER"]:
        pytest.skip(f"tie rule checked on Mesa's llvmpipe, not {gl.info['GL_RENDERER']}")
    patterns = [(1, 1, 0), (1, 0, 1), (0, 1, 1), (1, 1, 1)]
    signs = np.array(list(np.ndindex(2, 2, 2))) * -2.0 + 1.0
    d = np.unique(np.concatenate([signs * p for p in patterns]) * 0.75, axis=0)
    got = _sample_constant_faces(gl, d, gl.NEAREST)
    np.testing.assert_array_equal(got, np.asarray(sm.cube_face(d).face, dtype=np.float32))


def test_omni_pass_leaves_seamless_filtering_on(gl):
    """A non-seamless mask pass turns GL_TEXTURE_CUBE_MAP_SEAMLESS back on: LINEAR lookups
    half a texel from a face edge then blend the neighbouring face."""
    scene = SCENES["low corner"]
    room, *blockers = scene.bodies
    omni = OmniPass(filter="linear", seamless=False)
    assert omni.seamless is False
    d = [sm.cube_face_direction(0, 0.25 / 8, 0.5)]  # +X, a quarter texel from the +Z edge
    gl.disable_direct(GL_TEXTURE_CUBE_MAP_SEAMLESS)
    assert _sample_constant_faces(gl, d, gl.LINEAR)[0] == 0.0  # stays on +X
    gl.enable_direct(GL_TEXTURE_CUBE_MAP_SEAMLESS)
    seamless = _sample_constant_faces(gl, d, gl.LINEAR)[0]
    assert 0.0 < seamless < 4.0  # blends in +Z, face 4
    with pytest.MonkeyPatch.context() as mp:
        mp.setitem(PASSES, "omni", lambda o: omni)
        render_scene([room], blockers, [scene.light], scene.world_to_clip, image_size=16,
                     map_size=32, method="omni", ctx=gl)  # fmt: skip
    assert _sample_constant_faces(gl, d, gl.LINEAR)[0] == seamless


def test_omni_pass_filter_options():
    default = OmniPass()
    assert (default.filter, default.seamless) == (moderngl.NEAREST, True)
    assert OmniPass(filter="linear").filter == moderngl.LINEAR
    with pytest.raises(ValueError, match="filter: expected 'nearest' or 'linear'"):
        OmniPass(filter="cubic")
    with pytest.raises(ValueError, match="seamless: expected a bool"):
        OmniPass(seamless=1)


def _render_with(gl, monkeypatch, scene, map_size, **options):
    room, *blockers = scene.bodies
    monkeypatch.setitem(PASSES, "omni", lambda o: OmniPass(o.depth_bias, **options))
    frame = render_scene(
        [room], blockers, [scene.light], scene.world_to_clip, image_size=SIZE,
        map_size=map_size, method="omni", ctx=gl,
    )  # fmt: skip
    return frame, ray_cast(frame.body, frame.position, frame.normal, scene)


def seam_speckles(frame, truth: Truth) -> np.ndarray:
    """Pixels off the edge band whose mask differs from the ray caster at all: any shadow
    on a lit point, or less than full shadow on a shadowed one."""
    mask = frame.shadow[..., 0]
    wrong = np.where(truth.shadow, mask < 1.0, mask > 0.0)
    return truth.on & ~truth.band & wrong


def seam_acne(frame, truth: Truth, speckles: np.ndarray, n: int) -> None:
    """Assert the speckles are seam acne: on lit points, within 1.5 texels of a face edge."""
    assert not (speckles & truth.shadow).any(), "the speckles are acne on lit points"
    _, s, t = sm.cube_face(frame.position[speckles].astype(np.float64) - LIGHT)
    to_edge = np.minimum.reduce([s, 1 - s, t, 1 - t]) * n
    assert to_edge.max(initial=0.0) < 1.5, f"speckles off the seams, {to_edge.max():.2f} texels"


@pytest.mark.parametrize("name", list(SCENES))
def test_linear_filtering_speckles_the_seams_only_when_seamless(gl, monkeypatch, name):
    """LINEAR comparison (2x2 hardware PCF) near a face edge: seamless filtering compares
    the receiver's depth along the selected face's axis with the neighbouring face's texels,
    which hold depths along the neighbour's axis, smaller there, so points on a wall the
    neighbour sees face-on (where the polygon offset's slope term is zero) are partly
    shadowed: acne, within a texel of the seams. NEAREST reads one texel of the selected
    face (OpenGL 4.6 section 8.14.2, Vulkan "Cube Map Edge Handling"): no speckles.

    Non-seamless LINEAR is either of two results: filtered on the face alone as
    ARB_seamless_cube_map's "unextended" cube maps (no speckles: Mesa), or across the
    faces anyway (seam acne: NVIDIA's driver showed 50 and 23 on these views, see
    docs/cube-maps.md). Either way its speckles are seam acne and no more than seamless
    filtering's."""
    scene = SCENES[name]
    n = 128
    counts = {}
    for label, options in {
        "linear, seamless": {"filter": "linear", "seamless": True},
        "linear, non-seamless": {"filter": "linear", "seamless": False},
        "nearest (default)": {},
    }.items():
        frame, truth = _render_with(gl, monkeypatch, scene, n, **options)
        speckles = seam_speckles(frame, truth)
        counts[label] = int(speckles.sum())
        if label == "linear, seamless":
            assert speckles.any(), "seamless LINEAR filtering shows no speckles"
        seam_acne(frame, truth, speckles, n)
        # Thresholded at one half, every filter agrees with the ray caster off the band.
        assert compare(frame.shadow[..., 0] > 0.5, truth).differ_off_band == 0
    print(f"omni {name}, {n}² faces, seam speckles: {counts} on {gl.info['GL_RENDERER']}")
    assert counts["nearest (default)"] == 0
    assert counts["linear, non-seamless"] <= counts["linear, seamless"]
