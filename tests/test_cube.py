"""Cube shadow maps: the face-selection table, the six views, the projection, the depth.

The reference is the specification's table typed in below (OpenGL 4.6 §8.13,
Table 8.19) and each API's rule for where a rasterized NDC ``y`` lands in memory;
the package's matrices are checked against them, never against themselves.
"""

from __future__ import annotations

from typing import Any

import jax
import jax.numpy as jnp
import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays

import shadowmath as sm

from .strategies import unit_vectors

APIS = ("opengl", "vulkan", "direct3d", "metal", "webgpu")

# Table 8.19: face -> (s_c, t_c, m_a) as functions of (x, y, z).
SPEC_TABLE = {
    0: lambda x, y, z: (-z, -y, x),  # +X
    1: lambda x, y, z: (z, -y, x),  # -X
    2: lambda x, y, z: (x, z, y),  # +Y
    3: lambda x, y, z: (x, -z, y),  # -Y
    4: lambda x, y, z: (x, -y, z),  # +Z
    5: lambda x, y, z: (-x, -y, z),  # -Z
}


def spec_face(d: np.ndarray) -> int:
    """The major axis (a direction without ties) and its sign, as the spec selects."""
    axis = int(np.argmax(np.abs(d)))
    return 2 * axis + (0 if d[axis] > 0 else 1)


def spec_st(face: int, d: np.ndarray) -> tuple[float, float, float]:
    sc, tc, ma = SPEC_TABLE[face](*map(float, d))
    return (sc / abs(ma) + 1) / 2, (tc / abs(ma) + 1) / 2, ma


def first_row_fraction(y_ndc: np.ndarray, api: str) -> np.ndarray:
    """Distance of a rasterized NDC y from the image's first row in memory, in image heights.

    OpenGL: window y = H (y + 1)/2 counted from the bottom row, which is the first
    row in memory. Vulkan: framebuffer y = H (y + 1)/2 from the top row, again the
    first row. Direct3D, Metal, WebGPU: y up in NDC, the viewport sends y = +1 to
    the top row, the first in memory.
    """
    return (y_ndc + 1) / 2 if api in ("opengl", "vulkan") else (1 - y_ndc) / 2


def homog(p: np.ndarray) -> np.ndarray:
    return np.concatenate([p, np.ones((*p.shape[:-1], 1))], axis=-1)


def f64(x: Any) -> np.ndarray:
    return np.asarray(x, dtype=np.float64)


def eps_of(dtype: Any) -> float:
    return float(np.finfo(dtype).eps)


direction_arrays = arrays(
    np.float64, (16, 3), elements=st.floats(-1, 1, allow_subnormal=False)
).filter(lambda d: bool(np.all(np.linalg.norm(d, axis=-1) > 1e-3)))


def untied(d: np.ndarray, margin: float) -> np.ndarray:
    """Rows of d whose largest magnitude beats the second by a relative margin."""
    a = np.sort(np.abs(d), axis=-1)
    return d[a[:, 2] > a[:, 1] * (1 + margin)]


# ------------------------------------------------------------------ cube_face


@given(direction_arrays)
def test_cube_face_follows_the_specification_table(to: Any, dtype: Any, d: np.ndarray) -> None:
    d = f64(to(d))  # the directions as the dtype under test holds them
    face, s, t = sm.cube_face(to(d))
    assert np.asarray(face).dtype == np.int32
    assert np.asarray(s).dtype == dtype
    for i in range(len(d)):
        a = np.sort(np.abs(d[i]))
        if a[2] == a[1]:
            continue  # ties: tested separately
        ref_face = spec_face(d[i])
        ref_s, ref_t, _ = spec_st(ref_face, d[i])
        assert int(face[i]) == ref_face
        assert abs(float(s[i]) - ref_s) <= 2 * eps_of(dtype)
        assert abs(float(t[i]) - ref_t) <= 2 * eps_of(dtype)
    assert np.all((np.asarray(s) >= 0) & (np.asarray(s) <= 1))
    assert np.all((np.asarray(t) >= 0) & (np.asarray(t) <= 1))


