"""The errata of docs/errata.md: each printed formula of the seeds fails a geometric
property that shadowmath's corrected form passes.

The seeds' matrices are typed in here exactly as printed (row-vector ones
transposed where the test says so); the properties are checked by geometry
computed independently (line-plane intersections, where the light must go).
"""

from __future__ import annotations

import numpy as np
import pytest

import shadowmath as sm

RNG = np.random.default_rng(20260)


def h(p):
    return np.append(np.asarray(p, float), 1.0)


def dehom(q):
    return q[:3] / q[3]


def ray_hits_plane(light_xyz, p, plane):
    """Where the line from a point light through p meets the plane (independent geometry)."""
    n, d = np.asarray(plane[:3], float), float(plane[3])
    light_xyz, p = np.asarray(light_xyz, float), np.asarray(p, float)
    direction = p - light_xyz
    t = -(n @ light_xyz + d) / (n @ direction)
    return light_xyz + t * direction


def blocker_scene():
    """A light and a blocker cloud in front of it, away from the world origin."""
    light = np.array([3.0, 7.0, -2.0])
    verts = RNG.normal(size=(40, 3)) * 0.6 + np.array([1.0, 2.0, 1.5])
    return light, verts


# ---------------------------------------------------------------- Nagy (seed 000)
def nagy_world_to_light_printed(frame):
    """The article's M_WorldToLight, a row-vector matrix, with its last row -P_light."""
    X, Y, Z, P = frame.x_axis, frame.y_axis, frame.z_axis, frame.origin
    return np.array(
        [
            [X[0], Y[0], Z[0], 0.0],
            [X[1], Y[1], Z[1], 0.0],
            [X[2], Y[2], Z[2], 0.0],
            [-P[0], -P[1], -P[2], 1.0],
        ]
    )


def test_nagy_translation_row_does_not_send_the_light_to_the_origin():
    light, verts = blocker_scene()
    frame = sm.light_frame(light, verts)
    printed = nagy_world_to_light_printed(frame)
    assert not np.allclose(h(light) @ printed, [0, 0, 0, 1], atol=1e-3)  # row vector: p M
    ours = sm.world_to_light(frame)
    np.testing.assert_allclose(ours @ h(light), [0, 0, 0, 1], atol=1e-12)
    # The corrected row-vector matrix is ours transposed: last row -R P.
    fixed = printed.copy()
    fixed[3, :3] = -np.array([frame.x_axis, frame.y_axis, frame.z_axis]) @ light
    np.testing.assert_allclose(fixed, ours.T, atol=1e-12)
    # ... and it puts the blocker in front of the light.
    assert np.all((ours @ np.c_[verts, np.ones(len(verts))].T)[2] > 0)


def test_nagy_printed_translation_is_right_only_for_a_light_at_the_origin():
    _, verts = blocker_scene()
    frame = sm.light_frame([0.0, 0.0, 0.0], verts)
    np.testing.assert_allclose(nagy_world_to_light_printed(frame), sm.world_to_light(frame).T)


def test_nagy_mdv_code_points_from_the_blocker_to_the_light():
    """The C code starts from N P_light and subtracts the vertices: -N MDV."""
    light, verts = blocker_scene()
    code = light * len(verts)
    for v in verts:
        code = code - v
    z_code = code / np.linalg.norm(code)
    centroid_dir = verts.mean(axis=0) - light
    assert z_code @ centroid_dir < 0  # the code's Z_light looks away from the blocker
    z_ours = sm.light_frame(light, verts).z_axis
    np.testing.assert_allclose(z_ours, -z_code, atol=1e-12)
    assert z_ours @ centroid_dir > 0


def nagy_blocker_projection_printed(rx, ry, n, f, width=1, height=1):
    """The article's M_BlockerProjection as printed (row vectors), SMap factors optional."""
    return np.array(
        [
            [0.98 / rx * width, 0, 0, 0],
            [0, 0.98 / ry * height, 0, 0],
            [0, 0, (f + n) / (n - f), -1],
            [0, 0, 2 * f * n / (n - f), 0],
        ]
    )


def nagy_receiver_projection_printed(rx, ry, n, f, width=1, height=1):
    """The article's M_ReceiverProjection as printed (row vectors), SMap factors optional."""
    return np.array(
        [
            [0.49 / rx * width, 0, 0, 0],
            [0, 0.49 / ry * height, 0, 0],
            [-0.5, -0.5, (f + n) / (n - f), -1],
            [0, 0, 2 * f * n / (n - f), 0],
        ]
    )


