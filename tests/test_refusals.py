"""Inputs that are not what they claim are refused at the door, naming the argument.

A camera projection that is not one (transposed, scaled, singular, a last row neither
perspective nor orthographic); triangles given as a raw array where receivers are
points; a spec beside keywords that conflict with it; non-numeric input. Every
correct projection (each API, reversed Z, perspective, orthographic, infinite far)
is still accepted, and gives the cascades of the same camera in OpenGL's terms.
"""

from __future__ import annotations

from typing import Any

import jax
import jax.numpy as jnp
import numpy as np
import pytest
from jax.experimental import checkify

import shadowmath as sm
from shadowmath import meshes

from .cameras import look_at, orthographic, perspective

SUN = np.array([0.3, 1.0, 0.5])
VIEW = look_at([0, 2, 0], [0, 1, -10])
PERSPECTIVE = perspective(1.0, 1.5, 0.1, 300)
BOX = np.array([[-50.0, 0, -50], [50, 5, 50]])
FLIP_Z = np.diag([1.0, 1.0, -1.0, 1.0])


def _infinite(proj: np.ndarray) -> np.ndarray:
    near = proj[2, 3] / (proj[2, 2] - 1)
    out = proj.copy()
    out[2, 2], out[2, 3] = -1.0, -2 * near
    return out


CAMERAS = {
    "perspective": (PERSPECTIVE, {}),
    "orthographic": (orthographic(20, 15, 0.5, 120), {}),
    "infinite": (_infinite(PERSPECTIVE), {"max_distance": 80.0}),
}


# --- projections ----------------------------------------------------------------------------


@pytest.mark.parametrize("camera", CAMERAS)
@pytest.mark.parametrize("api", sm.GRAPHICS_APIS)
@pytest.mark.parametrize("reversed_z", [False, True])
@pytest.mark.parametrize("left_handed", [False, True])
def test_every_true_projection_is_accepted(
    camera: str, api: str, reversed_z: bool, left_handed: bool
) -> None:
    """The same camera in any API, reversed or not, looking down -z or +z of its view
    space (a left-handed view: last row (0, 0, 1, 0)), fits the OpenGL camera's cascades."""
    proj, options = CAMERAS[camera]
    gl = sm.fit_cascades(SUN, VIEW, proj, BOX, 256, **options)
    view, p = (FLIP_Z @ VIEW, proj @ FLIP_Z) if left_handed else (VIEW, proj)
    C = sm.api_convention(api=api, reversed_z=reversed_z).gl_clip_to_clip
    c = sm.fit_cascades(SUN, view, C @ p, BOX, 256, camera_api=api,
                        camera_reversed_z=reversed_z, **options)  # fmt: skip
    np.testing.assert_allclose(c.splits, gl.splits, rtol=1e-12)
    np.testing.assert_allclose(c.world_to_clip, gl.world_to_clip, rtol=1e-9, atol=1e-12)


def _bad_row(proj: np.ndarray, row: list[float]) -> np.ndarray:
    out = proj.copy()
    out[3] = row
    return out


BAD_PROJECTIONS = {
    "transposed perspective": PERSPECTIVE.T,
    "transposed off-centre orthographic": (
        orthographic(20, 15, 0.5, 120)
        @ np.array([[1, 0, 0, 0.3], [0, 1, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1.0]])
    ).T,
    "scaled": 2 * PERSPECTIVE,
    "projective mix": _bad_row(PERSPECTIVE, [0, 0, -1, 0.5]),
    "tilted": _bad_row(PERSPECTIVE, [0.1, 0, -1, 0]),
    "negative w": -orthographic(20, 15, 0.5, 120),
}


@pytest.mark.parametrize("name", BAD_PROJECTIONS)
@pytest.mark.parametrize("path", ["compiled", "array"])
def test_a_projection_that_is_not_one_is_refused(name: str, path: str) -> None:
    from shadowmath._backends import _kernels

    context = _kernels.array_path if path == "array" else _kernels.disabled
    with context(), pytest.raises(ValueError, match=r"projection: its last row is neither"):
        sm.fit_cascades(SUN, VIEW, BAD_PROJECTIONS[name], BOX, 256)


def test_the_transposed_projection_would_have_been_a_narrow_camera() -> None:
    """Why the scale is checked: up to scale the transpose is a camera (near 0.83, far
    1.25 for near 0.1, far 300), which a fit would silently use."""
    p = PERSPECTIVE.T / -PERSPECTIVE.T[3, 2]
    c = sm.fit_cascades(SUN, VIEW, p, BOX, 256)
    assert 0.8 < c.splits[0] < 0.9 and 1.2 < c.splits[-1] < 1.3


