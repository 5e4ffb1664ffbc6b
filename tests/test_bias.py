"""Depth-map bias: texel sizes against brute-force unprojection, acne-free lookups on planes.

The depth-map lookup is simulated in NumPy: the map stores, per texel, the depth of
the receiver plane along the ray through the texel's centre (found by unprojecting
the centre through ``inv(world_to_texture)``), and a receiver point is compared with
the texels its lookup reads.
"""

from __future__ import annotations

import jax
import jax.numpy as jnp
import numpy as np
import pytest
from hypothesis import assume, example, given
from hypothesis import strategies as st

from shadowmath import api_convention, normal_offset, slope_scaled_bias, texel_world_size

from .conftest import rtol_for


def rotation(rng: np.random.Generator) -> np.ndarray:
    q, r = np.linalg.qr(rng.normal(size=(3, 3)))
    return q * np.sign(np.diag(r))


def light_matrix(
    rng: np.random.Generator, *, directional: bool, api: str = "opengl", reversed_z: bool = False
) -> tuple[np.ndarray, np.ndarray, float]:
    """``(world_to_texture, light position or direction, depth range f - n)``.

    A random look-at from a random light looking down its -z (a glFrustum for a
    point or spot light, a glOrtho for a directional one), then ``api``'s conventions.
    """
    R = rotation(rng)
    eye = rng.uniform(-5, 5, 3)
    view = np.eye(4)
    view[:3, :3] = R
    view[:3, 3] = -R @ eye
    n = rng.uniform(0.5, 2)
    f = n + rng.uniform(5, 30)
    w, h = rng.uniform(0.3, 2, 2)
    if directional:
        P = np.array(
            [
                [1 / w, 0, 0, 0],
                [0, 1 / h, 0, 0],
                [0, 0, -2 / (f - n), -(f + n) / (f - n)],
                [0, 0, 0, 1],
            ]
        )
        P[:2] /= 5  # a 10 w x 10 h world-unit map
    else:
        P = np.array(
            [
                [n / w, 0, 0, 0],
                [0, n / h, 0, 0],
                [0, 0, -(f + n) / (f - n), -2 * f * n / (f - n)],
                [0, 0, -1, 0],
            ]
        )
    conv = api_convention(api=api, reversed_z=reversed_z)
    M = conv.gl_clip_to_texture @ P @ view
    toward = R.T @ np.array([0, 0, 1.0])  # the light's +z view axis points back toward it
    return M, (toward if directional else eye), f - n


def project(M: np.ndarray, X: np.ndarray) -> np.ndarray:
    h = X @ M[:, :3].T + M[:, 3]
    return h[..., :3] / h[..., 3:]


def unproject(M: np.ndarray, s: np.ndarray, t: np.ndarray, r: np.ndarray) -> np.ndarray:
    hom = np.stack([s, t, r, np.ones_like(s)], axis=-1) @ np.linalg.inv(M).T
    return hom[..., :3] / hom[..., 3:]


def ray_plane(M: np.ndarray, s: np.ndarray, t: np.ndarray, n: np.ndarray, c: float) -> np.ndarray:
    """Where the ray of texture coordinates ``(s, t)`` meets the plane ``n . X = c``."""
    A = unproject(M, s, t, np.full_like(s, 0.25))
    B = unproject(M, s, t, np.full_like(s, 0.75))
    lam = (c - A @ n) / ((B - A) @ n)
    return A + lam[..., None] * (B - A)


def plane_facing_light(
    rng: np.random.Generator, M: np.ndarray, light: np.ndarray, directional: bool, max_deg=75
):
    """A plane through a point inside the map, tilted up to ``max_deg`` from the ray there."""
    p0 = unproject(M, *rng.uniform(0.3, 0.7, 2), rng.uniform(0.3, 0.7))
    to_light = light if directional else light - p0
    to_light = to_light / np.linalg.norm(to_light)
    tilt = np.radians(rng.uniform(0, max_deg))
    side = np.cross(to_light, rng.normal(size=3))
    side /= np.linalg.norm(side)
    n = np.cos(tilt) * to_light + np.sin(tilt) * side
    return n, float(n @ p0), p0


def in_front(M: np.ndarray, X: np.ndarray) -> np.ndarray:
    return X @ M[3, :3] + M[3, 3] > 0


