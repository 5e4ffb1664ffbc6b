"""PCSS quantities (:func:`pcss_parameters`) against similar triangles in world space.

Each test puts a light disk (or a sun's cone) beside a blocker point and a receiver plane,
finds the true penumbra and blocker search region on the world's geometry, maps their
circles into the map with the fit's ``world_to_texture`` and compares their extent in
texels with ``K |d - d'|`` of the depths the map stores (``r`` of ``world_to_texture``).
"""

from __future__ import annotations

from typing import Any

import numpy as np
import pytest

import shadowmath as sm
from shadowmath._backends import _kernels

from .cameras import scene as camera_scene

RNG = np.random.default_rng(28)
APIS: tuple[Any, ...] = ("opengl", "vulkan", "direct3d")


@pytest.fixture(autouse=True, params=["compiled", "floats", "arrays"])
def path(request: pytest.FixtureRequest, monkeypatch: pytest.MonkeyPatch) -> None:
    """Every test on each of the door's paths: a few NumPy maps compiled by Numba (where it
    is installed) or on Python floats, and whole arrays (JAX, batches, atlases)."""
    if request.param == "floats":
        monkeypatch.setattr("shadowmath._fits.pcss._driver.form", _python_floats)
    if request.param == "arrays":
        monkeypatch.setattr("shadowmath._fits.pcss._door._SCALAR_MAPS", 0)


def _python_floats(numpy: bool, *, small: bool = False) -> str:
    """The backend choice of the "floats" path: the loop on Python floats, never compiled."""
    return "python"


def caster_box(rng: np.random.Generator) -> np.ndarray:
    c, h = rng.uniform(-2, 2, 3), rng.uniform(0.3, 1.5, 3)
    return np.array([c + h * [x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)])


def homogeneous(M: np.ndarray, p: np.ndarray) -> np.ndarray:
    return np.asarray(M @ np.r_[p, 1.0])


def depth(M: np.ndarray, p: np.ndarray) -> float:
    h = homogeneous(M, p)
    return float(h[2] / h[3])


def circle_extent(
    M: np.ndarray, size: tuple[float, float], centre: np.ndarray, radius: float, Z: np.ndarray
) -> np.ndarray:
    """Half the extent along ``s`` and ``t``, in texels, of the map's image of the circle of
    ``radius`` about ``centre`` in the plane perpendicular to ``Z``. On such a plane ``q`` is
    constant, so ``(s, t)`` is affine there and the image an ellipse: its half-extent along
    a coordinate is the norm of that coordinate's change along two orthonormal radii."""
    e1 = np.cross(Z, [0.3, 0.5, 0.8])
    e1 /= np.linalg.norm(e1)
    e2 = np.cross(Z, e1)

    def texels(p: np.ndarray) -> np.ndarray:
        h = homogeneous(M, p)
        return np.asarray(h[:2] / h[3] * np.asarray(size))

    c = texels(centre)
    a, b = texels(centre + radius * e1) - c, texels(centre + radius * e2) - c
    return np.asarray(np.hypot(a, b))


def perspective_case(M: np.ndarray, size: Any, L: np.ndarray, Z: np.ndarray, near: float,
                     p: sm.PcssParameters, R: float, B: np.ndarray, zR: float) -> None:  # fmt: skip
    """The penumbra of blocker point ``B`` and the search region of a receiver at light depth
    ``zR`` by similar triangles, against ``K`` through the stored depths."""
    zB = float((B - L) @ Z)
    receiver = L + (B - L) * zR / zB  # B's shadow from the light's centre
    # The disk's points L + rho send B to receiver + rho (1 - zR / zB): a circle about it.
    true_penumbra = circle_extent(M, size, receiver, R * (zR - zB) / zB, Z)
    dR, dB = depth(M, receiver), depth(M, B)
    widths = sm.pcss_widths(p, dR, dB)
    np.testing.assert_allclose(widths.penumbra, true_penumbra, rtol=1e-9)
    # The light seen from the receiver, cut by the near plane: a circle about the ray's point.
    on_near = receiver + (L - receiver) * (zR - near) / zR
    true_search = circle_extent(M, size, on_near, R * (zR - near) / zR, Z)
    np.testing.assert_allclose(widths.search, true_search, rtol=1e-9)
    np.testing.assert_allclose(depth(M, L + near * Z), p.near_depth, atol=1e-12)


