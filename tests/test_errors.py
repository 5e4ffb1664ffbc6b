"""Every bad-input condition: a ValueError naming the argument and the problem with NumPy,
NaN outputs (never a finite wrong matrix) under jax.jit, jax.vmap and jax.grad, and the
specific message back through jax.experimental.checkify.

Conditions from issue 2's "Bad input" list and issue 5: wrong shapes, non-finite values,
a plane with a zero normal, a light in the plane (point or directional), a zero
directional light, an empty vertex set, the light at the blocker's centroid (zero MDV),
a blocker vertex not strictly in front of the light, a zero silhouette, a map too small
for its border, near >= far, near <= 0, bad frames, frusta and placements.
"""

from __future__ import annotations

import re
import sys
from collections.abc import Callable
from typing import Any, NamedTuple

import jax
import jax.numpy as jnp
import numpy as np
import pytest
from jax.experimental import checkify

import shadowmath as sm

PLANE = np.array([0.0, 1.0, 0.0, 2.0])
LIGHT4 = np.array([0.3, 5.0, 0.1, 1.0])
LIGHT = np.array([0.5, -0.3, 0.0])
VERTS = np.random.default_rng(5).normal(size=(12, 3)) + [0.0, 0.0, 8.0]
FRAME = sm.light_frame(LIGHT, VERTS)
FRUSTUM = sm.Frustum(
    rx_max=np.array(0.5),
    ry_max=np.array(0.25),
    near=np.array(1.0),
    far=np.array(3.0),
    margin_x=np.array(0.98),
    margin_y=np.array(0.98),
)


CAMERA_VIEW = np.array([[1.0, 0, 0, 0], [0, 1, 0, -2], [0, 0, 1, 0], [0, 0, 0, 1]])
CAMERA = np.array([[1.2, 0, 0, 0], [0, 1.8, 0, 0], [0, 0, -1.0006, -0.20006], [0, 0, -1, 0]])
SCENE_BOX = np.array([[-50.0, -5, -50], [50, 5, 50]])
FLOOR = np.array([[[-30.0, -3, -30], [30, -3, -30], [30, -3, 30]],
                  [[-30.0, -3, -30], [30, -3, 30], [-30, -3, 30]]]) + [0.0, 0.0, 8.0]  # fmt: skip


def _cascades(light: Any, projection: Any) -> tuple[Any, ...]:
    c = sm.fit_cascades(light, CAMERA_VIEW, projection, SCENE_BOX, 64)
    return c.world_to_clip, c.world_to_texture, c.splits


def _with(a: np.ndarray, index: Any, value: float) -> np.ndarray:
    out = np.array(a, dtype=float)
    out[index] = value
    return out


def _frame_with(field: str, value: np.ndarray) -> sm.LightFrame:
    return FRAME._replace(**{field: value})


def _matrix_leaves(result: Any) -> list[Any]:
    """The outputs a failed check must turn into NaN."""
    if isinstance(result, sm.ShadowSetup):
        # world_to_light stays finite when only the frustum failed: the frame is valid.
        return [result.blocker_to_clip, result.world_to_texture]
    if isinstance(result, sm.Frustum):
        return [result.rx_max, result.ry_max, result.near, result.far]
    if isinstance(result, tuple):
        return list(result)
    return [result]


class Case(NamedTuple):
    fn: Callable[..., Any]
    bad: tuple[Any, ...]
    good: tuple[Any, ...]
    message: tuple[str, ...]  # fragments: the argument's name and the problem


