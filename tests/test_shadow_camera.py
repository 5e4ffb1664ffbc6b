"""Engine-neutral shadow cameras: every fit's matrices rebuilt from its camera's numbers.

The oracles are independent of shadowmath's code: PyGLM's double-precision ``lookAt``
(the bench extra, a port of the GLM library) for the view, and the OpenGL
specification's ``glFrustum`` and ``glOrtho`` matrices (``tests/cameras.py``; PyGLM's
own are float32 only) for the projection: what an engine builds its camera with.
"""

from __future__ import annotations

from typing import Any

import numpy as np
import pytest
from pyglm import glm

import shadowmath as sm
from shadowmath._fits.camera._shadow_camera import ShadowCamera, camera_to_world, shadow_camera

from .cameras import frustum, ortho, scene

RNG = np.random.default_rng(29)
BOX = np.array([[x, y, z] for x in (-1, 2) for y in (0, 3) for z in (-1.5, 1)], float)
FLOOR = np.array([[[-9.0, 0, -9], [9, 0, -9], [0, 0, 9]]])
PLACEMENT = np.array([[0, -1, 0, 2], [1, 0, 0, -1], [0, 0, 1, 0.5], [0, 0, 0, 1.0]])
LIGHTS = [[4.0, 9.0, 3.0, 1.0], [0.3, 1.0, -0.4, 0.0]]
APIS = [(api, rz) for api in sm.GRAPHICS_APIS for rz in (False, True)]


def _mat(m: Any) -> np.ndarray:
    return np.array(m, dtype=float)  # NumPy's array of a PyGLM matrix is row-major


def engine_clip(cam: ShadowCamera, i: Any = ()) -> np.ndarray:
    """OpenGL clip from world, as an engine builds it from the camera's numbers."""
    eye, f, up = (glm.dvec3(*np.asarray(v)[i]) for v in (cam.eye, cam.forward, cam.up))
    view = glm.lookAt(eye, eye + f, up)
    lo, r, b, t, n, far = (float(np.asarray(v)[i]) for v in cam[3:9])
    if cam.orthographic:
        return ortho(lo, r, b, t, n, far) @ _mat(view)
    return frustum(lo * n, r * n, b * n, t * n, n, far) @ _mat(view)


def assert_rebuilds(setup: sm.ShadowSetup, api: str, reversed_z: bool) -> None:
    cam = shadow_camera(setup)
    conv = sm.api_convention(api=api, reversed_z=reversed_z)
    for i in np.ndindex(np.shape(cam.near)):
        clip = engine_clip(cam, i)
        B = setup.blocker_to_world[i]
        scale = np.abs(setup.blocker_to_clip[i]).max()
        np.testing.assert_allclose(
            conv.gl_clip_to_clip @ clip @ B, setup.blocker_to_clip[i], rtol=0, atol=1e-12 * scale
        )
        tex = conv.clip_to_texture @ conv.gl_clip_to_clip @ clip
        np.testing.assert_allclose(
            tex, setup.world_to_texture[i], rtol=0, atol=1e-12 * np.abs(tex).max()
        )


@pytest.mark.parametrize(("api", "reversed_z"), APIS)
@pytest.mark.parametrize(
    "light",
    [
        sm.PointLight([4.0, 9.0, 3.0]),
        sm.DirectionalLight([0.3, 1.0, -0.4]),
        sm.SpotLight([4.0, 9.0, 3.0], [-0.4, -1.0, -0.3], np.radians(35.0)),
        np.array([[4.0, 9.0, 3.0, 1.0], [-2.0, 8.0, 1.0, 1.0]]),
        np.array([[0.3, 1.0, -0.4, 0.0], [-0.5, 1.0, 0.2, 0.0]]),  # a batch of boxes
    ],
    ids=["point", "directional", "spot", "points", "suns"],
)
def test_every_light_rebuilds_from_its_camera(light: Any, api: str, reversed_z: bool) -> None:
    setup = sm.fit_shadow(light, BOX, 256, api=api, reversed_z=reversed_z)
    assert_rebuilds(setup, api, reversed_z)


@pytest.mark.parametrize(
    "options",
    [
        {"up": [0.0, 0.0, 1.0]},
        {"stable": True, "up": [0.0, 1.0, 0.0]},
        {
            "pcf_radius": 3,
            "receivers": sm.Triangles(np.array([[[-9, 0, -9], [9, 0, -9], [0, 0, 9]]])),
        },
        {
            "blocker_to_world": np.array(
                [[0, -1, 0, 2], [1, 0, 0, -1], [0, 0, 1, 0.5], [0, 0, 0, 1.0]]
            )
        },
        {"map_size": (512, 128), "aim": "bbox"},
    ],
    ids=["up", "stable", "pcf-receivers", "placement", "non-square"],
)
@pytest.mark.parametrize(
    "light", [[4.0, 9.0, 3.0, 1.0], [0.3, 1.0, -0.4, 0.0]], ids=["point", "sun"]
)
def test_every_option_rebuilds_from_its_camera(light: list[float], options: dict[str, Any]) -> None:
    options = dict(options)
    size = options.pop("map_size", 256)
    setup = sm.fit_shadow(np.array(light), BOX, size, **options)
    assert_rebuilds(setup, "opengl", False)