def stored_depth(
    M: np.ndarray, n: np.ndarray, c: float, col, row, W: int, H: int
) -> tuple[np.ndarray, np.ndarray]:
    """The depth map of the plane: its depth along the ray through each texel centre.

    Also whether the plane is in front of the light there (where it is not, the map
    holds its clear value, which lights everything).
    """
    X = ray_plane(M, (col + 0.5) / W, (row + 0.5) / H, n, c)
    return project(M, X)[..., 2], in_front(M, X)


seeds = st.integers(0, 2**32 - 1)
sizes = st.tuples(st.integers(16, 1024), st.integers(16, 1024))


# --- texel_world_size -------------------------------------------------------------


@given(seed=seeds, size=sizes)
def test_directional_texel_is_extent_over_resolution(seed: int, size) -> None:
    rng = np.random.default_rng(seed)
    M, _, _ = light_matrix(rng, directional=True)
    W, H = size
    p = unproject(M, *rng.uniform(0, 1, (3, 10)))
    # The map spans |grad s|^-1 by |grad t|^-1 world units (orthographic, orthogonal axes).
    extent_x, extent_y = 1 / np.linalg.norm(M[0, :3]), 1 / np.linalg.norm(M[1, :3])
    h = texel_world_size(M, p, map_size=(W, H))
    np.testing.assert_allclose(h, np.sqrt(extent_x / W * extent_y / H), rtol=1e-12)


@pytest.mark.parametrize("directional", [False, True])
@given(seed=seeds)
def test_texel_size_is_the_unprojected_texel_area(directional: bool, seed: int) -> None:
    """Brute force: the four texel-corner rays cut the plane perpendicular to the ray."""
    rng = np.random.default_rng(seed)
    M, _, _ = light_matrix(rng, directional=directional)
    W, H = 2048, 1024
    s, t, r = rng.uniform(0.05, 0.95, 3)
    p = unproject(M, s, t, r)
    ray = unproject(M, s, t, r + 1e-3) - p
    ray /= np.linalg.norm(ray)
    corners = ray_plane(
        M,
        s + np.array([-0.5, 0.5, 0.5, -0.5]) / W,
        t + np.array([-0.5, -0.5, 0.5, 0.5]) / H,
        ray,
        float(ray @ p),
    )
    area = 0.5 * np.linalg.norm(np.cross(corners[2] - corners[0], corners[3] - corners[1]))
    h = texel_world_size(M, p, map_size=(W, H))
    np.testing.assert_allclose(h, np.sqrt(area), rtol=1e-3)
    # On a tilted surface the texel covers 1 / cos(theta) times as much.
    normal = rotation(rng)[0]
    cos = abs(normal @ ray)
    h_surface = texel_world_size(M, p, map_size=(W, H), normals=normal * 3.0)
    np.testing.assert_allclose(h_surface, h / np.sqrt(cos), rtol=1e-9)


def test_point_light_texel_grows_with_distance() -> None:
    rng = np.random.default_rng(1)
    M, light, _ = light_matrix(rng, directional=False)
    p = unproject(M, 0.5, 0.5, 0.5)
    farther = light + 2 * (p - light)
    ratio = texel_world_size(M, farther, map_size=64) / texel_world_size(M, p, map_size=64)
    np.testing.assert_allclose(ratio, 2.0, rtol=1e-9)


# --- slope_scaled_bias ----------------------------------------------------------------


@given(seed=seeds, size=st.integers(16, 1024))
@example(seed=91054, size=16)  # theta 6e-6 rad: arccos(n . L) lost 1e-6 of it (the oracle's)
def test_depth_slope_per_texel_is_texel_size_times_tan(seed: int, size: int) -> None:
    """Directional light, receiver tilted by theta: depth slope per texel = h tan(theta)."""
    rng = np.random.default_rng(seed)
    M, light, depth_range = light_matrix(rng, directional=True)
    # Square texels in world units: make the map's extents equal.
    M[1, :3] *= np.linalg.norm(M[0, :3]) / np.linalg.norm(M[1, :3])
    n, _, p0 = plane_facing_light(rng, M, light, True)
    # The angle between n and L, well conditioned at every angle (arccos of the dot
    # product loses ~eps / theta of a small theta).
    theta = np.arctan2(np.linalg.norm(np.cross(n, light)), n @ light)
    h = texel_world_size(M, p0, map_size=size)
    # One texel along s, and along t, on the plane: the slope vector (in depth units).
    slope_s = slope_scaled_bias(M, p0, n, map_size=size, constant=0, slope_factor=1.0)
    np.testing.assert_allclose(slope_s, _world_slope(M, n, p0, size), rtol=1e-9)
    # The magnitude of the per-texel depth change is h tan(theta) in world units.
    np.testing.assert_allclose(
        _world_slope_norm(M, n, p0, size) * depth_range, h * np.tan(theta), rtol=1e-8, atol=1e-15
    )