@pytest.mark.parametrize("api", APIS)
@pytest.mark.parametrize("reversed_z", [False, True])
def test_point_light_penumbra_and_search_are_similar_triangles(api: Any, reversed_z: bool) -> None:
    rng = np.random.default_rng(1)
    for _ in range(5):
        verts = caster_box(rng)
        L = rng.uniform(-3, 3, 3) + [0, 9, 0]
        size = (int(rng.integers(64, 2048)), int(rng.integers(64, 2048)))
        fit = sm.fit_shadow(L, verts, size, api=api, reversed_z=reversed_z,
                            border_texels=int(rng.integers(0, 6)))  # fmt: skip
        R = float(rng.uniform(0.05, 1.0))
        p = sm.pcss_parameters(fit, light_radius=R, map_size=size)
        Z = fit.world_to_light[2, :3]
        B = verts[rng.integers(8)]
        zR = float((B - L) @ Z) * rng.uniform(1.05, 3)
        perspective_case(fit.world_to_texture, size, L, Z, float(fit.frustum.near), p, R, B, zR)
        assert float(p.near_depth) == float(reversed_z)


def test_spot_light_off_centre_frustum() -> None:
    rng = np.random.default_rng(2)
    verts = caster_box(rng)
    L = np.array([6.0, 8.0, -1.0])
    spot = sm.SpotLight(L, np.array([-0.6, -1.0, 0.1]), np.array(0.5))
    fit = sm.fit_shadow(spot, verts, (640, 480), api="webgpu")
    p = sm.pcss_parameters(fit, light_radius=0.3, map_size=sm.ShadowMapSpec((640, 480)))
    Z = fit.world_to_light[2, :3]
    for B in verts:
        zB = float((B - L) @ Z)
        perspective_case(fit.world_to_texture, (640, 480), L, Z, float(fit.frustum.near), p,
                         0.3, B, 2.5 * zB)  # fmt: skip


def orthographic_case(M: np.ndarray, size: Any, Z: np.ndarray, near_point: np.ndarray,
                      p: Any, theta: float, B: np.ndarray, zR: float) -> None:  # fmt: skip
    """A sun of angular radius ``theta`` travelling along ``Z``: blocker point ``B``, a
    receiver plane ``zR`` farther along ``Z``; ``near_point`` a point of the near plane."""
    receiver = B + zR * Z
    true_penumbra = circle_extent(M, size, receiver, np.tan(theta) * zR, Z)
    dR, dB = depth(M, receiver), depth(M, B)
    widths = sm.pcss_widths(p, dR, dB)
    np.testing.assert_allclose(widths.penumbra, true_penumbra, rtol=1e-9)
    to_near = float((receiver - near_point) @ Z)
    true_search = circle_extent(M, size, receiver - to_near * Z, np.tan(theta) * to_near, Z)
    np.testing.assert_allclose(widths.search, true_search, rtol=1e-9)
    np.testing.assert_allclose(depth(M, near_point), p.near_depth, atol=1e-12)


@pytest.mark.parametrize("reversed_z", [False, True])
def test_sun_penumbra_is_the_cone_of_its_angular_radius(reversed_z: bool) -> None:
    rng = np.random.default_rng(3)
    for theta in np.radians([0.5, 2.0, 5.0]):
        verts = caster_box(rng)
        sun = np.r_[rng.normal(size=3), 0.0]
        size = (1024, 512)
        fit = sm.fit_shadow(sun, verts, size, api="vulkan", reversed_z=reversed_z)
        p = sm.pcss_parameters(fit, angular_radius=theta, map_size=size)
        Z = -sun[:3] / np.linalg.norm(sun[:3])
        np.testing.assert_allclose(fit.world_to_light[2, :3], Z, atol=1e-12)
        light_to_world = np.linalg.inv(fit.world_to_light)
        near_point = (light_to_world @ [0.0, 0.0, float(fit.frustum.near), 1.0])[:3]
        B = verts[rng.integers(8)]
        orthographic_case(fit.world_to_texture, size, Z, near_point, p, theta, B, 1.7)


