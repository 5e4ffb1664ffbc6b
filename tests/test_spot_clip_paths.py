"""A spot light's caster triangles clipped three ways agree: the compiled loop
(``_spot_select.clipped``, Numba), the same loop run by Python, the NumPy form that clips
only the straddling triangles (``_spot_casters.select_triangles``), and the static-shape
form every triangle goes through under JAX (``_spot_casters.clip_triangles``).

Agreement is what the fit reads: the number of triangles kept, whether a non-finite point
is kept, and the extremes of ``x / z``, ``y / z`` and ``z`` of the kept points in the
light's frame.
"""

from __future__ import annotations

import contextlib
import json
import os
import subprocess
import sys
from collections.abc import Iterator
from typing import Any

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import shadowmath as sm
from shadowmath._backends import _kernels
from shadowmath._boundary._validate import convert
from shadowmath._fits.shadow._spot_select import _frame, clipped
from shadowmath._math import _spot_casters as sc
from shadowmath._math._specialize import scalar_formulas

DTYPES = (np.float32, np.float64)
KINDS = ("inside", "straddling", "outside", "behind", "crossing", "degenerate", "non-finite")

needs_numba = pytest.mark.skipif(not _kernels.available(), reason="needs Numba (the fast extra)")


def _light(rng: np.random.Generator) -> np.ndarray:
    angle = rng.uniform(0.1, 1.3)
    return np.r_[rng.normal(size=3) * 3, rng.normal(size=3), np.tan(angle), angle]


def _triangles(rng: np.random.Generator, kinds: list[str], light: np.ndarray) -> np.ndarray:
    """Triangles of the given kinds in the light's frame ``(x, y, z)``, placed in the world."""
    t = light[6]
    out = []
    for kind in kinds:
        z = rng.uniform(0.5, 6.0, size=3)
        if kind == "inside":
            xy = rng.uniform(-0.95, 0.95, size=(3, 2)) * t * z[:, None]
        elif kind == "straddling":
            xy = rng.uniform(-2.5, 2.5, size=(3, 2)) * t * z[:, None]
        elif kind == "outside":  # beyond one side
            xy = rng.uniform(-1, 1, size=(3, 2)) * t * z[:, None]
            xy[:, rng.integers(2)] = rng.choice([-1, 1]) * t * z * rng.uniform(1.05, 3, size=3)
        elif kind == "behind":
            z = -z
            xy = rng.uniform(-3, 3, size=(3, 2)) * t * np.abs(z)[:, None]
        elif kind == "crossing":  # the light's plane
            z = np.array([rng.uniform(-3, -0.2), rng.uniform(0.5, 5), rng.uniform(-2, 5)])
            xy = rng.uniform(-2, 2, size=(3, 2)) * t * np.abs(z)[:, None]
        else:
            xy = rng.uniform(-2, 2, size=(3, 2)) * t * z[:, None]
        p = np.c_[xy, z]
        if kind == "degenerate":  # a repeated corner, collinear corners or a point
            which = rng.integers(3)
            p[2] = p[0] if which == 0 else p[0] + 0.5 * (p[1] - p[0]) if which == 1 else p[2]
            if which == 2:
                p[:] = p[0]
        out.append(p)
    ctx, _ = convert(light=light)
    position, axes, _ = _frame(ctx, light, None)
    world = position + np.array(out) @ axes
    for i, kind in enumerate(kinds):
        if kind == "non-finite":
            world[i, rng.integers(3), rng.integers(3)] = rng.choice([np.nan, np.inf, -np.inf])
    return world


@st.composite
def scenes(draw: st.DrawFn) -> tuple[np.ndarray, np.ndarray, Any]:
    """A spot light row, triangles of every kind (random counts), a dtype."""
    seed = draw(st.integers(0, 2**32 - 1))
    kinds = draw(st.lists(st.sampled_from(KINDS), min_size=1, max_size=40))
    dtype = draw(st.sampled_from(DTYPES))
    rng = np.random.default_rng(seed)
    light = _light(rng)
    return light.astype(dtype), _triangles(rng, kinds, light).astype(dtype), dtype


