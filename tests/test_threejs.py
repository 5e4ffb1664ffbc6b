"""The three.js data against three.js's own formulas, rewritten here from its source (r187).

Each helper below is a line-by-line port of a three.js function (file and function in its
docstring); the tests rebuild, from the data alone, the matrices three.js would draw and
sample with, and compare them with the package's fit (``api="opengl"``: three.js's
``WebGLRenderer``) to rounding.
"""

from __future__ import annotations

import json
import re

import numpy as np
import pytest

import shadowmath as sm
from shadowmath.integrations import threejs

BOX = np.array([[x, y, z] for x in (-1.0, 1.5) for y in (0.5, 2.0) for z in (-1.0, 0.8)])
FLOOR = np.array([[x, y, 0.0] for x in (-6.0, 6.0) for y in (-6.0, 6.0)])
EPS = 1e-12


def look_at(eye, target, up):
    """``src/math/Matrix4.js`` ``lookAt(eye, target, up)`` as ``Object3D.lookAt`` calls it
    for a camera or light (``_m1.lookAt(_position, _target, this.up)``): the rotation whose
    columns are ``x = normalize(up x z)``, ``y = z x x``, ``z = normalize(eye - target)``
    (with three.js's nudge of ``z`` by 1e-4 when ``up`` is parallel to it)."""
    eye, target, up = (np.asarray(v, dtype=np.float64) for v in (eye, target, up))
    z = eye - target
    if np.dot(z, z) == 0:
        z = np.array([0.0, 0.0, 1.0])
    z = z / np.linalg.norm(z)
    x = np.cross(up, z)
    if np.dot(x, x) == 0:
        if abs(up[2]) == 1:
            z[0] += 0.0001
        else:
            z[2] += 0.0001
        z = z / np.linalg.norm(z)
        x = np.cross(up, z)
    x = x / np.linalg.norm(x)
    y = np.cross(z, x)
    return np.column_stack([x, y, z])


def matrix_world(position, target, up):
    """``src/core/Object3D.js``: ``position``, ``quaternion`` from ``lookAt``, scale 1,
    composed by ``updateMatrixWorld`` (``Matrix4.compose``) for a camera without a parent."""
    m = np.eye(4)
    m[:3, :3] = look_at(position, target, up)
    m[:3, 3] = position
    return m


def make_perspective(left, right, top, bottom, near, far, system="webgl"):
    """``src/math/Matrix4.js`` ``makePerspective`` (no reversed depth)."""
    x, y = 2 * near / (right - left), 2 * near / (top - bottom)
    a, b = (right + left) / (right - left), (top + bottom) / (top - bottom)
    if system == "webgl":
        c, d = -(far + near) / (far - near), -2 * far * near / (far - near)
    else:  # WebGPUCoordinateSystem: depth 0..1
        c, d = -far / (far - near), -far * near / (far - near)
    return np.array([[x, 0, a, 0], [0, y, b, 0], [0, 0, c, d], [0, 0, -1, 0]])


def make_orthographic(left, right, top, bottom, near, far, system="webgl"):
    """``src/math/Matrix4.js`` ``makeOrthographic`` (no reversed depth)."""
    x, y = 2 / (right - left), 2 / (top - bottom)
    a, b = -(right + left) / (right - left), -(top + bottom) / (top - bottom)
    if system == "webgl":
        c, d = -2 / (far - near), -(far + near) / (far - near)
    else:
        c, d = -1 / (far - near), -near / (far - near)
    return np.array([[x, 0, 0, a], [0, y, 0, b], [0, 0, c, d], [0, 0, 0, 1.0]])


def perspective_camera_projection(fov, aspect, near, far):
    """``src/cameras/PerspectiveCamera.js`` ``updateProjectionMatrix`` (zoom 1, no view,
    no film offset): ``top = near tan(fov / 2)``, ``width = aspect * 2 top``."""
    top = near * np.tan(np.radians(0.5 * fov))
    height = 2 * top
    width = aspect * height
    left = -0.5 * width
    return make_perspective(left, left + width, top, top - height, near, far)


def shadow_matrix(projection, world, system="webgl"):
    """``src/lights/LightShadow.js`` ``_updateMatrix`` (no viewport): ``B P V`` with ``B``
    scaling x, y (and z under WebGL) by 1/2 about 1/2."""
    b = np.array([[0.5, 0, 0, 0.5], [0, 0.5, 0, 0.5], [0, 0, 0.5, 0.5], [0, 0, 0, 1.0]])
    if system != "webgl":
        b[2] = [0, 0, 1, 0]
    return b @ projection @ np.linalg.inv(world)