def test_a_point_light_and_a_sun_of_size_zero_cast_hard_shadows() -> None:
    """``light_radius = 0`` and ``angular_radius = 0`` lie inside the documented ranges
    (``>= 0``, ``[0, pi/2)``): accepted on every path (the fixture runs each), with no
    search and no penumbra, ``K = 0``; the smallest negative size is refused by name."""
    verts = caster_box(np.random.default_rng(5))
    point = sm.fit_shadow([0.0, 9.0, 0.0], verts, 256)
    sun = sm.fit_shadow(np.array([0.3, 1.0, 0.2, 0.0]), verts, 256)
    for fit, size in ((point, "light_radius"), (sun, "angular_radius")):
        p = sm.pcss_parameters(fit, **{size: 0.0})
        assert np.array_equal(p.texels_per_depth, np.zeros(2)), size
        with pytest.raises(ValueError, match=f"^{size}: expected"):
            sm.pcss_parameters(fit, **{size: -5e-324})


def cascade_points(view: np.ndarray, depth_: float) -> np.ndarray:
    """The point on the camera's axis at view depth ``depth_``."""
    inv = np.linalg.inv(view)
    return (inv @ [0.0, 0.0, -depth_, 1.0])[:3]


@pytest.mark.parametrize("layout", ["layers", "atlas"])
@pytest.mark.parametrize("seed", range(4))
def test_every_cascade_gives_the_same_world_penumbra(layout: Any, seed: int) -> None:
    sun, view, proj, box = camera_scene(seed)
    c = sm.fit_cascades(sun, view, proj, box, 1024, layout=layout, overlap=0.2)
    theta = np.radians(1.5)
    p = sm.pcss_parameters(c, angular_radius=theta)
    Z = -sun / np.linalg.norm(sun)
    n = c.splits.shape[-1] - 1
    for i in range(n - 1):  # a receiver in the band where cascades i and i + 1 blend
        receiver = cascade_points(view, 0.5 * (c.splits[i + 1] + c.band_end[i]))
        B = receiver - 3.0 * Z
        world = []
        for k in (i, i + 1):
            M = c.world_to_texture[k]
            one = sm.PcssParameters(p.texels_per_depth[k], p.near_depth[k])
            world.append(sm.pcss_widths(one, depth(M, receiver), depth(M, B)).penumbra
                         * c.texel_size[k])  # fmt: skip
            light_to_world = np.linalg.inv(c.world_to_light[k])
            near_point = (light_to_world @ [0.0, 0.0, float(c.frustum.near[k]), 1.0])[:3]
            orthographic_case(M, c.texture_size, Z, near_point, one, theta, B, 3.0)
        np.testing.assert_allclose(world[0], np.tan(theta) * 3.0, rtol=1e-9)
        np.testing.assert_allclose(world[1], world[0], rtol=1e-9)


@pytest.mark.parametrize("reversed_z", [False, True])
def test_cube_faces_are_similar_triangles(reversed_z: bool) -> None:
    rng = np.random.default_rng(4)
    L = np.array([0.5, 0.2, -0.3])
    verts = np.concatenate([caster_box(rng) * 0.5 + rng.uniform(-4, 4, 3) for _ in range(4)])
    N, b = 256, 3
    rng_ = sm.cube_depth_range(L, verts, map_size=N, border_texels=b)
    R = 0.2
    p = sm.pcss_parameters(rng_, light_radius=R, map_size=N, border_texels=b,
                           reversed_z=reversed_z)  # fmt: skip
    P = sm.cube_face_projection(rng_.near, rng_.far, map_size=N, border_texels=b,
                                api="metal", reversed_z=reversed_z)  # fmt: skip
    T = sm.api_convention(api="metal", reversed_z=reversed_z).clip_to_texture
    for B in verts:
        face = int(sm.cube_face(B - L).face)
        M = T @ P @ sm.cube_face_views(L)[face]
        Z = -sm.cube_face_views(L)[face][2, :3]  # a view looks down its -z
        zB = float((B - L) @ Z)
        perspective_case(M, (N, N), L, Z, float(rng_.near), p, R, B, 1.8 * zB)