def _planes(light: np.ndarray) -> tuple[Any, Any, np.ndarray, float]:
    ctx, _ = convert(light=light)
    position, axes, t = _frame(ctx, light, None)
    return position, axes, sc.pyramid_planes(np, position, axes, t), ctx.eps


SQUARE = np.full((4, 3), 7.0)  # not a caster: shows where the empty fit's square is taken


def _square() -> np.ndarray:
    return SQUARE


def _summary(points: np.ndarray, position: Any, axes: Any) -> tuple[bool, np.ndarray]:
    """Whether a non-finite point is kept, and the finite points' extremes of ``x / z``,
    ``y / z`` (where ``z`` is clear of the light) and ``z`` in the light's frame."""
    p = np.asarray(points, dtype=np.float64)
    finite = np.all(np.isfinite(p), axis=-1)
    q = (p[finite] - np.asarray(position, np.float64)) @ np.asarray(axes, np.float64).T
    if not len(q):
        return not finite.all(), np.zeros(0)
    clear = q[:, 2] > 1e-3
    u, v = q[clear, 0] / q[clear, 2], q[clear, 1] / q[clear, 2]
    ext = [u.max(), u.min(), v.max(), v.min()] if clear.any() else []
    return not finite.all(), np.array([*ext, q[:, 2].max(), q[:, 2].min()])


def _python_loop(planes: np.ndarray, tris: np.ndarray, eps: float) -> tuple[np.ndarray, int]:
    """The compiled loop's source run by Python (no Numba needed)."""
    out = np.empty((19 * len(tris), 3), dtype=tris.dtype)
    stop, at, kept = scalar_formulas().spot_clip_loop(tris.reshape(-1), planes, eps, out, (0, 0))
    assert stop == len(tris)
    return out[:at], kept


def _tolerance(dtype: Any) -> float:
    return 1e-4 if dtype == np.float32 else 1e-9


def _assert_same(a: tuple[bool, np.ndarray], b: tuple[bool, np.ndarray], dtype: Any) -> None:
    assert a[0] == b[0]
    np.testing.assert_allclose(a[1], b[1], rtol=_tolerance(dtype), atol=_tolerance(dtype))


@pytest.fixture(autouse=True)
def _quiet() -> Iterator[None]:
    """Non-finite corners: the selections' NaN arithmetic is expected (the fit's door
    runs them under ``np.errstate(all="ignore")`` too)."""
    with np.errstate(all="ignore"):
        yield


@settings(max_examples=150, deadline=None)
@given(scene=scenes())
def test_the_loop_keeps_what_the_array_form_keeps(scene: tuple[Any, ...]) -> None:
    light, tris, dtype = scene
    position, axes, planes, eps = _planes(light)
    ref = sc.select_triangles(planes, tris, _square, eps)
    want = _summary(ref.points, position, axes)
    found, kept = _python_loop(planes, tris, eps)
    assert kept == int(ref.kept)
    if kept:
        _assert_same(_summary(found, position, axes), want, dtype)
    else:
        assert len(found) == 0 and np.array_equal(ref.points, SQUARE)
    if _kernels.available():
        got = clipped(planes, tris, _square, eps)
        assert int(got.kept) == int(ref.kept)
        assert not int(got.kept) or got.points.dtype == tris.dtype
        _assert_same(_summary(got.points, position, axes), want, dtype)


@settings(max_examples=150, deadline=None)
@given(scene=scenes())
def test_the_array_form_keeps_what_clip_triangles_keeps(scene: tuple[Any, ...]) -> None:
    """Only straddling triangles are clipped; the kept count and extremes are unchanged."""
    light, tris, dtype = scene
    position, axes, planes, eps = _planes(light)
    ref = sc.clip_triangles(np, planes, tris, SQUARE, eps)
    got = sc.select_triangles(planes, tris, _square, eps)
    with _block(3):
        few = sc.select_triangles(planes, tris, _square, eps)
    assert int(few.kept) == int(ref.kept)
    _assert_same(_summary(few.points, position, axes), _summary(got.points, position, axes), dtype)
    assert int(got.kept) == int(ref.kept)
    _assert_same(_summary(got.points, position, axes), _summary(ref.points, position, axes), dtype)