# Conditions on values: ValueError with NumPy, NaN under transformations.
VALUE_CASES = {
    "planar: non-finite plane": Case(
        sm.planar_projection, (_with(PLANE, 1, np.nan), LIGHT4), (PLANE, LIGHT4),
        ("plane:", "non-finite"),
    ),
    "planar: non-finite light": Case(
        sm.planar_projection, (PLANE, _with(LIGHT4, 0, np.inf)), (PLANE, LIGHT4),
        ("light:", "non-finite"),
    ),
    "planar: zero normal": Case(
        sm.planar_projection, (np.array([0.0, 0.0, 0.0, 2.0]), LIGHT4), (PLANE, LIGHT4),
        ("plane:", "normal (a, b, c) is zero"),
    ),
    "planar: zero directional light": Case(
        sm.planar_projection, (PLANE, np.zeros(4)), (PLANE, LIGHT4),
        ("light:", "all components are zero", "directional light"),
    ),
    "planar: point light on the plane": Case(
        sm.planar_projection, (PLANE, np.array([3.0, -2.0, 7.0, 1.0])), (PLANE, LIGHT4),
        ("light lies in the plane", "move the light"),
    ),
    "planar: directional light parallel to the plane": Case(
        sm.planar_projection, (PLANE, np.array([1.0, 0.0, -2.0, 0.0])), (PLANE, LIGHT4),
        ("light lies in the plane", "directional light parallel"),
    ),
    "mdv: non-finite vertex": Case(
        sm.mean_direction_vector, (LIGHT, _with(VERTS, (3, 1), np.nan)), (LIGHT, VERTS),
        ("vertices:", "non-finite"),
    ),
    "mdv: non-finite light": Case(
        sm.mean_direction_vector, (_with(LIGHT, 2, -np.inf), VERTS), (LIGHT, VERTS),
        ("light_position:", "non-finite"),
    ),
    "helper_axis: non-finite": Case(
        sm.helper_axis, (np.array([0.1, np.nan, 0.3]),), (np.array([0.1, 0.2, 0.3]),),
        ("z_axis:", "non-finite"),
    ),
    "light_frame: light at the centroid": Case(
        sm.light_frame, (VERTS.mean(axis=0), VERTS), (LIGHT, VERTS),
        ("viewing direction is zero", "centre"),
    ),
    "light_frame: non-finite vertex": Case(
        sm.light_frame, (LIGHT, _with(VERTS, (0, 0), np.inf)), (LIGHT, VERTS),
        ("vertices:", "non-finite"),
    ),
    "light_frame_from_direction: zero direction": Case(
        sm.light_frame_from_direction, (LIGHT, np.zeros(3)), (LIGHT, np.array([0.0, 0, 1])),
        ("viewing direction is zero",),
    ),
    "light_frame_from_direction: non-finite direction": Case(
        sm.light_frame_from_direction, (LIGHT, np.array([0.0, np.nan, 1])),
        (LIGHT, np.array([0.0, 0, 1])), ("direction:", "non-finite"),
    ),
    "world_to_light: non-finite frame axis": Case(
        sm.world_to_light, (_frame_with("x_axis", np.array([np.nan, 0, 0])),), (FRAME,),
        ("frame.x_axis:", "non-finite"),
    ),
    "light_to_world: non-finite frame origin": Case(
        sm.light_to_world, (_frame_with("origin", np.array([np.inf, 0, 0])),), (FRAME,),
        ("frame.origin:", "non-finite"),
    ),
    "frustum: vertex behind the light": Case(
        lambda f, v: sm.adaptive_frustum(f, v, 64),
        (FRAME, np.concatenate([VERTS, [2 * LIGHT - VERTS[0]]])),
        (FRAME, np.concatenate([VERTS, VERTS[:1]])),
        ("vertices:", "not strictly in front of the light"),
    ),
    "frustum: vertex at the light": Case(
        lambda f, v: sm.adaptive_frustum(f, v, 64),
        (FRAME, np.concatenate([VERTS, [LIGHT]])),
        (FRAME, np.concatenate([VERTS, VERTS[:1]])),
        ("vertices:", "not strictly in front of the light"),
    ),
    "frustum: zero silhouette (a point on the axis)": Case(
        lambda f, v: sm.adaptive_frustum(f, v, 64),
        (FRAME, np.repeat((LIGHT + 4 * FRAME.z_axis)[None], 13, axis=0)),
        (FRAME, np.concatenate([VERTS, VERTS[:1]])),
        ("vertices:", "zero width or height"),
    ),
    "frustum: near <= 0": Case(
        lambda f, v, n: sm.adaptive_frustum(f, v, 64, near=n),
        (FRAME, VERTS, np.array(0.0)), (FRAME, VERTS, np.array(0.5)),
        ("near:", "near > 0"),
    ),
    "frustum: near inside the blocker": Case(
        lambda f, v, n: sm.adaptive_frustum(f, v, 64, near=n),
        (FRAME, VERTS, np.array(8.0)), (FRAME, VERTS, np.array(0.5)),
        ("near:", "cuts into the blocker"),
    ),
    "fit_shadow: far inside the blocker": Case(
        lambda L, V, fa: sm.fit_shadow(L, V, 64, far=fa),
        (LIGHT, VERTS, np.array(8.0)), (LIGHT, VERTS, np.array(40.0)),
        ("far:", "cuts into the blocker"),
    ),
    "frustum: near >= far": Case(
        lambda f, v, n, fa: sm.adaptive_frustum(f, v, 64, near=n, far=fa),
        (FRAME, VERTS, np.array(5.0), np.array(4.0)),
        (FRAME, VERTS, np.array(0.5), np.array(40.0)),
        ("near/far:", "closer than the far plane"),
    ),
    "frustum: non-finite far": Case(
        lambda f, v, fa: sm.adaptive_frustum(f, v, 64, far=fa),
        (FRAME, VERTS, np.array(np.inf)), (FRAME, VERTS, np.array(40.0)),
        ("far:", "finite"),
    ),
    "blocker_projection: rx_max <= 0": Case(
        sm.blocker_projection, (FRUSTUM._replace(rx_max=np.array(0.0)),), (FRUSTUM,),
        ("frustum", "rx_max and ry_max must be > 0"),
    ),
    "blocker_projection: near <= 0": Case(
        sm.blocker_projection, (FRUSTUM._replace(near=np.array(-1.0)),), (FRUSTUM,),
        ("frustum.near:", "> 0"),
    ),
    "receiver_projection: near >= far": Case(
        sm.receiver_projection, (FRUSTUM._replace(far=np.array(1.0)),), (FRUSTUM,),
        ("frustum:", "near must be < far"),
    ),
    "receiver_projection: non-finite field": Case(
        sm.receiver_projection, (FRUSTUM._replace(ry_max=np.array(np.nan)),), (FRUSTUM,),
        ("frustum.ry_max:", "finite"),
    ),
    "fit_shadow: light at the centroid": Case(
        lambda L, V: sm.fit_shadow(L, V, 128), (VERTS.mean(axis=0), VERTS), (LIGHT, VERTS),
        ("viewing direction is zero",),
    ),
    "fit_shadow: light inside the blocker": Case(
        lambda L, V: sm.fit_shadow(L, V, 128),
        (VERTS.mean(axis=0) + [0.0, 0.0, 0.1], VERTS), (LIGHT, VERTS),
        ("not strictly in front of the light",),
    ),
    "fit_shadow: non-finite blocker_to_world": Case(
        lambda L, V, B: sm.fit_shadow(L, V, 128, blocker_to_world=B),
        (LIGHT, VERTS, _with(np.eye(4), (0, 3), np.nan)), (LIGHT, VERTS, np.eye(4)),
        ("blocker_to_world:", "non-finite"),
    ),
    "fit_shadow: non-finite vertex under a placement": Case(
        lambda L, V, B: sm.fit_shadow(L, V, 128, blocker_to_world=B),
        (LIGHT, _with(VERTS, (2, 2), np.inf), np.eye(4)), (LIGHT, VERTS, np.eye(4)),
        ("blocker_vertices:", "non-finite"),
    ),
    "fit_shadow: projective placement with w <= 0": Case(
        lambda L, V, B: sm.fit_shadow(L, V, 128, blocker_to_world=B),
        (LIGHT, VERTS, _with(np.eye(4), (3, 2), -1.0)), (LIGHT, VERTS, np.eye(4)),
        ("blocker_to_world:", "last row is not (0, 0, 0, 1)", "projective"),
    ),
    "fit_shadow: row-major placement": Case(
        lambda L, V, B: sm.fit_shadow(L, V, 128, blocker_to_world=B),
        (LIGHT, VERTS, _with(np.eye(4), (3, 0), 0.5)),
        (LIGHT, VERTS, _with(np.eye(4), (0, 3), 0.5)),
        ("blocker_to_world:", "row-major", "transpose"),
    ),
    "smooth_max: temperature <= 0": Case(
        sm.smooth_max, (np.array([0.0, 1.0]), np.array(0.0)),
        (np.array([0.0, 1.0]), np.array(0.1)), ("temperature:", "> 0"),
    ),
    "smooth_frustum: non-finite temperature": Case(
        lambda f, v, t: sm.smooth_frustum(f, v, 64, temperature=t),
        (FRAME, VERTS, np.array(np.nan)), (FRAME, VERTS, np.array(0.01)),
        ("temperature:", "finite"),
    ),
    "offcenter_frustum: vertex behind the light": Case(
        lambda f, v: sm.offcenter_frustum(f, v, 64),
        (FRAME, np.concatenate([VERTS, [2 * LIGHT - VERTS[0]]])),
        (FRAME, np.concatenate([VERTS, VERTS[:1]])),
        ("vertices:", "not strictly in front of the light"),
    ),
    "rolled_light_frame: up parallel to the direction": Case(
        lambda L, d, r: sm.rolled_light_frame(L, d, r),
        (LIGHT, np.array([0.0, -2.0, 0.0]), np.array(0.3)),
        (LIGHT, np.array([0.0, 0.0, 1.0]), np.array(0.3)),
        ("up:", "parallel to the direction"),
    ),
    "rolled_light_frame: zero direction": Case(
        lambda L, d, r: sm.rolled_light_frame(L, d, r),
        (LIGHT, np.zeros(3), np.array(0.3)), (LIGHT, np.array([0.0, 0.0, 1.0]), np.array(0.3)),
        ("direction:", "zero"),
    ),
    "fit_shadow: zero directional light": Case(
        lambda d, V: sm.fit_shadow(sm.DirectionalLight(d), V, 64), (np.zeros(3), VERTS),
        (np.array([0.2, 0.3, -1.0]), VERTS), ("light:", "zero directional light"),
    ),
    "fit_shadow: up parallel to the light direction": Case(
        lambda d, V, U: sm.fit_shadow(sm.DirectionalLight(d), V, 64, up=U),
        (np.array([0.0, 0.0, 1.0]), VERTS, np.array([0.0, 0.0, 2.0])),
        (np.array([0.0, 0.0, 1.0]), VERTS, np.array([0.0, 1.0, 0.0])),
        ("up:", "parallel"),
    ),
    "fit_shadow: non-finite receiver": Case(
        lambda L, V, R: sm.fit_shadow(L, V, 64, receivers=R),
        (LIGHT, VERTS, _with(VERTS, (0, 0), np.nan)), (LIGHT, VERTS, VERTS + [0, 0, 3.0]),
        ("receivers:", "non-finite"),
    ),
    "fit_shadow: directional light with a vertex at NaN": Case(
        lambda d, V: sm.fit_shadow(sm.DirectionalLight(d), V, 64), (np.array([0.2, 0.3, -1.0]),
        _with(VERTS, (1, 2), np.nan)), (np.array([0.2, 0.3, -1.0]), VERTS),
        ("blocker_vertices:", "non-finite"),
    ),
    "fit_cascades: transposed projection": Case(
        _cascades, (LIGHT, CAMERA.T), (LIGHT, CAMERA), ("projection:", "last row is neither"),
    ),
    "receiver_texture_matrix: non-finite receiver_to_world": Case(
        lambda L, V, R: sm.receiver_texture_matrix(sm.fit_shadow(L, V, 64), R),
        (LIGHT, VERTS, _with(np.eye(4), (2, 2), np.inf)), (LIGHT, VERTS, np.eye(4)),
        ("receiver_to_world:", "non-finite"),
    ),
    "receiver_texture_matrix: row-major receiver_to_world": Case(
        lambda L, V, R: sm.receiver_texture_matrix(sm.fit_shadow(L, V, 64), R),
        (LIGHT, VERTS, _with(np.eye(4), (3, 1), 2.0)),
        (LIGHT, VERTS, _with(np.eye(4), (1, 3), 2.0)),
        ("receiver_to_world:", "row-major", "transpose"),
    ),
}  # fmt: skip