def _slopes(M: np.ndarray, n: np.ndarray, p0: np.ndarray, size: int) -> np.ndarray:
    """Depth change per texel along s and along t on the plane, by finite steps on the plane."""
    s, t, _ = project(M, p0)
    c = float(n @ p0)
    r0 = project(M, ray_plane(M, s, t, n, c))[2]
    rs = project(M, ray_plane(M, s + 1 / size, t, n, c))[2]
    rt = project(M, ray_plane(M, s, t + 1 / size, n, c))[2]
    return np.array([rs - r0, rt - r0])


def _world_slope(M, n, p0, size) -> float:
    return float(np.max(np.abs(_slopes(M, n, p0, size))))


def _world_slope_norm(M, n, p0, size) -> float:
    return float(np.linalg.norm(_slopes(M, n, p0, size)))


def lookup_ok(M, n, c, points, bias, W, H, reach: float, reversed_z: bool) -> np.ndarray:
    """Per point: lit (``r -/+ bias`` not past the stored depth) at every texel the lookup reads."""
    s, t, r = project(M, points).T
    # box: reach k + 1/2 reads texels -k..k; bilinear: reach k + 1 reads -k-1..k+1 (weighted)
    bilinear = float(reach).is_integer()
    k = int(reach) - 1 if bilinear else int(reach - 0.5)
    col0, row0 = np.floor(s * W), np.floor(t * H)
    offsets = range(-k, k + 1) if not bilinear else range(-k - 1, k + 2)
    ok = np.ones(len(points), bool)
    for i in offsets:
        for j in offsets:
            col, row = col0 + i, row0 + j
            if bilinear:
                # Only the texels whose centre is within reach (per axis) get a weight.
                dx = np.abs((col + 0.5) - s * W)
                dy = np.abs((row + 0.5) - t * H)
                used = (dx < reach) & (dy < reach)
            else:
                used = np.ones(len(points), bool)
            d, drawn = stored_depth(M, n, c, col, row, W, H)
            used &= drawn
            scale = 1 + 1e-9
            # r and d are the same plane's depth computed along two paths: a few ulps apart
            # where the plane faces the light and the bias or offset is (nearly) zero.
            ulps = 64 * np.finfo(np.float64).eps * np.maximum(np.abs(r), np.abs(d))
            lit = r + bias * scale >= d - ulps if reversed_z else r - bias * scale <= d + ulps
            ok &= lit | ~used
    return ok


@pytest.mark.parametrize("directional", [False, True])
@pytest.mark.parametrize(("api", "reversed_z"), [("opengl", False), ("webgpu", True)])
@pytest.mark.parametrize(("radius", "filt"), [(0, "box"), (1, "box"), (2, "bilinear")])
@given(seed=seeds, size=sizes)
def test_slope_scaled_bias_makes_a_plane_acne_free(
    directional: bool, api: str, reversed_z: bool, radius: int, filt: str, seed: int, size
) -> None:
    rng = np.random.default_rng(seed)
    W, H = size
    M, light, _ = light_matrix(rng, directional=directional, api=api, reversed_z=reversed_z)
    n, c, _ = plane_facing_light(rng, M, light, directional)
    # Receiver points on the plane anywhere in their texels, the corners included.
    st_ = rng.uniform(0.2, 0.8, (200, 2))
    corner = (np.floor(st_ * [W, H]) + rng.choice([1e-9, 1 - 1e-9], (200, 2))) / [W, H]
    st_ = np.concatenate([st_, corner])
    points = ray_plane(M, st_[:, 0], st_[:, 1], n, c)
    points = points[in_front(M, points)]
    bias = slope_scaled_bias(
        M,
        points,
        n,
        map_size=(W, H),
        pcf_radius=radius,
        pcf_filter=filt,
        constant=0,  # type: ignore[arg-type]
    )
    reach = radius + (1.0 if filt == "bilinear" else 0.5)
    assert lookup_ok(M, n, c, points, bias, W, H, reach, reversed_z).all()