def fitted_100():
    light, verts = blocker_scene()
    setup = sm.fit_shadow(light, verts, 100)
    p_light = (setup.world_to_light @ np.c_[verts, np.ones(len(verts))].T).T
    return setup, p_light


def test_nagy_projection_minus_one_entries_assume_a_camera_looking_down_minus_z():
    setup, p_light = fitted_100()
    fr = setup.frustum
    rx, ry, n, f = (float(v) for v in (fr.rx_max, fr.ry_max, fr.near, fr.far))
    printed = nagy_blocker_projection_printed(rx, ry, n, f)
    clip = p_light @ printed  # row vectors, as the article multiplies
    assert np.all(clip[:, 3] < 0)  # w_clip = -z < 0: OpenGL clips the whole blocker away
    ours = sm.blocker_projection(fr)
    clip_ours = p_light @ ours.T
    assert np.all(clip_ours[:, 3] > 0)
    depth = clip_ours[:, 2] / clip_ours[:, 3]
    assert np.all((depth > -1) & (depth < 1))
    # The printed matrix is gluPerspective's: right for view coordinates (x, y, -z),
    # i.e. ours after flipping z, exactly what a look-at camera's view matrix does.
    flip = np.diag([1.0, 1.0, -1.0, 1.0])
    np.testing.assert_allclose(printed.T @ flip, ours, atol=1e-12)


def test_nagy_smapwidth_factor_throws_the_blocker_out_of_the_map():
    setup, p_light = fitted_100()
    fr = setup.frustum
    rx, ry, n, f = (float(v) for v in (fr.rx_max, fr.ry_max, fr.near, fr.far))
    flip = np.diag([1.0, 1.0, -1.0, 1.0])
    with_width = nagy_blocker_projection_printed(rx, ry, n, f, 100, 100).T @ flip
    clip = p_light @ with_width.T
    x_ndc = clip[:, 0] / clip[:, 3]
    assert np.max(np.abs(x_ndc)) == pytest.approx(98.0)  # far outside NDC [-1, 1]
    ours = p_light @ sm.blocker_projection(fr).T
    assert np.max(np.abs(ours[:, 0] / ours[:, 3])) == pytest.approx(0.98)


def test_nagy_receiver_projection_minus_half_and_missing_r_bias():
    setup, p_light = fitted_100()
    fr = setup.frustum
    rx, ry, n, f = (float(v) for v in (fr.rx_max, fr.ry_max, fr.near, fr.far))
    printed = nagy_receiver_projection_printed(rx, ry, n, f)
    stq = p_light @ printed
    assert np.all(stq[:, 3] < 0)  # q = -z: every receiver point reads as "behind the light"
    # For a -Z camera (view z = -z_light) the s and t entries are right...
    view = p_light * np.array([1, 1, -1, 1])
    stq_view = view @ printed
    s_view = stq_view[:, 0] / stq_view[:, 3]
    ours = p_light @ sm.receiver_projection(fr).T
    s, r = ours[:, 0] / ours[:, 3], ours[:, 2] / ours[:, 3]
    np.testing.assert_allclose(s_view, s, atol=1e-12)
    assert s.min() == pytest.approx(0.01) or s.max() == pytest.approx(0.99)
    # ... but r is left as NDC depth in [-1, 1]: the 0.5 scale and bias are missing.
    r_printed = stq_view[:, 2] / stq_view[:, 3]
    np.testing.assert_allclose(r, 0.5 * r_printed + 0.5, atol=1e-12)
    near_point = np.array([0.0, 0.0, n, 1.0])
    r_near = (sm.receiver_projection(fr) @ near_point)[2] / n
    assert r_near == pytest.approx(0.0, abs=1e-12)  # window depth 0 at near
    near_view = np.array([0, 0, -n, 1.0]) @ printed  # the printed matrix at its own near plane
    assert near_view[2] / near_view[3] == pytest.approx(-1.0)  # r = -1, outside [0, 1]


def test_margins_are_the_articles_constants_at_100_texels_only():
    assert sm.border_margin(100) == (0.98, 0.98)
    # Below 100 texels the constant 0.98 lets the silhouette reach into the
    # one-texel border: the border starts at 1 - 2/size in NDC.
    for size in (16, 32, 64, 99):
        assert 1 - 2 / size < 0.98
        assert sm.border_margin(size)[0] == pytest.approx(1 - 2 / size)
    # Below 50 texels it covers the centres of border texels (1 - 1/size).
    assert all(1 - 1 / s < 0.98 for s in (16, 32, 49))
    assert all(1 - 1 / s >= 0.98 for s in (50, 64, 99))