@pytest.mark.parametrize("case", VALUE_CASES.values(), ids=VALUE_CASES.keys())
def test_numpy_raises_a_value_error_naming_the_argument_and_the_problem(case: Case) -> None:
    with pytest.raises(ValueError, match=re.escape(case.message[0])) as info:
        case.fn(*case.bad)
    for fragment in case.message:
        assert fragment in str(info.value), (fragment, str(info.value))
    for leaf in _matrix_leaves(case.fn(*case.good)):  # the valid twin passes
        assert np.all(np.isfinite(leaf))


def _jax(tree: Any) -> Any:
    return jax.tree_util.tree_map(jnp.asarray, tree)


def _good_then_bad(case: Case) -> Any:
    """The valid and the invalid arguments stacked into a batch of two."""

    return jax.tree_util.tree_map(lambda g, b: jnp.stack([g, b]), _jax(case.good), _jax(case.bad))


def _all_nan(leaves: list[Any]) -> bool:
    return all(bool(jnp.all(jnp.isnan(leaf))) for leaf in leaves)


@pytest.mark.parametrize("case", VALUE_CASES.values(), ids=VALUE_CASES.keys())
def test_jit_gives_nan_never_a_finite_wrong_result(case: Case) -> None:
    result = jax.jit(case.fn)(*_jax(case.bad))
    assert _all_nan(_matrix_leaves(result))
    good = jax.jit(case.fn)(*_jax(case.good))
    for leaf, ref in zip(_matrix_leaves(good), _matrix_leaves(case.fn(*case.good)), strict=True):
        np.testing.assert_allclose(np.asarray(leaf), ref, rtol=1e-12, atol=1e-12)