@given(seed=seeds)
def test_slope_factor_one_is_tight_for_diagonal_slopes(seed: int) -> None:
    """At a texel corner on a diagonal slope the error is the whole slope m: factor 0.95 fails."""
    rng = np.random.default_rng(seed)
    M, light, _ = light_matrix(rng, directional=True)
    W = H = 64
    # A plane whose depth rises equally along s and t: normal mixes the ray with s + t.
    p0 = unproject(M, 0.5, 0.5, 0.5)
    # One texel's step along s and along t (r fixed: across the ray).
    v_s = np.linalg.solve(M[:3, :3], [1 / W, 0, 0])
    v_t = np.linalg.solve(M[:3, :3], [0, 1 / H, 0])
    tilt = np.radians(rng.uniform(10, 70))
    ray = light / np.linalg.norm(light)
    side = v_s / (v_s @ v_s) + v_t / (v_t @ v_t)  # n . v_s = n . v_t: equal slopes per texel
    n = np.cos(tilt) * ray + np.sin(tilt) * side / np.linalg.norm(side)
    c = float(n @ p0)
    corners = (np.array([[31, 31], [31, 32], [32, 31], [32, 32]]) + 0.5) / 64
    pts = []
    for sign in ([1, 1], [-1, -1], [1, -1], [-1, 1]):
        pts.append(corners + np.array(sign) * (0.5 - 1e-9) / 64)
    st_ = np.concatenate(pts)
    points = ray_plane(M, st_[:, 0], st_[:, 1], n, c)
    exact = slope_scaled_bias(M, points, n, map_size=64, constant=0)
    assert lookup_ok(M, n, c, points, exact, W, H, 0.5, False).all()
    low = slope_scaled_bias(M, points, n, map_size=64, constant=0, slope_factor=0.95)
    assert not lookup_ok(M, n, c, points, low, W, H, 0.5, False).all()


def test_constant_term_and_depth_bits() -> None:
    M, _, _ = light_matrix(np.random.default_rng(3), directional=True)
    p = unproject(M, 0.5, 0.5, 0.5)
    ray = np.cross(M[0, :3], M[1, :3])
    b = slope_scaled_bias(M, p, ray, map_size=64, constant=3, depth_bits=16)
    np.testing.assert_allclose(b, 3 / (2**16 - 1), rtol=1e-6)  # facing the light: no slope
    b = slope_scaled_bias(M, p, ray, map_size=64, depth_bits=None)
    np.testing.assert_allclose(b, 2 * 2.0**-24, rtol=1e-6)
    edge_on = np.cross(ray, M[0, :3])
    assert slope_scaled_bias(M, p, edge_on, map_size=64) > 1e6  # inf up to rounding


# --- normal_offset --------------------------------------------------------------------


@pytest.mark.parametrize(("radius", "filt"), [(0, "box"), (1, "box"), (1, "bilinear")])
@given(seed=seeds, size=sizes)
@example(seed=4393, size=(128, 272))  # a plane facing the light within 0.01 degrees
def test_normal_offset_makes_a_plane_acne_free_directional(
    radius: int, filt: str, seed: int, size
) -> None:
    """Exact for a directional light: lookup points anywhere in a texel, corners included."""
    rng = np.random.default_rng(seed)
    W, H = size
    M, light, _ = light_matrix(rng, directional=True)
    n, c, p0 = plane_facing_light(rng, M, light, True, max_deg=85)
    o = normal_offset(M, p0, n, map_size=(W, H), pcf_radius=radius, pcf_filter=filt)  # type: ignore[arg-type]
    # Constant over the plane: choose the lookup points p' (texel corners too, and for
    # the bilinear kernel, whose reach ends at texel centres, points next to centres),
    # then p = p' - o.
    st_ = rng.uniform(0.2, 0.8, (200, 2))
    corner = (np.floor(st_ * [W, H]) + rng.choice([1e-9, 1 - 1e-9], (200, 2))) / [W, H]
    centre = (np.floor(st_ * [W, H]) + 0.5 + rng.choice([-1e-9, 1e-9], (200, 2))) / [W, H]
    st_ = np.concatenate([st_, corner, centre])
    lookup = ray_plane(M, st_[:, 0], st_[:, 1], n, c + float(n @ o))
    np.testing.assert_allclose((lookup - o) @ n, c, rtol=1e-9, atol=1e-9)
    reach = radius + (1.0 if filt == "bilinear" else 0.5)
    assert lookup_ok(M, n, c, lookup, 0.0, W, H, reach, False).all()
    # 5 % less offset: acne at some texel corner (the offset is tight in every direction).
    if np.degrees(np.arccos(n @ light)) > 5:
        lookup = ray_plane(M, st_[:, 0], st_[:, 1], n, c + 0.95 * float(n @ o))
        assert not lookup_ok(M, n, c, lookup, 0.0, W, H, reach, False).all()