def test_texture_coordinates_span_texel_edges():
    """The margin's edge lands on the edge between border and inner texels, s = b / size."""
    for size, border in ((16, 1), (100, 1), (256, 2)):
        m = sm.border_margin(size, border_texels=border)[0]
        fr = sm.Frustum(rx_max=0.5, ry_max=0.5, near=1.0, far=3.0, margin_x=m, margin_y=m)
        z = 2.0
        for x_over_z, s_expected in ((-0.5, border / size), (0.5, 1 - border / size)):
            stq = sm.receiver_projection(fr) @ np.array([x_over_z * z, 0.0, z, 1.0])
            assert stq[0] / stq[3] * size == pytest.approx(s_expected * size)


# ------------------------------------------------------------- planar projection
def bentley_ground_matrix(light_point):
    """Seed 001's C code for the ground-plane (z = 0) shadow matrix, as printed."""
    lx, ly, lz = light_point
    W = np.eye(4)
    W[0][0] = -lz
    W[0][2] = lx
    W[1][1] = -lz
    W[1][2] = ly
    W[2][2] = 0
    W[3][3] = -lz
    return W


def test_bentley_code_is_the_light_at_infinity_matrix_with_negative_w():
    light = np.array([1.5, -0.5, 6.0])
    W = bentley_ground_matrix(light)
    p = np.array([0.4, 0.3, 2.0])
    q = W @ h(p)
    # As a local (point) light it misses the ray through the light ...
    assert not np.allclose(dehom(q), ray_hits_plane(light, p, [0, 0, 1, 0]), atol=1e-3)
    # ... because it is the projection along the direction l: the light at infinity.
    np.testing.assert_allclose(dehom(q), p - p[2] / light[2] * light, atol=1e-12)
    assert q[3] < 0  # and its w = -l_z is negative: a GPU would clip the shadow away
    # The local light needs W[3][2] = 1 (w = z - l_z), and the whole matrix negated
    # for w > 0: that is shadowmath's matrix up to a positive scale.
    fixed = W.copy()
    fixed[3][2] = 1.0
    ours = sm.planar_projection([0, 0, 1, 0], [*light, 1])
    np.testing.assert_allclose(-fixed, ours, atol=1e-12)
    np.testing.assert_allclose(dehom(ours @ h(p)), ray_hits_plane(light, p, [0, 0, 1, 0]))
    assert (ours @ h(p))[3] > 0
    np.testing.assert_allclose(-W, sm.planar_projection([0, 0, 1, 0], [*light, 0]), atol=1e-12)


def marias_matrix(n, d, light):
    """Seed 002's equation (2), column vectors."""
    n, l_ = np.asarray(n, float), np.asarray(light, float)
    nl = n @ l_
    return np.array(
        [
            [nl + d - n[0] * l_[0], -n[1] * l_[0], -n[2] * l_[0], -d * l_[0]],
            [-n[0] * l_[1], nl + d - n[1] * l_[1], -n[2] * l_[1], -d * l_[1]],
            [-n[0] * l_[2], -n[1] * l_[2], nl + d - n[2] * l_[2], -d * l_[2]],
            [-n[0], -n[1], -n[2], nl],
        ]
    )


def test_marias_matrix_is_right_but_its_sign_follows_the_plane_orientation():
    light = np.array([1.0, 5.0, -1.0])
    plane = np.array([0.2, 1.0, 0.1, 0.5])
    p = np.array([0.5, 2.0, 0.0])  # between the light and the plane
    for pl in (plane, -plane):
        M = marias_matrix(pl[:3], pl[3], light)
        np.testing.assert_allclose(dehom(M @ h(p)), ray_hits_plane(light, p, pl), atol=1e-12)
        ours = sm.planar_projection(pl, [*light, 1])
        assert (ours @ h(p))[3] > 0  # oriented: kept by clipping for either sign
        sign = np.sign(pl @ h(light))
        np.testing.assert_allclose(ours, sign * M, atol=1e-12)
    # With the normal facing away from the light, equation (2) gives w < 0.
    assert (marias_matrix(-plane[:3], -plane[3], light) @ h(p))[3] < 0