@pytest.mark.parametrize("case", VALUE_CASES.values(), ids=VALUE_CASES.keys())
def test_vmap_poisons_only_the_bad_batch_entry(case: Case) -> None:
    stacked = _good_then_bad(case)
    result = jax.vmap(case.fn)(*stacked)
    for leaf in _matrix_leaves(result):
        assert bool(jnp.all(jnp.isfinite(leaf[0])))
        assert bool(jnp.all(jnp.isnan(leaf[1])))


@pytest.mark.parametrize("case", VALUE_CASES.values(), ids=VALUE_CASES.keys())
def test_grad_sees_nan_values_and_keeps_valid_gradients_finite(case: Case) -> None:
    def loss(*args: Any) -> Any:
        leaves = _matrix_leaves(case.fn(*args))
        return sum(jnp.sum(jnp.where(jnp.isfinite(x), x, 0.0)) for x in leaves)

    def raw(*args: Any) -> Any:
        return sum(jnp.sum(x) for x in _matrix_leaves(case.fn(*args)))

    # allow_int: an integer leaf (casters_used) has a float0 cotangent.
    assert bool(jnp.isnan(jax.value_and_grad(raw, allow_int=True)(*_jax(case.bad))[0]))
    stacked = _good_then_bad(case)
    argnums = tuple(range(len(case.bad)))
    grads = jax.vmap(jax.grad(loss, argnums=argnums, allow_int=True))(*stacked)
    for g in _float_leaves(grads):
        assert bool(jnp.all(jnp.isfinite(g[0]))), "NaN leaked into a valid entry's gradient"