@given(seed=seeds, size=sizes)
def test_normal_offset_point_light(seed: int, size) -> None:
    """A point or spot light: exact to first order in the texel's angle; 5 % covers the rest."""
    rng = np.random.default_rng(seed)
    W, H = size
    M, light, _ = light_matrix(rng, directional=False)
    n, c, _ = plane_facing_light(rng, M, light, False, max_deg=80)
    st_ = rng.uniform(0.2, 0.8, (300, 2))
    points = ray_plane(M, st_[:, 0], st_[:, 1], n, c)
    points = points[in_front(M, points)]
    o = normal_offset(M, points, n, map_size=(W, H), scale=1.05)
    assert lookup_ok(M, n, c, points + o, 0.0, W, H, 0.5, False).all()


def test_normal_offset_is_bounded_at_grazing_angles() -> None:
    """sin(theta), not tan(theta): c h sin(theta) (|cos phi| + |sin phi|) for square texels."""
    M, light, _ = light_matrix(np.random.default_rng(5), directional=True)
    M[1, :3] *= np.linalg.norm(M[0, :3]) / np.linalg.norm(M[1, :3])  # square texels
    p = unproject(M, 0.5, 0.5, 0.5)
    e_s = M[0, :3] / np.linalg.norm(M[0, :3])
    e_t = M[1, :3] / np.linalg.norm(M[1, :3])
    h = texel_world_size(M, p, map_size=128)
    for phi in np.radians([0, 20, 45, 90]):
        side = np.cos(phi) * e_s + np.sin(phi) * e_t
        for theta in np.radians([0, 30, 60, 89.99]):
            normal = np.cos(theta) * light + np.sin(theta) * side
            length = np.linalg.norm(normal_offset(M, p, normal, map_size=128))
            expected = 0.5 * h * np.sin(theta) * (abs(np.cos(phi)) + abs(np.sin(phi)))
            np.testing.assert_allclose(length, expected, rtol=1e-9, atol=1e-15)
            assert length <= np.sqrt(2) * 0.5 * h + 1e-15


# --- a concave crease: a face standing on the ground ----------------------------------


def crease_heights(M, nA, nB, W, H, k, heights, along) -> np.ndarray:
    """Per height ``z'`` of the lifted point above the ground: whether every point of the
    face (plane ``nA . X = 0``) lifted to that height, at ``along`` (world units along the
    crease through the origin), is lit. The map holds the nearer of the two planes at each
    texel centre (the air is in front of both); the lookup is the renderers': the point
    moved by the face's normal offset, less the face's slope-scaled bias, against the
    ``(2k + 1)^2`` texels around it."""
    p0 = np.zeros(3)
    o = np.asarray(normal_offset(M, p0, nA, map_size=(W, H), pcf_radius=k))
    b = float(slope_scaled_bias(M, p0, nA, map_size=(W, H), pcf_radius=k, constant=0))
    e = np.cross(nA, nB)
    up = np.cross(e, nA)  # up the face, away from the ground
    up /= up @ nB
    lit = []
    for z in heights:  # the lifted point's height above the ground: z + o . nB
        s, t, r = project(M, along[:, None] * e + (z - o @ nB) * up + o).T
        ok = np.ones(len(along), bool)
        for i in range(-k, k + 1):
            for j in range(-k, k + 1):
                cs, ct = (np.floor(s * W) + i + 0.5) / W, (np.floor(t * H) + j + 0.5) / H
                stored = np.minimum(project(M, ray_plane(M, cs, ct, nA, 0.0))[..., 2],
                                    project(M, ray_plane(M, cs, ct, nB, 0.0))[..., 2])  # fmt: skip
                ok &= r - b * (1 + 1e-9) <= stored + 64 * np.finfo(np.float64).eps
        lit.append(bool(ok.all()))
    return np.array(lit)


