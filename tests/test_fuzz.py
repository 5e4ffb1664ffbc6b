"""Fuzzing every public function with valid and invalid scenes.

Each test draws a scene that is either valid (then the call must succeed and its output
must pass the function's property checks, within a tolerance of a few ulps times the
scene's condition) or invalid in a known way (then the call must raise the documented
``ValueError``). The regular run uses the short ``default`` hypothesis profile; ``make
fuzz`` runs ``HYPOTHESIS_PROFILE=fuzz`` and prints how many cases were tried.
"""

from __future__ import annotations

import contextlib
import os
import re
from collections import Counter
from collections.abc import Iterator
from typing import Any

import numpy as np
import pytest
from hypothesis import assume, given, settings
from hypothesis import strategies as st

import shadowmath as sm
from shadowmath._backends import _kernels

from .strategies import (
    Invalid,
    Placement,
    PlanarScene,
    invalid_placements,
    invalid_planar,
    placements,
    planar_scenes,
    sized_maps,
    unit_vectors,
)

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
        _check_fit(data.draw(placements(dtype)), map_size, border, dtype)
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
    fr = sm.Frustum(rx, ry, near, far, 0.98, 0.96)
    tiny = np.finfo(np.float64).tiny  # subnormal ratios are refused: m / r would overflow
    if not (rx >= tiny and ry >= tiny and 0 < near < far):
        with pytest.raises(ValueError, match="frustum"):
            sm.blocker_projection(fr)
        with pytest.raises(ValueError, match="frustum"):
            sm.receiver_projection(fr)
        return
    P = sm.blocker_projection(fr)
    T = sm.receiver_projection(fr)
    assert np.all(np.isfinite(P))
    assert np.all(np.isfinite(T))
    if near < 1e-290:  # subnormal corners: the check below would measure its own underflow
        return
    # Depth loses (f + n) / (f - n) ulps to cancellation, whatever the formula.
    tol = 1e-13 * (far + near) / (far - near)
    for z, depth in ((near, -1.0), (far, 1.0)):
        corner = np.array([rx * z, -ry * z, z, 1.0])
        clip = P @ corner
        np.testing.assert_allclose(clip[:2] / clip[3], [0.98, -0.96], rtol=1e-12)
        assert clip[2] / clip[3] == pytest.approx(depth, abs=tol)
        stq = T @ corner
        np.testing.assert_allclose(stq[:2] / stq[3], [0.99, 0.02], rtol=1e-12)
        assert stq[2] / stq[3] == pytest.approx((depth + 1) / 2, abs=tol)


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