def test_atlas_tiles_match_their_own_fits() -> None:
    verts = np.concatenate([caster_box(RNG) for _ in range(3)])
    lights = [sm.SpotLight(np.array([0.0, 12.0, 1.0]), np.array([0.0, -1.0, 0.0]), np.array(0.7)),
              sm.PointLight(np.array([0.5, 9.0, 0.0])),
              sm.DirectionalLight(np.array([0.2, 1.0, 0.3])),
              sm.PointLight(np.array([8.0, 0.5, 8.0]))]  # fmt: skip
    a = sm.allocate_atlas([0.5, 0.3, 0.4, 0.2], atlas_size=2048, border_texels=2,
                          cube=[False, False, False, True])  # fmt: skip
    fit = sm.fit_atlas(lights, verts, a, api="direct3d", reversed_z=True)
    R, theta = 0.25, np.radians(2.0)
    p = sm.pcss_parameters(fit, light_radius=R, angular_radius=theta)
    assert np.all(p.near_depth == 1.0)
    for li in range(3):
        t = a.light_tiles[li, 0]
        n = int(a.light_size[li])
        own = sm.fit_shadow(lights[li], verts, n, border_texels=2, api="direct3d",
                            reversed_z=True)  # fmt: skip
        kw = {"angular_radius": theta} if li == 2 else {"light_radius": R}
        ref = sm.pcss_parameters(own, map_size=n, **kw)
        # the tile's texels are the own map's: the same K
        np.testing.assert_allclose(p.texels_per_depth[t], ref.texels_per_depth, rtol=1e-9)
    L = np.array([8.0, 0.5, 8.0])
    n = int(a.light_size[3])
    rng_ = sm.cube_depth_range(L, verts, map_size=n, border_texels=2)
    ref = sm.pcss_parameters(rng_, light_radius=R, map_size=n, border_texels=2, reversed_z=True)
    for face in range(6):
        t = a.light_tiles[3, face]
        np.testing.assert_allclose(p.texels_per_depth[t], ref.texels_per_depth, rtol=1e-9)


# --- the door -------------------------------------------------------------------------------


def point_fit() -> sm.ShadowSetup:
    verts = caster_box(np.random.default_rng(5))
    return sm.fit_shadow([0.0, 9.0, 0.0], verts, 256)


@pytest.mark.parametrize(
    ("kwargs", "message"),
    [
        ({"light_radius": -0.1, "map_size": 256}, "light_radius: expected finite"),
        ({"light_radius": np.inf, "map_size": 256}, "light_radius: expected finite"),
        (
            {"light_radius": 0.1, "map_size": 512},
            "map_size: the fit was made for a 256x256 map, not 512x512",
        ),
        (
            {"light_radius": 0.1, "map_size": (256, 128)},
            "map_size: the fit was made for a 256x256 map, not 256x128",
        ),
        (
            {"angular_radius": 0.1, "map_size": 256},
            r"angular_radius: the fit's maps are all a point or spot light's, which take the "
            r"light's radius \(light_radius\), not the sun's angular radius; give light_radius "
            "instead",
        ),
        (
            {"angular_radius": 0.1, "light_radius": 0.1},
            r"angular_radius: .*; give light_radius only",
        ),
        (
            {"map_size": 256},
            "light_radius: the fit has a point or spot light's map, which needs the light's "
            "radius: give light_radius",
        ),
        ({"light_radius": 0.1, "map_size": 256, "reversed_z": True}, "reversed_z: the fit's"),
        ({"light_radius": 0.1, "map_size": 256, "border_texels": 2}, "border_texels: only"),
    ],
)
def test_the_door_names_the_argument(kwargs: dict[str, Any], message: str) -> None:
    with pytest.raises(ValueError, match=message):
        sm.pcss_parameters(point_fit(), **kwargs)


# --- the fit's recorded map size --------------------------------------------------------------


def test_a_fit_records_its_map_size_and_k_follows_it() -> None:
    """K counts the texels of the map the fit was made for: read from the fit, it equals K
    given that size by hand, and a map of twice the texels (same border) has twice the K."""
    verts, L = caster_box(np.random.default_rng(5)), np.array([0.0, 9.0, 0.0])
    small = sm.fit_shadow(L, verts, sm.ShadowMapSpec((256, 128), margin=0.9))
    large = sm.fit_shadow(L, verts, sm.ShadowMapSpec((512, 256), margin=0.9))
    assert small.map_size == (256, 128) and large.map_size == (512, 256)
    k = sm.pcss_parameters(large, light_radius=0.2).texels_per_depth
    by_hand = sm.pcss_parameters(large._replace(map_size=None), light_radius=0.2,
                                 map_size=(512, 256))  # fmt: skip
    np.testing.assert_array_equal(k, by_hand.texels_per_depth)
    np.testing.assert_allclose(k, 2 * sm.pcss_parameters(small, light_radius=0.2).texels_per_depth,
                               rtol=1e-12)  # fmt: skip