@pytest.mark.parametrize("case", VALUE_CASES.values(), ids=VALUE_CASES.keys())
def test_checkify_reports_the_specific_message(case: Case) -> None:
    err, _ = checkify.checkify(jax.jit(case.fn))(*_jax(case.bad))
    message = err.get()
    assert message is not None
    for fragment in case.message:
        assert fragment in message, (fragment, message)
    err, _ = checkify.checkify(jax.jit(case.fn))(*_jax(case.good))
    assert err.get() is None


# Conditions on shapes and static arguments: ValueError everywhere, under jit too.
STATIC_CASES: dict[str, tuple[Callable[[], Any], tuple[str, ...]]] = {
    "fit_shadow: empty blocker": (
        lambda: sm.fit_shadow(LIGHT, VERTS[:0], 64),
        ("blocker_vertices:", "the vertex set is empty (N = 0)")),
    "fit_shadow: blocker of 2 numbers": (
        lambda: sm.fit_shadow(LIGHT, VERTS[:, :2], 64),
        ("blocker_vertices:", "(*batch, N, 3)", "(12, 2)")),
    "optimize_frustum: empty vertex set": (
        lambda: sm.optimize_frustum(LIGHT, VERTS[:0], 64), ("vertices:", "empty")),
    "fit_shadow: receivers of 2 numbers": (
        lambda: sm.fit_shadow(LIGHT, VERTS, 64, receivers=VERTS[:, :2]),
        ("receivers:", "(*batch, N, 3)")),
    "fit_shadow: unknown api": (
        lambda: sm.fit_shadow(LIGHT, VERTS, 64, api="gles"), ("api:", "'webgpu'")),
    "fit_shadow: light of 5 numbers": (
        lambda: sm.fit_shadow(np.zeros(5), VERTS, 64), ("light:", "(*batch, 3)")),
    "fit_shadow: up of 2 numbers": (
        lambda: sm.fit_shadow(LIGHT, VERTS, 64, up=np.ones(2)), ("up:", "(*batch, 3)")),
    "planar: plane of 3 numbers": (
        lambda: sm.planar_projection(PLANE[:3], LIGHT4), ("plane:", "(*batch, 4)", "(3,)")),
    "planar: light without w": (
        lambda: sm.planar_projection(PLANE, LIGHT4[:3]), ("light:", "(*batch, 4)", "w=1")),
    "planar: batches that do not broadcast": (
        lambda: sm.planar_projection(np.tile(PLANE, (2, 1)), np.tile(LIGHT4, (3, 1))),
        ("do not broadcast", "plane (2,)", "light (3,)")),
    "mdv: vertices without a vertex axis": (
        lambda: sm.mean_direction_vector(LIGHT, VERTS[0]), ("vertices:", "(*batch, N, 3)")),
    "mdv: empty vertex set": (
        lambda: sm.mean_direction_vector(LIGHT, VERTS[:0]), ("vertices:", "empty")),
    "light_frame: empty vertex set": (
        lambda: sm.light_frame(LIGHT, np.zeros((0, 3))), ("vertices:", "empty")),
    "light_frame: 2-d light": (
        lambda: sm.light_frame(LIGHT[:2], VERTS), ("light_position:", "(*batch, 3)")),
    "light_frame: unknown aim": (
        lambda: sm.light_frame(LIGHT, VERTS, aim="centre"), ("aim:", "'mean' or 'bbox'")),  # type: ignore[arg-type]
    "helper_axis: 4 components": (lambda: sm.helper_axis(np.ones(4)), ("z_axis:", "(*batch, 3)")),
    "world_to_light: not a frame": (
        lambda: sm.world_to_light((LIGHT, LIGHT)), ("frame:", "LightFrame")),  # type: ignore[arg-type]
    "frustum: empty vertex set": (
        lambda: sm.adaptive_frustum(FRAME, VERTS[:0], 64), ("vertices:", "empty")),
    "frustum: map too small for its border": (
        lambda: sm.adaptive_frustum(FRAME, VERTS, 2), ("map_size:", "2x2", "at least 3")),
    "frustum: map too small for a wide border": (
        lambda: sm.adaptive_frustum(FRAME, VERTS, (64, 8), border_texels=4),
        ("map_size:", "64x8", "at least 9")),
    "frustum: zero texels": (
        lambda: sm.adaptive_frustum(FRAME, VERTS, 0), ("map_size:", "positive")),
    "frustum: fractional texels": (
        lambda: sm.adaptive_frustum(FRAME, VERTS, 64.5), ("map_size:", "an integer")),  # type: ignore[arg-type]
    "frustum: negative border": (
        lambda: sm.adaptive_frustum(FRAME, VERTS, 64, border_texels=-1),
        ("border_texels:", ">= 0")),
    "frustum: margin above 1": (
        lambda: sm.adaptive_frustum(FRAME, VERTS, 64, margin=1.5), ("margin:", "(0, 1]")),
    "blocker_projection: not a frustum": (
        lambda: sm.blocker_projection((1.0, 2.0)), ("frustum:", "Frustum")),  # type: ignore[arg-type]
    "fit_shadow: stable point light without up": (
        lambda: sm.fit_shadow(LIGHT, VERTS, 64, stable=True), ("up:", "stable=True")),
    "fit_shadow: near for a directional light": (
        lambda: sm.fit_shadow(sm.DirectionalLight(LIGHT), VERTS, 64, near=1.0),
        ("near/far:", "placed by the fit")),
    "fit_shadow: mixed point and directional lights": (
        lambda: sm.fit_shadow(np.array([[0, 0, 1, 0], [0, 0, 0, 1.0]]), VERTS, 64),
        ("light:", "mixes point lights")),
    "fit_shadow: spec and keyword options": (
        lambda: sm.fit_shadow(LIGHT, VERTS, sm.ShadowMapSpec(64), api="vulkan"),
        ("api:", "set them in the spec")),
    "fit_shadow: map too small": (
        lambda: sm.fit_shadow(LIGHT, VERTS, 1), ("map_size:", "1x1")),
    "fit_shadow: placement not 4x4": (
        lambda: sm.fit_shadow(LIGHT, VERTS, 64, blocker_to_world=np.eye(3)),
        ("blocker_to_world:", "(*batch, 4, 4)")),
    "receiver_texture_matrix: not 4x4": (
        lambda: sm.receiver_texture_matrix(sm.fit_shadow(LIGHT, VERTS, 64), np.eye(3)),
        ("receiver_to_world:", "(*batch, 4, 4)")),
    "fit_shadow: raw triangles as receivers": (
        lambda: sm.fit_shadow(LIGHT, VERTS, 64, receivers=FLOOR),
        ("receivers:", "batch shape (2,)", "sm.Triangles")),
    "cube_depth_range: raw triangles as receivers": (
        lambda: sm.cube_depth_range(LIGHT, VERTS, receivers=FLOOR),
        ("receivers:", "batch shape (2,)", "sm.Triangles")),
    "fit_cascades: spec beside keywords": (
        lambda: sm.fit_cascades(LIGHT, CAMERA_VIEW, CAMERA, SCENE_BOX, sm.ShadowMapSpec(64),
                                api="vulkan", stable=True),
        ("api, stable:", "given both in the ShadowMapSpec")),
    "allocate_atlas: coverage strings": (
        lambda: sm.allocate_atlas(["0.5"]), ("coverage:", "expected real numbers")),
    "column_major_bytes: not 4x4": (
        lambda: sm.column_major_bytes(np.eye(3)), ("matrix:", "(*batch, 4, 4)")),
    "column_major_bytes: NaN from upstream": (
        lambda: sm.column_major_bytes(np.full((4, 4), np.nan)), ("matrix:", "non-finite")),
    "check_finite: NaN output": (
        lambda: sm.check_finite(sm.Frustum(*(np.array([1.0, np.nan]),) * 6), name="fr"),
        ("fr.rx_max:", "NaN", "(1,)")),
}  # fmt: skip