def test_every_direction_lies_in_exactly_one_face_frustum() -> None:
    """The six views and projections tile the sphere: no gap, no double coverage."""
    rng = np.random.default_rng(11)
    light = np.array([0.5, -2.0, 3.0])
    d = untied(rng.normal(size=(20000, 3)), 1e-9)
    p = light + d * rng.uniform(0.1, 50, size=(len(d), 1))
    clip = np.einsum(
        "fij,nj->nfi",
        sm.cube_face_projection(0.01, 100.0, map_size=64) @ sm.cube_face_views(light),
        homog(p),
    )
    x, y, w = clip[..., 0], clip[..., 1], clip[..., 3]
    inside = (w > 0) & (np.abs(x) <= w) & (np.abs(y) <= w)
    assert np.all(inside.sum(axis=1) == 1)
    np.testing.assert_array_equal(np.argmax(inside, axis=1), sm.cube_face(p - light).face)
    # ... and the spec's table agrees on each direction's face and range.
    for i in range(0, len(d), 97):
        f = spec_face(d[i])
        s, t, ma = spec_st(f, d[i])
        assert inside[i, f] and ma * (1 if f % 2 == 0 else -1) > 0 and 0 <= s <= 1 and 0 <= t <= 1


# Vulkan, "Cube Map Face Selection": "r_z wins over r_y and r_x, and [...] r_y wins over r_x".
TIE_PRIORITY = (2, 1, 0)


def vulkan_face(d: np.ndarray) -> int:
    """The face the specification's rule selects, ties included, typed in from its text."""
    a = np.abs(d)
    axis = next(k for k in TIE_PRIORITY if a[k] == a.max())
    return 2 * axis + (0 if d[axis] > 0 else 1)


TIED_AXES = [(0, 1), (0, 2), (1, 2), (0, 1, 2)]


def exact_ties() -> tuple[np.ndarray, np.ndarray]:
    """Every pattern of exact ties: each pair of axes and all three, every sign of each
    component, the untied component smaller (or zero); magnitudes exact in float32.

    Returns ``(directions (n, 3), expected faces (n,))``: the tied axis that comes last
    in x, y, z wins (Vulkan's rule), where the old rule picked the first.
    """
    directions, faces = [], []
    for tied in TIED_AXES:
        for m in (0.75, 3.0, 2.0**-10):
            for signs in np.ndindex(2, 2, 2):
                for rest in (0.0, 0.5):
                    d = np.array([1.0 - 2.0 * k for k in signs]) * m * rest
                    for axis in tied:
                        d[axis] = m * (1.0 - 2.0 * signs[axis])
                    directions.append(d)
                    winner = max(tied)
                    faces.append(2 * winner + (0 if d[winner] > 0 else 1))
    return np.array(directions), np.array(faces, dtype=np.int32)


def test_exact_ties_follow_the_vulkan_rule_on_every_pair_and_corner(to: Any, dtype: Any) -> None:
    d, expected = exact_ties()
    assert np.all(f64(to(d)) == d)  # exact in the dtype under test: still ties
    face, s, t = sm.cube_face(to(d))
    np.testing.assert_array_equal(face, expected)
    np.testing.assert_array_equal(expected, [vulkan_face(x) for x in d])
    for i in range(len(d)):
        ref_s, ref_t, _ = spec_st(int(expected[i]), d[i])
        assert (float(s[i]), float(t[i])) == (ref_s, ref_t)
    # cube_face_depth selects with the same rule, at D = the tied magnitude.
    n, f = 2.0**-12, 8.0
    r = sm.cube_face_depth(to(np.zeros(3)), to(d), to(n), to(f))
    np.testing.assert_array_equal(r.face, expected)
    D = np.max(np.abs(d), axis=-1)
    np.testing.assert_allclose(f64(r.depth), f * (D - n) / ((f - n) * D), rtol=8 * eps_of(dtype))


@pytest.mark.parametrize("dtype", [np.float64, np.float32], ids=["f64", "f32"])
def test_exact_ties_follow_the_vulkan_rule_under_jit(dtype: Any) -> None:
    d, expected = exact_ties()
    got = jax.jit(sm.cube_face)(jnp.asarray(d, dtype=dtype))
    assert got.s.dtype == dtype
    np.testing.assert_array_equal(got.face, expected)
    eager = sm.cube_face(jnp.asarray(d, dtype=dtype))
    np.testing.assert_array_equal(got.s, eager.s)
    np.testing.assert_array_equal(got.t, eager.t)
    depth = jax.jit(lambda p: sm.cube_face_depth(jnp.zeros(3, dtype), p, 0.25, 8.0).face)
    np.testing.assert_array_equal(depth(jnp.asarray(d, dtype=dtype)), expected)