#: ``src/renderers/webgl/WebGLShadowMap.js``: ``_cubeDirections`` and ``_cubeUps``.
CUBE_DIRECTIONS = [(1, 0, 0), (-1, 0, 0), (0, 1, 0), (0, -1, 0), (0, 0, 1), (0, 0, -1)]
CUBE_UPS = [(0, -1, 0), (0, -1, 0), (0, 0, 1), (0, 0, -1), (0, -1, 0), (0, -1, 0)]


def matrix(elements):
    """``Matrix4.fromArray``: 16 column-major elements."""
    return np.asarray(elements, dtype=np.float64).reshape(4, 4).T


def three_projection(data, system="webgl"):
    make = make_orthographic if data["type"] == "orthographic" else make_perspective
    window = (data["left"], data["right"], data["top"], data["bottom"])
    return make(*window, data["near"], data["far"], system)


def three_world_to_clip(data, system="webgl"):
    world = matrix_world(data["position"], data["target"], data["up"])
    return three_projection(data, system) @ np.linalg.inv(world)


def close(a, b, rel=1e-9):
    scale = max(1.0, float(np.abs(b).max()))
    return float(np.abs(np.asarray(a) - np.asarray(b)).max()) <= rel * scale


FITS = {
    "sun": lambda: sm.fit_shadow(
        sm.DirectionalLight([0.4, -0.7, 1.0]), BOX, (512, 256), receivers=FLOOR
    ),
    "sun-up": lambda: sm.fit_shadow(
        sm.DirectionalLight([0.0, 0.3, 1.0]), BOX, 512, receivers=FLOOR, up=[0, 1, 0]
    ),
    "spot": lambda: sm.fit_shadow(
        sm.SpotLight([2.0, -1.0, 5.0], [-0.3, 0.3, -1.0], 0.6), BOX, 256, receivers=FLOOR
    ),
    "point": lambda: sm.fit_shadow(sm.PointLight([0.0, -3.0, 4.0]), BOX, 300, pcf_radius=1),
    "placed": lambda: sm.fit_shadow(
        sm.PointLight([0.0, -3.0, 4.0]),
        BOX,
        256,
        blocker_to_world=np.array([[0, -1, 0, 1], [1, 0, 0, 0], [0, 0, 1, 0.5], [0, 0, 0, 1]]),
    ),
}


@pytest.mark.parametrize("name", FITS)
def test_three_builds_the_fits_world_to_clip(name):
    """three.js's look-at and projection of the data's numbers give the fit's OpenGL
    ``world_to_clip`` (``blocker_to_clip`` without the placement), and its
    ``LightShadow.matrix`` the fit's ``world_to_texture``. A wrong window (tangents not
    multiplied by ``near``), a wrong up (the map rolled), the orthographic eye not moved to
    the box's centre line or ``bottom``/``top`` swapped (three.js's argument order) each
    fail."""
    fit = FITS[name]()
    data = json.loads(json.dumps(threejs.shadow_data(fit)))  # JSON-ready, as sent
    world_to_clip = np.asarray(fit.blocker_to_clip) @ np.linalg.inv(fit.blocker_to_world)
    assert close(three_world_to_clip(data), world_to_clip)
    world = matrix_world(data["position"], data["target"], data["up"])
    assert close(shadow_matrix(three_projection(data), world), fit.world_to_texture)
    # The matrices shipped beside the numbers are the same ones.
    assert close(matrix(data["worldToClip"]), world_to_clip)
    assert close(matrix(data["matrixWorld"]), world)
    assert close(matrix(data["projectionMatrix"]), three_projection(data))
    assert data["mapSize"] == list(fit.map_size)


def test_a_perspective_cameras_fov_and_aspect_give_its_projection():
    """``PerspectiveCamera(fov, aspect, near, far).updateProjectionMatrix()`` of the data's
    ``fov`` (degrees) and ``aspect`` is its projection for a symmetric window (a point
    light's fit); a spot's window clipped to its cone is off-centre, which ``fov`` and
    ``aspect`` cannot say: the ES module builds it with ``makePerspective`` of the window."""
    data = threejs.shadow_data(FITS["point"]())
    built = perspective_camera_projection(data["fov"], data["aspect"], data["near"], data["far"])
    assert close(built, three_projection(data))
    spot = threejs.shadow_data(FITS["spot"]())
    built = perspective_camera_projection(spot["fov"], spot["aspect"], spot["near"], spot["far"])
    assert not close(built, three_projection(spot), rel=1e-3)


