"""Graphics API conventions: each API's texture matrix samples the texel its rasterizer drew.

The rasterizer of each API is simulated here in plain NumPy from its specification
(perspective divide, clip volume, viewport transform, framebuffer origin, which row
comes first in memory), independently of the matrices under test.
"""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from shadowmath import GRAPHICS_APIS, api_convention
from shadowmath._math._conventions import clip_from_gl, texture_from_clip, texture_from_gl_clip

TOP_LEFT_APIS = ("direct3d", "metal", "webgpu")


def gl_frustum(lf: float, r: float, b: float, t: float, n: float, f: float) -> np.ndarray:
    """``glFrustum``: OpenGL clip coordinates from eye coordinates (camera looks down -z)."""
    return np.array(
        [
            [2 * n / (r - lf), 0, (r + lf) / (r - lf), 0],
            [0, 2 * n / (t - b), (t + b) / (t - b), 0],
            [0, 0, -(f + n) / (f - n), -2 * f * n / (f - n)],
            [0, 0, -1, 0],
        ]
    )


def gl_ortho(lf: float, r: float, b: float, t: float, n: float, f: float) -> np.ndarray:
    """``glOrtho``: the affine clip matrix of a directional light's map."""
    return np.array(
        [
            [2 / (r - lf), 0, 0, -(r + lf) / (r - lf)],
            [0, 2 / (t - b), 0, -(t + b) / (t - b)],
            [0, 0, -2 / (f - n), -(f + n) / (f - n)],
            [0, 0, 0, 1],
        ]
    )


def rasterize(api: str, clip: np.ndarray, width: int, height: int) -> tuple[np.ndarray, ...]:
    """By the API's rules: ``(x_window, row_coordinate, stored_depth, inside)``.

    ``row_coordinate`` counts from the first row in memory (its floor is the row
    index). The viewport covers the whole ``width x height`` target and the depth
    range is the default ``[0, 1]``.
    """
    ndc = clip[..., :3] / clip[..., 3:]
    x, y, z = ndc[..., 0], ndc[..., 1], ndc[..., 2]
    x_window = width * (x + 1) / 2
    if api == "opengl":
        # Window origin lower left; glReadPixels / the attached texture's first row
        # is the bottom row. z_w = (f - n)/2 z + (n + f)/2 with n = 0, f = 1.
        row = height * (y + 1) / 2
        depth = (z + 1) / 2
        z_min = -1.0
    elif api == "vulkan":
        # Vulkan spec, viewport: y_f = (p_y / 2) y + o_y, o_y = y + height/2 with
        # the viewport's (x, y) its upper-left corner: y = -1 is framebuffer row 0,
        # the first row of the image in memory. z_f = p_z z + o_z = z.
        row = height / 2 * y + height / 2
        depth = z
        z_min = 0.0
    else:
        # D3D RSSetViewports, Metal, WebGPU: Y = (1 - y) * H/2 + TopLeftY, origin top left.
        row = (1 - y) * height / 2
        depth = z
        z_min = 0.0
    inside = (clip[..., 3] > 0) & (np.abs(x) <= 1) & (np.abs(y) <= 1) & (z >= z_min) & (z <= 1)
    return x_window, row, depth, inside


def api_clip(api: str, reversed_z: bool, gl_clip: np.ndarray) -> np.ndarray:
    C = api_convention(api=api, reversed_z=reversed_z).gl_clip_to_clip
    return gl_clip @ C.T


def texture(api: str, reversed_z: bool, clip: np.ndarray) -> tuple[np.ndarray, ...]:
    T = api_convention(api=api, reversed_z=reversed_z).clip_to_texture
    tex = clip @ T.T
    q = tex[..., 3]
    return tex[..., 0] / q, tex[..., 1] / q, tex[..., 2] / q, q


sizes = st.tuples(st.integers(1, 512), st.integers(1, 512))