def crease_bound(M, ray, nA, nB, W, H, k) -> float:
    """``o_B - b |cos theta_B| / |grad r . d|``: the ground's offset less the face's bias
    (docs/depth-maps.md, trade-offs), the height above which the face is acne-free."""
    o_B = np.linalg.norm(normal_offset(M, np.zeros(3), nB, map_size=(W, H), pcf_radius=k))
    b = float(slope_scaled_bias(M, np.zeros(3), nA, map_size=(W, H), pcf_radius=k, constant=0))
    return float(o_B - b * abs(ray @ nB) / abs(M[2, :3] @ ray))


@pytest.mark.parametrize("radius", [0, 1])
@given(seed=seeds, size=sizes)
def test_a_face_on_the_ground_is_acne_free_above_the_grounds_offset_less_its_bias(
    radius: int, seed: int, size
) -> None:
    """At a concave crease the texels past the foot hold the ground, which the face's own
    bias does not cover: only a sliver up the face may shadow itself, below the bound."""
    rng = np.random.default_rng(seed)
    W, H = size
    M, light, _ = light_matrix(rng, directional=True)
    M[:, 3] += M[:, :3] @ unproject(M, 0.5, 0.5, 0.5)  # the crease at the map's middle
    nA, nB = plane_facing_light(rng, M, light, True)[0], plane_facing_light(rng, M, light, True)[0]
    assume(abs(nA @ nB) < np.cos(np.radians(20)))  # a dihedral angle of 20 degrees at least
    bound = crease_bound(M, light, nA, nB, W, H, radius)
    along = rng.uniform(-20, 20, 4000) / max(W, H)  # some 80 texels of the crease
    heights = np.maximum(bound, 0.0) * np.array([1.0, 1.5]) + 1e-12
    assert crease_heights(M, nA, nB, W, H, radius, heights, along).all()


@pytest.mark.parametrize("roll", [0, 1, 2, 3, 4])
def test_the_crease_bound_is_tight_for_the_cascade_scenes_faces(roll: int) -> None:
    """A block's face (normal ``(0.342, -0.940, 0)``) on the ground under the cascade
    tests' sun, the map rolled about the ray: 10 % below the bound some point of the foot
    shadows itself (the renderers showed one such pixel, docs/cascades.md)."""
    rng = np.random.default_rng(roll)
    ray = np.array([0.6, -0.6, 0.45]) / np.linalg.norm([0.6, -0.6, 0.45])
    side = np.cross(ray, rng.normal(size=3))
    side /= np.linalg.norm(side)
    M = np.eye(4)
    M[:3, :3] = np.stack([side / 20, np.cross(ray, side) / 20, -ray / 40])  # 20 x 20 x 40
    M[:3, 3] = 0.5
    nA, nB = np.array([0.34202015, -0.93969262, 0.0]), np.array([0.0, 0.0, 1.0])
    bound = crease_bound(M, ray, nA, nB, 512, 512, 0)
    assert bound > 0
    along = rng.uniform(-5, 5, 100_000)
    lit = crease_heights(M, nA, nB, 512, 512, 0, bound * np.array([1.0, 0.9]), along)
    assert lit.tolist() == [True, False]


# --- backends, shapes, errors -------------------------------------------------------


def scene(batch: tuple[int, ...] = ()) -> tuple[np.ndarray, ...]:
    """``(world_to_texture, points, normals, light position)`` of a point light."""
    rng = np.random.default_rng(11)
    M, light, _ = light_matrix(rng, directional=False)
    n, c, _ = plane_facing_light(rng, M, light, False)
    st_ = rng.uniform(0.2, 0.8, (*batch, 2))
    points = ray_plane(M, st_[..., 0], st_[..., 1], n, c)
    return M, points, np.broadcast_to(n, (*batch, 3)), light


@pytest.mark.parametrize("batch", [(), (1,), (3, 1, 2)])
def test_backends_dtypes_and_batches(to, dtype, batch) -> None:
    M, p, n, _ = scene(batch)
    expected = [
        texel_world_size(M, p, map_size=(64, 32)),
        slope_scaled_bias(M, p, n, map_size=(64, 32), pcf_radius=1),
        normal_offset(M, p, n, map_size=(64, 32), pcf_filter="bilinear"),
    ]
    got = [
        texel_world_size(to(M), to(p), map_size=(64, 32)),
        slope_scaled_bias(to(M), to(p), to(n), map_size=(64, 32), pcf_radius=1),
        normal_offset(to(M), to(p), to(n), map_size=(64, 32), pcf_filter="bilinear"),
    ]
    for g, e in zip(got, expected, strict=True):
        assert g.shape == e.shape
        assert g.dtype == np.dtype(dtype)
        assert type(g) is type(to(M))
        np.testing.assert_allclose(np.asarray(g), e, rtol=rtol_for(dtype) * 10, atol=1e-12)