@contextlib.contextmanager
def _block(size: int) -> Iterator[None]:
    """:func:`sc.select_triangles` classifying ``size`` triangles at a time."""
    old = sc.BLOCK
    sc.BLOCK = size
    try:
        yield
    finally:
        sc.BLOCK = old


@settings(max_examples=40, deadline=None)
@given(
    seed=st.integers(0, 2**32 - 1), dtype=st.sampled_from(DTYPES), block=st.sampled_from([5, 2048])
)
def test_batched_lights_and_casters_keep_each_entrys_points(
    seed: int, dtype: Any, block: int
) -> None:
    """Lights ``(2, 3)`` over shared casters, and over casters per light: each entry holds
    its own kept points (padded with its first), or its square when it keeps none; alike
    when the triangles are classified a few at a time."""
    rng = np.random.default_rng(seed)
    lights = np.array([_light(rng) for _ in range(6)]).reshape(2, 3, 8)
    shared = _triangles(rng, list(rng.choice(KINDS[:5], size=12)), lights[1, 2])
    kinds = list(rng.choice(KINDS[:3], size=12))  # all in front of their light
    own = np.array([[_triangles(rng, kinds, light) for light in row] for row in lights])
    lights[0, 1, 3:6] *= -1  # turned away from its own casters: the empty fit
    squares = rng.normal(size=(2, 3, 4, 3)).astype(dtype)
    for casters in (shared, own):
        ctx, _ = convert(light=lights.astype(dtype))
        position, axes, t = _frame(ctx, lights.astype(dtype), None)
        planes = sc.pyramid_planes(np, position, axes, t)
        with _block(block):
            got = sc.select_triangles(planes, casters.astype(dtype), lambda: squares, ctx.eps)
        assert got.points.shape[:2] == (2, 3) and got.kept.shape == (2, 3)
        for i in np.ndindex(2, 3):
            tris = (casters if casters.ndim == 3 else casters[i]).astype(dtype)
            ref = sc.clip_triangles(np, planes[i], tris, squares[i], ctx.eps)
            assert int(got.kept[i]) == int(ref.kept)
            a = _summary(got.points[i], position[i], axes[i])
            _assert_same(a, _summary(ref.points, position[i], axes[i]), dtype)
            if int(ref.kept) == 0:
                assert {tuple(p) for p in got.points[i]} == {tuple(p) for p in squares[i]}
    assert int(got.kept[0, 1]) == 0


@needs_numba
def test_the_loop_resumes_where_its_output_is_full() -> None:
    """A loop given too few rows stops before a triangle and resumes from there: the same
    points as one call with room for all."""
    rng = np.random.default_rng(5)
    light = _light(rng)
    tris = _triangles(rng, ["straddling"] * 30 + ["inside"] * 10, light)
    _, _, planes, eps = _planes(light)
    loop = _kernels.loops().spot_clip_loop
    flat = tris.reshape(-1)
    whole = np.empty((19 * len(tris), 3))
    stop, end, kept = loop(flat, planes, eps, whole, (0, 0))
    assert stop == len(tris)
    out, start, at, total = np.empty((20, 3)), 0, 0, 0
    while start < len(tris):
        start, at, more = loop(flat, planes, eps, out, (start, at))
        total += more
        if start < len(tris):
            out = np.concatenate([out[:at], np.empty((len(out), 3))])
    assert (at, total) == (end, kept)
    np.testing.assert_array_equal(out[:at], whole[:end])
    np.testing.assert_array_equal(clipped(planes, tris, _square, eps).points, whole[:end])