def test_a_singular_projection_is_refused() -> None:
    with pytest.raises(ValueError, match="projection: singular"):
        sm.fit_cascades(SUN, VIEW, np.diag([0.0, 1, 1, 1]), BOX, 256)
    with pytest.raises(ValueError, match=r"projection: expected shape \(\*batch, 4, 4\)"):
        sm.fit_cascades(SUN, VIEW, np.eye(3), BOX, 256)


def test_a_concrete_jax_projection_raises_too() -> None:
    with pytest.raises(ValueError, match=r"projection: its last row is neither"):
        sm.fit_cascades(SUN, VIEW, jnp.asarray(PERSPECTIVE.T), BOX, 256)


def test_under_jit_a_bad_projection_is_nan_and_checkify_names_it() -> None:
    def fit(p: Any) -> Any:
        return sm.fit_cascades(SUN, VIEW, p, BOX, 256).world_to_clip

    bad = np.asarray(jax.jit(fit)(jnp.asarray(PERSPECTIVE.T)))
    good = np.asarray(jax.jit(fit)(jnp.asarray(PERSPECTIVE)))
    assert np.all(np.isnan(bad)) and np.all(np.isfinite(good))
    both = np.asarray(jax.vmap(fit)(jnp.stack([PERSPECTIVE, PERSPECTIVE.T])))
    assert np.all(np.isfinite(both[0])) and np.all(np.isnan(both[1]))
    err, _ = checkify.checkify(jax.jit(fit))(jnp.asarray(PERSPECTIVE.T))
    with pytest.raises(checkify.JaxRuntimeError, match=r"projection: its last row is neither"):
        err.throw()


# --- a spec beside conflicting keywords -----------------------------------------------------

SPEC_KEYWORDS = [
    {"api": "vulkan"}, {"pcf_radius": 3}, {"stable": True}, {"border_texels": 2},
    {"reversed_z": True}, {"pcf_filter": "bilinear"}, {"pcf_radius": 3, "api": "vulkan"},
]  # fmt: skip


@pytest.mark.parametrize("keywords", SPEC_KEYWORDS)
def test_fit_cascades_refuses_keywords_beside_a_spec(keywords: dict[str, Any]) -> None:
    names = ", ".join(keywords)
    with pytest.raises(ValueError, match=f"{names}: given both in the ShadowMapSpec"):
        sm.fit_cascades(SUN, VIEW, PERSPECTIVE, BOX, sm.ShadowMapSpec(1024), **keywords)


def test_fit_cascades_reads_its_options_from_the_spec() -> None:
    spec = sm.ShadowMapSpec(1024, api="vulkan", pcf_radius=3, stable=True)
    from_spec = sm.fit_cascades(SUN, VIEW, PERSPECTIVE, BOX, spec)
    from_keywords = sm.fit_cascades(SUN, VIEW, PERSPECTIVE, BOX, 1024, api="vulkan",
                                    pcf_radius=3, stable=True)  # fmt: skip
    plain = sm.fit_cascades(SUN, VIEW, PERSPECTIVE, BOX, 1024)
    np.testing.assert_array_equal(from_spec.world_to_clip, from_keywords.world_to_clip)
    assert not np.allclose(from_spec.world_to_clip, plain.world_to_clip)


ATLAS_BOX = np.array([[x, y, z] for x in (-1, 1) for y in (0, 2) for z in (-1, 1)], float)
ATLAS_LIGHTS = [
    sm.SpotLight(np.array([0.0, 6.0, 0.0]), np.array([0.0, -1.0, 0.0]), np.array(0.6)),
    sm.PointLight(np.array([3.0, 1.0, 0.0])),
]


def _atlas(border: int = 1) -> sm.ShadowAtlas:
    return sm.allocate_atlas([0.5, 0.25], atlas_size=1024, cube=[False, True],
                             border_texels=border)  # fmt: skip


def test_fit_atlas_takes_its_options_from_a_spec() -> None:
    atlas = _atlas(border=2)
    spec = sm.ShadowMapSpec(1024, api="vulkan", reversed_z=True, pcf_radius=1)
    a = sm.fit_atlas(ATLAS_LIGHTS, ATLAS_BOX, atlas, spec=spec)
    b = sm.fit_atlas(ATLAS_LIGHTS, ATLAS_BOX, atlas, api="vulkan", reversed_z=True, pcf_radius=1)
    np.testing.assert_array_equal(a.world_to_texture, b.world_to_texture)
    plain = sm.fit_atlas(ATLAS_LIGHTS, ATLAS_BOX, atlas)
    assert not np.allclose(a.world_to_clip, plain.world_to_clip)