def test_a_setup_made_by_hand_needs_its_map_size() -> None:
    fit = point_fit()._replace(map_size=None)
    with pytest.raises(ValueError, match="map_size: a ShadowSetup made without fit_shadow"):
        sm.pcss_parameters(fit, light_radius=0.1)
    assert sm.pcss_parameters(fit, light_radius=0.1, map_size=256).texels_per_depth.shape == (2,)


def test_every_fit_path_records_the_map_size() -> None:
    """Compiled, on arrays (no Numba), one small fit on Python floats, batched, ShadowFitter:
    each ShadowSetup records the map it was fitted for, as Python ints."""
    verts, L, spec = caster_box(np.random.default_rng(5)), np.array([0.0, 9.0, 0.0]), (64, 32)
    fits = [sm.fit_shadow(L, verts, spec), sm.fit_shadow(np.stack([L, L]), verts, spec)]
    fitter = sm.ShadowFitter(L, verts, spec)
    fits.append(fitter.setup(fitter.fit(L, verts)))
    sun = sm.DirectionalLight(np.array([0.2, 1.0, 0.1]))
    fits.append(sm.fit_shadow(sun, sm.Triangles(verts[:6].reshape(2, 3, 3)), spec))
    with _kernels.disabled():  # one entry on Python floats, a batch on arrays
        fits += [sm.fit_shadow(L, verts, spec), sm.fit_shadow(np.stack([L, L]), verts, spec)]
        fits.append(fitter.setup(fitter.fit(L, verts)))
        with _kernels.array_path():
            fits.append(sm.fit_shadow(L, verts, spec))
    for fit in fits:
        assert fit.map_size == (64, 32)
        assert all(type(n) is int for n in fit.map_size)


def test_the_recorded_size_goes_through_jit_and_vmap() -> None:
    """JAX makes the recorded size arrays at a jit's or vmap's output (one per entry under
    vmap): pcss_parameters reads them; inside a transformation the size is given."""
    jax = pytest.importorskip("jax")
    jnp = jax.numpy
    verts = jnp.asarray(caster_box(np.random.default_rng(5)))
    ref = sm.pcss_parameters(sm.fit_shadow(np.array([0.0, 9.0, 0.0]), np.asarray(verts), 128),
                             light_radius=0.2).texels_per_depth  # fmt: skip

    def fit(position: Any) -> Any:
        return sm.fit_shadow(sm.PointLight(position), verts, 128)

    one = jax.jit(fit)(jnp.asarray([0.0, 9.0, 0.0]))
    many = jax.vmap(fit)(jnp.asarray([[0.0, 9.0, 0.0]] * 3))
    assert [int(n) for n in one.map_size] == [128, 128]
    rtol = 1e-12 if jax.config.jax_enable_x64 else 1e-5
    np.testing.assert_allclose(sm.pcss_parameters(one, light_radius=0.2).texels_per_depth, ref,
                               rtol=rtol)  # fmt: skip
    K = sm.pcss_parameters(many, light_radius=0.2).texels_per_depth
    np.testing.assert_allclose(K, np.broadcast_to(ref, (3, 2)), rtol=rtol)
    with pytest.raises(ValueError, match="map_size: the fit was made for a 128x128 map"):
        sm.pcss_parameters(many, light_radius=0.2, map_size=256)

    def inside(position: Any) -> Any:  # a fit made inside the transformation: Python ints
        return sm.pcss_parameters(fit(position), light_radius=0.2).texels_per_depth

    np.testing.assert_allclose(jax.jit(inside)(jnp.asarray([0.0, 9.0, 0.0])), ref, rtol=rtol)
    traced = jax.jit(lambda s: sm.pcss_parameters(s, light_radius=0.2, map_size=128))(one)
    np.testing.assert_allclose(traced.texels_per_depth, ref, rtol=rtol)
    with pytest.raises(ValueError, match="map_size: the fit's recorded map size is traced"):
        jax.jit(lambda s: sm.pcss_parameters(s, light_radius=0.2))(one)