def test_three_js_default_spot_camera_is_not_the_fit():
    """What the ES module must override: three.js's ``SpotLightShadow.updateMatrices``
    (``fov = 2 angle focus`` in degrees, ``aspect`` of the map, the light's ``far``) draws a
    different map than the fit, which is tighter than the cone here."""
    fit = FITS["spot"]()
    data = threejs.shadow_data(fit)
    cone = perspective_camera_projection(np.degrees(2 * 0.6), 1.0, 0.5, 500.0)
    assert data["fov"] < np.degrees(2 * 0.6) - 10
    assert not close(cone, three_projection(data), rel=1e-3)


def test_the_webgpu_renderer_depth_is_the_0_1_depth_of_the_fit():
    """three.js's ``WebGPUCoordinateSystem`` projection is its WebGL one with depth mapped
    from [-1, 1] to [0, 1], ``z' = (z + w) / 2``: the fit's depth for the APIs with [0, 1]
    depth (its ``api_convention`` ``gl_clip_to_clip``'s depth row for WebGPU), and
    ``LightShadow``'s WebGPU shadow matrix is again the fit's texture matrix in x, y and
    depth."""
    for name in ("sun", "spot"):
        fit = FITS[name]()
        data = threejs.shadow_data(fit)
        gl, gpu = three_projection(data), three_projection(data, "webgpu")
        to01 = np.array([[1, 0, 0, 0], [0, 1, 0, 0], [0, 0, 0.5, 0.5], [0, 0, 0, 1.0]])
        assert close(gpu, to01 @ gl)
        convention = np.asarray(sm.api_convention(api="webgpu").gl_clip_to_clip)
        assert close(convention[2:], to01[2:])
        world = matrix_world(data["position"], data["target"], data["up"])
        assert close(shadow_matrix(gpu, world, "webgpu"), fit.world_to_texture)


def test_point_light_faces_are_three_js_cube_cameras():
    """Each face three.js draws (``WebGLShadowMap.js``: the camera at the light,
    ``up = _cubeUps[i]``, looking at ``light + _cubeDirections[i]``, through
    ``PerspectiveCamera(90, 1, near, far)``) is the package's face ``i``:
    ``cube_face_projection @ cube_face_views`` for OpenGL; the data's near and far are the
    fitted ones."""
    light = np.array([0.5, -1.0, 0.3])
    depth = sm.cube_depth_range(light, BOX, receivers=FLOOR)
    data = threejs.point_shadow_data(light, depth, map_size=128)
    projection = perspective_camera_projection(data["fov"], data["aspect"], depth.near, depth.far)
    expected = np.asarray(sm.cube_face_projection(depth.near, depth.far, map_size=128)) @ (
        np.asarray(sm.cube_face_views(light))
    )
    for i, (direction, up) in enumerate(zip(CUBE_DIRECTIONS, CUBE_UPS, strict=True)):
        world = matrix_world(light, light + np.array(direction), up)
        assert close(projection @ np.linalg.inv(world), expected[i])
        assert close(matrix(data["worldToClip"][i]), expected[i])
    assert (data["near"], data["far"]) == (float(depth.near), float(depth.far))


def test_cascades_each_cascade_is_its_fitted_camera():
    """Cascade ``i``'s numbers rebuild, through three.js's formulas, the cascade's
    ``world_to_clip`` and ``world_to_texture`` (``layout="layers"``, OpenGL), and the data
    carries the splits."""
    view = np.eye(4)
    view[:3, :3] = look_at([0, -10, 4], [0, 0, 0], [0, 0, 1]).T
    view[:3, 3] = -view[:3, :3] @ np.array([0.0, -10.0, 4.0])
    projection = perspective_camera_projection(50.0, 1.5, 0.5, 40.0)
    bounds = np.array([[-8.0, -8.0, -0.1], [8.0, 8.0, 3.0]])
    cascades = sm.fit_cascades([0.3, -0.4, 1.0], view, projection, bounds, 256, count=3)
    data = threejs.cascade_shadow_data(cascades)
    assert np.allclose(data["splits"], cascades.splits, rtol=0, atol=0)
    for i, cascade in enumerate(data["cascades"]):
        assert close(three_world_to_clip(cascade), cascades.world_to_clip[i])
        world = matrix_world(cascade["position"], cascade["target"], cascade["up"])
        assert close(shadow_matrix(three_projection(cascade), world), cascades.world_to_texture[i])