@pytest.mark.parametrize(
    ("spec", "keywords", "message"),
    [
        (sm.ShadowMapSpec(1024), {"api": "vulkan"}, "api: given both in the ShadowMapSpec"),
        (sm.ShadowMapSpec(1024), {"pcf_radius": 1}, "pcf_radius: given both in the"),
        (sm.ShadowMapSpec(1024), {"reversed_z": True}, "reversed_z: given both in the"),
        (sm.ShadowMapSpec(2048), {}, r"spec: its size \(2048, 2048\) is not the atlas's"),
        (sm.ShadowMapSpec(1024, stable=True), {}, "spec: an atlas's tiles take no stable"),
        (sm.ShadowMapSpec(1024, border_texels=3), {}, "spec: border_texels=3, but the atlas"),
        (sm.ShadowMapSpec(1024, pcf_radius=2), {}, "pcf_radius: a box kernel of radius 2"),
        (1024, {}, "spec: expected a ShadowMapSpec or None, got int"),
    ],
)
def test_fit_atlas_refuses_a_spec_that_conflicts(
    spec: Any, keywords: dict[str, Any], message: str
) -> None:
    with pytest.raises(ValueError, match=message):
        sm.fit_atlas(ATLAS_LIGHTS, ATLAS_BOX, _atlas(), spec=spec, **keywords)


# --- receivers never add batch dimensions ---------------------------------------------------

CASTERS = np.random.default_rng(3).normal(size=(20, 3)) * 0.5 + [0.0, 0.0, 8.0]
FLOOR = np.array([[[-30.0, -3, -30], [30, -3, -30], [30, -3, 30]],
                  [[-30.0, -3, -30], [30, -3, 30], [-30, -3, 30]]]) + [0.0, 0.0, 8.0]  # fmt: skip
RECEIVER_BATCH = r"receivers: its batch shape \(2,\) would make a batch of fits \(2,\)"


def test_raw_triangles_as_receivers_are_refused_not_read_as_a_batch() -> None:
    """The floor's triangles as a raw (2, 3, 3) array would be two sets of three points:
    two fits nobody asked for. Refused, naming sm.Triangles; wrapped, they are one fit
    whose far holds the floor."""
    with pytest.raises(ValueError, match=RECEIVER_BATCH + r".*sm\.Triangles"):
        sm.fit_shadow(np.zeros(3), CASTERS, 256, receivers=FLOOR)
    with pytest.raises(ValueError, match=RECEIVER_BATCH + r".*sm\.Triangles"):
        sm.cube_depth_range(np.zeros(3), CASTERS, receivers=FLOOR)
    with pytest.raises(ValueError, match=r"receivers: expected shape.*sm\.Triangles"):
        sm.fit_atlas(ATLAS_LIGHTS, ATLAS_BOX, _atlas(), receivers=FLOOR)
    fit = sm.fit_shadow(np.zeros(3), CASTERS, 256, receivers=sm.Triangles(FLOOR))
    assert fit.frustum.far.shape == ()
    assert fit.frustum.far > sm.fit_shadow(np.zeros(3), CASTERS, 256).frustum.far


def test_receivers_may_follow_the_batch_the_other_arguments_ask_for() -> None:
    lights = np.array([[0.0, 0.0, 0.0], [0.5, 0.0, 0.0]])
    points = np.stack([FLOOR.reshape(-1, 3), FLOOR.reshape(-1, 3) + [0, -1, 0]])  # (2, 6, 3)
    batched = sm.fit_shadow(lights, CASTERS, 256, receivers=points)
    for i in range(2):
        one = sm.fit_shadow(lights[i], CASTERS, 256, receivers=points[i])
        np.testing.assert_allclose(batched.frustum.far[i], one.frustum.far, rtol=1e-12)
    with pytest.raises(ValueError, match=r"receivers: its batch shape \(3, 2\)"):
        sm.fit_shadow(lights, CASTERS, 256, receivers=np.broadcast_to(points, (3, 2, 6, 3)))
    with pytest.raises(ValueError, match="batch dimensions do not broadcast"):
        sm.fit_shadow(lights, CASTERS, 256, receivers=np.zeros((3, 6, 3)))