@st.composite
def gl_scenes(draw: st.DrawFn) -> tuple[np.ndarray, np.ndarray]:
    """A random perspective or orthographic OpenGL projection and eye points inside it."""
    seed = draw(st.integers(0, 2**32 - 1))
    rng = np.random.default_rng(seed)
    n = rng.uniform(0.1, 5)
    f = n * rng.uniform(1.5, 50)
    lf, r = np.sort(rng.uniform(-3, 3, 2)) + np.array([0, 0.1])
    b, t = np.sort(rng.uniform(-3, 3, 2)) + np.array([0, 0.1])
    ortho = draw(st.booleans())
    P = gl_ortho(lf, r, b, t, n, f) if ortho else gl_frustum(lf, r, b, t, n, f)
    # Points at uniform NDC inside the box, at random eye depths between near and far.
    u = rng.uniform(0.001, 0.999, (64, 2))
    z_eye = -rng.uniform(n, f, 64)
    scale = np.ones(64) if ortho else -z_eye / n
    x_eye = (lf + (r - lf) * u[:, 0]) * scale
    y_eye = (b + (t - b) * u[:, 1]) * scale
    eye = np.stack([x_eye, y_eye, z_eye, np.ones(64)], axis=-1)
    return P, eye


def check_api(api: str, reversed_z: bool, P: np.ndarray, eye: np.ndarray, size: tuple[int, int]):
    W, H = size
    gl_clip = eye @ P.T
    clip = api_clip(api, reversed_z, gl_clip)
    x_window, row, depth, inside = rasterize(api, clip, W, H)
    assert inside.all(), "a point inside the OpenGL frustum left the API's clip volume"
    s, t, r, q = texture(api, reversed_z, clip)
    assert (q > 0).all()
    # Same place, as continuous coordinates: s W is the window x, t H the memory row.
    np.testing.assert_allclose(s * W, x_window, rtol=1e-12, atol=1e-9 * W)
    np.testing.assert_allclose(t * H, row, rtol=1e-12, atol=1e-9 * H)
    np.testing.assert_allclose(r, depth, rtol=1e-12, atol=1e-12)
    # Same texel: nearest sampling at (s, t) reads texel (floor(s W), floor(t H)),
    # the texel the rasterizer wrote (away from texel edges, where rounding decides).
    margin = 1e-6
    clear_x = np.abs(x_window - np.round(x_window)) > margin
    clear = clear_x & (np.abs(row - np.round(row)) > margin)
    np.testing.assert_array_equal(np.floor(s * W)[clear], np.floor(x_window)[clear])
    np.testing.assert_array_equal(np.floor(t * H)[clear], np.floor(row)[clear])
    # The depth the API stores for the near and far planes.
    conv = api_convention(api=api, reversed_z=reversed_z)
    assert ((depth >= 0) & (depth <= 1)).all()
    z_eye = -eye[:, 2]
    order = np.argsort(z_eye)
    d_sorted = depth[order]
    if conv.near_depth < conv.far_depth:
        assert (np.diff(d_sorted) >= -1e-12).all()
    else:
        assert (np.diff(d_sorted) <= 1e-12).all()


@pytest.mark.parametrize("reversed_z", [False, True])
@given(scene=gl_scenes(), size=sizes)
def test_opengl_samples_the_texel_it_drew(reversed_z: bool, scene, size) -> None:
    check_api("opengl", reversed_z, *scene, size)


@pytest.mark.parametrize("reversed_z", [False, True])
@given(scene=gl_scenes(), size=sizes)
def test_vulkan_samples_the_texel_it_drew(reversed_z: bool, scene, size) -> None:
    check_api("vulkan", reversed_z, *scene, size)


@pytest.mark.parametrize("reversed_z", [False, True])
@given(scene=gl_scenes(), size=sizes)
def test_direct3d_samples_the_texel_it_drew(reversed_z: bool, scene, size) -> None:
    check_api("direct3d", reversed_z, *scene, size)


@pytest.mark.parametrize("reversed_z", [False, True])
@given(scene=gl_scenes(), size=sizes)
def test_metal_samples_the_texel_it_drew(reversed_z: bool, scene, size) -> None:
    check_api("metal", reversed_z, *scene, size)


@pytest.mark.parametrize("reversed_z", [False, True])
@given(scene=gl_scenes(), size=sizes)
def test_webgpu_samples_the_texel_it_drew(reversed_z: bool, scene, size) -> None:
    check_api("webgpu", reversed_z, *scene, size)