def test_the_door_refuses_suns_and_other_fits() -> None:
    sun, view, proj, box = camera_scene(0)
    c = sm.fit_cascades(sun, view, proj, box, 256)
    with pytest.raises(ValueError, match=r"angular_radius: expected radians in \[0, pi/2\)"):
        sm.pcss_parameters(c, angular_radius=np.pi / 2)
    with pytest.raises(
        ValueError, match=r"light_radius: the fit's maps are all a directional light's.*only"
    ):
        sm.pcss_parameters(c, light_radius=0.1, angular_radius=0.01)
    with pytest.raises(ValueError, match="angular_radius: the fit has a directional light's map"):
        sm.pcss_parameters(c)
    with pytest.raises(ValueError, match="map_size: a Cascades records"):
        sm.pcss_parameters(c, angular_radius=0.01, map_size=256)
    with pytest.raises(ValueError, match="fit: expected a ShadowSetup"):
        sm.pcss_parameters(c.frustum, angular_radius=0.01)  # type: ignore[arg-type]
    sun, view, proj, box = camera_scene(1)  # a pose where the warp applies
    warped = sm.fit_cascades(sun, view, proj, box, 256, warp="lispsm")
    assert np.any(warped.world_to_texture[..., 3, :3] != 0)
    with pytest.raises(ValueError, match="fit: a warped cascade"):
        sm.pcss_parameters(warped, angular_radius=0.01)


def test_an_atlas_of_suns_needs_reversed_z() -> None:
    verts = caster_box(np.random.default_rng(6))
    a = sm.allocate_atlas([0.5], atlas_size=512)
    fit = sm.fit_atlas([sm.DirectionalLight(np.array([0.0, 1.0, 0.0]))], verts, a,
                       reversed_z=True)  # fmt: skip
    with pytest.raises(ValueError, match="reversed_z: an atlas of directional"):
        sm.pcss_parameters(fit, angular_radius=0.01)
    p = sm.pcss_parameters(fit, angular_radius=0.01, reversed_z=True)
    t = a.light_tiles[0, 0]
    M = np.asarray(fit.world_to_texture[t])
    assert p.near_depth[t] == 1.0
    down = np.array([0.0, -1.0, 0.0])  # the light's travel: depth falls along it, from 1
    assert depth(M, verts[0] + down) < depth(M, verts[0])


# --- JAX ------------------------------------------------------------------------------------


def test_derivatives_match_finite_differences() -> None:
    jax = pytest.importorskip("jax")
    jnp = jax.numpy
    from jax.test_util import check_grads

    verts = jnp.asarray(caster_box(np.random.default_rng(7)))

    def point(light: Any, vertices: Any, radius: Any) -> Any:
        fit = sm.fit_shadow(light, vertices, 256)
        return sm.pcss_parameters(fit, light_radius=radius, map_size=256).texels_per_depth

    def sun(direction: Any, theta: Any) -> Any:
        fit = sm.fit_shadow(sm.DirectionalLight(direction), verts, (256, 128))
        return sm.pcss_parameters(fit, angular_radius=theta, map_size=(256, 128)).texels_per_depth

    args = (jnp.asarray([0.3, 9.0, -0.2]), verts, jnp.asarray(0.2))
    check_grads(point, args, order=1, modes=("fwd", "rev"), eps=1e-5, atol=1e-6, rtol=1e-6)
    args = (jnp.asarray([0.3, 1.0, 0.4]), jnp.asarray(0.03))
    check_grads(sun, args, order=1, modes=("fwd", "rev"), eps=1e-5, atol=1e-6, rtol=1e-6)


@pytest.mark.parametrize("output", ["K", "widened"])
def test_cascades_derivatives_match_finite_differences(output: str) -> None:
    """K of each cascade, and widen_cascades' matrices, in the sun and its angular radius."""
    jax = pytest.importorskip("jax")
    jnp = jax.numpy
    from jax.test_util import check_grads

    sun, view, proj, box = camera_scene(2)

    def f(direction: Any, theta: Any) -> Any:
        c = sm.fit_cascades(direction, view, proj, box, 512)
        if output == "K":
            return sm.pcss_parameters(c, angular_radius=theta).texels_per_depth
        return sm.widen_cascades(c, angular_radius=theta).world_to_texture

    args = (jnp.asarray(sun), jnp.asarray(0.02))
    check_grads(f, args, order=1, modes=("rev",), eps=1e-6, atol=1e-5, rtol=1e-5)


def test_invalid_sizes_are_nan_under_jit() -> None:
    jax = pytest.importorskip("jax")
    jnp = jax.numpy
    fit = sm.fit_shadow(jnp.asarray([0.0, 9.0, 0.0]), jnp.asarray(caster_box(RNG)), 256)

    @jax.jit
    def run(radius: Any) -> Any:
        return sm.pcss_parameters(fit, light_radius=radius, map_size=256)

    p = run(jnp.asarray([0.1, -0.1, jnp.inf]))
    assert np.all(np.isfinite(p.texels_per_depth[0])) and np.isfinite(p.near_depth[0])
    assert np.all(np.isnan(p.texels_per_depth[1:])) and np.all(np.isnan(p.near_depth[1:]))


