"""Derivatives of every public function, held to finite differences in float64.

``jax.test_util.check_grads`` compares forward- and reverse-mode derivatives
(first and second order) with central differences, on random well-conditioned
inputs: a blocker a few units across, several units in front of the light, with
no ties among its extreme projection ratios (the maxima are then smooth within
the finite-difference step). Separately, at the points where a function is only
piecewise smooth (ties of ``|x / z|`` maxima, ties in the helper-axis choice,
``abs`` at zero) the gradients must still be finite: never NaN where the value
is fine.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import jax
import jax.numpy as jnp
import numpy as np
import pytest
from jax.test_util import check_grads

import shadowmath as sm

MAP = 128


def _scene(seed: int) -> dict[str, Any]:
    rng = np.random.default_rng(seed)
    light = rng.uniform(-1, 1, 3)
    centre = light + np.array([0.5, -0.4, 6.0]) + rng.uniform(-0.5, 0.5, 3)
    verts = centre + rng.uniform(-1, 1, (8, 3))
    angle = rng.uniform(0, 2 * np.pi)
    c, s = np.cos(angle), np.sin(angle)
    placement = np.array(
        [[c, -s, 0, 0.2], [s, c, 0, -0.1], [0, 0, 1.2, 0.3], [0, 0, 0, 1.0]]
    ) + rng.uniform(-0.05, 0.05, (4, 4)) * np.array([[1, 1, 1, 1]] * 3 + [[0, 0, 0, 0]])
    return {
        "light": jnp.asarray(light),
        "verts": jnp.asarray(verts),
        "local": jnp.asarray(verts - centre),
        # A placement's rows above its last, (0, 0, 0, 1): a placement is affine (a last
        # row off it is refused), so the derivatives are taken along the three rows only.
        "placement": jnp.asarray(placement[:3]),
        "plane": jnp.asarray(np.r_[rng.normal(size=3) + [0, 2, 0], rng.uniform(-1, 1)]),
        "light4": jnp.asarray(np.r_[rng.normal(size=3) * 2 + [0, 8, 0], 1.0]),
        "direction": jnp.asarray(rng.normal(size=3) + [0, 0, 3]),
        "roll": jnp.asarray(rng.uniform(-np.pi, np.pi)),
    }


def _affine(rows: Any) -> Any:
    """The placement of its three rows above the last, ``(0, 0, 0, 1)``."""
    return jnp.concatenate([rows, jnp.asarray([[0.0, 0.0, 0.0, 1.0]], dtype=rows.dtype)])


def _frame_array(f: sm.LightFrame) -> Any:
    return jnp.stack(list(f), axis=-2)


def _frustum_array(fr: sm.Frustum) -> Any:
    return jnp.stack([jnp.asarray(v) for v in fr], axis=-1)


def _frustum_fields(frame_fn: Callable[..., sm.LightFrame]) -> Callable[..., Any]:
    def f(light: Any, verts: Any) -> Any:
        frame = frame_fn(light, verts)
        return _frustum_array(sm.adaptive_frustum(frame, verts, MAP))

    return f


def _texel(points: Any, normals: Any, light: Any) -> Any:
    setup = sm.fit_shadow(light, jnp.asarray(_scene(0)["verts"]), MAP)
    return sm.receiver_texel_size(setup.world_to_texture, points, normals, MAP)


# Each case: a function of JAX arrays and the names of its arguments in _scene.
CASES: dict[str, tuple[Callable[..., Any], tuple[str, ...]]] = {
    "planar_projection": (sm.planar_projection, ("plane", "light4")),
    "mean_direction_vector": (sm.mean_direction_vector, ("light", "verts")),
    "light_frame": (lambda p, v: _frame_array(sm.light_frame(p, v)), ("light", "verts")),
    "light_frame_bbox": (
        lambda p, v: _frame_array(sm.light_frame(p, v, aim="bbox")),
        ("light", "verts"),
    ),
    "light_frame_from_direction": (
        lambda p, d: _frame_array(sm.light_frame_from_direction(p, d)),
        ("light", "direction"),
    ),
    "world_to_light": (
        lambda p, d: sm.world_to_light(sm.light_frame_from_direction(p, d)),
        ("light", "direction"),
    ),
    "light_to_world": (
        lambda p, d: sm.light_to_world(sm.light_frame_from_direction(p, d)),
        ("light", "direction"),
    ),
    "adaptive_frustum": (_frustum_fields(sm.light_frame), ("light", "verts")),
    "offcenter_frustum": (
        lambda p, v: _frustum_array(sm.offcenter_frustum(sm.light_frame(p, v), v, MAP)),
        ("light", "verts"),
    ),
    "smooth_frustum": (
        lambda p, v: _frustum_array(
            sm.smooth_frustum(sm.light_frame(p, v), v, MAP, temperature=0.02)
        ),
        ("light", "verts"),
    ),
    "smooth_frustum_offcenter": (
        lambda p, v: _frustum_array(
            sm.smooth_frustum(sm.light_frame(p, v), v, MAP, temperature=0.02, symmetric=False)
        ),
        ("light", "verts"),
    ),
    "blocker_projection": (
        lambda p, v: sm.blocker_projection(sm.offcenter_frustum(sm.light_frame(p, v), v, MAP)),
        ("light", "verts"),
    ),
    "receiver_projection": (
        lambda p, v: sm.receiver_projection(sm.offcenter_frustum(sm.light_frame(p, v), v, MAP)),
        ("light", "verts"),
    ),
    "cross_section_area": (
        lambda p, v: sm.cross_section_area(sm.offcenter_frustum(sm.light_frame(p, v), v, MAP)),
        ("light", "verts"),
    ),
    "fit_shadow": (
        lambda p, v, b: jnp.stack(
            [
                (s := sm.fit_shadow(p, v, MAP, blocker_to_world=_affine(b))).blocker_to_clip,
                s.world_to_texture,
            ]
        ),
        ("light", "local", "placement"),
    ),
    "receiver_texture_matrix": (
        lambda p, b: sm.receiver_texture_matrix(
            sm.fit_shadow(p, _scene(0)["verts"], MAP), _affine(b)
        ),
        ("light", "placement"),
    ),
    "smooth_max": (lambda v: sm.smooth_max(v[:, 0], 0.3), ("verts",)),
    "rolled_light_frame": (
        lambda p, d, r: _frame_array(sm.rolled_light_frame(p, d, r)),
        ("light", "direction", "roll"),
    ),
    "rolled_light_frame_up": (
        lambda d, u: _frame_array(sm.rolled_light_frame(jnp.zeros(3), d, 0.3, up=u)),
        ("direction", "light4"),
    ),
    "receiver_texel_size": (
        lambda q, n: _texel(q + jnp.array([0.0, 0.0, 9.0]), n, jnp.zeros(3)),
        ("light", "direction"),
    ),
}


# Second order for every pipeline, forward over forward and reverse over reverse
# (about 35 s on two CPU cores).
SECOND_ORDER = tuple(sorted(CASES))


def _args(name: str, seed: int) -> tuple[Any, ...]:
    scene = _scene(seed)
    if name == "rolled_light_frame_up":
        return (scene["direction"], scene["light4"][:3])
    return tuple(scene[a] for a in CASES[name][1])


@pytest.mark.parametrize("name", sorted(CASES))
def test_first_derivatives_match_finite_differences(name: str) -> None:
    fn = CASES[name][0]
    for seed in (1, 3):
        args = _args(name, seed)
        assert np.all(np.isfinite(np.asarray(fn(*args))))
        check_grads(fn, args, order=1, modes=("fwd", "rev"), eps=1e-5, atol=1e-6, rtol=1e-6)


@pytest.mark.parametrize("mode", ["fwd", "rev"])
@pytest.mark.parametrize("name", SECOND_ORDER)
def test_second_derivatives_match_finite_differences(name: str, mode: str) -> None:
    # Forward over forward, and reverse over reverse (mixed modes are left out:
    # each costs as much again).
    fn = CASES[name][0]
    check_grads(fn, _args(name, 1), order=2, modes=(mode,), eps=1e-5, atol=1e-5, rtol=1e-5)


def _all_finite(tree: Any) -> bool:
    return all(bool(jnp.all(jnp.isfinite(leaf))) for leaf in jax.tree_util.tree_leaves(tree))


def _derivatives_finite(fn: Callable[..., Any], *args: Any) -> bool:
    """Forward (random tangents) and reverse (random cotangent) derivatives are finite.

    Random directions rather than whole Jacobians: a NaN anywhere in a Jacobian
    shows up in a random projection of it, and the shapes match check_grads's
    (so the op-by-op compilations are shared).
    """
    rng = np.random.default_rng(7)
    tangents = tuple(jnp.asarray(rng.normal(size=np.shape(a))) for a in args)
    out, jvp_out = jax.jvp(fn, args, tangents)
    _, pullback = jax.vjp(fn, *args)
    cotangents = pullback(jnp.asarray(rng.normal(size=np.shape(out))))
    return _all_finite((out, jvp_out, cotangents))


def _box(half: tuple[float, float, float], centre: tuple[float, float, float]) -> Any:
    corners = [[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)]
    return jnp.asarray(np.array(corners) * half + centre)


def test_maximum_ties_give_finite_gradients() -> None:
    # A box centred on the light's axis: |x / z| ties between +x and -x corners
    # (four vertices share the maximum), and so does |y / z|.
    verts = _box((1.0, 0.5, 0.5), (0.0, 0.0, 5.0))
    light = jnp.zeros(3)

    def rx(p: Any, v: Any) -> Any:
        fr = sm.adaptive_frustum(sm.light_frame_from_direction(p, jnp.array([0.0, 0, 1])), v, MAP)
        return fr.rx_max + fr.ry_max

    assert _derivatives_finite(rx, light, verts)
    # The gradient of the maximum flows to the extreme vertices only: an
    # interior vertex gets none.
    inner = verts.at[0].set(jnp.array([0.1, 0.0, 5.0]))
    grad_v = jax.grad(rx, argnums=1)(light, inner)
    assert np.allclose(grad_v[0], 0.0)
    assert np.any(grad_v[1:] != 0)


def test_abs_at_zero_gives_finite_gradients() -> None:
    # Vertices on the light's axis: x = y = 0 for the first, abs(0) inside the maximum.
    verts = (
        _box((1.0, 0.5, 0.5), (0.3, -0.2, 5.0))
        .at[:2]
        .set(jnp.array([[0.0, 0.0, 5.0], [0.0, 0.7, 4.0]]))
    )

    def f(v: Any) -> Any:
        frame = sm.light_frame_from_direction(jnp.zeros(3), jnp.array([0.0, 0, 1]))
        return _frustum_array(sm.adaptive_frustum(frame, v, MAP))

    assert _derivatives_finite(f, verts)


@pytest.mark.parametrize(
    "direction",
    [(1.0, 1.0, 2.0), (2.0, 1.0, -1.0), (1.0, 1.0, 1.0), (0.0, 0.0, 1.0), (0.0, 1.0, 0.0)],
    ids=["x=y", "y=-z", "all-equal", "x=y=0", "x=z=0"],
)
def test_helper_axis_ties_give_finite_gradients(direction: tuple[float, float, float]) -> None:
    d = jnp.asarray(direction)

    def frame(p: Any, d: Any) -> Any:
        return _frame_array(sm.light_frame_from_direction(p, d))

    assert _derivatives_finite(frame, jnp.ones(3), d)
    # The helper axis itself is piecewise constant: zero derivative.
    _, tangent = jax.jvp(sm.helper_axis, (d,), (jnp.ones(3),))
    assert np.all(tangent == 0)


def test_mdv_frame_at_helper_ties_is_finite() -> None:
    # The mean direction (1, 1, 2) / |.|: the helper-axis test ties between x and y.
    verts = _box((0.5, 0.5, 0.5), (3.0, 3.0, 6.0))
    light = jnp.zeros(3)
    assert np.allclose(sm.helper_axis(sm.mean_direction_vector(light, verts)), [1, 0, 0])
    assert _derivatives_finite(_frustum_fields(sm.light_frame), light, verts)


def test_planar_projection_gradients_at_zero_components() -> None:
    # A point light at the origin (|L_xyz| = 0 enters only the validity check)
    # and a plane with zero components.
    plane, light = jnp.array([0.0, 1.0, 0.0, 2.0]), jnp.array([0.0, 0.0, 0.0, 1.0])
    assert _derivatives_finite(sm.planar_projection, plane, light)


def test_smooth_max_at_ties_and_soft_frustum_on_axis() -> None:
    x = jnp.array([1.0, 1.0, 1.0, -2.0])
    g = jax.grad(sm.smooth_max)(x, 0.1)
    assert _all_finite(g)
    assert np.isclose(float(jnp.sum(g)), 1.0)  # the soft max shifts with a common shift
    verts = _box((1.0, 0.5, 0.5), (0.0, 0.0, 5.0))

    def f(v: Any) -> Any:
        frame = sm.light_frame_from_direction(jnp.zeros(3), jnp.array([0.0, 0, 1]))
        return _frustum_array(sm.smooth_frustum(frame, v, MAP, temperature=0.01))

    assert _derivatives_finite(f, verts)


def test_jit_and_vmap_of_gradients() -> None:
    scene = _scene(2)
    lights = scene["light"] + jnp.linspace(-0.3, 0.3, 4)[:, None]

    def area(p: Any) -> Any:
        frame = sm.rolled_light_frame(p, scene["verts"].mean(0) - p, 0.4)
        return sm.cross_section_area(
            sm.smooth_frustum(frame, scene["verts"], MAP, temperature=0.01)
        )

    batched = jax.jit(jax.vmap(jax.grad(area)))(lights)
    one_by_one = jnp.stack([jax.grad(area)(p) for p in lights])
    assert np.allclose(batched, one_by_one, rtol=1e-10, atol=1e-12)