def test_jit_and_grad() -> None:
    M, p, n, _ = scene((4,))
    f = jax.jit(lambda M, p, n: normal_offset(M, p, n, map_size=128))
    np.testing.assert_allclose(
        f(jnp.asarray(M), jnp.asarray(p), jnp.asarray(n)),
        normal_offset(M, p, n, map_size=128),
        rtol=1e-12,
    )
    g = jax.grad(lambda p: jnp.sum(texel_world_size(jnp.asarray(M), p, map_size=128)))(
        jnp.asarray(p)
    )
    assert np.isfinite(np.asarray(g)).all()


def test_invalid_values_raise_eagerly_and_poison_under_jit() -> None:
    M, p, n, light = scene((3,))
    behind = p.copy()
    behind[1] = 2 * light - p[1]  # mirrored through the light
    with pytest.raises(ValueError, match=r"points: .*behind the light.*batch index \(1,\)"):
        texel_world_size(M, behind, map_size=64)
    out = jax.jit(lambda p: texel_world_size(jnp.asarray(M), p, map_size=64))(jnp.asarray(behind))
    assert np.isnan(out[1])
    assert np.isfinite(np.asarray(out)[[0, 2]]).all()
    zero = n.copy()
    zero[2] = 0
    with pytest.raises(ValueError, match="normals: a normal is zero"):
        normal_offset(M, p, zero, map_size=64)
    nan = p.copy()
    nan[0, 0] = np.nan
    with pytest.raises(ValueError, match="points: contains non-finite"):
        slope_scaled_bias(M, nan, n, map_size=64)


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"map_size": 0}, "map_size"),
        ({"map_size": (3, 4, 5)}, "map_size"),
        ({"map_size": 2.5}, "map_size"),
        ({"map_size": 8, "pcf_radius": -1}, "radius"),
        ({"map_size": 8, "pcf_filter": "gauss"}, "filter"),
        ({"map_size": 8, "slope_factor": -1.0}, "slope_factor"),
        ({"map_size": 8, "constant": float("nan")}, "constant"),
        ({"map_size": 8, "depth_bits": 0}, "depth_bits"),
    ],
)
def test_bad_options(kwargs, match: str) -> None:
    M, p, n, _ = scene()
    with pytest.raises(ValueError, match=match):
        slope_scaled_bias(M, p, n, **kwargs)


def test_bad_shapes() -> None:
    M, p, _, _ = scene((2,))
    with pytest.raises(ValueError, match=r"world_to_texture: expected shape \(\*batch, 4, 4\)"):
        texel_world_size(M[:3], p, map_size=8)
    with pytest.raises(ValueError, match=r"points: expected shape"):
        texel_world_size(M, p[:, :2], map_size=8)
    with pytest.raises(ValueError, match="do not broadcast"):
        normal_offset(M, p, np.ones((3, 3)), map_size=8)
    with pytest.raises(TypeError):
        texel_world_size(M, p, 8)  # type: ignore[misc]


def test_numpy_integers_are_sizes() -> None:
    M, p, n, _ = scene()
    np.testing.assert_array_equal(
        slope_scaled_bias(M, p, n, map_size=(np.int64(64), np.int32(32)), pcf_radius=np.int64(1)),
        slope_scaled_bias(M, p, n, map_size=(64, 32), pcf_radius=1),
    )


def test_texel_size_where_the_gradients_square_past_float32() -> None:
    """Found by the fuzz: a tiny float32 scene has |grad s x grad t| ~ 1e20, whose square
    overflows float32; the texel size, 1 / sqrt(W H |D|), is representable and exact."""
    import warnings

    M = np.diag([1e10, 1e10, 1.0, 1.0]).astype(np.float32)  # |D| = 1e20
    p = np.array([0.1, 0.2, 0.3], np.float32)
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # no overflow on the way either
        h = texel_world_size(M, p, map_size=4)
    assert h.dtype == np.float32
    assert float(h) == pytest.approx(1 / np.sqrt(16 * 1e20), rel=1e-6)