@pytest.mark.parametrize("api", GRAPHICS_APIS)
@pytest.mark.parametrize("reversed_z", [False, True])
@given(size=sizes, seed=st.integers(0, 2**32 - 1))
def test_texel_centres_map_to_texel_centres(api: str, reversed_z: bool, size, seed: int) -> None:
    """A point the rasterizer places at a texel's centre gets exactly that centre's (s, t)."""
    W, H = size
    rng = np.random.default_rng(seed)
    col = rng.integers(0, W, 32)
    row = rng.integers(0, H, 32)
    x = 2 * (col + 0.5) / W - 1
    # Invert each API's viewport: the NDC y that lands on the centre of memory row `row`.
    y = 2 * (row + 0.5) / H - 1 if api in ("opengl", "vulkan") else 1 - 2 * (row + 0.5) / H
    z = rng.uniform(-1 if api == "opengl" else 0, 1, 32)
    w = rng.uniform(0.5, 4, 32)
    clip = np.stack([x * w, y * w, z * w, w], axis=-1)
    s, t, r, _ = texture(api, reversed_z, clip)
    np.testing.assert_allclose(s, (col + 0.5) / W, rtol=1e-13)
    np.testing.assert_allclose(t, (row + 0.5) / H, rtol=1e-13)
    _, _, depth, _ = rasterize(api, clip, W, H)
    np.testing.assert_allclose(r, depth, atol=1e-14)


@pytest.mark.parametrize("api", GRAPHICS_APIS)
@pytest.mark.parametrize("reversed_z", [False, True])
def test_near_and_far_depths(api: str, reversed_z: bool) -> None:
    """The OpenGL near plane (NDC -1) is stored as near_depth, the far plane as far_depth."""
    conv = api_convention(api=api, reversed_z=reversed_z)
    near_far = np.array([[0.3, -0.2, -1.0, 1.0], [0.3, -0.2, 1.0, 1.0]]) * 2.5
    r = near_far @ conv.gl_clip_to_texture.T
    np.testing.assert_allclose(r[:, 2] / r[:, 3], [conv.near_depth, conv.far_depth])
    assert conv.near_depth == (1.0 if reversed_z else 0.0)
    assert conv.far_depth == 1.0 - conv.near_depth
    np.testing.assert_array_equal(
        conv.gl_clip_to_texture, conv.clip_to_texture @ conv.gl_clip_to_clip
    )


def test_first_row_in_memory() -> None:
    """The light's image top (OpenGL clip y = +1): the last row in OpenGL, the first elsewhere."""
    top = np.array([0.0, 1.0, 0.0, 1.0])
    for api in GRAPHICS_APIS:
        t = (api_convention(api=api).gl_clip_to_texture @ top)[1]
        assert t == (1.0 if api == "opengl" else 0.0), api


def test_opengl_is_the_identity_and_the_standard_bias() -> None:
    conv = api_convention()
    np.testing.assert_array_equal(conv.gl_clip_to_clip, np.eye(4))
    bias = np.array([[0.5, 0, 0, 0.5], [0, 0.5, 0, 0.5], [0, 0, 0.5, 0.5], [0, 0, 0, 1]])
    np.testing.assert_array_equal(conv.clip_to_texture, bias)


def test_private_cores_are_nested_tuples() -> None:
    for api in GRAPHICS_APIS:
        for rz in (False, True):
            for core in (clip_from_gl, texture_from_clip, texture_from_gl_clip):
                m = core(api, rz)
                assert isinstance(m, tuple)
                assert np.asarray(m).shape == (4, 4)
    np.testing.assert_array_equal(
        np.asarray(texture_from_gl_clip("vulkan", True)),
        api_convention(api="vulkan", reversed_z=True).gl_clip_to_texture,
    )


@pytest.mark.parametrize("api", ["OpenGL", "d3d", "gl", "", None, 3])
def test_unknown_api(api: object) -> None:
    with pytest.raises(ValueError, match=r"api: unknown graphics API") as err:
        api_convention(api=api)  # type: ignore[arg-type]
    for name in GRAPHICS_APIS:
        assert repr(name) in str(err.value)


def test_reversed_z_must_be_a_boolean() -> None:
    with pytest.raises(ValueError, match="reversed_z"):
        api_convention(reversed_z="yes")  # type: ignore[arg-type]


def test_options_are_keyword_only() -> None:
    with pytest.raises(TypeError):
        api_convention("vulkan")  # type: ignore[misc]