def slides_matrix(plane, light):
    """Seed 003's matrix, row-vector form: entry (i, j) = P delta_ij - plane_i L_j."""
    P = plane @ light
    return P * np.eye(4) - np.outer(plane, light)


def test_slides_matrix_is_row_vector_form_and_wrong_as_column_vector():
    light = np.array([1.0, 5.0, -1.0, 1.0])
    plane = np.array([0.2, 1.0, 0.1, 0.5])
    p = np.array([0.5, 2.0, 0.0])
    S = slides_matrix(plane, light)
    hit = ray_hits_plane(light[:3], p, plane)
    np.testing.assert_allclose(dehom(h(p) @ S), hit, atol=1e-12)  # p' = p S: right
    wrong = dehom(S @ h(p))  # read as column vectors (M * p in GLSL): off the plane
    assert abs(plane @ h(wrong)) > 1e-3
    np.testing.assert_allclose(S.T, sm.planar_projection(plane, light), atol=1e-12)


def test_jang_first_equation_sign_and_the_generalized_matrix():
    L = np.array([1.0, -2.0, 6.0])
    P = np.array([0.5, 0.8, 2.0])
    a = P[2] / (L[2] - P[2])
    printed = a * (L - P) - P  # "S = a(L - P) - P"
    assert printed[2] == pytest.approx(0.0)
    true = ray_hits_plane(L, P, [0, 0, 1, 0])
    np.testing.assert_allclose(printed[:2], -true[:2])  # mirrored through the origin
    np.testing.assert_allclose(P - a * (L - P), true)  # the corrected S = P - a(L - P)
    # Jang's z = 0 matrix (row vectors) is right, and is ours transposed.
    J = np.array([[L[2], 0, 0, 0], [0, L[2], 0, 0], [-L[0], -L[1], 0, -1], [0, 0, 0, L[2]]])
    np.testing.assert_allclose(dehom(h(P) @ J), true)
    np.testing.assert_allclose(J.T, sm.planar_projection([0, 0, 1, 0], [*L, 1]), atol=1e-12)
    # "G is the normal of the plane": it must be the plane's 4-vector (n, d).
    G_plane = np.array([0.0, 0.0, 1.0, -1.0])  # z = 1
    LL = np.append(L, 1.0)
    G_normal = np.append(G_plane[:3], 0.0)
    with_normal = (LL @ G_normal) * np.eye(4) - np.outer(G_normal, LL)
    assert dehom(h(P) @ with_normal)[2] == pytest.approx(0.0)  # lands on z = 0, not z = 1
    general = (LL @ G_plane) * np.eye(4) - np.outer(G_plane, LL)
    assert dehom(h(P) @ general)[2] == pytest.approx(1.0)


def jang_pyramid_printed(a, b, ex, ey, ew):
    """Seed 004's Heckbert-Herf matrix as printed ("axnxx" read as a_x n_x,x), e_w a parameter:
    the seed never defines it."""
    nx, ny, nw = np.cross(ew, ey), np.cross(ex, ew), np.cross(ey, ex)
    ax, ay, aw = 1 / (nx @ ex), 1 / (ny @ ey), 1 / (nw @ ew)
    return np.array(
        [
            [*(ax * nx), -ax * nx @ b],
            [*(ay * ny), -ay * ny @ b],
            [0.0, 0.0, 0.0, 1.0],
            [*(aw * nw), -aw * nw @ a],
        ]
    )


PYRAMID = (
    np.array([0.4, 0.3, 3.0]),  # apex: a light sample
    np.array([-1.0, -0.5, 0.2]),  # base corner b
    np.array([2.5, 0.3, 0.0]),  # e_x
    np.array([-0.2, 1.8, 0.1]),  # e_y
)


def test_jang_pyramid_matrix_needs_ew_from_the_apex_to_the_corner():
    a, b, ex, ey = PYRAMID
    inside = a + 0.5 * (b + 0.25 * ex + 0.75 * ey - a)  # halfway down a ray, between a and base
    far_corner = b + ex + ey
    # e_w = a - b (the other reading): w < 0 inside the pyramid (clipped away), x, y mirrored.
    wrong = jang_pyramid_printed(a, b, ex, ey, a - b)
    assert (wrong @ h(inside))[3] < 0
    np.testing.assert_allclose(dehom(wrong @ h(far_corner))[:2], [-1.0, -1.0])
    # e_w = b - a: rows x, y, w are right, and are ours.
    right = jang_pyramid_printed(a, b, ex, ey, b - a)
    assert (right @ h(inside))[3] == pytest.approx(0.5)
    np.testing.assert_allclose(dehom(right @ h(inside))[:2], [0.25, 0.75])
    ours = sm.pyramid_to_unit_cube(a, b, ex, ey)
    np.testing.assert_allclose(ours[[0, 1, 3]], right[[0, 1, 3]], rtol=1e-14, atol=1e-15)