def test_bias_is_three_js_sign():
    """three.js adds ``shadow.bias`` to the receiver's [0, 1] depth before comparing
    (``shadowCoord.z += shadowBias``): a bias toward the light is negative there."""
    data = threejs.shadow_data(FITS["sun"](), depth_bias=2e-4)
    assert data["bias"] == -2e-4


@pytest.mark.parametrize(
    ("call", "match"),
    [
        (lambda: threejs.shadow_data("fit"), "fit: expected a ShadowSetup"),
        (
            lambda: threejs.shadow_data(sm.fit_shadow(np.zeros((2, 3)) + [0, 0, 9], BOX, 64)),
            "fit: expected one light's fit",
        ),
        (lambda: threejs.shadow_data(FITS["sun"](), depth_bias=np.nan), "depth_bias"),
        (
            lambda: threejs.point_shadow_data([0, 0, 0], sm.CubeDepthRange(2.0, 1.0), map_size=8),
            "depth_range: expected 0 < near < far",
        ),
        (
            lambda: threejs.point_shadow_data([0, 0, 0], sm.CubeDepthRange(1.0, 2.0), map_size=0),
            "map_size",
        ),
    ],
)
def test_bad_input_names_the_argument(call, match):
    with pytest.raises(ValueError, match=match):
        call()


def test_atlas_tiles_sample_as_three_js_viewports():
    """``LightShadow._updateMatrix`` with a viewport (``scaleX = viewport.z / frameExtents.x``,
    ``offsetX = viewport.x / frameExtents.x``, in units of the tile, as ``WebGLShadowMap``
    sizes them) of tile ``t``, applied to the tile's clip matrix, is the atlas's
    ``world_to_texture`` for OpenGL: three.js's viewport convention and the atlas's agree
    (a tile flipped, or placed from the top, fails)."""
    lights = [sm.PointLight([0.0, -3.0, 4.0]), sm.DirectionalLight([0.3, -0.2, 1.0])]
    lights.append(sm.SpotLight([2.0, -1.0, 5.0], [-0.3, 0.3, -1.0], 0.6))
    atlas = sm.allocate_atlas([1.0, 0.5, 0.2], atlas_size=1024)
    fit = sm.fit_atlas(lights, BOX, atlas, receivers=FLOOR)
    tiles = threejs.atlas_tile_data(fit)
    assert [t["light"] for t in tiles] == [0, 1, 2]
    for t, tile in enumerate(tiles):
        x, y, w, h = tile["viewport"]
        size = tile["atlasSize"]
        scale_x, scale_y, offset_x, offset_y = w / size[0], h / size[1], x / size[0], y / size[1]
        b = np.array(
            [
                [0.5 * scale_x, 0, 0, 0.5 * scale_x + offset_x],
                [0, 0.5 * scale_y, 0, 0.5 * scale_y + offset_y],
                [0, 0, 0.5, 0.5],
                [0, 0, 0, 1.0],
            ]
        )
        assert close(matrix(tile["worldToClip"]), fit.world_to_clip[t])
        assert close(b @ matrix(tile["worldToClip"]), fit.world_to_texture[t])


def test_the_pages_data_example_runs():
    """docs/threejs.md's first code block, run as it is: the three kinds of data."""
    from pathlib import Path

    text = (Path(__file__).parents[1] / "docs" / "threejs.md").read_text(encoding="utf-8")
    fence = "`" * 3
    block = text.split(fence + "python\n", 1)[1].split(fence, 1)[0]
    scope: dict[str, object] = {}
    exec(block, scope)
    assert scope["data"]["type"] == "orthographic"
    assert scope["spot_data"]["type"] == "perspective"
    assert scope["lamp_data"]["type"] == "cube"


def test_three_js_is_bundled_with_its_licence():
    """The package ships three.js (one ES module exporting the renderer and both controls)
    and its MIT notice."""
    source = threejs.THREE_PATH.read_text(encoding="utf-8")
    exports = source[source.rindex("export{") :]
    names = set(re.findall(r"(?:\bas |[{,])(\w+)(?=[,}])", exports))
    assert {"WebGLRenderer", "OrbitControls", "TransformControls", "CameraHelper"} <= names
    assert "NotAThreeName" not in names
    licence = threejs.LICENSE_PATH.read_text(encoding="utf-8")
    assert licence.startswith("The MIT License") and "three.js authors" in licence
    assert threejs.MODULE_PATH.is_file()
