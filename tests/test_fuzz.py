"""Fuzzing every public function with valid and invalid scenes.

Each test draws a scene that is either valid (then the call must succeed and its output
must pass the function's property checks, within a tolerance of a few ulps times the
scene's condition) or invalid in a known way (then the call must raise the documented
``ValueError``). The regular run uses the short ``default`` hypothesis profile; ``make
fuzz`` runs ``HYPOTHESIS_PROFILE=fuzz`` and prints how many cases were tried.
"""

from __future__ import annotations

import contextlib
import functools
import os
import re
import warnings
from collections import Counter
from collections.abc import Iterator
from typing import Any, NamedTuple

import numpy as np
import pytest
from hypothesis import assume, example, given, settings
from hypothesis import strategies as st

import shadowmath as sm
from shadowmath._backends import _kernels

from .strategies import (
    GRAPHICS_APIS,
    NON_FINITE,
    VALUE_MUTATIONS,
    AreaLight,
    CubeSetup,
    FitCall,
    Invalid,
    InvalidFit,
    PcfCase,
    Placement,
    PlanarScene,
    _spec_margins,
    area_lights,
    cube_directions,
    cube_setups,
    fit_calls,
    given_options,
    invalid_fit_calls,
    invalid_placements,
    invalid_planar,
    pcf_cases,
    placements,
    planar_scenes,
    receiver_points,
    receiver_surfaces,
    sized_maps,
    unit_vectors,
)
from .test_scene import (
    _clip_inside,
    _cone_distance,
    _inside_map,
    _random_scene,
    _samples,
    _world,
)
from .test_stable_sphere import DUPLICATE

CASES: Counter[str] = Counter()


@pytest.fixture(scope="module", autouse=True)
def _report_counts(request: pytest.FixtureRequest) -> Iterator[None]:
    yield
    reporter = request.config.pluginmanager.get_plugin("terminalreporter")
    total = sum(CASES.values())
    lines = [f"fuzz: {total} cases tried"] + [f"  {k}: {v}" for k, v in sorted(CASES.items())]
    capture = request.config.pluginmanager.get_plugin("capturemanager")
    if reporter is not None and capture is not None:
        with capture.global_and_fixture_disabled():
            reporter.write_line("\n" + "\n".join(lines))


DTYPES = pytest.mark.parametrize("dtype", [np.float64, np.float32], ids=["f64", "f32"])


def _eps(dtype: Any) -> float:
    return float(np.finfo(dtype).eps)


def _raises(invalid: Invalid, fn: Any, *args: Any, **kwargs: Any) -> None:
    with pytest.raises(ValueError, match=re.escape(invalid.message)) as info:
        fn(*args, **kwargs)
    assert invalid.message in str(info.value), (invalid.message, str(info.value))


# --- planar projection -------------------------------------------------------------------


def _check_planar(scene: PlanarScene, dtype: Any) -> None:
    plane, light = scene.plane.astype(dtype), scene.light.astype(dtype)
    M = sm.planar_projection(plane, light).astype(np.float64)
    pi, L = plane.astype(np.float64), light.astype(np.float64)
    tol = 64 * _eps(dtype)
    size = np.abs(M).max()
    # Every point lands on the plane, the light is M's null vector, M @ M = |pi.L| M.
    rng = np.random.default_rng(0)
    pts = np.c_[rng.normal(size=(8, 3)) * scene.scale, np.ones(8)]
    shadow = pts @ M.T
    assert np.all(np.abs(shadow @ pi) <= tol * size * np.abs(pts).sum(-1) * np.abs(pi).sum())
    assert np.all(np.abs(M @ L) <= tol * size * np.abs(L).sum())
    trace_part = np.trace(M) / 3  # tr M = 4 |pi.L| - |pi.L|
    np.testing.assert_allclose(M @ M, trace_part * M, atol=tol * 4 * size**2)
    # A point between a point light and the plane gets w > 0 (the shadow is not clipped).
    if L[3] != 0:
        pos = L[:3] / L[3]
        n = pi[:3]
        foot = pos - (n @ pos + pi[3]) / (n @ n) * n
        mid = np.append((pos + foot) / 2, 1.0)
        assert (M @ mid)[3] > 0


@DTYPES
@given(data=st.data())
def test_fuzz_planar_projection(dtype: Any, data: st.DataObject) -> None:
    if data.draw(st.booleans()):
        CASES["planar_projection valid"] += 1
        _check_planar(data.draw(planar_scenes(dtype)), dtype)
    else:
        CASES["planar_projection invalid"] += 1
        bad = data.draw(invalid_planar())
        _raises(bad, sm.planar_projection, *(np.asarray(a, dtype) for a in bad.args))


# --- helper axis and light frame ---------------------------------------------------------


@given(
    z=st.one_of(
        unit_vectors(),
        st.lists(st.floats(-1e6, 1e6, width=32), min_size=3, max_size=3).map(np.array),
    ),
    dtype=st.sampled_from([np.float64, np.float32]),
)
def test_fuzz_helper_axis(z: np.ndarray, dtype: Any) -> None:
    CASES["helper_axis"] += 1
    z = z.astype(dtype)
    v = sm.helper_axis(z)
    assert sorted(v.tolist()) == [0.0, 0.0, 1.0]
    k = int(np.argmax(v))
    a = np.abs(z)
    assert a[k] == a.min()
    assert k == int(np.argmin(a))  # ties: the lowest index
    # |z x V|^2 >= (2/3) |z|^2 exactly (the components are compared exactly).
    z64 = z.astype(np.float64)
    assert 3 * (z64 @ z64 - z64[k] ** 2) >= 2 * (z64 @ z64) * (1 - 4 * 2.0**-52)


def _kappa(p: Placement) -> float:
    """The scene's condition: coordinates' size over the blocker's size, times 1 + ratio."""
    r = np.linalg.norm(p.vertices - p.vertices.mean(0), axis=-1).max()
    size = np.abs(p.light).max() + np.abs(p.vertices).max()
    return float(size / r + p.distance_ratio)


def _check_frame(p: Placement, dtype: Any) -> None:
    light, verts = p.light.astype(dtype), p.vertices.astype(dtype)
    tol = 64 * _eps(dtype)
    f = sm.light_frame(light, verts)
    X, Y, Z = (np.asarray(a, np.float64) for a in f[1:])
    R = np.stack([X, Y, Z])
    np.testing.assert_allclose(R @ R.T, np.eye(3), atol=tol)
    np.testing.assert_allclose(np.cross(X, Y), -Z, atol=tol)  # left-handed
    mdv = np.asarray(sm.mean_direction_vector(light, verts), np.float64)
    off = verts.astype(np.float64) - light.astype(np.float64)
    kappa_mdv = np.linalg.norm(off, axis=-1).mean() / np.linalg.norm(off.mean(0))
    np.testing.assert_allclose(mdv, off.mean(0), atol=tol * kappa_mdv * np.linalg.norm(mdv))
    assert np.linalg.norm(np.cross(Z, mdv)) <= tol * kappa_mdv * np.linalg.norm(mdv)
    assert Z @ mdv > 0
    V = np.asarray(sm.helper_axis(f.z_axis), np.float64)
    assert np.linalg.norm(np.cross(Z, V)) >= np.sqrt(2 / 3) * (1 - tol)
    W = np.asarray(sm.world_to_light(f), np.float64)
    Wi = np.asarray(sm.light_to_world(f), np.float64)
    np.testing.assert_allclose(W @ Wi, np.eye(4), atol=tol * (1 + np.abs(light).max()))
    origin = W @ np.append(light.astype(np.float64), 1.0)
    assert np.abs(origin[:3]).max() <= tol * (1 + np.abs(light).max())


@DTYPES
@given(data=st.data())
def test_fuzz_light_frame(dtype: Any, data: st.DataObject) -> None:
    if data.draw(st.booleans()):
        CASES["light_frame valid"] += 1
        _check_frame(data.draw(placements(dtype)), dtype)
        return
    bad = data.draw(invalid_placements())
    light, verts = (np.asarray(a, dtype) for a in bad.args)
    CASES["light_frame invalid"] += 1
    if bad.message in ("not strictly in front", "zero width or height"):
        sm.light_frame(light, verts)  # a valid frame; only a frustum is impossible
        with pytest.raises(ValueError, match=re.escape(bad.message)):
            sm.adaptive_frustum(sm.light_frame(light, verts), verts, 64)
        return
    _raises(bad, sm.light_frame, light, verts)
    if bad.message != "viewing direction is zero":
        _raises(bad, sm.mean_direction_vector, light, verts)


@given(direction=unit_vectors(), length=st.sampled_from([1e-30, 1e-6, 1.0, 1e6, 1e30]))
def test_fuzz_light_frame_from_direction(direction: np.ndarray, length: float) -> None:
    CASES["light_frame_from_direction"] += 1
    for dtype in (np.float64, np.float32):
        d = (direction * length).astype(dtype)
        if not np.any(d):
            _raises(Invalid((), "viewing direction is zero"), sm.light_frame_from_direction, d, d)
            continue
        f = sm.light_frame_from_direction(np.zeros(3, dtype), d)
        Z = np.asarray(f.z_axis, np.float64)
        unit = d.astype(np.float64) / np.linalg.norm(d.astype(np.float64))
        np.testing.assert_allclose(Z, unit, atol=8 * _eps(dtype))


# --- frustum, projections, fit_shadow ----------------------------------------------------


def _array_path() -> contextlib.AbstractContextManager[None]:
    """Run on whole arrays (no compiled loop) inside the block."""
    return _kernels.array_path()


def _check_fit(p: Placement, map_size: Any, border: int, dtype: Any) -> None:
    light, verts = p.light.astype(dtype), p.vertices.astype(dtype)
    s = sm.fit_shadow(light, verts, map_size, border_texels=border)
    mx, my = sm.border_margin(map_size, border_texels=border)
    tol = 64 * _eps(dtype) * _kappa(p)
    h = np.c_[verts.astype(np.float64), np.ones(len(verts))]
    clip = h @ np.asarray(s.blocker_to_clip, np.float64).T
    assert np.all(clip[:, 3] > 0)
    ndc = clip[:, :3] / clip[:, 3:]
    # Every vertex inside the margin, and one touching it on each axis (the article).
    assert np.abs(ndc[:, 0]).max() == pytest.approx(mx, rel=tol, abs=tol)
    assert np.abs(ndc[:, 1]).max() == pytest.approx(my, rel=tol, abs=tol)
    assert np.all(np.abs(ndc[:, 2]) <= 1)  # inside near and far: nothing clipped
    # The texture matrix agrees: s = (1 + x_ndc) / 2, q = z > 0.
    stq = h @ np.asarray(s.world_to_texture, np.float64).T
    np.testing.assert_allclose(stq[:, :2] / stq[:, 3:], (1 + ndc[:, :2]) / 2, atol=tol)
    R = sm.receiver_texture_matrix(s, np.eye(4, dtype=dtype))
    np.testing.assert_array_equal(R, s.world_to_texture)
    raw = np.frombuffer(sm.column_major_bytes(s.blocker_to_clip), np.float32).reshape(4, 4)
    np.testing.assert_array_equal(raw.T, np.asarray(s.blocker_to_clip, np.float32))
    # The parts agree with the whole: exactly on the array path; to rounding where
    # fit_shadow ran the compiled loop (it sums in float64, the parts in the input dtype).
    fr = sm.adaptive_frustum(s.frame, verts, map_size, border_texels=border)
    for project in (sm.blocker_projection, sm.receiver_projection):
        np.testing.assert_allclose(project(fr), project(s.frustum), rtol=tol, atol=0)
    with _array_path():
        whole = sm.fit_shadow(light, verts, map_size, border_texels=border)
    part = sm.adaptive_frustum(whole.frame, verts, map_size, border_texels=border)
    for project in (sm.blocker_projection, sm.receiver_projection):
        np.testing.assert_array_equal(project(part), project(whole.frustum))


@DTYPES
@given(data=st.data())
def test_fuzz_fit_shadow(dtype: Any, data: st.DataObject) -> None:
    map_size, border = data.draw(sized_maps())
    if data.draw(st.booleans()):
        CASES["fit_shadow valid"] += 1
        p = data.draw(placements(dtype))
        # Refused exactly when wider than 170 degrees at the map's edge (tan 85 deg = 11.43).
        light, verts = p.light.astype(dtype), p.vertices.astype(dtype)
        fr = sm.adaptive_frustum(sm.light_frame(light, verts), verts, map_size,
                                 border_texels=border)  # fmt: skip
        t = max(float(fr.rx_max) / float(fr.margin_x), float(fr.ry_max) / float(fr.margin_y))
        edge = np.tan(np.radians(85))
        tol = 64 * _eps(dtype) * _kappa(p)
        if t > edge * (1 + tol):
            with pytest.raises(ValueError, match="wider than 170 degrees"):
                sm.fit_shadow(light, verts, map_size, border_texels=border)
        elif t < edge * (1 - tol):
            _check_fit(p, map_size, border, dtype)
        return
    CASES["fit_shadow invalid"] += 1
    bad = data.draw(invalid_placements())
    bad = bad._replace(message=bad.message.replace("light_position:", "light:"))  # its name
    _raises(bad, sm.fit_shadow, *(np.asarray(a, dtype) for a in bad.args), map_size)


@given(
    map_size=st.one_of(
        st.integers(-3, 5000), st.tuples(st.integers(-3, 300), st.integers(-3, 300))
    ),
    border=st.integers(-2, 8),
)
def test_fuzz_border_margin(map_size: Any, border: int) -> None:
    CASES["border_margin"] += 1
    sizes = map_size if isinstance(map_size, tuple) else (map_size, map_size)
    if min(sizes) <= 0 or border < 0 or min(sizes) <= 2 * border:
        with pytest.raises(ValueError, match=r"map_size: |border_texels: "):
            sm.border_margin(map_size, border_texels=border)
        return
    margins = sm.border_margin(map_size, border_texels=border)
    assert margins == tuple((n - 2 * border) / n for n in sizes)
    assert all(0 < m <= 1 for m in margins)


@given(data=st.data())
def test_fuzz_projections_of_any_frustum(data: st.DataObject) -> None:
    CASES["blocker/receiver_projection"] += 1
    values = st.one_of(st.floats(-1, 0), st.floats(1e-30, 1e4), st.just(1e-310))
    rx, ry, near, far = (data.draw(values) for _ in range(4))
    kind = data.draw(st.sampled_from([sm.Frustum, sm.OrthographicBox]))
    box = kind is sm.OrthographicBox
    fr = kind(rx, ry, near, far, 0.98, 0.96)
    tiny = np.finfo(np.float64).tiny  # subnormal ratios are refused: m / r would overflow
    # A box needs no eye (any near), but a depth range of at least a normal float.
    depth_ok = far - near >= tiny if box else 0 < near < far
    if not (rx >= tiny and ry >= tiny and depth_ok):
        with pytest.raises(ValueError, match="frustum"):
            sm.blocker_projection(fr)
        with pytest.raises(ValueError, match="frustum"):
            sm.receiver_projection(fr)
        return
    P = sm.blocker_projection(fr)
    T = sm.receiver_projection(fr)
    assert np.all(np.isfinite(P))
    assert np.all(np.isfinite(T))
    if abs(near) < 1e-290 and not box:  # subnormal corners: the check would measure underflow
        return
    # Depth loses |f + n| / (f - n) ulps to cancellation, whatever the formula.
    tol = 1e-13 * (abs(far) + abs(near)) / (far - near)
    for z, depth in ((near, -1.0), (far, 1.0)):
        scale = 1.0 if box else z  # x_ndc = m (x - c) / R for a box, m (x / z - c) / R else
        corner = np.array([rx * scale, -ry * scale, z, 1.0])
        clip = P @ corner
        np.testing.assert_allclose(clip[:2] / clip[3], [0.98, -0.96], rtol=1e-12)
        assert clip[2] / clip[3] == pytest.approx(depth, abs=tol)
        stq = T @ corner
        np.testing.assert_allclose(stq[:2] / stq[3], [0.99, 0.02], rtol=1e-12)
        assert stq[2] / stq[3] == pytest.approx((depth + 1) / 2, abs=tol)


@given(
    shape=st.lists(st.integers(1, 3), min_size=0, max_size=2),
    near=st.floats(1e-3, 10),
    ratio=st.floats(1.01, 1e4),
    orthographic=st.booleans(),
    wrong=st.sampled_from(["none", "transposed", "scaled"]),
    scale=st.floats(1.5, 8),
)
def test_fuzz_check_projection(
    shape: list[int], near: float, ratio: float, orthographic: bool, wrong: str, scale: float
) -> None:
    """A projection built from glFrustum's and glOrtho's formulas passes unchanged; its
    transpose (row-major memory read as column-major) or a multiple of it is refused."""
    CASES["check_projection"] += 1
    n, f = near, near * ratio
    if orthographic:
        rows = [[0.5, 0, 0, 0.1], [0, 0.7, 0, 0], [0, 0, -2 / (f - n), -(f + n) / (f - n)]]
        P = np.array([*rows, [0, 0, 0, 1.0]])
    else:
        rows = [[1.2, 0, 0.1, 0], [0, 1.6, 0, 0], [0, 0, -(f + n) / (f - n), -2 * f * n / (f - n)]]
        P = np.array([*rows, [0, 0, -1.0, 0]])
        # The transpose's last row (0, 0, -2fn/(f-n), 0) is a camera's where 2fn = f - n.
        assume(wrong != "transposed" or abs(2 * f * n / (f - n) - 1) > 1e-6)
    M = np.broadcast_to(P, (*shape, 4, 4))
    if wrong == "none":
        np.testing.assert_array_equal(sm.check_projection(M), M)
        return
    bad = np.swapaxes(M, -1, -2) if wrong == "transposed" else scale * M
    with pytest.raises(ValueError, match="projection: its last row is neither"):
        sm.check_projection(bad)


@given(
    shape=st.lists(st.integers(0, 3), min_size=0, max_size=2),
    nan_at=st.integers(-1, 50),
)
def test_fuzz_check_finite(shape: list[int], nan_at: int) -> None:
    CASES["check_finite"] += 1
    M = np.ones((*shape, 4, 4))
    if 0 <= nan_at < M.size:
        M.flat[nan_at] = np.nan
        with pytest.raises(ValueError, match="NaN or infinite"):
            sm.check_finite(M)
    else:
        assert sm.check_finite(M) is M


# --- the reference render ------------------------------------------------------------------


@pytest.fixture(scope="module")
def gl() -> Any:
    """The shared offscreen context; as tests/render: fails under SHADOWMATH_REQUIRE_GL=1."""
    try:
        from shadowmath.render import standalone_context

        return standalone_context()
    except Exception as err:  # ImportError (no moderngl) or GLUnavailableError
        if os.environ.get("SHADOWMATH_REQUIRE_GL") == "1":
            pytest.fail(f"SHADOWMATH_REQUIRE_GL=1: no OpenGL context: {err}")
        pytest.skip(f"no OpenGL context for the reference render: {err}")