@pytest.mark.parametrize("call", STATIC_CASES.values(), ids=STATIC_CASES.keys())
def test_static_conditions_raise(call: tuple[Callable[[], Any], tuple[str, ...]]) -> None:
    fn, fragments = call
    with pytest.raises(ValueError, match=re.escape(fragments[0])) as info:
        fn()
    for fragment in fragments:
        assert fragment in str(info.value), (fragment, str(info.value))


@pytest.mark.parametrize(
    "fn",
    [
        lambda p, L: sm.planar_projection(p[:3], L),
        lambda p, L: sm.fit_shadow(L[:3], jnp.zeros((0, 3)), 64),
        lambda p, L: sm.fit_shadow(L[:3], jnp.ones((4, 3)), 2),
        lambda p, L: sm.fit_shadow(L, jnp.ones((4, 3)), 64),
        lambda p, L: sm.fit_shadow(L[:3], jnp.ones((4, 3)), 64, receivers=jnp.asarray(FLOOR)),
    ],
    ids=["shape", "empty vertex set", "map too small", "homogeneous light", "raw triangles"],
)
def test_static_conditions_raise_under_jit_too(fn: Callable[..., Any]) -> None:
    with pytest.raises(ValueError, match=r"plane:|vertices:|map_size:|light:|receivers:"):
        jax.jit(fn)(jnp.asarray(PLANE), jnp.asarray(LIGHT4))