def test_an_off_centre_fit_has_its_offset() -> None:
    # The optimized fit of a light far off the box's side is off-centre: the offset is the
    # window's centre, and the window still rebuilds the matrices (above).
    setup = sm.fit_shadow(sm.PointLight([9.0, 2.0, 0.0]), BOX, 256, method="optimized")
    cam = shadow_camera(setup)
    assert_rebuilds(setup, "opengl", False)
    fr = setup.frustum
    centre = np.array([fr.x_offset, fr.y_offset])
    assert np.abs(centre).min() > 0.01  # really off-centre
    np.testing.assert_allclose(cam.offset, centre, atol=1e-15)
    assert np.isclose(cam.width, 2 * fr.rx_max / fr.margin_x)
    assert np.isclose(cam.fov_y, 2 * np.arctan(fr.ry_max / fr.margin_y))


def test_an_orthographic_camera_is_centred_on_its_box() -> None:
    setup = sm.fit_shadow(sm.DirectionalLight([0.3, 1.0, -0.4]), BOX, 256)
    cam = shadow_camera(setup)
    fr, frame = setup.frustum, setup.frame
    assert isinstance(fr, sm.OrthographicBox) and cam.orthographic is True
    assert cam.left == -cam.right and cam.bottom == -cam.top
    np.testing.assert_array_equal(cam.offset, [0.0, 0.0])
    assert np.isnan(cam.fov_y)
    # The eye is the old origin moved across to the box's centre line, not along it.
    moved = cam.eye - frame.origin
    np.testing.assert_allclose(moved, fr.center_x * frame.x_axis + fr.center_y * frame.y_axis)
    # Every caster lies inside the window and the depth range, measured from the eye.
    rel = BOX - cam.eye
    right = np.cross(cam.forward, cam.up)
    x, y, z = rel @ right, rel @ cam.up, rel @ cam.forward
    assert np.all(np.abs(x) <= cam.right) and np.all(np.abs(y) <= cam.top)
    assert np.all((cam.near <= z) & (z <= cam.far))
    assert np.isclose(np.abs(x).max(), fr.half_width)
    assert np.isclose(np.abs(y).max(), fr.half_height)


def test_perspective_window_holds_the_casters_with_the_margin() -> None:
    setup = sm.fit_shadow(sm.PointLight([4.0, 9.0, 3.0]), BOX, 100)
    cam = shadow_camera(setup)
    rel = BOX - cam.eye
    right = np.cross(cam.forward, cam.up)
    z = rel @ cam.forward
    tx, ty = rel @ right / z, rel @ cam.up / z
    # MDV is symmetric: the widest caster sits at 0.98 of the half-window (the margin).
    assert np.isclose(np.abs(tx - cam.offset[0]).max(), 0.98 * cam.width / 2)
    assert np.all((cam.left < tx) & (tx < cam.right) & (cam.bottom < ty) & (ty < cam.top))
    assert np.all((cam.near < z) & (z < cam.far))


@pytest.mark.parametrize(("api", "reversed_z"), [("opengl", False), ("webgpu", True)])
@pytest.mark.parametrize("seed", [0, 1])
def test_each_cascade_rebuilds_from_its_camera(seed: int, api: str, reversed_z: bool) -> None:
    sun, view, proj, box = scene(seed)
    cas = sm.fit_cascades(sun, view, proj, box, 512, count=3, api=api, reversed_z=reversed_z)
    cam = shadow_camera(cas)
    assert cam.near.shape == (3,)
    conv = sm.api_convention(api=api, reversed_z=reversed_z)
    for i in range(3):
        clip = conv.gl_clip_to_clip @ engine_clip(cam, (i,))
        np.testing.assert_allclose(clip, cas.world_to_clip[i], atol=1e-12 * np.abs(clip).max())


def test_lispsm_cascades_have_no_orthographic_camera() -> None:
    sun, view, proj, box = scene(3)
    cas = sm.fit_cascades(sun, view, proj, box, 512, count=3, warp="lispsm")
    with pytest.raises(ValueError, match=r"^fit: these cascades are warped by LiSPSM"):
        shadow_camera(cas)