@pytest.mark.parametrize("tied", TIED_AXES)
def test_ties_pick_the_last_axis_and_land_on_both_faces_edges(tied: tuple[int, ...]) -> None:
    rng = np.random.default_rng(len(tied) * 10 + tied[-1])
    for _ in range(50):
        m = rng.uniform(0.5, 2.0)
        d = rng.uniform(-0.99, 0.99, size=3) * m
        for axis in tied:
            d[axis] = m * rng.choice([-1.0, 1.0])
        face, s, t = sm.cube_face(d)
        assert int(face) // 2 == tied[-1], "z before y before x"
        candidates = [2 * axis + (0 if d[axis] > 0 else 1) for axis in tied]
        for f in candidates:
            sf, tf, _ = spec_st(f, d)
            # On every candidate face the direction is on the face's border ...
            assert 0 <= sf <= 1 and 0 <= tf <= 1
            assert sf in (0.0, 1.0) or tf in (0.0, 1.0)
            # ... and each face's (s, t) leads back to the same direction.
            back = sm.cube_face_direction(f, sf, tf)
            np.testing.assert_allclose(back * m, d, rtol=0, atol=4e-16 * m)
        assert (float(s), float(t)) == spec_st(int(face), d)[:2]


@st.composite
def directions_with_ties(draw: st.DrawFn) -> np.ndarray:
    """Nonzero directions, often with exactly tied magnitudes (edges and corners)."""
    if draw(st.booleans()):
        v = draw(unit_vectors())
        return np.asarray(v) * draw(st.sampled_from([1.0, 2.0**-20, 2.0**20]))
    magnitudes = draw(st.lists(st.sampled_from([0.0, 0.25, 0.5, 1.0, 3.0]), min_size=3, max_size=3))
    if not any(magnitudes):
        magnitudes[draw(st.integers(0, 2))] = 1.0
    signs = draw(st.lists(st.sampled_from([-1.0, 1.0]), min_size=3, max_size=3))
    return np.array(magnitudes) * np.array(signs)