# --- one Mesh type --------------------------------------------------------------------------


def test_the_mesh_builders_return_what_every_function_takes() -> None:
    """shadowmath.meshes builds sm.Mesh: as receivers it is the same surface as its
    triangles, as cube casters too; no second mesh type leaks NumPy's errors."""
    assert meshes.Mesh is sm.Mesh
    ground = meshes.grid((60.0, 60.0))
    ground = sm.Mesh(ground.vertices[:, [0, 2, 1]] * [1, 1, -1] + [0, -3, 8], ground.faces)
    assert isinstance(ground, sm.Mesh) and ground.faces.dtype == np.int64
    corners = sm.Triangles(ground.vertices[ground.faces])
    as_mesh = sm.fit_shadow(np.zeros(3), CASTERS, 256, receivers=ground)
    as_triangles = sm.fit_shadow(np.zeros(3), CASTERS, 256, receivers=corners)
    assert as_mesh.frustum.far == as_triangles.frustum.far
    box = meshes.box((1.0, 1.0, 1.0))
    box = sm.Mesh(box.vertices + [2.0, 0.0, 0.0], box.faces)
    a = sm.cube_depth_range(np.zeros(3), box, receivers=ground)
    b = sm.cube_depth_range(np.zeros(3), sm.Triangles(box.vertices[box.faces]), receivers=corners)
    assert (a.near, a.far) == (b.near, b.far)


# --- numbers, and nothing else --------------------------------------------------------------

NOT_NUMBERS = {
    "allocate_atlas coverage strings": (lambda: sm.allocate_atlas(["0.5"]),
                                        r"coverage: expected real numbers, got text \(dtype <U3\)"),
    "allocate_atlas coverage booleans": (lambda: sm.allocate_atlas([True, False]),
                                         "coverage: expected real numbers, got booleans"),
    "allocate_atlas coverage objects": (lambda: sm.allocate_atlas([object()]),
                                        "coverage: expected real numbers, got Python objects"),
    "allocate_atlas atlas_size string": (lambda: sm.allocate_atlas([0.5], atlas_size="4096"),
                                         "atlas_size: expected an integer, got '4096'"),
    "allocate_atlas atlas_size bool": (lambda: sm.allocate_atlas([0.5], atlas_size=True),
                                       "atlas_size: expected an integer, got True"),
    "allocate_atlas budget bytes": (lambda: sm.allocate_atlas([0.5], budget=b"1"),
                                    "budget: expected a number"),
    "allocate_atlas hysteresis bool": (lambda: sm.allocate_atlas([0.5], hysteresis=False),
                                       "hysteresis: expected a number, got False"),
    "allocate_atlas cube ragged": (lambda: sm.allocate_atlas([0.5, 0.1], cube=[[True], [1, 0]]),
                                   "cube: expected booleans"),
    "allocate_atlas light_ids strings": (lambda: sm.allocate_atlas([0.5], light_ids=["a"]),
                                         "light_ids: expected integers"),
    "fit_shadow light bytes": (lambda: sm.fit_shadow(b"abc", CASTERS, 64),
                               r"light: expected real numbers, got bytes \(dtype \|S3\)"),
    "fit_shadow vertices booleans": (lambda: sm.fit_shadow(np.zeros(3), CASTERS > 8, 64),
                                     "blocker_vertices: expected real numbers, got booleans"),
    "fit_shadow up with a bool": (lambda: sm.fit_shadow(np.zeros(3), CASTERS, 64, up=(0, True, 0)),
                                  "up: expected real numbers, got booleans"),
    "fit_shadow near string": (lambda: sm.fit_shadow(np.zeros(3), CASTERS, 64, near="0.5"),
                               "near: expected real numbers"),
    "fit_shadow map_size string": (lambda: sm.fit_shadow(np.zeros(3), CASTERS, "64"),
                                   "map_size: expected an integer, got '64'"),
    "fit_shadow map_size bool": (lambda: sm.fit_shadow(np.zeros(3), CASTERS, (64, True)),
                                 "map_size: expected an integer, got True"),
    "border_margin border string": (lambda: sm.border_margin(64, border_texels="1"),
                                    "border_texels: expected an integer, got '1'"),
    "fit_cascades lam bool": (lambda: sm.fit_cascades(SUN, VIEW, PERSPECTIVE, BOX, 64, lam=True),
                              "lam: expected real numbers, got booleans"),
    "fit_cascades overlap string": (
        lambda: sm.fit_cascades(SUN, VIEW, PERSPECTIVE, BOX, 64, overlap="0.1"),
        "overlap: expected real"),
    "fit_atlas near string": (lambda: sm.fit_atlas(ATLAS_LIGHTS, ATLAS_BOX, _atlas(), near="1"),
                              "near: expected real numbers"),
    "cube_depth_range map_size float": (
        lambda: sm.cube_depth_range(np.zeros(3), CASTERS, map_size=64.0, border_texels=1),
        "map_size: expected an integer"),
    "cube_face_projection map_size string": (lambda: sm.cube_face_projection(1.0, 2.0,
                                             map_size="8"), "map_size: expected an integer"),
    "torus radius string": (lambda: meshes.torus("1"), "major_radius: expected a number"),
    "grid segments bool": (lambda: meshes.grid(segments=(True, 2)),
                           r"segments\[0\]: expected an integer, got True"),
    "silhouette_coverage border bool": (lambda: sm.silhouette_coverage(np.ones((8, 8), bool),
                                        border_texels=True), "border_texels: expected an integer"),
}  # fmt: skip