@pytest.mark.parametrize(
    ("look", "axis", "up_axis"), [("-z", [0, 0, -1], [0, 1, 0]), ("+y", [0, 1, 0], [0, 0, 1]),
                                  ("+z", [0, 0, 1], [0, 1, 0])],
)  # fmt: skip
def test_camera_to_world_points_the_engines_axis_along_forward(
    look: str, axis: list[int], up_axis: list[int]
) -> None:
    setup = sm.fit_shadow(np.array([[4.0, 9.0, 3.0, 1.0], [-2.0, 8.0, 1.0, 1.0]]), BOX, 64)
    cam = shadow_camera(setup)
    M = camera_to_world(cam, look=look)  # type: ignore[arg-type]
    assert M.shape == (2, 4, 4)
    np.testing.assert_allclose(np.linalg.det(M[:, :3, :3]), 1.0, atol=1e-12)
    np.testing.assert_allclose(M[:, :3, :3] @ axis, cam.forward, atol=1e-12)
    np.testing.assert_allclose(M[:, :3, :3] @ up_axis, cam.up, atol=1e-12)
    np.testing.assert_allclose(M[:, :3, 3], cam.eye, atol=0)
    if look == "-z":  # the inverse of the right-handed look-at view
        for i in range(2):
            eye, f, up = (glm.dvec3(*v[i]) for v in (cam.eye, cam.forward, cam.up))
            view = _mat(glm.lookAt(eye, eye + f, up))
            np.testing.assert_allclose(M[i] @ view, np.eye(4), atol=1e-12)


def test_a_left_handed_look_at_mirrors_the_window() -> None:
    # Babylon.js's LookAtLH with the same up: its x axis is -right, which camera_to_world
    # "+z" says, so its window along x is [-right, -left].
    cam = shadow_camera(sm.fit_shadow(sm.PointLight([9.0, 2.0, 0.0]), BOX, 64, method="optimized"))
    eye, f, up = (glm.dvec3(*v) for v in (cam.eye, cam.forward, cam.up))
    view_lh = _mat(glm.lookAtLH(eye, eye + f, up))
    np.testing.assert_allclose(camera_to_world(cam, look="+z") @ view_lh, np.eye(4), atol=1e-12)


def test_jax_fits_give_jax_cameras_with_gradients() -> None:
    jax = pytest.importorskip("jax")
    jnp = jax.numpy
    jax.config.update("jax_enable_x64", True)
    box = jnp.asarray(BOX)

    def fov(z: Any) -> Any:
        light = sm.PointLight(jnp.stack([jnp.asarray(4.0), jnp.asarray(9.0), z]))
        return shadow_camera(sm.fit_shadow(light, box, 256)).fov_y

    value, grad = jax.value_and_grad(fov)(jnp.asarray(3.0))
    h = 1e-6
    central = (fov(jnp.asarray(3.0 + h)) - fov(jnp.asarray(3.0 - h))) / (2 * h)
    assert np.isclose(float(value), float(fov(jnp.asarray(3.0))))
    assert np.isclose(float(grad), float(central), rtol=1e-6)
    np_cam = shadow_camera(sm.fit_shadow(np.array([4.0, 9.0, 3.0, 1.0]), BOX, 256))
    assert np.isclose(float(value), np_cam.fov_y, rtol=1e-12)

    @jax.jit
    def eye_of(setup: sm.ShadowSetup) -> Any:
        return shadow_camera(setup).eye

    bad = sm.fit_shadow(jnp.asarray([4.0, 9.0, 3.0, 1.0]), box, 256)
    bad = bad._replace(frustum=bad.frustum._replace(near=jnp.asarray(jnp.nan)))
    assert np.all(np.isnan(np.asarray(eye_of(bad))))


CAMERA = shadow_camera(sm.fit_shadow(sm.PointLight([0, 9, 0.0]), BOX, 8))


@pytest.mark.parametrize(
    ("call", "message"),
    [
        (lambda: shadow_camera((1, 2)), r"^fit: expected a ShadowSetup \(from fit_shadow\) or "
         r"Cascades \(from fit_cascades\), got tuple$"),
        (lambda: camera_to_world(CAMERA, look="-y"),
         r"^look: expected one of '-z', '\+z', '\+y', got '-y'$"),
        (lambda: camera_to_world((1, 2)), r"^camera: expected a ShadowCamera, got tuple$"),
    ],
)  # fmt: skip
def test_errors_name_the_argument(call: Any, message: str) -> None:
    with pytest.raises(ValueError, match=message):
        call()


def test_non_finite_fits_are_refused() -> None:
    setup = sm.fit_shadow(sm.PointLight([0.0, 9.0, 0.0]), BOX, 64)
    bad = setup._replace(frustum=setup.frustum._replace(far=np.inf))
    with pytest.raises(ValueError, match=r"^fit.frustum.far: contains non-finite values"):
        shadow_camera(bad)