def test_jang_pyramid_third_row_puts_the_base_at_z_1_not_0():
    a, b, ex, ey = PYRAMID
    printed = jang_pyramid_printed(a, b, ex, ey, b - a)
    ours = sm.pyramid_to_unit_cube(a, b, ex, ey)
    on_base = b + 0.3 * ex + 0.6 * ey
    # The text says "the base plane ... maps to zu = 0"; the row (0 0 0 1) gives z = 1/w = 1
    # there (which is why its pseudocode clips at zu.near = 1 - e).
    assert dehom(printed @ h(on_base))[2] == pytest.approx(1.0)
    assert dehom(ours @ h(on_base))[2] == pytest.approx(0.0, abs=1e-15)
    # Ours is the printed z minus 1 everywhere: Z = 1 - W.
    for lam in (0.1, 0.5, 1.0, 2.0):
        p = a + lam * (on_base - a)
        assert dehom(ours @ h(p))[2] == pytest.approx(dehom(printed @ h(p))[2] - 1)


def test_jang_pyramid_matrix_is_column_vector_form_unlike_the_articles_other_matrices():
    a, b, ex, ey = PYRAMID
    M = jang_pyramid_printed(a, b, ex, ey, b - a)
    corner = b + ex
    np.testing.assert_allclose(dehom(M @ h(corner)), [1.0, 0.0, 1.0], atol=1e-14)  # M p: right
    row_vector = h(corner) @ M  # the article's own p M convention (its z = 0 matrix)
    assert not np.allclose(dehom(row_vector), [1.0, 0.0, 1.0], atol=1e-3)


# ------------------------------------------------------------------ conventions
def look_at(eye, center, up):
    """gluLookAt: right-handed view matrix, camera looking down its -z."""
    f = (center - eye) / np.linalg.norm(center - eye)
    s = np.cross(f, up)
    s /= np.linalg.norm(s)
    u = np.cross(s, f)
    R = np.array([s, u, -f])
    return np.block([[R, (-R @ eye)[:, None]], [np.zeros((1, 3)), np.ones((1, 1))]])


def gl_frustum(left, right, bottom, top, n, f):
    """glFrustum's matrix (OpenGL specification)."""
    return np.array(
        [
            [2 * n / (right - left), 0, (right + left) / (right - left), 0],
            [0, 2 * n / (top - bottom), (top + bottom) / (top - bottom), 0],
            [0, 0, -(f + n) / (f - n), -2 * f * n / (f - n)],
            [0, 0, -1, 0],
        ]
    )


def test_light_frame_is_a_look_at_camera_with_z_flipped():
    light, verts = blocker_scene()
    setup = sm.fit_shadow(light, verts, (96, 64))
    fr, frame = setup.frustum, setup.frame
    np.testing.assert_allclose(np.cross(frame.x_axis, frame.y_axis), -frame.z_axis, atol=1e-12)
    V = look_at(light, light + frame.z_axis, frame.y_axis)
    np.testing.assert_allclose(V, np.diag([1.0, 1.0, -1.0, 1.0]) @ setup.world_to_light, atol=1e-12)
    # blocker_to_clip = glFrustum(...) @ lookAt(...) with the frustum's half-extents at near.
    n, f = float(fr.near), float(fr.far)
    hx = n * float(fr.rx_max) / float(fr.margin_x)
    hy = n * float(fr.ry_max) / float(fr.margin_y)
    np.testing.assert_allclose(
        gl_frustum(-hx, hx, -hy, hy, n, f) @ V, setup.blocker_to_clip, rtol=1e-10, atol=1e-12
    )


def test_column_major_bytes_are_the_transpose_in_memory_not_in_meaning():
    M = RNG.normal(size=(4, 4))
    floats = np.frombuffer(sm.column_major_bytes(M), np.float32)
    np.testing.assert_allclose(floats.reshape(4, 4, order="F"), M, rtol=1e-6)