def test_check_finite_under_jit_needs_checkify_and_then_reports() -> None:
    def fitted(L: Any, V: Any) -> Any:
        return sm.check_finite(sm.fit_shadow(L, V, 64), name="setup")

    with pytest.raises(ValueError, match="checkify"):
        jax.jit(fitted)(jnp.asarray(LIGHT), jnp.asarray(VERTS))
    err, _ = checkify.checkify(jax.jit(fitted))(jnp.asarray(VERTS.mean(0)), jnp.asarray(VERTS))
    assert err.get() is not None
    err, setup = checkify.checkify(jax.jit(fitted))(jnp.asarray(LIGHT), jnp.asarray(VERTS))
    assert err.get() is None
    assert bool(jnp.all(jnp.isfinite(setup.blocker_to_clip)))


def _float_leaves(tree: Any) -> list[Any]:
    return [x for x in jax.tree_util.tree_leaves(tree) if jnp.issubdtype(x.dtype, jnp.floating)]


@pytest.mark.parametrize("case", VALUE_CASES.values(), ids=VALUE_CASES.keys())
def test_grad_is_nan_where_the_value_is_nan(case: Case) -> None:
    """The promise holds for derivatives too: an invalid input never gets a finite gradient.

    (A zero gradient at an invalid configuration would stall an optimizer silently.)
    """
    bad = _jax(case.bad)

    def raw(*args: Any) -> Any:
        return sum(jnp.sum(x) for x in _matrix_leaves(case.fn(*args)))

    value, grads = jax.value_and_grad(raw, argnums=tuple(range(len(bad))), allow_int=True)(*bad)
    assert bool(jnp.isnan(value))
    leaves = _float_leaves(grads)
    assert leaves
    for g in leaves:
        assert bool(jnp.any(jnp.isnan(g))), "a finite gradient at an invalid input"


def test_optimized_fit_without_jax_names_the_extra(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setitem(sys.modules, "jax", None)  # as if JAX were not installed
    with pytest.raises(ImportError, match=re.escape("pip install 'shadowmath[jax]'")):
        sm.fit_shadow(LIGHT, VERTS, 64, method="optimized")