@st.composite
def bordered_maps(draw: st.DrawFn) -> tuple[tuple[int, int], int]:
    """Small maps (the render is the slow part) with a border of 1 to 3 texels."""
    w, h = draw(st.integers(3, 300)), draw(st.integers(3, 300))
    if draw(st.booleans()):
        h = w
    return (w, h), draw(st.integers(1, min(3, (min(w, h) - 1) // 2)))


@settings(max_examples=max(10, (settings.default.max_examples or 0) // 10))
@given(data=st.data())
def test_fuzz_reference_render_never_draws_into_the_border(gl: Any, data: st.DataObject) -> None:
    from shadowmath.render import render_shadow_map

    p = data.draw(placements(np.float32, max_vertices=10))
    (w, h), border = data.draw(bordered_maps())
    # The GPU applies the matrix in float32: its rounding, eps32 * kappa in NDC, must stay
    # under a quarter texel (2 / size in NDC) for the one-texel guarantee to be meaningful.
    assume(_eps(np.float32) * _kappa(p) * max(w, h) < 0.25)
    # Fits wider than 170 degrees are refused (test_fuzz_fit_shadow checks that).
    fr = sm.adaptive_frustum(sm.light_frame(p.light, p.vertices), p.vertices, (w, h),
                             border_texels=border)  # fmt: skip
    assume(max(float(fr.rx_max) / float(fr.margin_x), float(fr.ry_max) / float(fr.margin_y))
           < 0.99 * np.tan(np.radians(85)))  # fmt: skip
    CASES["render (reference, GL)"] += 1
    s = sm.fit_shadow(p.light, p.vertices, (w, h), border_texels=border)
    n = len(p.vertices)
    triangles = [(0, i, i + 1) for i in range(1, n - 1)] + [(i, i + 1, i + 2) for i in range(n - 2)]
    mask = render_shadow_map(p.vertices, triangles, s.blocker_to_clip, (w, h), ctx=gl)
    assert mask.shape == (h, w)
    assert set(np.unique(mask)) <= {0.0, 1.0}
    for edge in (mask[:border], mask[-border:], mask[:, :border], mask[:, -border:]):
        assert not edge.any(), "shadow drawn into the border"


# --- what the fitting issue added: smooth and off-centre frusta, rolled frames --------------


def _light_ratios(frame: sm.LightFrame, verts: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    off = verts.astype(np.float64) - np.asarray(frame.origin, np.float64)
    x, y, z = (off @ np.asarray(a, np.float64) for a in frame[1:])
    return x / z, y / z


@DTYPES
@given(data=st.data())
def test_fuzz_offcenter_and_smooth_frusta(dtype: Any, data: st.DataObject) -> None:
    map_size, border = data.draw(sized_maps())
    if not data.draw(st.booleans()):
        CASES["offcenter/smooth_frustum invalid"] += 1
        bad = data.draw(invalid_placements())
        light, verts = (np.asarray(a, dtype) for a in bad.args)
        if bad.message in ("not strictly in front", "zero width or height"):
            frame = sm.light_frame(light, verts)
            _raises(bad, sm.offcenter_frustum, frame, verts, map_size, border_texels=border)
            if bad.message == "not strictly in front":  # a point still gets T log 2 > 0
                _raises(bad, sm.smooth_frustum, frame, verts, map_size, temperature=1e-3)
        return
    CASES["offcenter/smooth_frustum valid"] += 1
    p = data.draw(placements(dtype))
    light, verts = p.light.astype(dtype), p.vertices.astype(dtype)
    frame = sm.light_frame(light, verts)
    tol = 64 * _eps(dtype) * _kappa(p)
    rx, ry = _light_ratios(frame, verts)
    fr = sm.offcenter_frustum(frame, verts, map_size, border_texels=border)
    # The off-centre frustum: smallest ratio on -R, largest on +R about the offset.
    for r, half, centre in ((rx, fr.rx_max, fr.x_offset), (ry, fr.ry_max, fr.y_offset)):
        u = (r - float(centre)) / float(half)
        assert u.min() == pytest.approx(-1, abs=tol)
        assert u.max() == pytest.approx(1, abs=tol)
    hard = sm.adaptive_frustum(frame, verts, map_size, border_texels=border)
    assert float(fr.rx_max) <= float(hard.rx_max) * (1 + tol)
    # The smooth symmetric frustum: never tighter than the hard one, at most T log(2N) wider.
    T = data.draw(st.sampled_from([1e-4, 1e-2, 1.0])) * float(hard.rx_max)
    soft = sm.smooth_frustum(frame, verts, map_size, temperature=T, border_texels=border)
    slack = T * np.log(2 * len(verts))
    for s_r, h_r in ((soft.rx_max, hard.rx_max), (soft.ry_max, hard.ry_max)):
        assert float(h_r) * (1 - tol) <= float(s_r) <= float(h_r) * (1 + tol) + slack * (1 + tol)
    with pytest.raises(ValueError, match="temperature: must be finite and > 0"):
        sm.smooth_frustum(frame, verts, map_size, temperature=-T)


@given(
    values=st.lists(st.floats(-1e6, 1e6), min_size=0, max_size=12),
    temperature=st.one_of(st.floats(1e-6, 1e3), st.sampled_from([0.0, -1.0, np.inf, np.nan])),
)
def test_fuzz_smooth_max(values: list[float], temperature: float) -> None:
    CASES["smooth_max"] += 1
    if not values or not (np.isfinite(temperature) and temperature > 0):
        message = "values: expected shape" if not values else "temperature: must be finite"
        with pytest.raises(ValueError, match=message):
            sm.smooth_max(np.array(values), temperature)
        return
    v = np.array(values)
    got = float(sm.smooth_max(v, temperature))
    tol = 8 * _eps(np.float64) * (np.abs(v).max() + temperature * np.log(len(v)) + 1)
    assert v.max() - tol <= got <= v.max() + temperature * np.log(len(v)) + tol


@given(direction=unit_vectors(), roll=st.floats(-10, 10), up=unit_vectors())
def test_fuzz_rolled_light_frame(direction: np.ndarray, roll: float, up: np.ndarray) -> None:
    CASES["rolled_light_frame"] += 1
    sin_angle = np.linalg.norm(np.cross(direction, up))
    if sin_angle < 1e-12:  # parallel: the documented error (256 ulps is the threshold)
        with pytest.raises(ValueError, match="up: the reference axis is zero or parallel"):
            sm.rolled_light_frame(np.zeros(3), direction, roll, up=up)
        return
    f = sm.rolled_light_frame(np.ones(3), direction, roll, up=up)
    X, Y, Z = (np.asarray(a) for a in f[1:])
    R = np.stack([X, Y, Z])
    np.testing.assert_allclose(R @ R.T, np.eye(3), atol=1e-12 / sin_angle)
    np.testing.assert_allclose(np.cross(X, Y), -Z, atol=1e-12 / sin_angle)
    np.testing.assert_allclose(Z, direction / np.linalg.norm(direction), atol=1e-15)


# --- JAX: the same answers under jit, and NaN exactly where NumPy raises --------------------


def _fit_64(light: Any, verts: Any) -> Any:
    return sm.fit_shadow(light, verts, 64).blocker_to_clip


@given(data=st.data())
def test_fuzz_jit_gives_numpy_results_or_nan_where_numpy_raises(data: st.DataObject) -> None:
    import jax
    import jax.numpy as jnp

    if data.draw(st.booleans()):
        p = data.draw(placements())
        args: tuple[np.ndarray, ...] = (p.light, p.vertices)
        plane_args: tuple[np.ndarray, ...] = tuple(data.draw(planar_scenes())[:2])
    else:
        args = data.draw(invalid_placements()).args
        plane_args = data.draw(invalid_planar()).args
    # Module-level functions, so that jit compiles once per vertex count, not per example.
    for fn, call_args in ((_fit_64, args), (sm.planar_projection, plane_args)):
        if any(np.asarray(a).shape[-2:-1] == (0,) for a in call_args):
            continue  # the empty vertex set is a shape error: it raises under jit too
        CASES["jit vs NumPy"] += 1
        got = np.asarray(jax.jit(fn)(*(jnp.asarray(a) for a in call_args)))
        try:
            want = fn(*call_args)
        except ValueError:
            assert np.all(np.isnan(got)), "a finite result where NumPy raises"
            continue
        atol = 1e-9 * np.abs(want).max()
        if fn is _fit_64 and not np.allclose(got, want, rtol=1e-9, atol=atol):
            # Only at a helper-axis tie may XLA's rounding pick the other (equally valid)
            # axis: then the jit matrix must still fit the blocker to the margins.
            z = np.sort(np.abs(np.asarray(sm.light_frame(*call_args).z_axis)))
            assert z[1] - z[0] <= 1e-12 * z[2], "jit and NumPy differ away from a tie"
            clip = np.c_[call_args[1], np.ones(len(call_args[1]))] @ got.T
            ndc = clip[:, :2] / clip[:, 3:]
            np.testing.assert_allclose(np.abs(ndc).max(axis=0), 62 / 64, rtol=1e-9)
            continue
        np.testing.assert_allclose(got, want, rtol=1e-9, atol=atol)


# --- issue 16: what renderers call ----------------------------------------------------------
#
# Scene options of fit_shadow (every light form, receivers, up, stable, api, reversed_z,
# ShadowMapSpec, blocker_to_world, near and far), cube maps, biases, PCF and area lights,
# each on NumPy and JAX (eager, jit, vmap) in float32 and float64. Every output is checked
# against properties computed here in float64 from the arrays as the package saw them.


def _jnp() -> Any:
    import jax.numpy as jnp

    return jnp


def _convert(value: Any, dtype: Any, xp: Any = np) -> Any:
    """Float arrays (inside typed lights and receivers too) in ``dtype`` on ``xp``."""
    if isinstance(value, tuple) and hasattr(value, "_fields"):
        return type(value)(*(_convert(v, dtype, xp) for v in value))
    if isinstance(value, np.ndarray) and value.dtype.kind == "f":
        return xp.asarray(value, dtype=dtype)
    return value


def _light_of(call: FitCall, dtype: Any, xp: Any = np) -> Any:
    """The light argument of ``call``: a typed light, ``(x, y, z)`` or ``(x, y, z, w)``."""
    s = call.scene
    if s.kind == "spot":
        return sm.SpotLight(*(xp.asarray(v, dtype) for v in (s.position, s.direction, s.angle)))
    if s.kind == "directional":
        if call.form == "typed":
            return sm.DirectionalLight(xp.asarray(s.direction, dtype))
        return xp.asarray(np.append(s.direction, 0.0), dtype)
    if call.form == "typed":
        return sm.PointLight(xp.asarray(s.position, dtype))
    if call.form == "xyzw":  # rounded first: times a power of two and back is exact
        position = s.position.astype(dtype).astype(np.float64)
        return xp.asarray(np.append(position * call.w, call.w), dtype)
    return xp.asarray(s.position, dtype)


def _spec_of(call: FitCall) -> sm.ShadowMapSpec:
    return sm.ShadowMapSpec(
        call.map_size,
        **call.map_options,
        api=call.api,  # type: ignore[arg-type]
        reversed_z=call.reversed_z,
        stable=call.stable,
    )


def _fit_args(
    call: FitCall, dtype: Any, xp: Any = np, light: Any = None, **extra: Any
) -> tuple[tuple[Any, ...], dict[str, Any]]:
    """``fit_shadow``'s arguments for ``call``, in ``dtype`` on ``xp``."""
    arrays = {
        "blocker_to_world": call.placement,
        "receivers": _receivers_of(call),
        "up": call.up,
        "near": None if call.near is None else np.asarray(call.near),
        "far": None if call.far is None else np.asarray(call.far),
    }
    kwargs: dict[str, Any] = {k: _convert(v, dtype, xp) for k, v in arrays.items() if v is not None}
    if call.aim != "mean":
        kwargs["aim"] = call.aim
    if call.as_spec:
        map_size: Any = _spec_of(call)
    else:
        map_size = call.map_size
        kwargs.update(call.map_options)
        kwargs.update(api=call.api, reversed_z=call.reversed_z, stable=call.stable)
    kwargs.update(extra)
    light = _light_of(call, dtype, xp) if light is None else _convert(light, dtype, xp)
    return (light, _convert(call.local, dtype, xp), map_size), kwargs


def _receivers_of(call: FitCall) -> Any:
    """``receivers=``: points, ``sm.Triangles`` or ``sm.Mesh``."""
    if call.receivers is None or call.receiver_kind == "points":
        return call.receivers
    if call.receiver_kind == "triangles":
        return sm.Triangles(call.receivers)
    return sm.Mesh(call.receivers, call.faces)


def _receiver_samples(call: FitCall, dtype: Any) -> np.ndarray:
    """Points of the receivers: the points themselves, or on every triangle its corners, edge
    midpoints, centre and a grid of barycentric points (float64, from the rounded corners)."""
    R = _rounded(call.receivers, dtype)
    if call.receiver_kind == "points":
        return R
    corners = R if call.receiver_kind == "triangles" else R[call.faces]
    k = 12
    w = np.array([(i, j, k - i - j) for i in range(k + 1) for j in range(k + 1 - i)]) / k
    return np.asarray(np.einsum("wc,tcx->twx", w, corners).reshape(-1, 3))


def _fit(call: FitCall, dtype: Any, xp: Any = np, **extra: Any) -> sm.ShadowSetup:
    args, kwargs = _fit_args(call, dtype, xp, **extra)
    return sm.fit_shadow(*args, **kwargs)


def _f64(x: Any) -> np.ndarray:
    return np.asarray(x, dtype=np.float64)


def _rounded(x: Any, dtype: Any) -> np.ndarray:
    """``x`` as the package saw it: rounded to ``dtype``, then exactly in float64."""
    return np.asarray(x, dtype=dtype).astype(np.float64)


def _homogeneous(points: np.ndarray) -> np.ndarray:
    return np.c_[points, np.ones(len(points))]


def _tex(M: Any, points: np.ndarray) -> np.ndarray:
    """``(s, t, r, q)`` of world points through a world-to-texture matrix (NaN where q = 0)."""
    h = _homogeneous(points) @ _f64(M).T
    q = h[:, 3:]
    safe = np.where(q == 0, np.nan, q)
    return np.c_[h[:, :3] / safe, h[:, 3]]


def _near_far_depths(reversed_z: bool) -> tuple[float, float]:
    """The depths stored at the near and far planes (the same in every API)."""
    return (1.0, 0.0) if reversed_z else (0.0, 1.0)


def _call_kappa(call: FitCall, dtype: Any) -> float:
    """The condition of a fit call: the scene's, through the placement (its condition, and
    the size of the placed coordinates, rounded in the sum, over the blocker's size)."""
    if call.placement is None:
        return call.scene.kappa
    B = _rounded(call.placement, dtype)
    world = call.scene.vertices
    r = float(np.linalg.norm(world - world.mean(axis=0), axis=-1).max())
    placed = float((np.abs(_homogeneous(_rounded(call.local, dtype))) @ np.abs(B).T).max())
    return call.scene.kappa * float(np.linalg.cond(B[:3, :3])) + placed / r


def _check_scene_setup(call: FitCall, s: sm.ShadowSetup, dtype: Any) -> None:
    """Every property a renderer relies on, for one fitted scene (NumPy or JAX result)."""
    scene = call.scene
    eps = _eps(dtype)
    B = np.eye(4) if call.placement is None else _rounded(call.placement, dtype)
    local = _rounded(call.local, dtype)
    world = (_homogeneous(local) @ B.T)[:, :3]
    tol = 64 * eps * _call_kappa(call, dtype)
    # The frame: orthonormal, left-handed, aimed as the light's kind says.
    X, Y, Z = (_f64(a) for a in s.frame[1:])
    R = np.stack([X, Y, Z])
    np.testing.assert_allclose(R @ R.T, np.eye(3), atol=64 * eps)
    np.testing.assert_allclose(np.cross(X, Y), -Z, atol=64 * eps)
    if scene.kind == "point" and call.aim == "mean":
        off = world - _rounded(scene.position, dtype)
        mdv = off.mean(axis=0)
        kappa_mdv = float(np.linalg.norm(off, axis=-1).mean() / np.linalg.norm(mdv))
        assert np.linalg.norm(np.cross(Z, mdv / np.linalg.norm(mdv))) <= tol * kappa_mdv
    elif scene.kind != "point":
        d = _rounded(scene.direction, dtype)
        aim = d if scene.kind == "spot" else -d
        np.testing.assert_allclose(Z, aim / np.linalg.norm(aim), atol=16 * eps)
    if call.up is not None:  # a look-at frame: Y is up's part perpendicular to Z
        up = _rounded(call.up, dtype)
        up /= np.linalg.norm(up)
        assert abs(X @ up) <= 64 * eps / np.linalg.norm(np.cross(Z, up))
        assert Y @ up > 0
    # Every caster vertex inside the margins and the depth range, in the API's convention.
    margins = _spec_of(call).margins
    assert margins == _spec_margins(call.map_size, call.map_options)
    clip = _homogeneous(local) @ _f64(s.blocker_to_clip).T
    assert np.all(clip[:, 3] > 0)
    if scene.kind == "directional":
        np.testing.assert_array_equal(_f64(s.blocker_to_clip)[3], [0, 0, 0, 1])
        assert isinstance(s.frustum, sm.OrthographicBox)
    ndc = clip[:, :3] / clip[:, 3:]
    inside = np.ones(len(world), dtype=bool)
    fr = s.frustum
    if not scene.covers:  # a spot narrower than the blocker: its bounding square only
        t = np.tan(_rounded(scene.angle, dtype))
        off = world - _f64(s.frame.origin)
        u, v = (off @ X) / (off @ Z), (off @ Y) / (off @ Z)
        inside = (np.abs(u) <= t * (1 - tol)) & (np.abs(v) <= t * (1 - tol))
        for half, centre in ((fr.rx_max, fr.x_offset), (fr.ry_max, fr.y_offset)):
            assert abs(float(centre)) + float(half) <= t * (1 + tol)
    for axis, m in ((0, margins[0]), (1, margins[1])):
        assert np.all(np.abs(ndc[inside, axis]) <= m * (1 + tol) + tol)
    tex = _tex(s.world_to_texture, world)
    assert np.all((tex[:, 2] >= -tol) & (tex[:, 2] <= 1 + tol))  # stored depth in [0, 1]
    # The article's tight fit touches the margins: each side (off-centre fits) or each axis.
    if not call.stable and scene.covers:
        for axis, m in ((0, margins[0]), (1, margins[1])):
            a = ndc[:, axis] * (-1 if call.api == "vulkan" and axis == 1 else 1)
            if scene.kind == "point":
                assert np.abs(a).max() == pytest.approx(m, rel=tol, abs=tol)
            else:
                assert a.max() == pytest.approx(m, rel=tol, abs=tol)
                assert a.min() == pytest.approx(-m, rel=tol, abs=tol)
    if call.stable and scene.kind == "directional":
        _check_stable(call, s, world, margins, tol)
    # The texture matrix samples the texel the caster was drawn into, in every API.
    conv = sm.api_convention(api=call.api, reversed_z=call.reversed_z)
    scale = np.abs(_f64(s.world_to_texture)).max() * np.abs(B).max()
    np.testing.assert_allclose(
        _f64(s.world_to_texture) @ B,
        conv.clip_to_texture @ _f64(s.blocker_to_clip),
        atol=16 * eps * scale,
    )
    placed = sm.receiver_texture_matrix(s, np.asarray(B, dtype=dtype))
    np.testing.assert_allclose(_f64(placed), _f64(s.world_to_texture) @ B, atol=16 * eps * scale)
    # Default near and far: NEAR_FAR_SLACK outside the casters (receivers only push far).
    if scene.kind != "directional":
        z = (world - _f64(s.frame.origin)) @ Z
        slack = sm.NEAR_FAR_SLACK
        if call.near is None:
            assert float(fr.near) == pytest.approx(
                z.min() * (1 - slack), rel=tol, abs=tol * z.max()
            )
        if call.far is None:
            assert float(fr.far) >= z.max() * (1 + slack) * (1 - tol)
            if call.receivers is None:
                assert float(fr.far) == pytest.approx(z.max() * (1 + slack), rel=tol)
    # Given near and far are the frustum's; receivers only ever extend the far end.
    if call.near is not None:
        assert float(fr.near) == float(np.asarray(call.near, dtype))
    if call.far is not None:
        assert float(fr.far) == float(np.asarray(call.far, dtype))
    elif call.receivers is not None:
        _check_receivers_before_far(call, s, _receiver_samples(call, dtype), tol)


def _check_receivers_before_far(
    call: FitCall, s: sm.ShadowSetup, receivers: np.ndarray, tol: float
) -> None:
    """Every receiver point the map covers (inside its sides, in front) lies at or before far."""
    scene = call.scene
    tex = _tex(s.world_to_texture, receivers)
    size = np.abs(receivers - scene.vertices.mean(axis=0)).max()
    r = np.linalg.norm(scene.vertices - scene.vertices.mean(axis=0), axis=-1).max()
    tol_r = tol * (1 + size / r)
    st_ = tex[:, :2]
    covered = np.all((st_ >= tol_r) & (st_ <= 1 - tol_r), axis=-1) & (tex[:, 3] > 0)
    _, far_depth = _near_far_depths(call.reversed_z)
    beyond = (tex[:, 2] - far_depth) * (1 if far_depth == 1 else -1)
    assert np.all(beyond[covered] <= tol_r), "a covered receiver lies beyond far"


def _check_stable(
    call: FitCall, s: sm.ShadowSetup, world: np.ndarray, margins: tuple[float, float], tol: float
) -> None:
    """A stable map: its scale is the blocker's shape's (a sphere about it, enlarged by half a
    texel, that rigid motions of the blocker leave alone) and its texel grid is anchored at
    the world origin."""
    W, H = call.map_size if isinstance(call.map_size, tuple) else (call.map_size,) * 2
    mean = world.mean(axis=0)
    r_mean = float(np.linalg.norm(world - mean, axis=-1).max())
    diameter = float(np.linalg.norm(world[:, None] - world[None], axis=-1).max())
    half_x, half_y = s.frustum[:2]  # a Frustum's rx_max, ry_max or a box's half extents
    for axis, m, n, half in ((0, margins[0], W, half_x), (1, margins[1], H, half_y)):
        # The sphere the map holds after its centre moved by half a texel: at least half the
        # diameter (no smaller sphere holds the blocker), at most the one about the mean.
        held = float(half) * (1 - 1 / (m * n))
        assert diameter / 2 * (1 - tol) - tol * r_mean <= held <= r_mean * (1 + tol)
        # The world origin sits on the texel grid: its NDC times n / 2 is a whole number.
        texel = 2 * float(half) / (m * n)
        noise = tol * (n + np.abs(mean).max() / texel)
        if noise < 0.05:
            origin = 2 * _tex(s.world_to_texture, np.zeros((1, 3)))[0, axis] - 1
            k = origin * n / 2
            assert abs(k - np.rint(k)) <= noise, "the texel grid moved off the world origin"


def _check_stable_scale(call: FitCall, s: sm.ShadowSetup, dtype: Any, rng_seed: int) -> None:
    """The blocker turned about its centre and moved by its size: the same texel size."""
    rng = np.random.default_rng(rng_seed)
    world = (
        _homogeneous(_rounded(call.local, dtype))
        @ (np.eye(4) if call.placement is None else _rounded(call.placement, dtype)).T
    )[:, :3]
    mean = world.mean(axis=0)
    q, _ = np.linalg.qr(rng.normal(size=(3, 3)))
    size = np.abs(world - mean).max()
    moved = (world - mean) @ q.T + mean + rng.uniform(-1, 1, 3) * size
    radius = float(np.linalg.norm(world - mean, axis=-1).max())
    kappa = _call_kappa(call, dtype) + float(np.abs(moved).max()) / radius + 2
    other = _fit(call._replace(local=moved, placement=None, receivers=None), dtype)
    for a, b in zip(s.frustum[:2], other.frustum[:2], strict=True):  # the half extents
        assert float(b) == pytest.approx(float(a), rel=64 * _eps(dtype) * kappa)


def _same_setup(a: sm.ShadowSetup, b: sm.ShadowSetup) -> None:
    for name in ("blocker_to_clip", "world_to_texture", "world_to_light"):
        np.testing.assert_array_equal(_f64(getattr(a, name)), _f64(getattr(b, name)), name)


def _check_equivalent_calls(call: FitCall, s: sm.ShadowSetup, dtype: Any) -> None:
    """Metamorphic checks: what must give the same fit (exactly, or to rounding)."""
    eps = _eps(dtype)
    scene = call.scene
    # Every form of the same light, and a spec or its keywords, give the same matrices.
    forms = ("typed",) if scene.kind == "spot" else ("typed", "xyzw")
    for form in forms:
        _same_setup(_fit(call._replace(form=form), dtype), s)
    if scene.kind == "point":
        _same_setup(_fit(call._replace(form="xyz"), dtype), s)
    _same_setup(_fit(call._replace(as_spec=not call.as_spec), dtype), s)
    # stable=True only changes a directional map (a point light's frame is up's already).
    if call.stable and scene.kind != "directional":
        _same_setup(_fit(call._replace(stable=False), dtype), s)
    # An API is C (and T) applied to OpenGL's matrices.
    if call.api != "opengl" or call.reversed_z:
        gl = _fit(call._replace(api="opengl", reversed_z=False), dtype)
        conv = sm.api_convention(api=call.api, reversed_z=call.reversed_z)
        T_gl = sm.api_convention().clip_to_texture
        pairs = (
            (s.blocker_to_clip, gl.blocker_to_clip),
            (
                np.linalg.solve(conv.clip_to_texture, _f64(s.world_to_texture)),
                np.linalg.solve(T_gl, _f64(gl.world_to_texture)),
            ),
        )
        for got, want in pairs:
            want = conv.gl_clip_to_clip @ _f64(want)
            np.testing.assert_allclose(_f64(got), want, atol=8 * eps * np.abs(want).max())


@DTYPES
@given(data=st.data())
def test_fuzz_fit_shadow_scene_options(dtype: Any, data: st.DataObject) -> None:
    call = data.draw(fit_calls(dtype))
    CASES[f"fit_shadow options ({call.scene.kind})"] += 1
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always", sm.ShadowFitWarning)
        s = _fit(call, dtype)
    _check_scene_setup(call, s, dtype)
    _check_wide_warning(call, s, dtype, [str(w.message) for w in caught])
    _check_equivalent_calls(call, s, dtype)
    if call.stable and call.scene.kind == "directional":
        _check_stable_scale(call, s, dtype, data.draw(st.integers(0, 2**32 - 1)))


_FRAME_OPERANDS = ("blocker_to_world", "receivers", "up", "near", "far")


def _fit_or_message(fn: Any, *args: Any, **kwargs: Any) -> Any:
    """``fn``'s result, or the message of the ValueError it raised (warnings silenced)."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", sm.ShadowFitWarning)
        try:
            return fn(*args, **kwargs)
        except ValueError as error:
            return str(error)


@DTYPES
@given(data=st.data())
def test_fuzz_shadow_fitter(dtype: Any, data: st.DataObject) -> None:
    """A ShadowFitter prepared on one call fits each later frame (the casters moved) exactly as
    fit_shadow fits that frame, into the caller's buffers, and refuses what fit_shadow refuses
    with the same message."""
    call = data.draw(fit_calls(dtype))
    CASES[f"ShadowFitter ({call.scene.kind})"] += 1
    (light, local, map_size), kwargs = _fit_args(call, dtype)
    frame = {k: v for k, v in kwargs.items() if k in _FRAME_OPERANDS}
    fitter = _fit_or_message(sm.ShadowFitter, light, local, map_size, **kwargs)
    if isinstance(fitter, str):  # refused as fit_shadow refuses it
        assert fitter == _fit_or_message(sm.fit_shadow, light, local, map_size, **kwargs)
        return
    out = fitter.buffers()
    shift = np.asarray(data.draw(st.tuples(*[st.floats(-0.5, 0.5)] * 3)))
    verts = np.asarray(local, np.float64)
    size = float(np.ptp(verts, axis=0).max())
    moved = (verts + shift * size).astype(dtype)
    got = _fit_or_message(fitter.fit, light, moved, out=out, **frame)
    want = _fit_or_message(sm.fit_shadow, light, moved, map_size, **kwargs)
    if isinstance(want, str):
        assert got == want
        return
    assert isinstance(got, sm.PreparedFit)
    for name in ("world_to_texture", "blocker_to_clip", "world_to_light"):
        np.testing.assert_array_equal(getattr(got, name), getattr(want, name))
    assert np.shares_memory(got.blocker_to_clip, out.mats)


def _check_wide_warning(call: FitCall, s: sm.ShadowSetup, dtype: Any, messages: list[str]) -> None:
    """A point or spot fit warns exactly when its frustum is wider than 120 degrees: the widest
    ratio at the map's edge, |c| + h / m, beyond tan 60 degrees (NumPy only)."""
    wide = [m for m in messages if m.startswith("light: the fitted frustum is wider than 120")]
    if call.scene.kind == "directional":
        assert not wide
        return
    fr, (mx, my) = s.frustum, _spec_of(call).margins
    t = max(abs(float(fr.x_offset)) + float(fr.rx_max) / mx,
            abs(float(fr.y_offset)) + float(fr.ry_max) / my)  # fmt: skip
    edge = 64 * _eps(dtype) * call.scene.kappa * t
    if abs(t - np.sqrt(3)) > edge:
        assert bool(wide) == (t > np.sqrt(3)), (t, wide)
    assert t <= np.tan(np.radians(85)) * (1 + edge)  # never wider than the 170 fitted


def _raises_named(bad: InvalidFit, dtype: Any) -> None:
    args, kwargs = _fit_args(bad.call, dtype, light=bad.light, **bad.kwargs)
    with pytest.raises(bad.error) as info:
        sm.fit_shadow(*args, **kwargs)
    assert bad.message in str(info.value), (bad.message, str(info.value))


@DTYPES
@given(data=st.data())
def test_fuzz_fit_shadow_invalid_options(dtype: Any, data: st.DataObject) -> None:
    bad = data.draw(invalid_fit_calls(dtype))
    CASES["fit_shadow options invalid"] += 1
    _raises_named(bad, dtype)


# --- fit_shadow on JAX: eager, jit and vmap agree with NumPy; NaN only where NumPy raises ----


def _examples(default: int, fuzz: int) -> int:
    """Examples for a test whose cases compile JAX code: ``default`` in the regular run,
    up to ``fuzz`` (in proportion) in the long one."""
    scaled = (settings.default.max_examples or 25) * default // 25
    return min(fuzz, max(default, scaled))


_TYPED = {"point": sm.PointLight, "spot": sm.SpotLight, "directional": sm.DirectionalLight}


def _light_arrays(call: FitCall) -> tuple[np.ndarray, ...]:
    s = call.scene
    if s.kind == "spot":
        return s.position, s.direction, np.asarray(s.angle)
    return (s.direction,) if s.kind == "directional" else (s.position,)


def _option_arrays(call: FitCall) -> tuple[np.ndarray, ...]:
    named = {
        "blocker_to_world": call.placement,
        "receivers": call.receivers,
        "up": call.up,
        "near": call.near,
        "far": call.far,
    }
    return tuple(np.asarray(named[n]) for n in given_options(call))


@functools.cache
def _vmapped_fit(
    kind: str, names: tuple[str, ...], aim: str, spec: sm.ShadowMapSpec, receiver_kind: str
) -> Any:
    """``fit_shadow`` of typed lights under ``jax.jit(jax.vmap(...))``, compiled once per key."""
    import jax

    def one(light: tuple[Any, ...], local: Any, *options: Any) -> sm.ShadowSetup:
        kwargs = dict(zip(names, options, strict=True))
        if receiver_kind == "triangles":
            kwargs["receivers"] = sm.Triangles(kwargs["receivers"])
        return sm.fit_shadow(_TYPED[kind](*light), local, spec, aim=aim, **kwargs)  # type: ignore[arg-type]

    return jax.jit(jax.vmap(one))


def _knife_edge(call: FitCall, s: sm.ShadowSetup, dtype: Any) -> bool:
    """Where rounding may pick either of two valid fits: a helper-axis tie, or a stable
    map's centre half a texel from two grid positions."""
    tol = 64 * _eps(dtype) * call.scene.kappa
    z = np.sort(np.abs(_f64(s.frame.z_axis)))
    if call.up is None and (z[1] - z[0] <= tol or z[2] - z[1] <= tol):
        return True
    return bool(call.stable)


def _agrees(call: FitCall, got: sm.ShadowSetup, want: sm.ShadowSetup, dtype: Any) -> None:
    """JAX's fit equals NumPy's to eps times the scene's condition (the frame through the
    placement too), or, at a knife edge, is another fit with every property."""
    tol = 64 * _eps(dtype) * _call_kappa(call, dtype)
    for name in ("blocker_to_clip", "world_to_texture"):
        g, w = _f64(getattr(got, name)), _f64(getattr(want, name))
        assert np.all(np.isfinite(g)), name
        if np.abs(g - w).max() > tol * np.abs(w).max():
            assert _knife_edge(call, want, dtype), (name, np.abs(g - w).max() / np.abs(w).max())
            _check_scene_setup(call, got, dtype)
            return


def _spot_packed_in_coords(call: FitCall, dtype: Any) -> bool:
    """Whether JAX's near-rounding check would count a spot light's direction and
    tan(angle) as coordinates and refuse the fit (test_fuzz_spot_light_jax_at_small_scale)."""
    scene = call.scene
    if scene.kind != "spot":
        return False
    packed = max(float(np.abs(scene.direction).max()), np.tan(scene.angle), scene.angle)
    z = (scene.vertices - scene.position) @ (scene.direction / np.linalg.norm(scene.direction))
    return bool(64 * _eps(dtype) * packed >= z.min())


def _entry(tree: Any, i: int) -> Any:
    import jax

    return jax.tree_util.tree_map(lambda x: x[i], tree)


@settings(max_examples=_examples(2, 30))
@given(data=st.data())
def test_fuzz_fit_shadow_jax_eager_jit_vmap(data: st.DataObject) -> None:
    jnp = _jnp()
    dtype = data.draw(st.sampled_from([np.float64, np.float32]))
    call = data.draw(fit_calls(dtype, vertex_count=12, receiver_count=4, forms=("typed",),
                                receiver_kinds=("points", "triangles")))  # fmt: skip
    # Few map layouts and shapes: each compiles its own fit.
    call = call._replace(map_size=data.draw(st.sampled_from([64, (96, 40)])), map_options={})
    if call.receiver_kind == "triangles":
        call = call._replace(receivers=np.resize(call.receivers, (4, 3, 3)))
    bad = data.draw(invalid_fit_calls(dtype, mutations=VALUE_MUTATIONS, call=call))
    if given_options(bad.call) != given_options(call) or bad.light is not None:
        local = call.local.copy()
        local[0, 0] = np.nan  # the twin every call has, with the same options
        bad = InvalidFit(call._replace(local=local), {}, "blocker_vertices: " + NON_FINITE,
                         ValueError, True, None)  # fmt: skip
    assume(not _spot_packed_in_coords(call, dtype))  # a known bug: its own target below
    CASES[f"fit_shadow JAX eager/jit/vmap ({call.scene.kind})"] += 1
    want = _fit(call, dtype)
    # Eager (concrete) JAX: the same fit, and the same error.
    _agrees(call, _fit(call, dtype, xp=jnp), want, dtype)
    args, kwargs = _fit_args(bad.call, dtype, jnp)
    with pytest.raises(ValueError, match=re.escape(bad.message)):
        sm.fit_shadow(*args, **kwargs)
    # jit(vmap): the valid entry agrees, the invalid entry is NaN and nothing else.
    fn = _vmapped_fit(
        call.scene.kind, given_options(call), call.aim, _spec_of(call), call.receiver_kind
    )

    def stacked(a: tuple[np.ndarray, ...], b: tuple[np.ndarray, ...]) -> tuple[Any, ...]:
        return tuple(jnp.asarray(np.stack([x, y]), dtype) for x, y in zip(a, b, strict=True))

    out = fn(
        stacked(_light_arrays(call), _light_arrays(bad.call)),
        *stacked((call.local,), (bad.call.local,)),
        *stacked(_option_arrays(call), _option_arrays(bad.call)),
    )
    _agrees(call, _entry(out, 0), want, dtype)
    for name in ("blocker_to_clip", "world_to_texture"):
        assert np.all(np.isnan(_f64(getattr(out, name)[1]))), f"{name}: finite where NumPy raises"


# --- agreement of the small functions across NumPy and JAX --------------------------------


def _condition(fn: Any, args: tuple[np.ndarray, ...], seed: int = 0) -> float:
    """The problem's componentwise relative condition, measured: the largest relative change
    of ``fn``'s outputs (normwise) over relative changes of ``1e-7`` of its float inputs,
    in float64. Rounding to eps changes the exact result by about ``eps * condition``."""
    rng = np.random.default_rng(seed)
    rel = 1e-7

    def flat(out: Any) -> np.ndarray:
        leaves = out if isinstance(out, tuple) else (out,)
        return np.concatenate([_f64(x).ravel() for x in leaves])

    base = flat(fn(*args))
    scale = np.abs(base[np.isfinite(base)]).max(initial=0.0)
    if scale == 0:
        return 1.0
    worst = 1.0
    for _ in range(4):
        moved = tuple(
            a * (1 + rel * rng.uniform(-1, 1, np.shape(a)))
            if np.asarray(a).dtype.kind == "f"
            else a
            for a in args
        )
        change = np.abs(flat(fn(*moved)) - base)
        worst = max(worst, float(np.nanmax(change, initial=0.0)) / scale / rel)
    return worst


def _jax_modes(
    fn: Any, args: tuple[np.ndarray, ...], bad_args: tuple[np.ndarray, ...], dtype: Any
) -> tuple[Any, Any, Any]:
    """``fn`` on JAX arrays eagerly, under ``jax.jit``, and under ``jax.jit(jax.vmap)`` of
    the batch ``[args, bad_args]``: the three results, the last two as NumPy."""
    import jax

    jnp = _jnp()
    to = functools.partial(_convert, dtype=dtype, xp=jnp)
    eager = fn(*(to(a) for a in args))
    jitted = jax.jit(fn)(*(to(a) for a in args))
    pairs = (np.stack([a, b]) for a, b in zip(args, bad_args, strict=True))
    batched = jax.jit(jax.vmap(fn))(*(to(p) for p in pairs))
    return eager, jitted, batched


def _leaves(out: Any) -> list[np.ndarray]:
    return [_f64(x) for x in (out if isinstance(out, tuple) else (out,))]


def _assert_close(got: Any, want: Any, tol: float, what: str) -> None:
    for g, w in zip(_leaves(got), _leaves(want), strict=True):
        scale = np.abs(w[np.isfinite(w)]).max(initial=0.0)
        assert g.shape == w.shape, what
        np.testing.assert_array_equal(np.isfinite(g), np.isfinite(w), what)
        ok = np.isfinite(w)
        np.testing.assert_allclose(g[ok], w[ok], rtol=0, atol=tol * scale, err_msg=what)


def _check_jax_agrees(
    name: str,
    fn: Any,
    args: tuple[np.ndarray, ...],
    bad_args: tuple[np.ndarray, ...],
    dtype: Any,
    *,
    nan_outputs: Any = None,
) -> None:
    """NumPy against JAX eager, jit and vmap, to ``64 eps`` times the measured condition;
    the invalid batch entry is NaN (``nan_outputs`` picks the outputs that must be)."""
    CASES[f"{name} JAX eager/jit/vmap"] += 1
    converted = tuple(_rounded(a, dtype) if np.asarray(a).dtype.kind == "f" else a for a in args)
    want = fn(*(_convert(a, dtype) for a in args))
    tol = 64 * _eps(dtype) * _condition(fn, converted)
    eager, jitted, batched = _jax_modes(fn, args, bad_args, dtype)
    for mode, got in (("eager", eager), ("jit", jitted), ("vmap", _entry(batched, 0))):
        _assert_close(got, want, tol, f"{name} {mode}")
    bad = _entry(batched, 1)
    leaves = nan_outputs(bad) if nan_outputs is not None else _leaves(bad)
    for leaf in leaves:
        assert np.all(np.isnan(_f64(leaf))), f"{name}: finite where NumPy raises"


# --- cube maps ------------------------------------------------------------------------------

_FACE_AXIS_SIGN = [(0, 1.0), (0, -1.0), (1, 1.0), (1, -1.0), (2, 1.0), (2, -1.0)]


@DTYPES
@given(data=st.data())
def test_fuzz_cube_face(dtype: Any, data: st.DataObject) -> None:
    CASES["cube_face / cube_face_direction / cube_face_views"] += 1
    d = data.draw(cube_directions(dtype))
    c = sm.cube_face(d.astype(dtype))
    face = np.asarray(c.face)
    assert face.dtype == np.int32
    s, t = _f64(c.s), _f64(c.t)
    a = np.abs(d)
    for i in range(len(d)):
        axis, sign = _FACE_AXIS_SIGN[face[i]]
        # Exactly one face: of the axes tied at the largest magnitude, the last (Vulkan's
        # rule: z over y and x, y over x), by its sign.
        tied = np.flatnonzero(a[i] == a[i].max())
        assert axis == tied[-1] and np.sign(d[i, axis]) == sign
        # The faces whose closed pyramid holds d: one per tied axis, the chosen among them.
        closed = [f for f, (ax, sg) in enumerate(_FACE_AXIS_SIGN) if ax in tied
                  and np.sign(d[i, ax]) == sg]  # fmt: skip
        assert face[i] in closed and len(closed) == len(tied)
    assert np.all((s >= 0) & (s <= 1) & (t >= 0) & (t <= 1))
    # The inverse: the same direction on the unit cube's surface.
    back = _f64(sm.cube_face_direction(face, c.s, c.t))
    ma = a.max(axis=1, keepdims=True)
    np.testing.assert_allclose(back, d / ma, rtol=0, atol=4 * _eps(dtype))
    # The face's view sees the direction at (s_c, t_c, -|m_a|): straight ahead, at (s, t).
    light = data.draw(cube_setups()).light.astype(dtype)
    V = _f64(sm.cube_face_views(light))
    assert V.shape == (6, 4, 4)
    R = V[:, :3, :3]
    np.testing.assert_array_equal(R @ R.transpose(0, 2, 1), np.broadcast_to(np.eye(3), (6, 3, 3)))
    np.testing.assert_allclose(np.linalg.det(R), 1.0, rtol=0, atol=1e-15)
    origin = V @ np.append(_f64(light), 1.0)  # entries 0 and +-1: exact
    np.testing.assert_array_equal(origin[:, :3], 0)
    view = np.einsum("fij,nj->nfi", R, d)[np.arange(len(d)), face]  # rotation only: exact
    np.testing.assert_array_equal(view[:, 2], -ma[:, 0])
    np.testing.assert_allclose(s, (view[:, 0] / ma[:, 0] + 1) / 2, rtol=0, atol=2 * _eps(dtype))
    np.testing.assert_allclose(t, (view[:, 1] / ma[:, 0] + 1) / 2, rtol=0, atol=2 * _eps(dtype))


def _window_depth(clip: np.ndarray, api: str) -> np.ndarray:
    z = clip[..., 2] / clip[..., 3]
    return (z + 1) / 2 if api == "opengl" else z


@DTYPES
@given(data=st.data())
def test_fuzz_cube_face_projection_and_depth(dtype: Any, data: st.DataObject) -> None:
    CASES["cube_face_projection / cube_face_depth"] += 1
    cube = data.draw(cube_setups())
    near, far = (np.asarray(v, dtype) for v in (cube.near, cube.far))
    n, f = float(near), float(far)
    assume(f > n)
    N, b = cube.map_size, cube.border
    P = _f64(sm.cube_face_projection(near, far, map_size=N, border_texels=b, api=cube.api,
                                     reversed_z=cube.reversed_z))  # fmt: skip
    light = cube.light.astype(dtype)
    # Receiver points at a distance D along their face's axis between near and far (and the
    # two planes themselves).
    d = data.draw(cube_directions(np.float64))
    fractions = data.draw(st.lists(st.floats(0, 1), min_size=len(d) - 2, max_size=len(d) - 2))
    D = n * (f / n) ** np.array([0.0, 1.0, *fractions])
    points = _rounded(_f64(light) + d / np.abs(d).max(axis=1, keepdims=True) * D[:, None], dtype)
    r = _f64(points.astype(dtype) - light)  # as the package computes it, in the dtype
    assume(np.all(np.any(r != 0, axis=1)))
    c = sm.cube_face(r)
    res = sm.cube_face_depth(light, points.astype(dtype), near, far, reversed_z=cube.reversed_z)
    np.testing.assert_array_equal(res.face, c.face)
    np.testing.assert_allclose(_f64(res.distance), np.linalg.norm(r, axis=1), rtol=4 * _eps(dtype))
    V = _f64(sm.cube_face_views(light))[np.asarray(c.face)]
    clip = np.einsum("ij,njk,nk->ni", P, V, _homogeneous(points))
    Dm = np.abs(r).max(axis=1)
    # V p is R p - R L in float64: rounding of the light's size, relative to the distance.
    noise = 4 * _eps(np.float64) * (1 + np.abs(light).max() / Dm)
    np.testing.assert_allclose(clip[:, 3], Dm, rtol=4 * _eps(dtype) + noise.max())
    # The texel drawn for the point is the texel its direction samples, border ring included.
    k = (N - 2 * b) / N
    x_win = N * (clip[:, 0] / clip[:, 3] + 1) / 2
    y = clip[:, 1] / clip[:, 3]
    row = N * ((1 - y) if cube.api in ("direct3d", "metal", "webgpu") else (y + 1)) / 2
    tol = 16 * (_eps(dtype) + noise) * N
    assert np.all(np.abs(x_win - (b + _f64(c.s) * (N - 2 * b))) <= tol)
    assert np.all(np.abs(row - (b + _f64(c.t) * (N - 2 * b))) <= tol)
    assert np.all(
        np.abs(clip[:, :2] / clip[:, 3:]) <= k * (1 + 4 * _eps(dtype) + 4 * noise[:, None])
    )
    # The stored depth: the projection's, and the formula's: near_depth at near, far_depth at
    # far, monotone between (OpenGL's -1..1 NDC depth is (z + 1) / 2 in the depth buffer).
    depth = _f64(res.depth)
    kappa = (f + n) / (f - n)
    tol_d = 16 * kappa * (_eps(dtype) + noise)
    assert np.all(np.abs(_window_depth(clip, cube.api) - depth) <= tol_d)
    want = n * (f - Dm) / ((f - n) * Dm) if cube.reversed_z else f * (Dm - n) / ((f - n) * Dm)
    np.testing.assert_allclose(depth, want, rtol=0, atol=16 * kappa * _eps(dtype))
    near_depth, far_depth = _near_far_depths(cube.reversed_z)
    between = (Dm >= n) & (Dm <= f)
    assert np.all((depth[between] >= -tol_d[between]) & (depth[between] <= 1 + tol_d[between]))
    order = np.argsort(Dm)
    step = np.diff(depth[order]) * (1 if far_depth == 1 else -1)
    assert np.all(step >= -tol_d[order][1:]), "depth not monotone in the distance"
    del near_depth


def _cube_invalid(name: str, cube: CubeSetup) -> tuple[Any, str]:
    """One invalid cube-map call: a thunk and the fragment of its message."""
    L, n, f, N = cube.light, cube.near, cube.far, cube.map_size

    def projection(**kw: Any) -> Any:
        options = {"map_size": N, "border_texels": cube.border, "api": cube.api} | kw
        near, far = options.pop("near", n), options.pop("far", f)
        return lambda: sm.cube_face_projection(near, far, **options)

    cases = {
        "zero_direction": (
            lambda: sm.cube_face(np.zeros((2, 3))),
            "directions: a direction is zero",
        ),
        "nan_direction": (lambda: sm.cube_face([np.nan, 1.0, 0.0]), "directions: " + NON_FINITE),
        "direction_shape": (lambda: sm.cube_face([1.0, 0.0]), "directions: expected shape"),
        "face_range": (
            lambda: sm.cube_face_direction([6], [0.5], [0.5]),
            "face: must be an integer",
        ),
        "face_negative": (lambda: sm.cube_face_direction(-1, 0.5, 0.5), "face: must be an integer"),
        "face_fraction": (
            lambda: sm.cube_face_direction(2.5, 0.5, 0.5),
            "face: must be an integer",
        ),
        "nan_s": (lambda: sm.cube_face_direction(1, np.nan, 0.5), "s: " + NON_FINITE),
        "inf_t": (lambda: sm.cube_face_direction(1, 0.5, np.inf), "t: " + NON_FINITE),
        "near_zero": (projection(near=0.0), "near: must be > 0"),
        "near_negative": (projection(near=-n), "near: must be > 0"),
        "far_before_near": (projection(far=n * 0.5), "far: must be greater than near"),
        "nan_near": (projection(near=np.nan), "near: " + NON_FINITE),
        "map_size_zero": (projection(map_size=0), "map_size: must be >= 1"),
        "map_size_fraction": (projection(map_size=2.5), "map_size: expected an integer"),
        "map_size_bool": (projection(map_size=True), "map_size: expected an integer"),
        "border_wide": (projection(border_texels=(N + 1) // 2), "border_texels: a border of"),
        "border_negative": (projection(border_texels=-1), "border_texels: must be >= 0"),
        "bad_api": (projection(api="opengles"), "api: unknown graphics API"),
        "bad_reversed_z": (projection(reversed_z=1), "reversed_z: expected True or False"),
        "nan_light": (lambda: sm.cube_face_views([np.nan, 0, 0]), "light_position: " + NON_FINITE),
        "light_shape": (lambda: sm.cube_face_views(np.zeros(4)), "light_position: expected shape"),
        "point_at_light": (lambda: sm.cube_face_depth(L, L, n, f), "points: a point coincides"),
        "depth_far": (lambda: sm.cube_face_depth(L, L + 1, n, n), "far: must be greater than near"),
        "depth_points_shape": (
            lambda: sm.cube_face_depth(L, L[:2], n, f),
            "points: expected shape",
        ),
    }
    return cases[name]


CUBE_INVALID = (
    "zero_direction", "nan_direction", "direction_shape", "face_range", "face_negative",
    "face_fraction", "nan_s", "inf_t", "near_zero", "near_negative", "far_before_near",
    "nan_near", "map_size_zero", "map_size_fraction", "map_size_bool", "border_wide",
    "border_negative", "bad_api", "bad_reversed_z", "nan_light", "light_shape",
    "point_at_light", "depth_far", "depth_points_shape",
)  # fmt: skip


@given(cube=cube_setups(), name=st.sampled_from(CUBE_INVALID))
def test_fuzz_cube_invalid(cube: CubeSetup, name: str) -> None:
    CASES["cube invalid"] += 1
    thunk, message = _cube_invalid(name, cube)
    with pytest.raises(ValueError, match=re.escape(message)):
        thunk()


@settings(max_examples=_examples(2, 100))
@given(data=st.data())
def test_fuzz_cube_jax_eager_jit_vmap(data: st.DataObject) -> None:
    import jax

    jnp = _jnp()
    dtype = data.draw(st.sampled_from([np.float64, np.float32]))
    CASES["cube JAX eager/jit/vmap"] += 1
    d = data.draw(cube_directions(dtype))
    bad_d = d.copy()
    bad_d[data.draw(st.integers(0, len(d) - 1))] = 0.0
    want = sm.cube_face(d.astype(dtype))
    tol = 4 * _eps(dtype)
    for mode, fn in (("eager", sm.cube_face), ("jit", jax.jit(sm.cube_face))):
        got = fn(jnp.asarray(d, dtype))
        np.testing.assert_array_equal(np.asarray(got.face), want.face, mode)  # the same tie rule
        _assert_close(got[1:], want[1:], tol, f"cube_face {mode}")
    out = jax.jit(jax.vmap(sm.cube_face))(jnp.asarray(np.stack([d, bad_d]), dtype))
    np.testing.assert_array_equal(np.asarray(out.face[0]), want.face)
    bad = np.all(bad_d == 0, axis=1)
    np.testing.assert_array_equal(np.asarray(out.face[1]), np.where(bad, -1, want.face))
    assert np.all(np.isnan(_f64(out.s[1])[bad])) and np.all(np.isfinite(_f64(out.s[1])[~bad]))
    # The other cube functions: exact arithmetic (views) or a few roundings.
    cube = data.draw(cube_setups())
    light = cube.light
    lights = np.stack([light, light + 1])
    _check_jax_agrees("cube_face_views", sm.cube_face_views, (lights,),
                      (np.where([[True], [False]], np.nan, lights),), dtype,
                      nan_outputs=lambda out: [out[0]])  # fmt: skip
    near = np.array([cube.near, cube.near * 2])
    far = np.array([cube.far, cube.far * 2])
    project = functools.partial(sm.cube_face_projection, map_size=cube.map_size,
                                border_texels=cube.border, api=cube.api,
                                reversed_z=cube.reversed_z)  # fmt: skip
    _check_jax_agrees("cube_face_projection", project, (near, far), (near, near * 0.5), dtype)
    points = light + d[:2] / np.abs(d[:2]).max(axis=1, keepdims=True) * cube.near * 1.5
    depth = functools.partial(sm.cube_face_depth, reversed_z=cube.reversed_z)
    assume(np.all(np.any(points.astype(dtype) != light.astype(dtype), axis=1)))
    _check_jax_agrees("cube_face_depth", depth, (lights[:1], points, near[:1], far[:1]),
                      (lights[:1], points, far[:1], near[:1]), dtype,
                      nan_outputs=lambda out: [out.depth, out.distance])  # fmt: skip
    directions = functools.partial(sm.cube_face_direction)
    s = data.draw(st.lists(st.floats(-0.5, 1.5), min_size=2, max_size=2))
    _check_jax_agrees("cube_face_direction", directions,
                      (np.array([0, 5]), np.array(s), np.array(s[::-1])),
                      (np.array([0, 5]), np.array([np.nan, 0.5]), np.array(s[::-1])), dtype,
                      nan_outputs=lambda out: [out[0]])  # fmt: skip


# --- biases and texel sizes -----------------------------------------------------------------


def _tex_exact(M: np.ndarray, points: np.ndarray) -> np.ndarray:
    """:func:`_tex` in extended precision (``np.longdouble``): a reference for rounding."""
    Ml = np.asarray(M, dtype=np.longdouble)
    h = np.c_[np.asarray(points, np.longdouble), np.ones(len(points), np.longdouble)] @ Ml.T
    return np.asarray(np.c_[h[:, :3] / h[:, 3:], h[:, 3]])


def _plane_depths(M: np.ndarray, p: np.ndarray, n: np.ndarray, st_: np.ndarray) -> np.ndarray:
    """The depth ``r`` where the rays through texture points ``(s, t)`` meet the plane through
    ``p`` of normal ``n``, in extended precision: the ray's two planes ``s q = row_0 . x``,
    ``t q = row_1 . x`` and the receiver's, solved by Cramer's rule."""
    Ml, pl, nl = (np.asarray(v, np.longdouble) for v in (M, p, n))
    out = []
    for s_, t_ in np.asarray(st_, np.longdouble):
        a0 = Ml[0, :3] - s_ * Ml[3, :3]
        a1 = Ml[1, :3] - t_ * Ml[3, :3]
        b = np.array([s_ * Ml[3, 3] - Ml[0, 3], t_ * Ml[3, 3] - Ml[1, 3], nl @ pl])
        c12, c20, c01 = np.cross(a1, nl), np.cross(nl, a0), np.cross(a0, a1)
        x = (b[0] * c12 + b[1] * c20 + b[2] * c01) / (a0 @ c12)
        out.append((Ml[2, :3] @ x + Ml[2, 3]) / (Ml[3, :3] @ x + Ml[3, 3]))
    return np.asarray(out, dtype=np.float64)


class BiasCase(NamedTuple):
    call: FitCall
    M: np.ndarray  # (4, 4) world_to_texture, in the dtype's values
    points: np.ndarray  # (K, 3) in front of the light
    normals: np.ndarray  # (K, 3) facing the light, not edge-on
    size: tuple[int, int]
    radius: int
    filter: str


def _draw_bias_case(data: st.DataObject, dtype: Any, count: int | None = None) -> BiasCase:
    call = data.draw(fit_calls(dtype, receiver_count=8))
    s = _fit(call, dtype)
    M = _f64(s.world_to_texture)
    scene = call.scene
    pts = _rounded(data.draw(receiver_points(scene, 8)), dtype)
    tex = _tex(M, pts)
    toward = (
        np.broadcast_to(scene.direction, pts.shape)
        if scene.kind == "directional"
        else scene.position - pts
    )
    ray = toward / np.maximum(np.linalg.norm(toward, axis=-1, keepdims=True), 1e-300)
    normals = np.array([data.draw(unit_vectors()) for _ in range(len(pts))])
    normals *= np.sign(np.sum(normals * ray, axis=-1, keepdims=True) + 1e-300)
    cos = np.sum(normals * ray, axis=-1)
    # In front of the light by more than the measured condition's perturbations move q.
    q_noise = 1e-5 * (np.abs(pts) @ np.abs(M[3, :3]) + abs(M[3, 3]))
    keep = (tex[:, 3] > q_noise) & (cos > 0.05) & np.all(np.abs(tex[:, :2] - 0.5) < 2, axis=-1)
    assume(keep.sum() >= (count or 1))
    pts, normals = pts[keep][:count], _rounded(normals[keep][:count], dtype)
    W, H = call.map_size if isinstance(call.map_size, tuple) else (call.map_size,) * 2
    filt = data.draw(st.sampled_from(["box", "bilinear"]))
    return BiasCase(call, _rounded(M, dtype), pts, normals, (W, H), data.draw(st.integers(0, 3)),
                    filt)  # fmt: skip


def _reach(radius: int, filt: str) -> float:
    """How far from its point, in texels per axis, a lookup compares (the docs' ``c``)."""
    return radius + (1.0 if filt == "bilinear" else 0.5)


@DTYPES
@settings(max_examples=_examples(25, 500))  # each case measures its conditions: slow
@given(data=st.data())
def test_fuzz_bias_and_texel_size(dtype: Any, data: st.DataObject) -> None:
    case = _draw_bias_case(data, dtype)
    kind = case.call.scene.kind
    CASES[f"texel sizes / slope_scaled_bias / normal_offset ({kind})"] += 1
    M, pts, normals, (W, H) = case.M, case.points, case.normals, case.size
    Md, pd, nd = (a.astype(dtype) for a in (M, pts, normals))
    eps = _eps(dtype)
    c = _reach(case.radius, case.filter)
    # The texel across the ray, against finite differences of (s, t) in float64.
    h = _f64(sm.texel_world_size(Md, pd, map_size=(W, H)))
    cond_h = _condition(lambda m, p: sm.texel_world_size(m, p, map_size=(W, H)), (M, pts))
    for i, p in enumerate(pts):
        step = 1e-5 * h[i]
        pl = p.astype(np.longdouble)  # steps far below p's own ulp would be lost in float64
        J = np.stack([
            (_tex_exact(M, (pl + step * e)[None]) - _tex_exact(M, (pl - step * e)[None]))[0, :2]
            / (2 * step)
            for e in np.eye(3)
        ], axis=-1)  # fmt: skip
        D = np.cross(J[0], J[1])
        want = 1 / np.sqrt(W * H * np.linalg.norm(D))
        cond_i = _condition(lambda m, q: sm.texel_world_size(m, q, map_size=(W, H)), (M, p[None]))
        assert h[i] == pytest.approx(want, rel=1e-6 + 64 * eps * cond_i), (i, h[i], want)
    # On the surface: never smaller than across the ray, and receiver_texel_size's value.
    hn = _f64(sm.texel_world_size(Md, pd, map_size=(W, H), normals=nd))
    assert np.all(hn >= h * (1 - 64 * eps * cond_h))
    np.testing.assert_allclose(_f64(sm.receiver_texel_size(Md, pd, nd, (W, H))), hn,
                               rtol=64 * eps * cond_h)  # fmt: skip
    # The slope-scaled bias covers every texel centre of the lookup on the receiver's plane:
    # the plane's depth under the corners (+-c, +-c) texels away differs from the point's
    # by c (|dr/dx| + |dr/dy|), between half and all of 2 c max(|dr/dx|, |dr/dy|).
    options = {"map_size": (W, H), "pcf_radius": case.radius, "pcf_filter": case.filter}
    slope = _f64(sm.slope_scaled_bias(Md, pd, nd, constant=0.0, **options))
    cond_b = _condition(lambda m, p, n: sm.slope_scaled_bias(m, p, n, constant=0.0, **options),
                        (M, pts, normals))  # fmt: skip
    tol = 64 * eps * cond_b
    corners = np.array([[a, b] for a in (-c, c) for b in (-c, c)]) / [W, H]
    # Normwise over the points (the condition is normwise), plus the depth's own rounding.
    # (The reference is exact but for its results' rounding to float64.)
    ph = np.abs(_homogeneous(pts))
    r_abs = np.abs(_tex(M, pts)[:, 2])
    q_abs = np.abs(_tex(M, pts)[:, 3])
    depth_noise = (
        4
        * _eps(np.float64)
        * float(
            ((ph @ np.abs(M[2])) + r_abs * (ph @ np.abs(M[3]))).max() / q_abs.min() + r_abs.max()
        )
    )
    slack = tol * slope.max() + depth_noise
    for i, (p, n) in enumerate(zip(pts, normals, strict=True)):
        st0 = _tex_exact(M, p[None])[0, :2]
        r = _plane_depths(M, p, n, np.vstack([st0, st0 + corners]))
        rise = np.abs(r[1:] - r[0]).max()
        assert slope[i] / 2 - slack <= rise <= slope[i] + slack, (i, rise, slope[i])
    bits = data.draw(st.sampled_from([16, 24, None]))
    constant = data.draw(st.floats(0, 8))
    full = _f64(sm.slope_scaled_bias(Md, pd, nd, constant=constant, depth_bits=bits, **options))
    r_min = 2.0**-24 if bits is None else 1 / (2.0**bits - 1)
    np.testing.assert_allclose(full, constant * r_min + slope, rtol=4 * eps, atol=4 * eps * r_min)
    assert np.all(full >= 0) and np.all(np.isfinite(full))
    # The normal offset: along the unit normal, linear in scale, and the lifted lookup point
    # is lit by every texel centre it compares on its own plane (exactly the minimum for a
    # directional light; to first order in the texel's angular size for point and spot).
    o = _f64(sm.normal_offset(Md, pd, nd, **options))
    o2 = _f64(sm.normal_offset(Md, pd, nd, scale=2.0, **options))
    cond_o = _condition(lambda m, p, n: sm.normal_offset(m, p, n, **options), (M, pts, normals))
    tol = 64 * eps * cond_o
    length = np.linalg.norm(o, axis=-1)
    unit_n = normals / np.linalg.norm(normals, axis=-1, keepdims=True)
    reach = 64 * eps * c * h.max()  # an offset's scale: the texel's reach (c h), times eps
    np.testing.assert_allclose(o, length[:, None] * unit_n, atol=tol * length.max() + reach)
    np.testing.assert_allclose(o2, 2 * o, rtol=4 * eps, atol=4 * eps * length.max() + reach)
    reversed_z = case.call.reversed_z
    gaps, spreads = [], []
    for i, (p, n) in enumerate(zip(pts, normals, strict=True)):
        lifted = _tex_exact(M, (p.astype(np.longdouble) + o[i])[None])[0]
        r = _plane_depths(M, p, n, lifted[:2] + corners)
        gaps.append((r.min() - lifted[2]) if not reversed_z else (lifted[2] - r.max()))
        spreads.append(np.abs(r - lifted[2]).max())
    gap, spread = np.array(gaps), np.array(spreads)
    # An offset that cancels to about zero (a normal along the ray) is known to eps times
    # the texel's reach, c h, along the normal: that much in depth too.
    tex = _tex(M, pts)
    grad_r = np.linalg.norm(M[2, :3] - tex[:, 2:3] * M[3, :3], axis=-1) / tex[:, 3]
    slack = tol * spread.max() + depth_noise + reach * grad_r.max()
    if kind == "directional":
        assert np.all(np.abs(gap) <= slack), (gap, spread)
    else:
        toward = case.call.scene.position - pts
        dist = np.linalg.norm(toward, axis=-1)
        cos = np.abs(np.sum(normals * toward, axis=-1)) / dist / np.linalg.norm(normals, axis=-1)
        NORMAL_OFFSET_GAPS.extend(zip(gap / (spread + 1e-300), c * h / dist, cos, strict=True))


NORMAL_OFFSET_GAPS: list[float] = []


# --- PCF --------------------------------------------------------------------------------------


def _pcf_reference(case: PcfCase, dtype: Any) -> np.ndarray:
    """PCF as its docs define it, tap by tap: the box's (2k+1)^2 texels around the point's
    texel; or (2k+1)^2 taps a whole texel apart, each the bilinear interpolation of the
    comparisons at the four texel centres around it. Texels off the map, and points off
    it, are lit. (Texel positions in the working dtype, as the GPU's, weights in float64.)"""
    Z = _rounded(case.depth_map, dtype)
    H, W = Z.shape
    k = case.radius

    def lit(i: int, j: int, d: float) -> float:
        if not (0 <= i < H and 0 <= j < W):
            return 1.0
        margin = d - Z[i, j] if case.reversed_z else Z[i, j] - d
        if case.softness == 0:
            return float(margin >= 0)
        x = min(max(margin / case.softness + 0.5, 0.0), 1.0)
        return x * x * (3 - 2 * x)

    out = []
    one = np.dtype(dtype).type
    for (s, t), d in zip(_rounded(case.coords, dtype), _rounded(case.depths, dtype), strict=True):
        if not (0 <= s <= 1 and 0 <= t <= 1):
            out.append(1.0)
            continue
        total = 0.0
        if case.filter == "box":
            j0, i0 = int(np.floor(one(s) * one(W))), int(np.floor(one(t) * one(H)))
            total = sum(lit(i0 + a, j0 + b, d) for a in range(-k, k + 1) for b in range(-k, k + 1))
        else:
            u = float(one(s) * one(W) - one(0.5))
            v = float(one(t) * one(H) - one(0.5))
            j0, i0 = int(np.floor(u)), int(np.floor(v))
            fx, fy = u - j0, v - i0
            for a in range(-k, k + 1):
                for b in range(-k, k + 1):
                    i, j = i0 + a, j0 + b
                    total += (1 - fx) * (1 - fy) * lit(i, j, d) + fx * (1 - fy) * lit(i, j + 1, d)
                    total += (1 - fx) * fy * lit(i + 1, j, d) + fx * fy * lit(i + 1, j + 1, d)
        out.append(total / (2 * k + 1) ** 2)
    return np.array(out)


def _pcf(case: PcfCase, dtype: Any, xp: Any = np, **changes: Any) -> np.ndarray:
    c = case._replace(**changes)
    arrays = (_convert(np.asarray(a, np.float64), dtype, xp) for a in c[:3])
    out = sm.pcf(*arrays, pcf_radius=c.radius, pcf_filter=c.filter,  # type: ignore[arg-type]
                 reversed_z=c.reversed_z, softness=c.softness)  # fmt: skip
    return _f64(out)


@DTYPES
@given(case=pcf_cases())
def test_fuzz_pcf(dtype: Any, case: PcfCase) -> None:
    CASES[f"pcf ({case.filter})"] += 1
    lit = _pcf(case, dtype)
    eps = _eps(dtype)
    assert lit.shape == case.depths.shape
    assert np.all((lit >= 0) & (lit <= 1))
    np.testing.assert_allclose(lit, _pcf_reference(case, dtype), rtol=0, atol=16 * eps)
    k = case.radius
    coords = _rounded(case.coords, dtype)
    off = ~np.all((coords >= 0) & (coords <= 1), axis=-1)
    np.testing.assert_array_equal(lit[off], 1.0)  # clamp-to-border: lit
    if case.filter == "box" and case.softness == 0:  # a fraction of the kernel's texels
        count = lit * (2 * k + 1) ** 2
        np.testing.assert_allclose(count, np.rint(count), rtol=0, atol=64 * eps)
    # reversed_z mirrors depths: 1 - z and 1 - d (exact for these dyadic depths).
    mirrored = _pcf(case, dtype, depth_map=1 - case.depth_map, depths=1 - case.depths,
                    reversed_z=not case.reversed_z)  # fmt: skip
    np.testing.assert_allclose(mirrored, lit, rtol=0, atol=16 * eps)
    # Nearer receivers are never less lit; a constant map lights all or nothing.
    nearer = _pcf(case, dtype, depths=case.depths + (1 / 64 if case.reversed_z else -1 / 64))
    assert np.all(nearer >= lit - 16 * eps)
    # (where the whole kernel lies on the map: texels off it are lit).
    flat = _pcf(case, dtype, depth_map=np.full_like(case.depth_map, 0.5), softness=0.0)
    H, W = case.depth_map.shape
    shift, extra = (0.5, 1) if case.filter == "bilinear" else (0.0, 0)
    first = np.floor(_rounded(case.coords, dtype) * [W, H] - shift)
    whole = np.all((first - k >= 0) & (first + k + extra <= [W - 1, H - 1]), axis=-1) & ~off
    want = (case.depths >= 0.5) if case.reversed_z else (case.depths <= 0.5)
    np.testing.assert_array_equal(flat[whole], want[whole].astype(float))
    # A smooth comparison lies between the step comparisons half its width either side.
    if case.softness > 0:
        h = case.softness / 2
        lo = _pcf(case, dtype, depths=case.depths + (-h if case.reversed_z else h), softness=0.0)
        hi = _pcf(case, dtype, depths=case.depths + (h if case.reversed_z else -h), softness=0.0)
        assert np.all((lit >= lo - 16 * eps) & (lit <= hi + 16 * eps))


@given(case=pcf_cases(), data=st.data())
def test_fuzz_pcf_border_texels(case: PcfCase, data: st.DataObject) -> None:
    """With pcf_border_texels empty texels around the silhouette, the map's clamp-to-border
    lookup equals that of the same map continued by lit texels without end: no soft shadow
    is cut off at the map's edge; one texel fewer would not do for a box kernel."""
    CASES["pcf_border_texels"] += 1
    k, filt = case.radius, case.filter
    b = sm.pcf_border_texels(k, filt)  # type: ignore[arg-type]
    assert b == (k + 1 if filt == "bilinear" else max(1, k))
    Z = case.depth_map.copy()
    H, W = Z.shape
    Z[:b], Z[-b:], Z[:, :b], Z[:, -b:] = 1.0, 1.0, 1.0, 1.0
    P = k + 3
    padded = np.pad(Z, P, constant_values=1.0)
    n = len(case.depths)
    cols = np.array(data.draw(st.lists(st.integers(-b - 1, W + b), min_size=n, max_size=n)))
    rows = np.array(data.draw(st.lists(st.integers(-b - 1, H + b), min_size=n, max_size=n)))
    frac = np.array(data.draw(st.lists(st.floats(0.05, 0.95), min_size=2 * n, max_size=2 * n)))
    s, t = (cols + frac[:n]) / W, (rows + frac[n:]) / H
    # (Receivers nearer than the empty texels' depth 1 by half the comparison's width: lit.)
    depths = np.minimum(case.depths, 1 - case.softness / 2 - 1 / 64)
    options = {"pcf_radius": k, "pcf_filter": filt, "reversed_z": False, "softness": case.softness}
    ours = sm.pcf(Z, np.c_[s, t], depths, **options)
    endless = sm.pcf(padded, np.c_[(s * W + P) / (W + 2 * P), (t * H + P) / (H + 2 * P)], depths,
                     **options)  # fmt: skip
    np.testing.assert_allclose(ours, endless, rtol=0, atol=1e-12)
    if filt == "box" and k >= 1:
        # A caster in texel b - 1 (a border one texel narrower) reaches a point just off the
        # map: lit there (clamp-to-border), shadowed on the endless map.
        Z2 = np.ones((H, W))
        Z2[H // 2, b - 1] = 0.0
        point = np.array([[-0.5 / W, (H // 2 + 0.5) / H]])
        on_padded = (point * [W, H] + P) / [W + 2 * P, H + 2 * P]
        assert float(sm.pcf(Z2, point, [0.5], pcf_radius=k)[0]) == 1.0
        assert (
            float(sm.pcf(np.pad(Z2, P, constant_values=1.0), on_padded, [0.5], pcf_radius=k)[0]) < 1
        )


PCF_INVALID = {
    "radius_negative": ({"pcf_radius": -1}, "radius: expected an integer >= 0"),
    "radius_fraction": ({"pcf_radius": 1.5}, "radius: expected an integer >= 0"),
    "radius_bool": ({"pcf_radius": True}, "radius: expected an integer >= 0"),
    "pcf_filter": ({"pcf_filter": "gaussian"}, "filter: expected 'box' or 'bilinear'"),
    "reversed_z": ({"reversed_z": 1}, "reversed_z: expected True or False"),
    "softness_negative": ({"softness": -0.1}, "softness: expected a finite number >= 0"),
    "softness_nan": ({"softness": np.nan}, "softness: expected a finite number >= 0"),
    "integer_map": ({"depth_map": "int"}, "depth_map: expected a floating dtype"),
    "map_shape": ({"depth_map": "1d"}, "depth_map: expected shape"),
    "coords_shape": ({"coords": "3d"}, "coords: expected shape"),
    "batch": ({"depths": "batch"}, "batch dimensions do not broadcast"),
    "too_small": ({"pcf_radius": 40}, "radius: a box kernel of radius 40"),
    "nan_map": ({"depth_map": "nan"}, "depth_map: " + NON_FINITE),
    "nan_coords": ({"coords": "nan"}, "coords: " + NON_FINITE),
    "inf_depth": ({"depths": "inf"}, "depths: " + NON_FINITE),
}


@given(case=pcf_cases(), name=st.sampled_from(sorted(PCF_INVALID)))
def test_fuzz_pcf_invalid(case: PcfCase, name: str) -> None:
    CASES["pcf invalid"] += 1
    change, message = PCF_INVALID[name]
    Z, c, d = case.depth_map, case.coords, case.depths
    options: dict[str, Any] = {"pcf_radius": case.radius, "pcf_filter": "box", "softness": 0.0}
    value = next(iter(change.values()))
    if name == "integer_map":
        Z = (Z * 64).astype(np.int32)
    elif name == "map_shape":
        Z = Z[0]
    elif name == "coords_shape":
        c = np.c_[c, c[:, :1]]
    elif name == "batch":
        d = np.r_[d, d[:1]]
    elif name == "nan_map":
        Z = Z.copy()
        Z[0, 0] = np.nan
    elif name == "nan_coords":
        c = c.copy()
        c[-1, 1] = np.nan
    elif name == "inf_depth":
        d = d.copy()
        d[0] = np.inf
    else:
        options.update(change)
        if name == "too_small":
            message = f"radius: a box kernel of radius {value}"
    with pytest.raises(ValueError, match=re.escape(message)):
        sm.pcf(Z, c, d, **options)


@settings(max_examples=_examples(2, 100))
@given(data=st.data())
def test_fuzz_pcf_jax_eager_jit_vmap(data: st.DataObject) -> None:
    """JAX's PCF is NumPy's (lookups a fraction of a texel from texel edges, where the two
    may round a coordinate to either texel); NaN only at a non-finite lookup under jit."""
    import jax

    dtype = data.draw(st.sampled_from([np.float64, np.float32]))
    case = data.draw(pcf_cases(count=6, shape=(12, 10)))
    CASES["pcf JAX eager/jit/vmap"] += 1
    frac = np.array(data.draw(st.lists(st.floats(0.05, 0.95), min_size=12, max_size=12)))
    cells = np.floor(case.coords * [10, 12])
    coords = (cells + frac.reshape(6, 2)) / [10, 12]
    case = case._replace(coords=coords)
    bad = coords.copy()
    bad[data.draw(st.integers(0, 5))] = np.nan
    fn = functools.partial(sm.pcf, pcf_radius=case.radius, pcf_filter=case.filter,
                           reversed_z=case.reversed_z, softness=case.softness)  # fmt: skip
    want = _pcf(case, dtype)
    eager, jitted, batched = _jax_modes(fn, case[:3], (case.depth_map, bad, case.depths), dtype)
    for mode, got in (("eager", eager), ("jit", jitted), ("vmap", _entry(batched, 0))):
        np.testing.assert_allclose(_f64(got), want, rtol=0, atol=16 * _eps(dtype), err_msg=mode)
    bad_entry = _f64(_entry(batched, 1))
    rows = np.any(np.isnan(bad), axis=-1)
    assert np.all(np.isnan(bad_entry[rows])) and np.all(np.isfinite(bad_entry[~rows]))
    del jax


# --- area lights: samples and Heckbert and Herf's pyramid ------------------------------------


def _grid(count: int) -> tuple[int, int]:
    rows = max(d for d in range(1, int(np.sqrt(count)) + 1) if count % d == 0)
    return rows, count // rows


def _check_samples(light: AreaLight, samples: np.ndarray, count: int, dtype: Any) -> None:
    """Every sample on the light's parallelogram, one in each cell of the rows x cols grid."""
    corner, eu, ev = (_rounded(v, dtype) for v in light[:3])
    A = np.stack([eu, ev], axis=-1)
    uv, *_ = np.linalg.lstsq(A, (samples - corner).T, rcond=None)
    u, v = uv
    tol = 64 * _eps(dtype) * light.kappa
    residual = samples - corner - (A @ uv).T
    scale = np.abs(corner).max() + np.linalg.norm(eu) + np.linalg.norm(ev)
    assert np.abs(residual).max() <= tol * scale, "a sample off the light's plane"
    rows, cols = _grid(count)
    k = np.arange(count)
    i, j = k // cols, k % cols
    assert np.all((u >= j / cols - tol) & (u <= (j + 1) / cols + tol)), "a sample outside its cell"
    assert np.all((v >= i / rows - tol) & (v <= (i + 1) / rows + tol)), "a sample outside its cell"


@DTYPES
@given(light=area_lights(), count=st.integers(1, 40), seed=st.integers(0, 2**32 - 1))
def test_fuzz_area_light_samples(dtype: Any, light: AreaLight, count: int, seed: int) -> None:
    CASES["area_light_samples"] += 1
    args = tuple(v.astype(dtype) for v in light[:3])
    samples = sm.area_light_samples(*args, count, seed=seed)
    assert samples.shape == (count, 3) and samples.dtype == dtype
    _check_samples(light, _f64(samples), count, dtype)
    np.testing.assert_array_equal(sm.area_light_samples(*args, count, seed=seed), samples)


@DTYPES
@given(light=area_lights(), data=st.data())
def test_fuzz_pyramid_to_unit_cube(dtype: Any, light: AreaLight, data: st.DataObject) -> None:
    CASES["pyramid_to_unit_cube"] += 1
    apex, corner, eu, ev = (_rounded(v, dtype) for v in (light.apex, *light[:3]))
    M = _f64(sm.pyramid_to_unit_cube(*(v.astype(dtype) for v in (apex, corner, eu, ev))))
    uv = np.array([[0, 0], [1, 0], [0, 1], [1, 1], *data.draw(st.lists(st.tuples(
        st.floats(-0.5, 1.5), st.floats(-0.5, 1.5)), min_size=1, max_size=4))])  # fmt: skip
    base = corner + uv[:, :1] * eu + uv[:, 1:] * ev
    lam = np.array(data.draw(st.lists(st.floats(0.05, 1), min_size=len(uv), max_size=len(uv))))
    up_ray = apex + lam[:, None] * (base - apex)
    points = np.vstack([base, up_ray])

    def mapped(*args: np.ndarray) -> np.ndarray:
        h = _homogeneous(points) @ _f64(sm.pyramid_to_unit_cube(*args)).T
        return np.asarray(h[:, :3] / h[:, 3:])

    # Base points go to (u, v, 0), and every point of the ray from the apex through one to
    # the same (u, v), at z = 1 / lambda - 1, all to eps times the measured condition.
    tol = 64 * _eps(dtype) * _condition(mapped, (apex, corner, eu, ev))
    h = _homogeneous(points) @ M.T
    assert np.all(h[:, 3] > 0)
    want = np.c_[np.vstack([uv, uv]), np.r_[np.zeros(len(uv)), 1 / lam - 1]]
    got = h[:, :3] / h[:, 3:]
    np.testing.assert_allclose(got, want, rtol=0, atol=tol * np.abs(want).max())
    # The apex's plane (parallel to the base) goes to w = 0.
    apex_w = float(M[3] @ np.append(apex, 1.0))
    assert abs(apex_w) <= 64 * _eps(dtype) * float(np.abs(M[3]) @ np.abs(np.append(apex, 1.0)))


SOFT_INVALID = (
    "parallel_edges", "zero_edge", "apex_in_plane", "count_zero", "count_fraction",
    "count_bool", "nan_corner", "corner_shape", "nan_apex",
)  # fmt: skip


@given(light=area_lights(), name=st.sampled_from(SOFT_INVALID))
def test_fuzz_area_light_invalid(light: AreaLight, name: str) -> None:
    CASES["area light invalid"] += 1
    corner, eu, ev, apex = light.corner, light.edge_u, light.edge_v, light.apex
    count: Any = 4
    pyramid = False
    message = ""
    if name == "parallel_edges":
        ev, message = eu * -3.0, "edge_u, edge_v: the parallelogram is degenerate"
    elif name == "zero_edge":
        eu, message = np.zeros(3), "edge_u, edge_v: the parallelogram is degenerate"
    elif name == "apex_in_plane":
        apex, pyramid = corner + 0.3 * eu + 0.6 * ev, True
        message = "apex: lies in the base plane"
    elif name.startswith("count"):
        count = {"count_zero": 0, "count_fraction": 2.5, "count_bool": True}[name]
        message = "count: "
    elif name == "nan_corner":
        corner, message = np.array([np.nan, 0, 0]), "corner: " + NON_FINITE
    elif name == "corner_shape":
        corner, message = corner[:2], "corner: expected shape"
    else:
        apex, pyramid, message = np.array([0, np.inf, 0]), True, "apex: " + NON_FINITE
    if pyramid:
        with pytest.raises(ValueError, match=re.escape(message)):
            sm.pyramid_to_unit_cube(apex, corner, eu, ev)
    else:
        with pytest.raises(ValueError, match=re.escape(message)):
            sm.area_light_samples(corner, eu, ev, count, seed=0)


@settings(max_examples=_examples(2, 100))
@given(light=area_lights(), count=st.sampled_from([4, 6]), data=st.data())
def test_fuzz_area_light_jax_eager_jit_vmap(
    light: AreaLight, count: int, data: st.DataObject
) -> None:
    import jax

    dtype = data.draw(st.sampled_from([np.float64, np.float32]))
    CASES["area lights JAX eager/jit/vmap"] += 1
    jnp = _jnp()
    # The same seed gives the same jitter on either backend.
    args = tuple(v.astype(dtype) for v in light[:3])
    want = _f64(sm.area_light_samples(*args, count, seed=7))
    got = sm.area_light_samples(*(jnp.asarray(a) for a in args), count, seed=7)
    cond = _condition(lambda *a: sm.area_light_samples(*a, count, seed=7),
                      tuple(_rounded(a, dtype) for a in args))  # fmt: skip
    _assert_close(got, want, 64 * _eps(dtype) * cond, "area_light_samples JAX")
    # Keyed jitter under jit and vmap: on the light, one sample per cell; NaN for a bad light.
    key = jax.random.key(data.draw(st.integers(0, 2**31 - 1)))
    fn = jax.jit(sm.area_light_samples, static_argnums=3)
    _check_samples(light, _f64(fn(*(jnp.asarray(a) for a in args), count, key=key)), count, dtype)
    both = jax.jit(jax.vmap(lambda c, u, v: sm.area_light_samples(c, u, v, count, key=key)))
    edges_v = np.stack([light.edge_v, light.edge_u * 2.0]).astype(dtype)  # parallel: bad
    out = both(*(jnp.asarray(np.stack([a, a])) for a in args[:2]), jnp.asarray(edges_v))
    _check_samples(light, _f64(out[0]), count, dtype)
    assert np.all(np.isnan(_f64(out[1])))
    # The pyramid matrix: NumPy's, eagerly, under jit and under vmap (a flat pyramid is NaN).
    flat_apex = light.corner + 0.5 * light.edge_u
    _check_jax_agrees("pyramid_to_unit_cube", sm.pyramid_to_unit_cube,
                      (light.apex, *light[:3]), (flat_apex, *light[:3]), dtype)  # fmt: skip


# --- graphics API conventions and the shadow map's spec -------------------------------------

_FLIP_T = ("direct3d", "metal", "webgpu")  # y up in NDC, first row at the top


@given(
    api=st.one_of(st.sampled_from(GRAPHICS_APIS), st.text(max_size=10), st.sampled_from(
        ["OpenGL", "d3d12", "gl", "", None, 1])),
    reversed_z=st.one_of(st.booleans(), st.sampled_from([0, 1, "no", None, np.bool_(True)])),
    data=st.data(),
)  # fmt: skip
def test_fuzz_api_convention(api: Any, reversed_z: Any, data: st.DataObject) -> None:
    CASES["api_convention"] += 1
    assert tuple(sm.GRAPHICS_APIS) == GRAPHICS_APIS  # the docs' table, in its order
    if api not in GRAPHICS_APIS:
        with pytest.raises(ValueError, match="api: unknown graphics API") as info:
            sm.api_convention(api=api, reversed_z=False)
        assert all(repr(a) in str(info.value) for a in GRAPHICS_APIS)  # the valid ones listed
        return
    if not isinstance(reversed_z, bool | np.bool_):
        with pytest.raises(ValueError, match="reversed_z: expected True or False"):
            sm.api_convention(api=api, reversed_z=reversed_z)
        return
    conv = sm.api_convention(api=api, reversed_z=reversed_z)
    C, T, TC = conv.gl_clip_to_clip, conv.clip_to_texture, conv.gl_clip_to_texture
    np.testing.assert_array_equal(TC, T @ C)
    near_depth, far_depth = _near_far_depths(bool(reversed_z))
    assert (conv.near_depth, conv.far_depth) == (near_depth, far_depth)
    # OpenGL clip points (any w > 0): the API's NDC and texture coordinates by the table.
    n = 8
    ndc = np.array(data.draw(st.lists(st.floats(-1, 1), min_size=3 * n, max_size=3 * n)))
    ndc = ndc.reshape(n, 3)
    w = np.array(data.draw(st.lists(st.floats(1e-3, 1e3), min_size=n, max_size=n)))
    clip = np.c_[ndc * w[:, None], w]
    api_clip = clip @ C.T
    x, y, z = (api_clip[:, i] / api_clip[:, 3] for i in range(3))
    np.testing.assert_array_equal(api_clip[:, 3], w)
    np.testing.assert_allclose(x, ndc[:, 0], rtol=0, atol=1e-15)
    np.testing.assert_allclose(y, -ndc[:, 1] if api == "vulkan" else ndc[:, 1], atol=1e-15)
    gl_z = -ndc[:, 2] if reversed_z else ndc[:, 2]  # OpenGL's own range, near -1 (or +1)
    np.testing.assert_allclose(z, gl_z if api == "opengl" else (gl_z + 1) / 2, atol=1e-15)
    tex = api_clip @ T.T
    s, t, r = (tex[:, i] / tex[:, 3] for i in range(3))
    np.testing.assert_allclose(s, (x + 1) / 2, atol=1e-15)
    np.testing.assert_allclose(t, (1 - y) / 2 if api in _FLIP_T else (y + 1) / 2, atol=1e-15)
    np.testing.assert_allclose(r, (z + 1) / 2 if api == "opengl" else z, atol=1e-15)
    # The near and far planes store the near and far depths; the top of the light's image
    # (OpenGL clip y = +1) is the first row in memory everywhere but in OpenGL.
    ends = np.array([[0, 1, -1, 1], [0, 1, 1, 1]], dtype=float) @ TC.T
    np.testing.assert_allclose(ends[:, 2], [near_depth, far_depth], atol=1e-15)
    np.testing.assert_allclose(ends[:, 1], 1.0 if api == "opengl" else 0.0, atol=1e-15)


@st.composite
def spec_options(draw: st.DrawFn) -> dict[str, Any]:
    """ShadowMapSpec keywords, valid or not."""
    options: dict[str, Any] = {}
    names = draw(st.lists(st.sampled_from(["border_texels", "pcf_radius", "margin"]),
                          max_size=2, unique=True))  # fmt: skip
    values = {
        # (booleans: test_fuzz_border_texels_refuses_booleans)
        "border_texels": st.one_of(st.integers(-2, 6), st.sampled_from([1.5, "1"])),
        "pcf_radius": st.one_of(st.integers(-2, 5), st.sampled_from([1.0, True])),
        "margin": st.one_of(st.floats(-0.5, 1.5), st.tuples(st.floats(0, 1), st.floats(0, 1)),
                            st.sampled_from([np.nan, (0.5,)])),
    }  # fmt: skip
    for name in names:
        options[name] = draw(values[name])
    if draw(st.booleans()):
        options["pcf_filter"] = draw(st.sampled_from(["box", "bilinear", "tent"]))
    if draw(st.booleans()):
        options["api"] = draw(st.sampled_from([*GRAPHICS_APIS, "glide"]))
    if draw(st.booleans()):
        options["reversed_z"] = draw(st.sampled_from([True, False, 1]))
    if draw(st.booleans()):
        options["stable"] = draw(st.sampled_from([True, False, "yes"]))
    return options


def _spec_error(size: Any, o: dict[str, Any]) -> str | None:
    """The field a spec of these options must name in its error, or None when valid (sizes of
    3 texels or more: a smaller map is refused by its default border of 1 even with a margin)."""

    def is_int(v: Any) -> bool:
        return isinstance(v, int) and not isinstance(v, bool)

    sizes = size if isinstance(size, tuple) else (size, size)
    if len(sizes) != 2 or not all(is_int(v) and v > 0 for v in sizes):
        return "map_size"
    if o.get("api", "opengl") not in GRAPHICS_APIS:
        return "api"
    if not isinstance(o.get("reversed_z", False), bool):
        return "reversed_z"
    if not isinstance(o.get("stable", False), bool):
        return "stable"
    k = o.get("pcf_radius", 0)
    if not is_int(k) or k < 0:
        return "pcf_radius"
    if o.get("pcf_filter", "box") not in ("box", "bilinear"):
        return "pcf_filter"
    given = [n for n in ("border_texels", "pcf_radius", "margin") if n in o]
    if len(given) > 1:
        return " and ".join(given)
    if "border_texels" in o and not is_int(o["border_texels"]):
        return "border_texels"
    if o.get("border_texels", 0) < 0:
        return "border_texels"
    if "margin" in o:
        m = o["margin"]
        pair = m if isinstance(m, tuple) else (m, m)
        if len(pair) != 2 or not all(0 < v <= 1 for v in pair):
            return "margin"
    if min(sizes) <= 2 * _spec_border(o):
        return "map_size"
    if o.get("stable"):
        margins = _spec_margins(size, o)
        if any(m * n <= 1 for m, n in zip(margins, sizes, strict=True)):
            return "map_size"
    return None


def _spec_border(o: dict[str, Any]) -> int:
    if "border_texels" in o:
        return int(o["border_texels"])
    if "pcf_radius" in o:
        k = o["pcf_radius"]
        return k + 1 if o.get("pcf_filter", "box") == "bilinear" else max(1, k)
    return 1


@given(
    size=st.one_of(st.integers(-2, 600), st.tuples(st.integers(3, 600), st.integers(-1, 600)),
                   st.sampled_from([2.5, True, (64,), "64", None])),
    options=spec_options(),
)  # fmt: skip
def test_fuzz_shadow_map_spec(size: Any, options: dict[str, Any]) -> None:
    CASES["ShadowMapSpec"] += 1
    sizes = size if isinstance(size, tuple) else (size, size)
    ints = all(isinstance(v, int) and not isinstance(v, bool) for v in sizes)
    assume(not ints or not 0 < min(sizes) < 3)
    error = _spec_error(size, options)
    if error is not None:
        with pytest.raises(ValueError, match=f"^{re.escape(error)}"):
            sm.ShadowMapSpec(size, **options)
        return
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always", sm.ShadowFitWarning)
        spec = sm.ShadowMapSpec(size, **options)
    assert spec.size == sizes
    assert spec.border == _spec_border(options)
    margins = _spec_margins(size, options)
    assert spec.margins == pytest.approx(margins, rel=1e-15)
    if "margin" not in options:
        assert spec.margins == sm.border_margin(size, border_texels=spec.border)
    if "pcf_radius" in options:
        k, filt = options["pcf_radius"], options.get("pcf_filter", "box")
        assert spec.border == sm.pcf_border_texels(k, filt)
    # Hashable and equal to a spec of the same options: a cache key for the fits.
    twin = sm.ShadowMapSpec(size, **options)
    assert twin == spec and hash(twin) == hash(spec)
    # A border that leaves less than half of the map's texels per axis warns.
    narrow = [w for w in caught if str(w.message).startswith("map_size: a border of")]
    assert bool(narrow) == (min(margins) < 0.5)


# --- what a frustum measures ----------------------------------------------------------------


@DTYPES
@given(data=st.data())
def test_fuzz_cross_section_area(dtype: Any, data: st.DataObject) -> None:
    CASES["cross_section_area"] += 1
    call = data.draw(fit_calls(dtype, kinds=("point", "spot")))
    s = _fit(call, dtype)
    area = float(sm.cross_section_area(s.frustum))
    fr = s.frustum
    assert area == pytest.approx(4 * float(fr.rx_max) * float(fr.ry_max), rel=4 * _eps(dtype))
    # The usable map at unit distance: 2 m / P00 by 2 m / P11 of the projection.
    P = _f64(sm.blocker_projection(fr))
    mx, my = _spec_of(call).margins
    want = (2 * mx / P[0, 0]) * (2 * my / P[1, 1])
    assert area == pytest.approx(want, rel=64 * _eps(dtype))


@given(
    shape=st.tuples(st.integers(0, 2), st.integers(1, 12), st.integers(1, 12)),
    border=st.one_of(st.integers(-1, 5), st.sampled_from([1.5, "1"])),
    data=st.data(),
)
def test_fuzz_silhouette_coverage(shape: tuple[int, int, int], border: Any,
                                  data: st.DataObject) -> None:  # fmt: skip
    CASES["silhouette_coverage"] += 1
    batch, h, w = shape
    mask = np.array(
        data.draw(
            st.lists(
                st.sampled_from([0.0, 1.0]),
                min_size=batch * h * w + h * w,
                max_size=batch * h * w + h * w,
            )
        )
    )[: max(batch, 1) * h * w]
    mask = mask.reshape((batch, h, w) if batch else (h, w))  # fmt: skip
    if not isinstance(border, int) or border < 0 or min(h, w) <= 2 * border:
        with pytest.raises(ValueError, match="border_texels: "):
            sm.silhouette_coverage(mask, border_texels=border)
        return
    got = _f64(sm.silhouette_coverage(mask, border_texels=border))
    inner = mask[..., border : h - border, border : w - border]
    count = inner.shape[-1] * inner.shape[-2]
    np.testing.assert_allclose(got, inner.sum(axis=(-2, -1)) / count, rtol=1e-15)
    assert np.all((got >= 0) & (got <= 1))
    on_jax = sm.silhouette_coverage(_jnp().asarray(mask), border_texels=border)
    np.testing.assert_allclose(_f64(on_jax), got, rtol=1e-15)
    with pytest.raises(ValueError, match="mask: expected shape"):
        sm.silhouette_coverage(mask.ravel()[:1].reshape(()))


# --- regressions: bugs the fuzz targets above found, fixed; each fails without its fix ------


@given(
    size=st.integers(3, 600),
    call=st.sampled_from(["spec", "fit_shadow", "border_margin", "silhouette_coverage"]),
)
def test_fuzz_border_texels_refuses_booleans(size: int, call: str) -> None:
    CASES["border_texels=True refused"] += 1
    box = np.array([[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (4, 6)], float)
    thunks = {
        "spec": lambda: sm.ShadowMapSpec(size, border_texels=True),
        "fit_shadow": lambda: sm.fit_shadow(np.zeros(3), box, size, border_texels=True),
        "border_margin": lambda: sm.border_margin(size, border_texels=True),
        "silhouette_coverage": lambda: sm.silhouette_coverage(np.ones((3, 3)), border_texels=True),
    }
    with pytest.raises(ValueError, match="border_texels: "):
        thunks[call]()


@given(
    option=st.sampled_from([
        {"pcf_radius": -1}, {"pcf_radius": 1.5}, {"pcf_radius": True}, {"pcf_filter": "tent"},
    ]),
    spec=st.booleans(),
)  # fmt: skip
def test_fuzz_pcf_options_are_named_in_errors(option: dict[str, Any], spec: bool) -> None:
    CASES["pcf_radius / pcf_filter named"] += 1
    box = np.array([[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (4, 6)], float)
    name = next(iter(option))
    make = (lambda: sm.ShadowMapSpec(64, **option)) if spec else (
        lambda: sm.fit_shadow(np.zeros(3), box, 64, **option))  # fmt: skip
    with pytest.raises(ValueError, match=f"^{name}: "):
        make()


@DTYPES
@given(data=st.data())
def test_fuzz_fit_shadow_placement_far_from_the_origin(dtype: Any, data: st.DataObject) -> None:
    """A renderer's model matrix: a unit blocker, turned and moved far from the origin."""
    CASES["fit_shadow far placement"] += 1
    call = data.draw(fit_calls(dtype, kinds=("point", "directional")))
    scene = call.scene
    # The same world scene, its blocker given in local coordinates about its centre and
    # placed by a pure translation of 1e3 (float32) or 1e6 (float64) sizes.
    far = 1e3 if np.dtype(dtype) == np.float32 else 1e6
    centre = scene.vertices.mean(0)
    size = float(np.linalg.norm(scene.vertices - centre, axis=-1).max())
    shift = np.full(3, far * size)
    B = np.diag([size, size, size, 1.0])
    B[:3, 3] = centre + shift
    moved = scene._replace(vertices=scene.vertices + shift, position=scene.position + shift,
                           kappa=scene.kappa + 2 * far)  # fmt: skip
    call = call._replace(scene=moved, local=(scene.vertices - centre) / size, placement=B,
                         receivers=None, near=None, far=None)  # fmt: skip
    try:
        s = _fit(call, dtype)
    except ValueError as err:  # the bug, and only the bug, is the expected failure
        if "blocker_to_world: the placement is singular" not in str(err):
            pytest.fail(f"another error: {err}")
        raise
    _check_scene_setup(call, s, dtype)


# --- the optimized fit --------------------------------------------------------------------


def _inside_and_touching(
    frame: sm.LightFrame, fr: sm.Frustum, verts: np.ndarray, tol: float, symmetric: bool
) -> None:
    """Every vertex inside the frustum's sides, touching them (each side, or each axis)."""
    ux, uy = _light_ratios(frame, verts)
    for u, half, centre in ((ux, fr.rx_max, fr.x_offset), (uy, fr.ry_max, fr.y_offset)):
        a = (u - float(centre)) / float(half)
        assert np.all(np.abs(a) <= 1 + tol)
        if symmetric:
            assert np.abs(a).max() == pytest.approx(1, abs=tol)
        else:
            assert a.max() == pytest.approx(1, abs=tol) and a.min() == pytest.approx(-1, abs=tol)


@settings(max_examples=_examples(2, 60))
@given(data=st.data())
def test_fuzz_optimize_frustum(data: st.DataObject) -> None:
    """The optimized fit holds the blocker, touches its sides, and never covers more of the
    plane z = 1 than the article's MDV frustum (the best of its starts includes the MDV)."""
    CASES["optimize_frustum / fit_shadow(method='optimized')"] += 1
    p = data.draw(placements(np.float64, max_vertices=12))
    # Moderate scenes: the optimizer runs in float64 but its soft bounds are temperature-
    # limited; a light far from a tiny blocker makes every frame alike.
    assume(p.distance_ratio < 1e3)
    map_size, border = data.draw(sized_maps())
    symmetric = data.draw(st.booleans())
    # fit_shadow(method="optimized")'s configuration: one compilation serves both.
    fit = sm.optimize_frustum(p.light, p.vertices, map_size, symmetric=symmetric, steps=80,
                              starts=6, border_texels=border)  # fmt: skip
    tol = 64 * _eps(np.float64) * _kappa(p)
    X, Y, Z = (_f64(a) for a in fit.frame[1:])
    np.testing.assert_allclose(np.stack([X, Y, Z]) @ np.stack([X, Y, Z]).T, np.eye(3), atol=tol)
    np.testing.assert_allclose(np.cross(X, Y), -Z, atol=tol)
    assert fit.losses.shape == (80,) and np.all(np.isfinite(fit.losses))
    _inside_and_touching(fit.frame, fit.frustum, p.vertices, tol, symmetric)
    mdv = sm.adaptive_frustum(sm.light_frame(p.light, p.vertices), p.vertices, map_size,
                              border_texels=border)  # fmt: skip
    area = float(sm.cross_section_area(fit.frustum))
    assert area <= float(sm.cross_section_area(mdv)) * (1 + tol)
    assert float(fit.losses.min()) <= tol
    s = sm.fit_shadow(p.light, p.vertices, map_size, method="optimized", border_texels=border)
    _inside_and_touching(s.frame, s.frustum, p.vertices, tol, symmetric=False)
    assert float(sm.cross_section_area(s.frustum)) <= float(sm.cross_section_area(mdv)) * (1 + tol)
    with pytest.raises(ValueError, match="steps and starts must be >= 1"):
        sm.optimize_frustum(p.light, p.vertices, map_size, steps=0)
    bad = p.light.copy()
    bad[0] = np.nan
    with pytest.raises(ValueError, match=re.escape("light_position: " + NON_FINITE)):
        sm.optimize_frustum(bad, p.vertices, map_size, steps=80, starts=6)


# --- bias: invalid input, and NumPy against JAX ---------------------------------------------

BIAS_FUNCTIONS = ("texel_world_size", "slope_scaled_bias", "normal_offset", "receiver_texel_size")


def _bias_call(name: str, M: Any, p: Any, n: Any, size: Any = 64, **options: Any) -> Any:
    if name == "texel_world_size":
        return sm.texel_world_size(M, p, map_size=size, normals=n)
    if name == "receiver_texel_size":
        return sm.receiver_texel_size(M, p, n, size)
    fn = sm.slope_scaled_bias if name == "slope_scaled_bias" else sm.normal_offset
    return fn(M, p, n, map_size=size, **options)


BIAS_INVALID: dict[str, tuple[tuple[str, ...], str]] = {
    "behind": (BIAS_FUNCTIONS, "points: a receiver point is "),
    "zero_normal": (BIAS_FUNCTIONS, "normals: a normal is zero"),
    "nan_matrix": (BIAS_FUNCTIONS, "world_to_texture: " + NON_FINITE),
    "nan_point": (BIAS_FUNCTIONS, "points: " + NON_FINITE),
    "nan_normal": (BIAS_FUNCTIONS, "normals: " + NON_FINITE),
    "map_size": (BIAS_FUNCTIONS, "map_size: "),
    "matrix_shape": (BIAS_FUNCTIONS, "world_to_texture: expected shape"),
    "points_shape": (BIAS_FUNCTIONS, "points: expected shape"),
    "singular": (BIAS_FUNCTIONS[:3], "world_to_texture: s and t do not vary"),
    "radius": (BIAS_FUNCTIONS[1:3], "radius: expected an integer >= 0"),
    "filter": (BIAS_FUNCTIONS[1:3], "filter: expected 'box' or 'bilinear'"),
    "slope_factor": (("slope_scaled_bias",), "slope_factor: expected a finite number >= 0"),
    "constant": (("slope_scaled_bias",), "constant: expected a finite number >= 0"),
    "depth_bits": (("slope_scaled_bias",), "depth_bits: expected an integer 1..32 or None"),
    "no_normals": (("slope_scaled_bias",), "normals: required"),
    "scale": (("normal_offset",), "scale: expected a finite number >= 0"),
}


@given(data=st.data(), name=st.sampled_from(sorted(BIAS_INVALID)))
def test_fuzz_bias_invalid(data: st.DataObject, name: str) -> None:
    case = _draw_bias_case(data, np.float64)
    functions, message = BIAS_INVALID[name]
    fn = data.draw(st.sampled_from(functions))
    CASES["bias / texel size invalid"] += 1
    M, p, n = case.M.copy(), case.points.copy(), case.normals.copy()
    size: Any = case.size
    options: dict[str, Any] = {}
    scene = case.call.scene
    if name == "behind":
        if scene.kind == "directional":  # every point is in front of a directional light
            M[3] = [0.0, 0.0, 0.0, -1.0]
        else:
            p[0] = 2 * scene.position - p[0]
    elif name == "zero_normal":
        n[-1] = 0.0
    elif name.startswith("nan_"):
        target = {"nan_matrix": M[1], "nan_point": p[0], "nan_normal": n[0]}[name]
        target[data.draw(st.integers(0, len(target) - 1))] = np.nan
    elif name == "map_size":
        size = data.draw(st.sampled_from([0, -1, 2.5, True, (64,), "64"]))
    elif name == "matrix_shape":
        M = M[:3]
    elif name == "points_shape":
        p = p[:, :2]
    elif name == "singular":
        M[:2] = 0.0
    elif name == "no_normals":
        n = None
    else:
        value = {"radius": -1, "filter": "tent", "slope_factor": data.draw(st.sampled_from(
            [-1.0, np.nan, np.inf])), "constant": -2.0, "depth_bits": data.draw(st.sampled_from(
            [0, 33, True, 16.0])), "scale": np.nan}[name]  # fmt: skip
        options[{"radius": "pcf_radius", "filter": "pcf_filter"}.get(name, name)] = value
    with pytest.raises(ValueError, match=re.escape(message)):
        _bias_call(fn, M, p, n, size, **options)


@settings(max_examples=_examples(1, 60))
@given(data=st.data())
def test_fuzz_bias_jax_eager_jit_vmap(data: st.DataObject) -> None:
    dtype = data.draw(st.sampled_from([np.float64, np.float32]))
    case = _draw_bias_case(data, dtype, count=4)
    bad = case.points.copy()
    row = data.draw(st.integers(0, 3))
    bad[row, 0] = np.nan
    options = {"pcf_radius": case.radius, "pcf_filter": case.filter}
    for name in BIAS_FUNCTIONS:
        extra = options if name in ("slope_scaled_bias", "normal_offset") else {}
        fn = functools.partial(_bias_call, name, size=case.size, **extra)
        _check_jax_agrees(name, fn, (case.M, case.points, case.normals),
                          (case.M, bad, case.normals), dtype,
                          nan_outputs=lambda out: [out[row]])  # fmt: skip


# --- every public name has a fuzz target ----------------------------------------------------

#: Which targets fuzz each public name of shadowmath (constants and types through the
#: functions that take or return them). A new public name must get a target here.
# --- cascaded shadow maps -------------------------------------------------------------------


@given(
    near=st.floats(1e-3, 10),
    ratio=st.floats(1.01, 1e5),
    count=st.integers(1, 8),
    lam=st.floats(0, 1),
    scheme=st.sampled_from(["uniform", "log", "practical"]),
)
def test_fuzz_cascade_splits(
    near: float, ratio: float, count: int, lam: float, scheme: str
) -> None:
    """Exact ends, increasing, and the blend of the two schemes."""
    CASES["cascade_splits"] += 1
    far = near * ratio
    s = sm.cascade_splits(near, far, count, scheme=scheme, lam=lam)  # type: ignore[arg-type]
    assert s.shape == (count + 1,) and s[0] == near and s[-1] == far
    assert np.all(np.diff(s) > 0)
    w = {"uniform": 0.0, "log": 1.0, "practical": lam}[scheme]
    i = np.arange(count + 1) / count
    want = w * near * (far / near) ** i + (1 - w) * (near + (far - near) * i)
    np.testing.assert_allclose(s, want, rtol=1e-12)
    with pytest.raises(ValueError, match="far: the split range must end beyond near"):
        sm.cascade_splits(far, near, count)


def _cascade_scene(data: st.DataObject) -> tuple[np.ndarray, ...]:
    from .cameras import look_at, perspective

    eye = np.array(data.draw(st.tuples(*[st.floats(-50, 50)] * 2)), float)
    height = data.draw(st.floats(0.5, 30))
    yaw, pitch = data.draw(st.floats(0, 2 * np.pi)), data.draw(st.floats(-1.2, 0.2))
    e = np.array([eye[0], height, eye[1]])
    d = np.array([np.cos(yaw) * np.cos(pitch), np.sin(pitch), np.sin(yaw) * np.cos(pitch)])
    proj = perspective(data.draw(st.floats(0.3, 2.0)), data.draw(st.floats(0.5, 2.5)),
                       data.draw(st.floats(0.01, 1.0)), data.draw(st.floats(20, 500)))  # fmt: skip
    sun = np.array(data.draw(st.tuples(st.floats(-1, 1), st.floats(0.05, 1), st.floats(-1, 1))))
    top = data.draw(st.floats(1, 40))
    box = np.array([[-200.0, -1.0, -200.0], [200.0, top, 200.0]])
    return sun, look_at(e, e + d), proj, box


@given(data=st.data())
def test_fuzz_fit_cascades(data: st.DataObject) -> None:
    """Random cameras, suns and scenes: every point of a slice inside the scene lands in its
    cascade's map and depth range, every caster of the box beyond near; the three paths
    (compiled, Python loop, arrays) agree; a zero sun is refused by name."""
    CASES["fit_cascades"] += 1
    sun, view, proj, box = _cascade_scene(data)
    state = sm.CascadeState(
        np.float64(data.draw(st.floats(0.5, 5))),
        np.float64(80.0),
        np.float64(data.draw(st.floats(0.5, 50))),
    )
    options = data.draw(st.sampled_from([{}, {"stable": True}, {"layout": "atlas"},
                                         {"scheme": "uniform", "count": 2},
                                         {"depth_range": "visible"},
                                         {"depth_range": "visible", "state": state,
                                          "stable": True}]))  # fmt: skip
    c = sm.fit_cascades(sun, view, proj, box, 512, **options)
    assert isinstance(c, sm.Cascades)
    assert np.all(np.isfinite(c.world_to_clip)) and np.all(np.diff(c.splits) > 0)
    assert np.all(c.band_end >= c.splits[1:] * (1 - 1e-12))
    # Points of each slice inside the box: sampled along the camera's rays.
    rng = np.random.default_rng(data.draw(st.integers(0, 2**32 - 1)))
    inv_p, inv_v = np.linalg.inv(proj), np.linalg.inv(view)
    for i in range(len(c.band_end)):
        ndc = np.c_[rng.uniform(-1, 1, (400, 2)), np.zeros(400), np.ones(400)]
        ray = (inv_p @ ndc.T).T
        ray = ray[:, :3] / ray[:, 3:]
        depth = rng.uniform(c.splits[i], c.band_end[i], 400)
        p = ray * (depth / -ray[:, 2])[:, None]
        w = (inv_v @ np.c_[p, np.ones(400)].T).T[:, :3]
        w = w[np.all((w >= box[0]) & (w <= box[1]), axis=1)]
        h = np.c_[w, np.ones(len(w))] @ c.world_to_clip[i].T
        q = h[:, :3] / h[:, 3:]
        m = c.frustum.margin_x[i]
        assert np.all(np.abs(q[:, :2]) <= m * (1 + 1e-9)), np.abs(q[:, :2]).max()
        assert np.all((q[:, 2] >= -1) & (q[:, 2] <= 1))
        b = np.array([[box[k & 1, 0], box[k >> 1 & 1, 1], box[k >> 2, 2]] for k in range(8)])
        hb = np.c_[b, np.ones(8)] @ c.world_to_clip[i].T
        assert np.all(hb[:, 2] / hb[:, 3] >= -1)
    with _kernels.array_path():
        slow = sm.fit_cascades(sun, view, proj, box, 512, **options)
    np.testing.assert_allclose(c.world_to_clip, slow.world_to_clip, rtol=1e-8, atol=1e-10)
    with pytest.raises(ValueError, match="light: zero direction"):
        sm.fit_cascades(np.zeros(3), view, proj, box, 512, **options)


@given(data=st.data())
def test_fuzz_shadow_camera(data: st.DataObject) -> None:
    """Random lights, casters and APIs: the camera's numbers rebuild the fit's clip matrix
    with the textbook look-at and glFrustum/glOrtho; camera_to_world is the rigid inverse of
    that look-at for every engine's axes."""
    from .cameras import frustum, look_at, ortho

    CASES["shadow_camera"] += 1
    coords = st.floats(-20, 20)
    centre = np.array(data.draw(st.tuples(coords, coords, coords)))
    half = np.array(data.draw(st.tuples(*[st.floats(0.1, 5)] * 3)))
    box = centre + half * np.array([[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)])
    direction = np.array(data.draw(st.tuples(coords, st.floats(0.5, 20), coords)))
    point = data.draw(st.booleans())
    light = (sm.PointLight(centre + direction * (1 + 2 * half.max() / np.linalg.norm(direction)))
             if point else sm.DirectionalLight(direction))  # fmt: skip
    api = data.draw(st.sampled_from(sm.GRAPHICS_APIS))
    setup = sm.fit_shadow(light, box, data.draw(st.integers(16, 2048)), api=api)
    cam = sm.shadow_camera(setup)
    view = look_at(cam.eye, cam.eye + cam.forward, cam.up)
    n, f = float(cam.near), float(cam.far)
    lo, r, b, t = (float(v) for v in (cam.left, cam.right, cam.bottom, cam.top))
    proj = frustum(lo * n, r * n, b * n, t * n, n, f) if point else ortho(lo, r, b, t, n, f)
    clip = sm.api_convention(api=api).gl_clip_to_clip @ proj @ view
    scale = np.abs(setup.blocker_to_clip).max()
    np.testing.assert_allclose(clip, setup.blocker_to_clip, rtol=0, atol=1e-9 * scale)
    look = data.draw(st.sampled_from(["-z", "+y", "+z"]))
    M = sm.camera_to_world(cam, look=look)
    np.testing.assert_allclose(M[:3, :3].T @ M[:3, :3], np.eye(3), atol=1e-12)
    assert np.isclose(np.linalg.det(M[:3, :3]), 1.0)
    if look == "-z":
        np.testing.assert_allclose(M @ view, np.eye(4), atol=1e-9 * max(1, np.abs(cam.eye).max()))


@given(data=st.data())
def test_fuzz_cube_depth_range(data: st.DataObject) -> None:
    """Random lights, caster triangles at every scale and border rings: every point of every
    caster triangle that any face draws (ring included) lies at a view depth in
    [near, far]; near is k (1 - s) times the exact nearest Chebyshev distance (a linear
    program per triangle); far holds the receivers' corners."""
    from .test_cube_depth import lp_min_chebyshev

    CASES["cube_depth_range"] += 1
    scale = 10.0 ** data.draw(st.integers(-3, 3))
    light = np.array(data.draw(st.tuples(*[st.floats(-1, 1)] * 3))) * scale
    count = data.draw(st.integers(1, 4))
    corners = data.draw(st.lists(st.floats(-5, 5), min_size=9 * count, max_size=9 * count))
    triangles = light + np.reshape(corners, (count, 3, 3)) * scale
    nearest = min(lp_min_chebyshev(t, light) for t in triangles)
    assume(nearest > 1e-6 * scale)  # a caster at the light is refused (tested elsewhere)
    size = data.draw(st.integers(2, 2048))
    border = data.draw(st.integers(0, (size - 1) // 2))
    k = (size - 2 * border) / size
    floor = light + np.array([[[-9, -9, -7], [9, -9, -7], [0, 9, -7.0]]]) * scale
    got = sm.cube_depth_range(light, sm.Triangles(triangles), receivers=sm.Triangles(floor),
                              map_size=size, border_texels=border)  # fmt: skip
    near, far = float(got.near), float(got.far)
    assert near == pytest.approx(k * (1 - sm.NEAR_FAR_SLACK) * nearest, rel=1e-7)
    assert far >= np.abs(np.concatenate([triangles, floor]) - light).max() * (1 + 0.5 / 64)
    rng = np.random.default_rng(data.draw(st.integers(0, 2**32 - 1)))
    u, v = rng.uniform(0, 1, (2, 400))
    u, v = np.where(u + v > 1, 1 - u, u), np.where(u + v > 1, 1 - v, v)
    pick = triangles[rng.integers(0, count, 400)]
    A, B, C = pick[:, 0], pick[:, 1], pick[:, 2]
    points = A + u[:, None] * (B - A) + v[:, None] * (C - A)
    V = np.asarray(sm.cube_face_views(light))
    view = np.einsum("fij,nj->fni", V, np.c_[points, np.ones(len(points))])
    depth = -view[..., 2]
    drawn = (depth > 0) & (np.abs(view[..., 0]) * k <= depth) & (np.abs(view[..., 1]) * k <= depth)
    assert np.all(depth[drawn] >= near * (1 - 1e-12)) and np.all(depth[drawn] <= far)


@given(data=st.data())
def test_fuzz_gather_meshes(data: st.DataObject) -> None:
    """Random meshes (indexed and triangle soups) under random affine transforms, or none:
    each gathered triangle's corners are its own corners sent through its transform by
    hand (M @ (v, 1), then / w = 1). One projective transform is refused, naming it."""
    CASES["gather_meshes"] += 1
    rng = np.random.default_rng(data.draw(st.integers(0, 2**32 - 1)))
    n = data.draw(st.integers(1, 4))
    projective = data.draw(st.sampled_from([None, *range(n)]))
    entries, expected = [], []
    for i in range(n):
        count, faces = int(rng.integers(1, 6)), int(rng.integers(1, 8))
        vertices = rng.normal(size=(count, 3)) * 10.0 ** rng.integers(-3, 4)
        F = rng.integers(0, count, (faces, 3))
        M = np.eye(4)
        M[:3] = rng.normal(size=(3, 4)) * 10.0 ** rng.integers(-2, 3)
        if i == projective:
            M[3, rng.integers(0, 4)] += data.draw(st.sampled_from([1e-9, 0.5, -1.0]))
        transform = None if i != projective and data.draw(st.booleans()) else M
        mesh = sm.Triangles(vertices[F]) if data.draw(st.booleans()) else sm.Mesh(vertices, F)
        entries.append((mesh, transform))
        h = np.c_[vertices, np.ones(count)] @ (np.eye(4) if transform is None else M).T
        with np.errstate(divide="ignore", invalid="ignore"):  # w = 0: the projective one
            expected.append((h[:, :3] / h[:, 3:])[F])
    if projective is not None:
        with pytest.raises(ValueError, match=rf"meshes\[{projective}\]: .*projective"):
            sm.gather_meshes(entries)
        return
    got = sm.gather_meshes(entries)
    want = np.concatenate(expected)
    assert got.faces.shape == (len(want), 3) and got.faces.max() < len(got.vertices)
    atol = 1e-12 * np.abs(want).max()
    np.testing.assert_allclose(got.vertices[got.faces], want, rtol=1e-12, atol=atol)


PUBLIC_TARGETS: dict[str, tuple[str, ...]] = {
    "ShadowFitter": ("test_fuzz_shadow_fitter",),
    "PreparedFit": ("test_fuzz_shadow_fitter",),
    "GRAPHICS_APIS": ("test_fuzz_api_convention", "test_fuzz_fit_shadow_scene_options"),
    "NEAR_FAR_SLACK": ("test_fuzz_fit_shadow_scene_options",),
    "ApiConvention": ("test_fuzz_api_convention",),
    "Cascades": ("test_fuzz_fit_cascades",),
    "CascadeState": ("test_fuzz_fit_cascades",),
    "CubeDepthRange": ("test_fuzz_cube_depth_range",),
    "CubeFaceCoords": ("test_fuzz_cube_face", "test_fuzz_cube_jax_eager_jit_vmap"),
    "CubeFaceDepth": ("test_fuzz_cube_face_projection_and_depth",),
    "DirectionalLight": ("test_fuzz_fit_shadow_scene_options",
                         "test_fuzz_fit_shadow_jax_eager_jit_vmap"),
    "Frustum": ("test_fuzz_projections_of_any_frustum", "test_fuzz_cross_section_area"),
    "OrthographicBox": ("test_fuzz_projections_of_any_frustum", "test_fuzz_fit_shadow"),
    "FrustumFit": ("test_fuzz_optimize_frustum",),
    "LightFrame": ("test_fuzz_light_frame", "test_fuzz_rolled_light_frame"),
    "Mesh": ("test_fuzz_fit_shadow_scene_options", "test_fuzz_fit_shadow_invalid_options"),
    "PointLight": ("test_fuzz_fit_shadow_scene_options",
                   "test_fuzz_fit_shadow_jax_eager_jit_vmap"),
    "ShadowCamera": ("test_fuzz_shadow_camera",),
    "ShadowFitWarning": ("test_fuzz_fit_shadow_scene_options", "test_fuzz_shadow_map_spec"),
    "ShadowMapSpec": ("test_fuzz_shadow_map_spec", "test_fuzz_fit_shadow_scene_options"),
    "ShadowSetup": ("test_fuzz_fit_shadow", "test_fuzz_fit_shadow_scene_options"),
    "SpotLight": ("test_fuzz_fit_shadow_scene_options",
                  "test_fuzz_fit_shadow_jax_eager_jit_vmap"),
    "Triangles": ("test_fuzz_fit_shadow_scene_options",
                  "test_fuzz_fit_shadow_jax_eager_jit_vmap"),
    "adaptive_frustum": ("test_fuzz_fit_shadow", "test_fuzz_light_frame"),
    "api_convention": ("test_fuzz_api_convention", "test_fuzz_fit_shadow_scene_options"),
    "area_light_samples": ("test_fuzz_area_light_samples",
                           "test_fuzz_area_light_jax_eager_jit_vmap"),
    "blocker_projection": ("test_fuzz_projections_of_any_frustum",),
    "border_margin": ("test_fuzz_border_margin", "test_fuzz_shadow_map_spec"),
    "check_finite": ("test_fuzz_check_finite",),
    "check_projection": ("test_fuzz_check_projection",),
    "column_major_bytes": ("test_fuzz_fit_shadow",),
    "cross_section_area": ("test_fuzz_cross_section_area", "test_fuzz_optimize_frustum"),
    "cube_depth_range": ("test_fuzz_cube_depth_range",),
    "cube_face": ("test_fuzz_cube_face", "test_fuzz_cube_jax_eager_jit_vmap"),
    "cube_face_depth": ("test_fuzz_cube_face_projection_and_depth",
                        "test_fuzz_cube_jax_eager_jit_vmap"),
    "cube_face_direction": ("test_fuzz_cube_face", "test_fuzz_cube_jax_eager_jit_vmap"),
    "cube_face_projection": ("test_fuzz_cube_face_projection_and_depth",
                             "test_fuzz_cube_jax_eager_jit_vmap"),
    "cube_face_views": ("test_fuzz_cube_face", "test_fuzz_cube_jax_eager_jit_vmap"),
    "cascade_splits": ("test_fuzz_cascade_splits",),
    "camera_to_world": ("test_fuzz_shadow_camera",),
    "shadow_camera": ("test_fuzz_shadow_camera",),
    "fit_cascades": ("test_fuzz_fit_cascades",),
    "gather_meshes": ("test_fuzz_gather_meshes",),
    "fit_shadow": ("test_fuzz_fit_shadow", "test_fuzz_fit_shadow_scene_options",
                   "test_fuzz_fit_shadow_invalid_options",
                   "test_fuzz_fit_shadow_jax_eager_jit_vmap"),
    "helper_axis": ("test_fuzz_helper_axis",),
    "light_frame": ("test_fuzz_light_frame",),
    "light_frame_from_direction": ("test_fuzz_light_frame_from_direction",),
    "light_to_world": ("test_fuzz_light_frame",),
    "mean_direction_vector": ("test_fuzz_light_frame",),
    "normal_offset": ("test_fuzz_bias_and_texel_size", "test_fuzz_bias_jax_eager_jit_vmap"),
    "offcenter_frustum": ("test_fuzz_offcenter_and_smooth_frusta",),
    "optimize_frustum": ("test_fuzz_optimize_frustum",),
    "pcf": ("test_fuzz_pcf", "test_fuzz_pcf_invalid", "test_fuzz_pcf_jax_eager_jit_vmap"),
    "pcf_border_texels": ("test_fuzz_pcf_border_texels", "test_fuzz_shadow_map_spec"),
    "planar_projection": ("test_fuzz_planar_projection",),
    "pyramid_to_unit_cube": ("test_fuzz_pyramid_to_unit_cube",
                             "test_fuzz_area_light_jax_eager_jit_vmap"),
    "receiver_projection": ("test_fuzz_projections_of_any_frustum",),
    "receiver_texel_size": ("test_fuzz_bias_and_texel_size", "test_fuzz_bias_jax_eager_jit_vmap"),
    "receiver_texture_matrix": ("test_fuzz_fit_shadow", "test_fuzz_fit_shadow_scene_options"),
    "rolled_light_frame": ("test_fuzz_rolled_light_frame",),
    "silhouette_coverage": ("test_fuzz_silhouette_coverage",),
    "slope_scaled_bias": ("test_fuzz_bias_and_texel_size", "test_fuzz_bias_jax_eager_jit_vmap"),
    "smooth_frustum": ("test_fuzz_offcenter_and_smooth_frusta",),
    "smooth_max": ("test_fuzz_smooth_max",),
    "texel_world_size": ("test_fuzz_bias_and_texel_size", "test_fuzz_bias_jax_eager_jit_vmap"),
    "AtlasFit": ("test_fuzz_fit_atlas",),
    "ShadowAtlas": ("test_fuzz_allocate_atlas",),
    "allocate_atlas": ("test_fuzz_allocate_atlas",),
    "atlas_redraw": ("test_fuzz_atlas_redraw",),
    "atlas_tile_transforms": ("test_fuzz_fit_atlas",),
    "atlas_viewports": ("test_fuzz_fit_atlas",),
    "fit_atlas": ("test_fuzz_fit_atlas",),
    "world_to_light": ("test_fuzz_light_frame",),
    "PcssParameters": ("test_fuzz_pcss",),
    "PcssWidths": ("test_fuzz_pcss",),
    "pcss_parameters": ("test_fuzz_pcss", "test_fuzz_widen_cascades"),
    "pcss_widths": ("test_fuzz_pcss",),
    "pcss_border_texels": ("test_fuzz_pcss",),
    "widen_cascades": ("test_fuzz_widen_cascades",),
}  # fmt: skip


def test_every_public_name_has_a_fuzz_target() -> None:
    assert set(PUBLIC_TARGETS) == set(sm.__all__), set(sm.__all__) ^ set(PUBLIC_TARGETS)
    for targets in PUBLIC_TARGETS.values():
        for target in targets:
            assert callable(globals().get(target)), target


#: The repeated vertex that the stable-sphere regression test keeps.
STABLE_DUPLICATE = DUPLICATE


@example(vertices=STABLE_DUPLICATE[1:], offset=1e4, turn=0, gap=0.0)
@given(
    gap=st.sampled_from([0.0, 1e-9, 1e-6]),
    vertices=st.integers(4, 12).flatmap(lambda n: st.lists(
        st.tuples(*[st.floats(-1, 1)] * 3), min_size=n, max_size=n).map(np.array)),
    offset=st.sampled_from([1e3, 1e4, 1e6]),
    turn=st.integers(0, 2**32 - 1),
)  # fmt: skip
def test_fuzz_stable_map_with_a_repeated_vertex(
    vertices: np.ndarray, offset: float, turn: int, gap: float
) -> None:
    """A stable map's texel size is the blocker's shape's: a repeated vertex and the
    blocker's place in the world change nothing."""
    CASES["stable map, repeated vertex"] += 1
    v = np.r_[vertices[:1] * (1 + gap), vertices]
    size = float(np.linalg.norm(v - v.mean(0), axis=-1).max())
    assume(size > 0.1)
    light = np.array([*np.random.default_rng(turn).normal(size=3), 0.0])
    assume(np.linalg.norm(light) > 0.1)
    near = sm.fit_shadow(light, v - v.mean(0), 64, stable=True).frustum
    far = sm.fit_shadow(light, v + [0.0, offset, 0.0], 64, stable=True).frustum
    tol = 1e-9 * offset / size
    for a, b in zip(near[:2], far[:2], strict=True):  # the half extents (a box's for a sun)
        assert float(b) == pytest.approx(float(a), rel=tol), (float(a), float(b))


@DTYPES
@given(data=st.data())
def test_fuzz_non_finite_up_beside_surface_receivers(dtype: Any, data: st.DataObject) -> None:
    CASES["non-finite up beside surface receivers"] += 1
    call = data.draw(fit_calls(dtype, receiver_kinds=("triangles", "mesh")))
    if call.receivers is None:
        points = data.draw(receiver_points(call.scene, 4))
        vertices, faces = data.draw(receiver_surfaces(call.scene, points))
        call = call._replace(receivers=vertices, faces=faces, receiver_kind="mesh")
    up = np.array([1.0, 0.0, 0.0]) if call.up is None else call.up.copy()
    up[data.draw(st.integers(0, 2))] = data.draw(st.sampled_from([np.nan, np.inf, -np.inf]))
    args, kwargs = _fit_args(call._replace(up=up), dtype)
    with pytest.raises(ValueError, match="contains non-finite values") as info:
        sm.fit_shadow(*args, **kwargs)
    assert str(info.value).startswith("up: "), str(info.value)


@DTYPES
@example(angle=1.5, length=100.0, jitter=[0.0] * 24)
@given(
    angle=st.floats(1.2, 1.5),
    length=st.floats(1, 100),
    jitter=st.lists(st.floats(-1, 1), min_size=24, max_size=24),
)
def test_fuzz_spot_light_jax_at_small_scale(
    dtype: Any, angle: float, length: float, jitter: list[float]
) -> None:
    CASES["spot light on JAX at a small scale"] += 1
    scale = 1e-6 if np.dtype(dtype) == np.float32 else 1e-14
    box = np.array([[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (4, 6)], float)
    box = (box + 0.1 * np.reshape(jitter, (8, 3))) * scale
    arrays = (np.zeros(3), np.array([0.0, 0.0, length]), np.array(angle), box)
    want = sm.fit_shadow(sm.SpotLight(*(a.astype(dtype) for a in arrays[:3])),
                         box.astype(dtype), 64)  # fmt: skip
    jnp = _jnp()
    light = sm.SpotLight(*(jnp.asarray(a, dtype) for a in arrays[:3]))
    got = sm.fit_shadow(light, jnp.asarray(box, dtype), 64)
    # Entries that are zero up to rounding (the centre's offset of a symmetric box) compare
    # against the matrix's scale, not relatively: 8 ulps of its largest entry.
    scale = 8 * np.finfo(dtype).eps * float(np.abs(_f64(want.blocker_to_clip)).max())
    np.testing.assert_allclose(_f64(got.blocker_to_clip), _f64(want.blocker_to_clip),
                               rtol=1e-3 if np.dtype(dtype) == np.float32 else 1e-9,
                               atol=scale)  # fmt: skip


# ---- the shadow atlas ------------------------------------------------------------------------


@st.composite
def atlas_wishes(draw: Any) -> dict[str, Any]:
    """Coverage (zeros included), cube flags, borders and the atlas's options."""
    count = draw(st.integers(1, 24))
    return {
        "coverage": np.array(draw(st.lists(
            st.one_of(st.just(0.0), st.floats(0.0, 2.0)), min_size=count, max_size=count))),
        "cube": np.array(draw(st.lists(st.booleans(), min_size=count, max_size=count))),
        "border_texels": np.array(draw(st.lists(st.integers(0, 3), min_size=count,
                                                max_size=count))),
        "atlas_size": draw(st.sampled_from([256, 1024, 4096])),
        "budget": draw(st.sampled_from([1.0, 0.5, 0.1, 0.01])),
        "hysteresis": draw(st.sampled_from([0.0, 0.1, 0.3])),
    }  # fmt: skip


@given(wishes=atlas_wishes(), noise=st.floats(0.0, 0.02), seed=st.integers(0, 2**32 - 1))
def test_fuzz_allocate_atlas(wishes: dict[str, Any], noise: float, seed: int) -> None:
    """A valid quadtree layout for any wishes, sizes that never favour the lower-ranked
    light, Godot's classes when the budget admits them, the same atlas for the same
    inputs, and no tile moved by coverage noise that changes no light's size."""
    from .test_atlas import check_layout, godot_class

    CASES["allocate_atlas"] += 1
    a = sm.allocate_atlas(**wishes)
    check_layout(a)
    assert np.array_equal(sm.allocate_atlas(**wishes).tile_rect, a.tile_rect)
    size = wishes["atlas_size"]
    smallest = int(max(size // 64, 4 * wishes["border_texels"].max()))
    wish = [godot_class(c, size // 2, 1 << (smallest - 1).bit_length()) for c in wishes["coverage"]]
    assert a.light_wish.tolist() == wish
    area = sum(w * w * (6 if c else 1) for w, c in zip(wish, wishes["cube"], strict=True))
    if area <= wishes["budget"] * size * size:
        assert a.light_size.tolist() == wish
    order = sorted(range(len(wish)), key=lambda i: (-wish[i], i))
    sizes = a.light_size[order]
    assert np.all(sizes[:-1] >= sizes[1:])  # the light ahead never gets the smaller tile
    rng = np.random.default_rng(seed)
    moved = wishes["coverage"] * (1 + noise * rng.uniform(-1, 1, len(wish)))
    b = sm.allocate_atlas(**{**wishes, "coverage": moved}, previous=a)
    check_layout(b)
    if np.array_equal(b.light_size, a.light_size) and not b.repacked:
        assert not b.moved.any()


@st.composite
def atlas_scenes(draw: Any) -> tuple[np.ndarray, list[Any], np.ndarray]:
    """Casters in the unit cube and 1 to 8 lights: cube point lights anywhere off the
    casters, 2D point lights and spots (aimed at the origin) 3 to 6 away, suns."""
    rng = np.random.default_rng(draw(st.integers(0, 2**32 - 1)))
    verts = rng.uniform(-1, 1, (draw(st.integers(4, 24)), 3))  # a silhouette of some width
    lights, cube = [], []
    for _ in range(draw(st.integers(1, 8))):
        kind = draw(st.sampled_from(["cube", "point", "spot", "sun"]))
        direction = draw(unit_vectors())
        far_away = direction * draw(st.floats(3.0, 6.0))
        if kind == "cube":
            p = rng.uniform(-3, 3, 3)
            assume(np.abs(verts - p).max(axis=1).min() > 0.05)
            lights.append(sm.PointLight(p))
        elif kind == "point":
            lights.append(sm.PointLight(far_away))
        elif kind == "spot":
            angle = draw(st.floats(0.2, 1.2))
            lights.append(sm.SpotLight(far_away, -far_away, np.array(angle)))
        else:
            lights.append(sm.DirectionalLight(direction))
        cube.append(kind == "cube")
    return verts, lights, np.array(cube)


@given(scene=atlas_scenes(), seed=st.integers(0, 2**32 - 1))
def test_fuzz_atlas_redraw(scene: Any, seed: int) -> None:
    """Frames of lights leaving, joining, reordered, moved and resized: previous_index
    maps tiles by (light id, face), a tile not moved kept its index, key and rect, and
    renderers keeping tiles by atlas_redraw (one texture, a cache by key, a cache by
    index with moved) sample every light's own depths, as a fresh draw gives them."""
    from .test_atlas_identity import check_identity, run_renderers

    verts, lights, cube = scene
    CASES["atlas_redraw"] += 1
    rng = np.random.default_rng(seed)
    coverage = rng.uniform(0.02, 0.6, len(lights))
    atlases: list[sm.ShadowAtlas] = []
    frame_lights: list[list[Any]] = []
    for _ in range(4):
        ids = rng.permutation(len(lights))[: rng.integers(1, len(lights) + 1)]
        coverage = np.where(rng.uniform(size=len(lights)) < 0.3, coverage * 2, coverage)
        lights = [_nudged(light) if rng.uniform() < 0.3 and not c else light
                  for light, c in zip(lights, cube, strict=True)]  # fmt: skip
        previous = atlases[-1] if atlases else None
        atlas = sm.allocate_atlas(coverage[ids], atlas_size=1024, cube=cube[ids], light_ids=ids,
                                  budget=0.5, previous=previous)  # fmt: skip
        if atlases:
            check_identity(atlases[-1], atlas)
        atlases.append(atlas)
        frame_lights.append([lights[i] for i in ids])
    run_renderers(atlases, frame_lights, verts)


def _nudged(light: Any) -> Any:
    """A 2D light moved a little (a spot keeps aiming at the origin's side)."""
    if isinstance(light, sm.DirectionalLight):
        return light._replace(direction=np.asarray(light.direction) + [0.01, 0.0, 0.0])
    return light._replace(position=np.asarray(light.position) * 1.01)


@given(
    scene=atlas_scenes(),
    api=st.sampled_from(GRAPHICS_APIS),
    reversed_z=st.booleans(),
    border=st.integers(1, 3),
    coverage=st.floats(0.05, 1.0),
)
def test_fuzz_fit_atlas(scene: Any, api: Any, reversed_z: bool, border: int,
                        coverage: float) -> None:  # fmt: skip
    """Every tile's matrices are its light's own fit moved into the tile: a 2D tile's clip
    matrix is fit_shadow's for its size and border, and every caster it draws samples the
    tile's inner texels; every caster of a cube light samples, in the face tile that
    sm.cube_face picks, a texel inside that tile at a depth in [0, 1]."""
    verts, lights, cube = scene
    CASES["fit_atlas"] += 1
    a = sm.allocate_atlas(np.full(len(lights), coverage), atlas_size=2048, cube=cube,
                          border_texels=border)  # fmt: skip
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", sm.ShadowFitWarning)
        fit = sm.fit_atlas(lights, verts, a, api=api, reversed_z=reversed_z)
    assert np.array_equal(fit.viewports, sm.atlas_viewports(a, api=api))
    assert np.array_equal(fit.viewports[:, 2], a.tile_rect[:, 2])
    moves = sm.atlas_tile_transforms(a, api=api)
    A = a.atlas_size
    for i, light in enumerate(lights):
        n = int(a.light_size[i])
        if cube[i]:
            faces = sm.cube_face(verts - np.asarray(light.position)).face
            tiles = a.light_tiles[i, faces]
        else:
            with warnings.catch_warnings():
                warnings.simplefilter("ignore", sm.ShadowFitWarning)
                ref = sm.fit_shadow(light, verts, n, border_texels=border, api=api,
                                    reversed_z=reversed_z)  # fmt: skip
            t = a.light_tiles[i, 0]
            scale = np.abs(ref.blocker_to_clip).max()
            assert np.allclose(fit.world_to_clip[t], ref.blocker_to_clip, rtol=1e-9,
                               atol=1e-12 * scale)  # fmt: skip
            tiles = np.full(len(verts), t)
            expected = moves[t] @ ref.world_to_texture
            assert np.allclose(fit.world_to_texture[t], expected, rtol=1e-9,
                               atol=1e-12 * np.abs(expected).max())  # fmt: skip
        stq = np.einsum(
            "vij,vj->vi", fit.world_to_texture[tiles], np.c_[verts, np.ones(len(verts))]
        )
        assert np.all(stq[:, 3] > 0)
        s, t_, r = (stq[:, :3] / stq[:, 3:]).T
        x, y = a.tile_rect[tiles, 0], a.tile_rect[tiles, 1]
        inside = np.ones(len(verts), dtype=bool)
        if isinstance(light, sm.SpotLight):  # the map is clipped to the cone's square
            axis = -np.asarray(light.position) / np.linalg.norm(light.position)
            d = verts - np.asarray(light.position)
            inside = d @ axis >= np.cos(float(light.angle)) * np.linalg.norm(d, axis=1)
        inner = 0 if cube[i] else border
        slack = 1e-7 * A
        col, row = s * A, t_ * A
        assert np.all(col[inside] >= x[inside] + inner - slack)
        assert np.all(col[inside] <= x[inside] + n - inner + slack)
        assert np.all(row[inside] >= y[inside] + inner - slack)
        assert np.all(row[inside] <= y[inside] + n - inner + slack)
        assert np.all((r > -1e-9) & (r < 1 + 1e-9))


@given(data=st.data())
def test_fuzz_pcss(data: st.DataObject) -> None:
    """Random point lights and suns, light sizes, APIs, reversed Z, map sizes and borders:
    ``pcss_parameters``'s ``K`` and ``d_near`` give, through ``pcss_widths`` and the stored
    depths, the penumbra and the blocker search found by similar triangles in world space
    (``tests/test_pcss.py``'s oracles); ``pcss_border_texels`` holds the widest search
    (``>= ceil(max K)``); a negative or non-finite size is refused naming its argument."""
    from .test_pcss import caster_box, orthographic_case, perspective_case

    CASES["pcss_parameters"] += 1
    rng = np.random.default_rng(data.draw(st.integers(0, 2**32 - 1)))
    verts = caster_box(rng)
    size = (data.draw(st.integers(16, 2048)), data.draw(st.integers(16, 2048)))
    api = data.draw(st.sampled_from(sm.GRAPHICS_APIS))
    rev = data.draw(st.booleans())
    border = data.draw(st.integers(0, 5))
    sun = data.draw(st.booleans())
    B = verts[data.draw(st.integers(0, 7))]
    if sun:
        theta = float(np.radians(data.draw(st.floats(0.05, 10.0))))
        light = np.r_[rng.normal(size=3), 0.0]
        assume(np.linalg.norm(light[:3]) > 0.1)
        fit = sm.fit_shadow(light, verts, size, api=api, reversed_z=rev, border_texels=border)
        p = sm.pcss_parameters(fit, angular_radius=theta, map_size=size)
        Z = fit.world_to_light[2, :3]
        near_point = (np.linalg.inv(fit.world_to_light) @ [0, 0, float(fit.frustum.near), 1])[:3]
        zR = data.draw(st.floats(0.1, 5.0))
        orthographic_case(fit.world_to_texture, size, Z, near_point, p, theta, B, zR)
        bad = {"angular_radius": data.draw(st.sampled_from([-0.1, np.inf, np.pi / 2]))}
    else:
        R = data.draw(st.floats(0.01, 2.0))
        L = rng.uniform(-3, 3, 3) + [0, data.draw(st.floats(6.0, 60.0)), 0]
        fit = sm.fit_shadow(L, verts, size, api=api, reversed_z=rev, border_texels=border)
        p = sm.pcss_parameters(fit, light_radius=R, map_size=size)
        Z = fit.world_to_light[2, :3]
        zR = float((B - L) @ Z) * data.draw(st.floats(1.01, 4.0))
        perspective_case(fit.world_to_texture, size, L, Z, float(fit.frustum.near), p, R, B, zR)
        bad = {"light_radius": data.draw(st.sampled_from([-0.5, np.inf, np.nan]))}
    assert float(p.near_depth) == float(rev)
    assert sm.pcss_border_texels(p) >= np.ceil(np.max(p.texels_per_depth))
    with pytest.raises(ValueError, match=f"^{next(iter(bad))}:"):
        sm.pcss_parameters(fit, map_size=size, **bad)


@given(data=st.data())
def test_fuzz_widen_cascades(data: st.DataObject) -> None:
    """Random cameras, suns and angular radii: the widened cascades keep every depth row and
    every world penumbra (``K`` times the texel size), and each box grows by
    ``tan(theta) (f - n)`` on every side, about the same centre."""
    from .cameras import scene as camera_scene

    CASES["widen_cascades"] += 1
    sun, view, proj, box = camera_scene(data.draw(st.integers(0, 7)))
    theta = float(np.radians(data.draw(st.floats(0.05, 5.0))))
    c = sm.fit_cascades(sun, view, proj, box, data.draw(st.integers(64, 2048)),
                        border_texels=data.draw(st.integers(0, 4)))  # fmt: skip
    wide = sm.widen_cascades(c, angular_radius=theta)
    p, q = (sm.pcss_parameters(x, angular_radius=theta) for x in (c, wide))
    np.testing.assert_allclose(p.texels_per_depth * c.texel_size,
                               q.texels_per_depth * wide.texel_size, rtol=1e-9)  # fmt: skip
    np.testing.assert_allclose(wide.world_to_texture[..., 2, :], c.world_to_texture[..., 2, :])
    a, b = c.frustum, wide.frustum
    w = np.tan(theta) * (np.asarray(a.far) - np.asarray(a.near))
    np.testing.assert_allclose(b.half_width, np.asarray(a.half_width) + w, rtol=1e-9)
    np.testing.assert_allclose(b.half_height, np.asarray(a.half_height) + w, rtol=1e-9)
    np.testing.assert_allclose(b.center_x, a.center_x, rtol=1e-9, atol=1e-9)
    np.testing.assert_allclose(b.center_y, a.center_y, rtol=1e-9, atol=1e-9)


@given(st.integers(0, 2**32 - 1))
@settings(deadline=None)
def test_fuzz_shadow_scene(seed: int) -> None:
    """Random scenes and lights through ``ShadowScene.fit``: an object left out of a map's
    draw list has no point (sampled on its own triangles) in the map's clip volume (so no
    texel changes: no lit point's lookup sees it), a spot skipped has nothing in its cone,
    and every caster's points that a map can shadow lie in it (the spot's texture square
    for the points in its cone, the sun's box, the cube's depth range)."""
    rng = np.random.default_rng(seed)
    scene, objects = _random_scene(rng, int(rng.integers(1, 8)))
    lights = [
        sm.SpotLight(np.r_[rng.uniform(-4, 4, 2), rng.uniform(6, 12)],
                     np.r_[rng.uniform(-0.5, 0.5, 2), -1.0], np.float64(rng.uniform(0.1, 1.2))),
        sm.DirectionalLight(np.r_[rng.uniform(-0.7, 0.7, 2), 1.0]),
        sm.PointLight(np.r_[rng.uniform(-4, 4, 2), rng.uniform(6, 12)]),
    ]  # fmt: skip
    spot, sun, point = scene.fit(lights, 512)
    points = [_samples(_world(mesh, M), 3) for mesh, M in objects]
    L, axis, theta = lights[0]
    faces = None
    if point.fit is not None:
        P = sm.cube_face_projection(point.fit.near, point.fit.far, map_size=512, border_texels=1)
        faces = P @ sm.cube_face_views(lights[2].position)
    for k in range(1, len(objects)):
        in_cone = _cone_distance(L, axis, float(theta), points[k]) == 0
        if spot.fit is not None:
            assert np.all(_inside_map(spot.fit, points[k][in_cone]))
            if k not in spot.draws[0]:  # culled: no fragment in the map at all
                assert not np.any(_clip_inside(np.asarray(spot.fit.blocker_to_clip), points[k]))
        else:
            assert not np.any(in_cone)  # skipped: nothing in its cone
        assert k in sun.draws[0]
        assert sun.fit is not None and np.all(_inside_map(sun.fit, points[k]))
        if faces is not None:
            depth = np.max(np.abs(points[k] - lights[2].position), axis=1)
            assert np.all((depth >= float(point.fit.near)) & (depth <= float(point.fit.far)))
            for face in range(6):
                if k not in point.draws[face]:
                    assert not np.any(_clip_inside(faces[face], points[k]))