@pytest.mark.parametrize("case", NOT_NUMBERS)
def test_what_is_not_a_number_is_refused_naming_the_argument(case: str) -> None:
    call, message = NOT_NUMBERS[case]
    with pytest.raises(ValueError, match=message):
        call()


def test_a_boolean_mask_is_still_a_mask() -> None:
    """Booleans are refused as coordinates, not as what they are: a coverage mask."""
    mask = np.zeros((8, 8), bool)
    mask[2:6, 2:4] = True
    assert float(sm.silhouette_coverage(mask, border_texels=2)) == 0.5


def test_the_reference_renderer_refuses_a_transposed_camera_too() -> None:
    from shadowmath import render as r

    ground = r.Body(*meshes.grid((20.0, 20.0)))
    sun = r.Light(direction=(0.3, 1.0, 0.5))
    lamp = sm.PointLight(np.array([0.0, 3.0, 0.0]))
    with pytest.raises(ValueError, match=r"projection: its last row is neither"):
        r.render_cascades([ground], sun, VIEW, PERSPECTIVE.T)
    with pytest.raises(ValueError, match=r"projection: its last row is neither"):
        r.render_atlas([ground], [lamp], VIEW, PERSPECTIVE.T)


@pytest.mark.parametrize("scale", [1e-3, 1.0, 1e6])
@pytest.mark.parametrize("path", ["compiled", "array"])
def test_a_placement_is_affine_to_rounding_of_its_own_size(scale: float, path: str) -> None:
    """blocker_to_world's last row is (0, 0, 0, 1) to rounding relative to the matrix's
    largest entry, whatever its units: a residue of 2 eps max|B| (a product's or an
    inverse's rounding) is taken, and places the blocker in the map as the exact row
    does; w = 1 + 1/4 (a projective scale) is refused at every scale."""
    from shadowmath._backends import _kernels

    context = _kernels.array_path if path == "array" else _kernels.disabled
    eps = float(np.finfo(np.float64).eps)
    B = np.diag([scale, scale, scale, 1.0])
    B[:3, 3] = [3.0 * scale, -scale, 2.0 * scale]
    verts = np.array([[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (4.0, 6.0)])
    light = np.array([3.3, -0.8, 2.0]) * scale  # off the box's axis: no helper-axis tie
    rounded = B.copy()
    rounded[3, 3] += 2 * eps * np.abs(B).max()
    with context():
        exact = sm.fit_shadow(light, verts, 64, blocker_to_world=B)
        taken = sm.fit_shadow(light, verts, 64, blocker_to_world=rounded)
        for setup in (exact, taken):  # every vertex inside the map's margins
            clip = np.c_[verts, np.ones(8)] @ np.asarray(setup.blocker_to_clip).T
            ndc = clip[:, :3] / clip[:, 3:]
            m = float(setup.frustum.margin_x)
            assert np.all(np.abs(ndc[:, :2]) <= m * (1 + 1e-6)) and np.all(np.abs(ndc[:, 2]) < 1)
        projective = B.copy()
        projective[3, 3] = 1.25
        with pytest.raises(
            ValueError, match=r"^blocker_to_world: .*last row is not \(0, 0, 0, 1\)"
        ):
            sm.fit_shadow(light, verts, 64, blocker_to_world=projective)