def _scene(count: int = 40, seed: int = 11) -> tuple[sm.SpotLight, np.ndarray]:
    rng = np.random.default_rng(seed)
    light = _light(rng)
    kinds = list(rng.choice(KINDS[:5], size=count))
    spot = sm.SpotLight(light[:3], light[3:6], np.array(light[7]))
    return spot, _triangles(rng, kinds, light)


@needs_numba
@pytest.mark.parametrize("dtype", DTYPES)
@pytest.mark.parametrize("placed", [False, True])
def test_fit_shadow_is_the_same_with_and_without_numba(dtype: Any, placed: bool) -> None:
    spot, tris = _scene()
    spot = sm.SpotLight(*(np.asarray(v, dtype=dtype) for v in spot))
    B = None
    if placed:
        B = np.array([[1.1, 0.1, 0, 0.3], [0, 0.9, 0.2, -0.5], [0.1, 0, 1, 0.2], [0, 0, 0, 1.0]])
        tris = (tris - B[:3, 3]) @ np.linalg.inv(B[:3, :3]).T
        B = B.astype(dtype)
    casters = sm.Triangles(tris.astype(dtype))
    fast = sm.fit_shadow(spot, casters, 256, blocker_to_world=B)
    with _kernels.disabled():
        slow = sm.fit_shadow(spot, casters, 256, blocker_to_world=B)
    assert 0 < int(fast.casters_used) == int(slow.casters_used) < len(tris)
    rtol = 1e-5 if dtype == np.float32 else 1e-12
    for a, b in zip(_leaves(fast), _leaves(slow), strict=True):
        np.testing.assert_allclose(a, b, rtol=rtol, atol=rtol)


def _leaves(value: Any) -> list[np.ndarray]:
    """A setup's arrays, in order (its frame and frustum unpacked)."""
    if isinstance(value, tuple):
        return [leaf for v in value for leaf in _leaves(v)]
    return [np.asarray(value, dtype=np.float64)]


@needs_numba
def test_shadowmath_numba_0_gives_the_same_fit() -> None:
    """The switch read at import: a process with ``SHADOWMATH_NUMBA=0`` fits alike."""
    spot, tris = _scene()
    code = (
        "import json, sys, numpy as np, shadowmath as sm\n"
        "from shadowmath._backends import _kernels\n"
        "a = json.load(sys.stdin)\n"
        "assert not _kernels.available()\n"
        "s = sm.fit_shadow(sm.SpotLight(*(np.array(v) for v in a['spot'])),\n"
        "                  sm.Triangles(np.array(a['tris'])), 256)\n"
        "print(json.dumps([s.blocker_to_clip.tolist(), int(s.casters_used)]))\n"
    )
    data = json.dumps({"spot": [np.asarray(v).tolist() for v in spot], "tris": tris.tolist()})
    env = {**os.environ, "SHADOWMATH_NUMBA": "0"}
    proc = subprocess.run(
        [sys.executable, "-c", code], input=data, env=env, capture_output=True, text=True,
        check=True, timeout=120,
    )  # fmt: skip
    clip, used = json.loads(proc.stdout)
    fast = sm.fit_shadow(spot, sm.Triangles(tris), 256)
    assert used == int(fast.casters_used)
    np.testing.assert_allclose(fast.blocker_to_clip, np.array(clip), rtol=1e-12, atol=1e-12)


@pytest.mark.parametrize("path", ["compiled", "array"])
def test_every_triangle_behind_or_outside_gives_the_empty_fit(path: str) -> None:
    spot, _ = _scene()
    light = np.r_[spot.position, spot.direction, np.tan(spot.angle), spot.angle]
    rng = np.random.default_rng(2)
    tris = _triangles(rng, ["behind", "outside"] * 5, light)
    with _kernels.disabled() if path == "array" else contextlib.nullcontext():
        s = sm.fit_shadow(spot, sm.Triangles(tris), 64)
    assert int(s.casters_used) == 0
    assert np.isfinite(s.blocker_to_clip).all()