# --- room for the kernel --------------------------------------------------------------------


def test_a_refit_with_the_border_holds_the_widest_search() -> None:
    rng = np.random.default_rng(8)
    verts, L, R = caster_box(rng), np.array([0.5, 7.0, -0.3]), 0.4
    p = sm.pcss_parameters(sm.fit_shadow(L, verts, 512), light_radius=R, map_size=512)
    b = sm.pcss_border_texels(p)
    fit = sm.fit_shadow(L, verts, 512, border_texels=b)
    q = sm.pcss_parameters(fit, light_radius=R, map_size=512)
    assert np.all(q.texels_per_depth <= p.texels_per_depth)
    # the widest search: a receiver on the far plane at the inner edge's corner
    fr = fit.frustum
    light_to_world = np.linalg.inv(fit.world_to_light)
    far = float(fr.far)
    corner = (light_to_world @ [float(fr.rx_max) * far, float(fr.ry_max) * far, far, 1.0])[:3]
    Z, near = fit.world_to_light[2, :3], float(fr.near)
    on_near = corner + (L - corner) * (far - near) / far
    reach = circle_extent(fit.world_to_texture, (512, 512), on_near, R * (far - near) / far, Z)
    h = homogeneous(fit.world_to_texture, on_near)
    centre = h[:2] / h[3] * 512
    assert np.all(centre + reach <= 512 - 0.5) and np.all(centre - reach >= 0.5)
    assert b >= np.ceil(q.texels_per_depth.max())


def test_widened_cascades_hold_the_search_of_their_edges() -> None:
    sun, view, proj, box = camera_scene(3)
    theta = np.radians(2.0)
    c = sm.fit_cascades(sun, view, proj, box, 1024, border_texels=2)
    wide = sm.widen_cascades(c, angular_radius=theta)
    Z = -sun / np.linalg.norm(sun)
    p, q = (sm.pcss_parameters(x, angular_radius=theta) for x in (c, wide))
    # the same world widths; the same depths
    np.testing.assert_allclose(p.texels_per_depth * c.texel_size,
                               q.texels_per_depth * wide.texel_size, rtol=1e-9)  # fmt: skip
    np.testing.assert_allclose(wide.world_to_texture[..., 2, :], c.world_to_texture[..., 2, :])
    for k in range(c.splits.shape[-1] - 1):
        fr = c.frustum
        to_world = np.linalg.inv(c.world_to_light[k])
        x = float(fr.center_x[k] + fr.half_width[k])
        y = float(fr.center_y[k] - fr.half_height[k])
        edge = (to_world @ [x, y, float(fr.far[k]), 1.0])[:3]  # a corner of the old box
        depth_span = float(fr.far[k] - fr.near[k])
        on_near = edge - depth_span * Z
        for fit, inside in ((c, False), (wide, True)):
            M = fit.world_to_texture[k]
            reach = circle_extent(M, (1024, 1024), on_near, np.tan(theta) * depth_span, Z)
            centre = homogeneous(M, on_near)[:2] * 1024
            held = np.all(centre + reach <= 1022 + 1e-6) and np.all(centre - reach >= 2 - 1e-6)
            assert held == inside


def test_widen_cascades_refuses_stable_and_bad_angles() -> None:
    sun, view, proj, box = camera_scene(0)
    with pytest.raises(ValueError, match="cascades: stable cascades cannot be widened"):
        sm.widen_cascades(sm.fit_cascades(sun, view, proj, box, 256, stable=True),
                          angular_radius=0.01)  # fmt: skip
    c = sm.fit_cascades(sun, view, proj, box, 256)
    with pytest.raises(ValueError, match="angular_radius: expected radians"):
        sm.widen_cascades(c, angular_radius=-0.01)


def test_a_cube_range_needs_a_positive_near() -> None:
    for near, far in ((0.0, 5.0), (2.0, 1.0), (np.nan, 3.0)):
        with pytest.raises(ValueError, match="fit: a CubeDepthRange needs 0 < near < far"):
            sm.pcss_parameters(sm.CubeDepthRange(np.array(near), np.array(far)),
                               light_radius=0.1, map_size=64)  # fmt: skip