@given(st.lists(directions_with_ties(), min_size=1, max_size=12))
def test_every_nonzero_direction_falls_in_exactly_one_face_of_its_major_axis(
    to: Any, dtype: Any, ds: list[np.ndarray]
) -> None:
    d = f64(to(np.stack(ds)))  # the directions as the dtype under test holds them
    face, s, t = sm.cube_face(to(d))
    face = np.asarray(face)
    a = np.abs(d)
    for i in range(len(d)):
        # The faces whose closed pyramid holds d: a largest-magnitude axis, with its sign
        # (two or three on an edge or a corner) ...
        holding = [
            f for f in range(6) if a[i, f // 2] == a[i].max() and (d[i, f // 2] > 0) == (f % 2 == 0)
        ]
        # ... of which the rule selects exactly one, the same every time.
        assert int(face[i]) in holding
        assert int(face[i]) == vulkan_face(d[i])
        axis = int(face[i]) // 2
        assert np.all(a[i, axis + 1 :] < a[i, axis]), "no later axis ties the winner"
    assert np.all((f64(s) >= 0) & (f64(s) <= 1) & (f64(t) >= 0) & (f64(t) <= 1))


@given(direction_arrays)
def test_round_trip_direction_face_st_direction(to: Any, dtype: Any, d: np.ndarray) -> None:
    d = f64(to(d))
    face, s, t = sm.cube_face(to(d))
    back = f64(sm.cube_face_direction(face, s, t))
    ma = np.max(np.abs(d), axis=-1, keepdims=True)
    assert np.all(np.max(np.abs(back), axis=-1) == 1)  # on the cube's surface
    assert np.all(np.abs(back * ma - d) <= 6 * eps_of(dtype) * ma)


@given(
    st.integers(0, 5),
    arrays(np.float64, (8, 2), elements=st.floats(0.001, 0.999)),
)
def test_round_trip_face_st_direction_face_st(
    to: Any, dtype: Any, face: int, st_: np.ndarray
) -> None:
    s, t = to(st_[:, 0]), to(st_[:, 1])
    d = sm.cube_face_direction(to(np.full(8, face)), s, t)
    assert np.asarray(d).dtype == dtype
    f2, s2, t2 = sm.cube_face(d)
    np.testing.assert_array_equal(f2, face)
    np.testing.assert_allclose(f64(s2), f64(s), rtol=0, atol=4 * eps_of(dtype))
    np.testing.assert_allclose(f64(t2), f64(t), rtol=0, atol=4 * eps_of(dtype))


def test_cube_face_direction_continues_the_face_plane_beyond_its_edges() -> None:
    # s = -0.25 on +X: a direction of the neighbouring face +Z, seen through +X's plane.
    d = sm.cube_face_direction(0, -0.25, 0.5)
    np.testing.assert_array_equal(d, [1.0, 0.0, 1.5])
    assert int(sm.cube_face(d).face) == 4


# ------------------------------------------------------------------ views


@pytest.mark.parametrize("batch", [(), (1,), (3, 1, 2)])
def test_views_are_rigid_and_put_the_light_at_the_origin(to: Any, dtype: Any, batch: Any) -> None:
    rng = np.random.default_rng(3)
    light = rng.normal(size=(*batch, 3)) * 100
    V = sm.cube_face_views(to(light))
    assert V.shape == (*batch, 6, 4, 4) and V.dtype == dtype
    V = f64(V)
    light = f64(to(light))
    R = V[..., :3, :3]
    np.testing.assert_array_equal(R @ np.swapaxes(R, -1, -2), np.broadcast_to(np.eye(3), R.shape))
    np.testing.assert_array_equal(np.linalg.det(R), 1.0)
    np.testing.assert_array_equal(V[..., 3, :], np.broadcast_to([0, 0, 0, 1.0], (*batch, 6, 4)))
    at_light = np.einsum("...fij,...j->...fi", V, homog(light))
    np.testing.assert_array_equal(at_light, np.broadcast_to([0, 0, 0, 1.0], (*batch, 6, 4)))


@pytest.mark.parametrize(
    ("face", "target", "up"),
    [(0, "+x", "-y"), (1, "-x", "-y"), (2, "+y", "+z"), (3, "-y", "-z"), (4, "+z", "-y")]
    + [(5, "-z", "-y")],
)
def test_views_are_look_at_cameras_with_the_specified_target_and_up(
    face: int, target: str, up: str
) -> None:
    axis = {"x": 0, "y": 1, "z": 2}

    def vec(spec: str) -> np.ndarray:
        v = np.zeros(3)
        v[axis[spec[1]]] = 1.0 if spec[0] == "+" else -1.0
        return v

    f, u = vec(target), vec(up)
    s = np.cross(f, u)
    look_at = np.array([s, np.cross(s, f), -f])  # gluLookAt's rotation
    np.testing.assert_array_equal(sm.cube_face_views(np.zeros(3))[face, :3, :3], look_at)


def test_a_batch_of_lights_gives_each_light_its_own_views(to: Any, dtype: Any) -> None:
    lights = np.random.default_rng(4).normal(size=(2, 3, 3)) * 10
    V = sm.cube_face_views(to(lights))
    assert V.shape == (2, 3, 6, 4, 4) and V.dtype == dtype
    for i in np.ndindex(lights.shape[:-1]):
        np.testing.assert_array_equal(V[i], sm.cube_face_views(to(lights[i])))


# ------------------------------------------------------------------ projection


@given(
    arrays(np.float64, (12, 3), elements=st.floats(-1, 1)).filter(
        lambda d: bool(np.all(np.linalg.norm(d, axis=-1) > 0.05))
    ),
    st.integers(1, 4096),
    st.integers(0, 8),
    st.sampled_from(APIS),
    st.booleans(),
)
def test_the_texel_drawn_for_p_is_the_texel_sampled_with_p_minus_light(
    to: Any, dtype: Any, d: np.ndarray, size: int, border: int, api: str, reversed_z: bool
) -> None:
    border = min(border, (size - 1) // 2)
    light = np.array([2.0, -1.0, 0.5])
    p = light + d * 3
    face, s, t = sm.cube_face(to(p - light))
    VP = f64(
        sm.cube_face_projection(
            to(0.1), to(10.0), map_size=size, border_texels=border, api=api, reversed_z=reversed_z
        )
    ) @ f64(sm.cube_face_views(to(light)))
    clip = np.einsum("nij,nj->ni", VP[np.asarray(face)], homog(f64(to(p))))
    assert np.all(clip[:, 3] > 0)
    ndc = clip[:, :3] / clip[:, 3:]
    inner = (size - 2 * border) / size
    tol = 16 * eps_of(dtype)
    np.testing.assert_allclose((ndc[:, 0] + 1) / 2, (border / size) + f64(s) * inner, atol=tol)
    np.testing.assert_allclose(
        first_row_fraction(ndc[:, 1], api), border / size + f64(t) * inner, atol=tol
    )


@pytest.mark.parametrize("api", APIS)
@pytest.mark.parametrize(("size", "border"), [(1, 0), (64, 0), (64, 1), (100, 3), (4096, 7)])
def test_a_45_degree_edge_direction_lands_on_the_inner_edge_of_the_border(
    api: str, size: int, border: int
) -> None:
    P = sm.cube_face_projection(0.5, 50.0, map_size=size, border_texels=border, api=api)
    V = sm.cube_face_views(np.zeros(3))
    rng = np.random.default_rng(size + border)
    for face in range(6):
        for s, t in [(0.0, rng.uniform()), (1.0, rng.uniform()), (rng.uniform(), 0.0)] + [
            (rng.uniform(), 1.0)
        ]:
            d = sm.cube_face_direction(face, s, t)
            clip = P @ V[face] @ np.append(d, 1.0)
            x = (clip[0] / clip[3] + 1) / 2 * size
            row = first_row_fraction(clip[1] / clip[3], api) * size
            # The face's edge at texel boundary b (or N - b), to a few ulps of N.
            assert x == pytest.approx(border + s * (size - 2 * border), abs=4e-16 * size)
            assert row == pytest.approx(border + t * (size - 2 * border), abs=4e-16 * size)
            edge = x if s in (0.0, 1.0) else row
            assert min(abs(edge - border), abs(edge - (size - border))) <= 4e-16 * size


@pytest.mark.parametrize("api", APIS)
@pytest.mark.parametrize("reversed_z", [False, True])
def test_depth_range_of_each_api(api: str, reversed_z: bool) -> None:
    n, f = 0.25, 40.0
    P = sm.cube_face_projection(n, f, map_size=16, api=api, reversed_z=reversed_z)
    lo = -1.0 if api == "opengl" else 0.0
    near_ndc, far_ndc = (1.0, lo) if reversed_z else (lo, 1.0)
    for D, expected in ((n, near_ndc), (f, far_ndc)):
        clip = P @ np.array([0.1, -0.2, -D, 1.0])
        assert clip[3] == D
        assert clip[2] / clip[3] == pytest.approx(expected, abs=1e-15)
    # Monotone in between: nearer is smaller depth, unless reversed.
    Ds = np.linspace(n, f, 50)
    z = np.array([(P @ [0, 0, -D, 1])[2] / D for D in Ds])
    assert np.all(np.diff(z) < 0) if reversed_z else np.all(np.diff(z) > 0)


@pytest.mark.parametrize("api", APIS)
@pytest.mark.parametrize("reversed_z", [False, True])
def test_depth_matches_the_api_conventions_but_y_follows_the_cube_map_table(
    api: str, reversed_z: bool
) -> None:
    """Rows 0, 2, 3 are api_convention's clip transform of the OpenGL projection; row 1 is not.

    For a 2D shadow map any y convention works as long as drawing and sampling
    agree (api_convention flips Vulkan's clip y and undoes it in its texture
    matrix). A cube map's sampling is fixed by the specification's table, so
    the face projection keeps OpenGL's y for Vulkan and flips it for the APIs
    whose first row is NDC y = +1.
    """
    P_gl = sm.cube_face_projection(0.5, 20.0, map_size=32, border_texels=2)
    P = sm.cube_face_projection(
        0.5, 20.0, map_size=32, border_texels=2, api=api, reversed_z=reversed_z
    )
    C = sm.api_convention(api=api, reversed_z=reversed_z).gl_clip_to_clip
    converted = C @ P_gl
    np.testing.assert_allclose(P[[0, 2, 3]], converted[[0, 2, 3]], rtol=1e-15, atol=1e-15)
    flip = api in ("direct3d", "metal", "webgpu")
    assert P[1, 1] == (-P_gl[1, 1] if flip else P_gl[1, 1])
    if api == "vulkan":
        assert converted[1, 1] == -P[1, 1]  # the 2D-map convention would mirror the face


@pytest.mark.parametrize("api", APIS)
@pytest.mark.parametrize("reversed_z", [False, True])
def test_a_batch_of_near_far_gives_each_pair_its_own_projection(
    to: Any, dtype: Any, api: str, reversed_z: bool
) -> None:
    near, far = np.array([[0.05], [0.5], [3.0]]), np.array([10.0, 300.0])
    kw: dict[str, Any] = {"map_size": 100, "border_texels": 3, "api": api, "reversed_z": reversed_z}
    P = sm.cube_face_projection(to(near), to(far), **kw)
    assert P.shape == (3, 2, 4, 4) and P.dtype == dtype
    for i, j in np.ndindex(3, 2):
        np.testing.assert_array_equal(
            P[i, j], sm.cube_face_projection(to(near[i, 0]), to(far[j]), **kw)
        )


@pytest.mark.parametrize(
    ("near", "far", "dtype"),
    [
        (0.5, 20.0, np.float64),
        (np.float64(0.5), 20.0, np.float64),
        (np.float32(0.5), np.float32(20.0), np.float32),
        (np.asarray(0.5, np.float32), np.asarray(20.0, np.float32), np.float32),
        (np.float32(0.5), 20.0, np.float64),  # float32 with float64 promotes, as everywhere
        (np.float16(0.5), np.float16(20.0), np.float32),
        (1, 20, np.float64),
    ],
)
def test_scalar_near_far_give_numpy_in_their_dtype_equal_to_the_batched_result(
    near: Any, far: Any, dtype: Any
) -> None:
    """One light's scalars (the per-frame case) give what a batch of one gives."""
    for api in APIS:
        kw: dict[str, Any] = {"map_size": 64, "border_texels": 1, "api": api}
        P = sm.cube_face_projection(near, far, **kw)
        assert type(P) is np.ndarray and P.shape == (4, 4) and P.dtype == dtype
        one = [np.full(1, x, dtype=np.result_type(x)) for x in (near, far)]
        np.testing.assert_array_equal(P, sm.cube_face_projection(*one, **kw)[0])


@given(
    arrays(np.float64, (10, 3), elements=st.floats(-20, 20)).filter(
        lambda p: bool(np.all(np.max(np.abs(p), axis=-1) > 0.6))
    ),
    st.sampled_from(APIS),
    st.booleans(),
)
def test_cube_face_depth_is_the_depth_the_face_projection_stores(
    to: Any, dtype: Any, p: np.ndarray, api: str, reversed_z: bool
) -> None:
    light = np.array([0.25, 0.5, -0.125])
    p = light + p
    n, f = 0.5, 30.0
    r = sm.cube_face_depth(to(light), to(p), to(n), to(f), reversed_z=reversed_z)
    assert np.asarray(r.depth).dtype == dtype
    p64, light64 = f64(to(p)), f64(to(light))
    # The direction as the dtype computes it (one correctly rounded subtraction).
    np.testing.assert_array_equal(r.face, sm.cube_face(f64(to(p64 - light64))).face)
    VP = f64(sm.cube_face_projection(n, f, map_size=8, api=api, reversed_z=reversed_z))
    clip = np.einsum(
        "nij,nj->ni", VP @ f64(sm.cube_face_views(light64))[np.asarray(r.face)], homog(p64)
    )
    z = clip[:, 2] / clip[:, 3]
    stored = (z + 1) / 2 if api == "opengl" else z  # the default depth range [0, 1]
    cond = f / (f - n) * np.maximum(1, n / np.max(np.abs(p64 - light64), axis=-1)) + 1
    assert np.all(np.abs(f64(r.depth) - stored) <= 8 * eps_of(dtype) * cond)
    np.testing.assert_allclose(
        f64(r.distance), np.linalg.norm(p64 - light64, axis=-1), rtol=4 * eps_of(dtype)
    )


def test_cube_face_depth_broadcasts_points_against_lights() -> None:
    lights = np.zeros((2, 1, 3)) + [[[0.0, 0.0, 0.0]], [[0.0, 0.0, 1.0]]]
    points = np.array([[0.0, 0.0, 5.0], [0.0, 3.0, 0.0], [-2.0, 0.0, 0.0]])
    r = sm.cube_face_depth(lights, points, 1.0, np.array([10.0, 20.0, 30.0]))
    assert r.face.shape == r.depth.shape == r.distance.shape == (2, 3)
    np.testing.assert_array_equal(r.face, [[4, 2, 1], [4, 2, 1]])
    np.testing.assert_allclose(r.distance[1], [4.0, np.sqrt(10), np.sqrt(5)])
    np.testing.assert_allclose(r.depth[0, 0], 10 * 4 / (9 * 5))


# ------------------------------------------------------------------ errors


@pytest.mark.parametrize(
    ("call", "message"),
    [
        (lambda: sm.cube_face_projection(0.0, 1.0, map_size=8), "near: must be > 0"),
        (lambda: sm.cube_face_projection(-1.0, 1.0, map_size=8), "near: must be > 0"),
        (lambda: sm.cube_face_projection(2.0, 2.0, map_size=8), "far: must be greater than near"),
        (lambda: sm.cube_face_projection(1.0, [5.0, 0.5], map_size=8), "far: must be greater"),
        (lambda: sm.cube_face_projection(np.nan, 1.0, map_size=8), "near: contains non-finite"),
        (lambda: sm.cube_face_projection(1.0, 2.0, map_size=8, api="gl"), "api: unknown"),
        (lambda: sm.cube_face_projection(1.0, 2.0, map_size=0), "map_size: must be >= 1"),
        (lambda: sm.cube_face_projection(1.0, 2.0, map_size=8.0), "map_size: expected an integer"),
        (
            lambda: sm.cube_face_projection(1.0, 2.0, map_size=8, border_texels=4),
            "leaves no inner texel",
        ),
        (lambda: sm.cube_face_projection(1, 2, map_size=8, border_texels=-1), "border_texels"),
        (lambda: sm.cube_face([[1.0, 0, 0], [0, 0, 0]]), "directions: a direction is zero"),
        (lambda: sm.cube_face([1.0, np.inf, 0]), "directions: contains non-finite"),
        (lambda: sm.cube_face([1.0, 0]), r"directions: expected shape \(\*batch, 3\)"),
        (lambda: sm.cube_face_views([1.0, np.nan, 0]), "light_position: contains non-finite"),
        (lambda: sm.cube_face_views(np.zeros((2, 4))), "light_position: expected shape"),
        (lambda: sm.cube_face_direction(6, 0.5, 0.5), "face: must be an integer from 0 to 5"),
        (lambda: sm.cube_face_direction(1.5, 0.5, 0.5), "face: must be an integer"),
        (lambda: sm.cube_face_direction(-1, 0.5, 0.5), "face: must be an integer"),
        (lambda: sm.cube_face_direction(1, np.nan, 0.5), "s: contains non-finite"),
        (
            lambda: sm.cube_face_depth([0.0, 0, 0], [[1.0, 0, 0], [0, 0, 0]], 0.1, 2.0),
            "points: a point coincides with light_position",
        ),
        (lambda: sm.cube_face_depth([0.0, 0, 0], [1.0, 0, 0], 3.0, 2.0), "far: must be greater"),
    ],
)
def test_bad_input_raises_a_value_error_naming_the_argument(call: Any, message: str) -> None:
    with pytest.raises(ValueError, match=message):
        call()


def test_the_first_failing_batch_entry_is_reported() -> None:
    with pytest.raises(ValueError, match=r"first at batch index \(2,\)"):
        sm.cube_face([[1.0, 0, 0], [0, 1.0, 0], [0, 0, 0]])


# ------------------------------------------------------------------ JAX


def test_jit_and_vmap_equal_numpy() -> None:
    rng = np.random.default_rng(5)
    d = rng.normal(size=(7, 3))
    got = jax.jit(sm.cube_face)(jnp.asarray(d))
    want = sm.cube_face(d)
    np.testing.assert_array_equal(got.face, want.face)
    np.testing.assert_allclose(got.s, want.s, rtol=1e-15)
    np.testing.assert_allclose(got.t, want.t, rtol=1e-15)
    lights = jnp.asarray(rng.normal(size=(4, 3)))
    np.testing.assert_array_equal(jax.vmap(sm.cube_face_views)(lights), sm.cube_face_views(lights))
    proj = jax.jit(lambda n, f: sm.cube_face_projection(n, f, map_size=64, border_texels=1))
    np.testing.assert_allclose(
        proj(jnp.asarray(0.5), jnp.asarray(9.0)),
        sm.cube_face_projection(0.5, 9.0, map_size=64, border_texels=1),
        rtol=1e-15,
    )
    depth = jax.jit(lambda L, p: sm.cube_face_depth(L, p, 0.5, 9.0).depth)
    np.testing.assert_allclose(
        depth(lights, jnp.asarray(d[:4])), sm.cube_face_depth(lights, d[:4], 0.5, 9.0).depth
    )


def test_gradients_match_finite_differences() -> None:
    d0 = np.array([0.8, -0.3, 0.45])

    def s_plus_2t(d: Any) -> Any:
        r = sm.cube_face(d)
        return r.s + 2 * r.t

    g = np.asarray(jax.grad(s_plus_2t)(jnp.asarray(d0)))
    h = 1e-6
    fd = [
        (float(s_plus_2t(d0 + h * e)) - float(s_plus_2t(d0 - h * e))) / (2 * h) for e in np.eye(3)
    ]
    np.testing.assert_allclose(g, fd, rtol=1e-7, atol=1e-9)

    def depth(light: Any) -> Any:
        return sm.cube_face_depth(light, jnp.asarray([3.0, 1.0, -0.5]), 0.5, 10.0).depth

    L0 = np.array([0.1, 0.2, 0.3])
    g = np.asarray(jax.grad(depth)(jnp.asarray(L0)))
    fd = [(float(depth(L0 + h * e)) - float(depth(L0 - h * e))) / (2 * h) for e in np.eye(3)]
    np.testing.assert_allclose(g, fd, rtol=1e-7, atol=1e-9)


def test_the_views_derivative_is_minus_the_rotation_in_the_translation_column() -> None:
    light = jnp.asarray([0.3, -1.2, 2.5])
    J = np.asarray(jax.jacobian(sm.cube_face_views)(light))  # (6, 4, 4, 3)
    R = np.asarray(sm.cube_face_views(light))[:, :3, :3]
    expected = np.zeros((6, 4, 4, 3))
    expected[:, :3, 3, :] = -R
    np.testing.assert_array_equal(J, expected)


def test_bad_values_give_nan_under_jit_never_a_finite_wrong_result() -> None:
    d = jnp.asarray([[1.0, 0.0, 0.0], [0.0, 0.0, 0.0]])
    r = jax.jit(sm.cube_face)(d)
    assert np.isfinite(r.s[0]) and np.isnan(r.s[1]) and np.isnan(r.t[1])
    np.testing.assert_array_equal(r.face, [0, -1])

    proj = jax.jit(lambda n, f: sm.cube_face_projection(n, f, map_size=8))
    P = np.asarray(proj(jnp.asarray([0.5, -0.5, 2.0]), jnp.asarray([1.0, 1.0, 1.0])))
    assert np.all(np.isfinite(P[0])) and np.all(np.isnan(P[1])) and np.all(np.isnan(P[2]))

    V = np.asarray(jax.jit(sm.cube_face_views)(jnp.asarray([[0.0, 1, 2], [np.nan, 0, 0]])))
    assert np.all(np.isfinite(V[0])) and np.all(np.isnan(V[1]))

    back = jax.jit(sm.cube_face_direction)(jnp.asarray([2, 7]), jnp.asarray(0.5), jnp.asarray(0.5))
    assert np.all(np.isfinite(back[0])) and np.all(np.isnan(back[1]))

    depth = jax.jit(lambda p: sm.cube_face_depth(jnp.zeros(3), p, 0.5, 9.0))(d)
    assert np.isfinite(depth.depth[0]) and np.isnan(depth.depth[1]) and np.isnan(depth.distance[1])
    np.testing.assert_array_equal(depth.face, [0, -1])


def test_float32_stays_float32_with_jax() -> None:
    d = jnp.asarray([[0.3, -0.9, 0.1]], dtype=jnp.float32)
    r = sm.cube_face(d)
    assert r.s.dtype == jnp.float32 and r.face.dtype == jnp.int32
    assert sm.cube_face_views(d[0]).dtype == jnp.float32
    assert sm.cube_face_direction(r.face, r.s, r.t).dtype == jnp.float32


def test_jax_scalar_near_far_give_jax_in_their_dtype() -> None:
    n, f = jnp.asarray(0.5, dtype=jnp.float32), jnp.asarray(9.0, dtype=jnp.float32)
    P = sm.cube_face_projection(n, f, map_size=8)
    assert isinstance(P, jax.Array) and P.dtype == jnp.float32
    P = sm.cube_face_projection(jnp.asarray(0.5), 9.0, map_size=8)  # a mix gives JAX
    assert isinstance(P, jax.Array) and P.dtype == jnp.float64
