"""Inputs of every kind: sequences and scalars, integer and float16 arrays, read-only and
non-contiguous arrays, empty batches; masked, object, complex and ragged input refused;
and no function ever writes into its arguments.
"""

from __future__ import annotations

import warnings
from collections.abc import Callable
from typing import Any

import jax.numpy as jnp
import numpy as np
import pytest

import shadowmath as sm

PLANE = np.array([0.0, 1.0, 0.0, 2.0])
LIGHT4 = np.array([0.5, 6.0, -0.25, 1.0])
LIGHT = np.array([0.5, -0.25, 0.0])
VERTS = np.array(
    [[1.0, 0.5, 6.0], [-1.0, 0.25, 7.0], [0.5, -1.0, 6.5], [0.0, 1.0, 8.0], [-0.5, -0.5, 5.0]]
)


def every_function(plane: Any, light4: Any, light: Any, verts: Any) -> dict[str, Any]:
    """Each public function's array output for the given arguments."""
    frame = sm.light_frame(light, verts)
    frustum = sm.adaptive_frustum(frame, verts, 64)
    setup = sm.fit_shadow(light, verts, 64)
    return {
        "planar_projection": sm.planar_projection(plane, light4),
        "mean_direction_vector": sm.mean_direction_vector(light, verts),
        "helper_axis": sm.helper_axis(frame.z_axis),
        "light_frame.y_axis": frame.y_axis,
        "light_frame_from_direction.x_axis": sm.light_frame_from_direction(
            light, frame.z_axis
        ).x_axis,
        "world_to_light": sm.world_to_light(frame),
        "light_to_world": sm.light_to_world(frame),
        "adaptive_frustum.rx_max": frustum.rx_max,
        "blocker_projection": sm.blocker_projection(frustum),
        "receiver_projection": sm.receiver_projection(frustum),
        "fit_shadow.blocker_to_clip": setup.blocker_to_clip,
        "receiver_texture_matrix": sm.receiver_texture_matrix(
            setup, np.eye(4, dtype=setup.world_to_texture.dtype)
        ),
    }


REFERENCE = every_function(PLANE, LIGHT4, LIGHT, VERTS)


def _assert_same(got: dict[str, Any], rtol: float = 1e-15) -> None:
    for name, want in REFERENCE.items():
        np.testing.assert_allclose(np.asarray(got[name]), want, rtol=rtol, atol=1e-15, err_msg=name)


def test_lists_and_tuples_are_read_as_arrays() -> None:
    _assert_same(
        every_function(
            PLANE.tolist(), tuple(LIGHT4), tuple(LIGHT.tolist()), [tuple(v) for v in VERTS]
        )
    )


def test_scalars_are_accepted_where_a_scalar_is_meant() -> None:
    frame = sm.light_frame(LIGHT, VERTS)
    fr = sm.adaptive_frustum(frame, VERTS, 64, near=1.0, far=np.float32(20.0))
    assert fr.near.dtype == np.float64  # a NumPy float32 scalar does not demote float64 input
    np.testing.assert_allclose([fr.near, fr.far], [1.0, 20.0])
    fr = sm.Frustum(rx_max=0.5, ry_max=0.5, near=1, far=3, margin_x=0.98, margin_y=0.98)
    M = sm.blocker_projection(fr)
    assert M.shape == (4, 4)
    assert M.dtype == np.float64


def test_a_scalar_where_a_vector_is_meant_is_refused() -> None:
    with pytest.raises(ValueError, match=r"z_axis: expected shape \(\*batch, 3\), got \(\)"):
        sm.helper_axis(3.0)
    with pytest.raises(ValueError, match=r"light: expected shape \(\*batch, 4\)"):
        sm.planar_projection(PLANE, 1.0)


@pytest.mark.parametrize("kind", [np.int8, np.int32, np.int64, np.uint16])
def test_integer_arrays_become_float64(kind: Any) -> None:
    plane, light4 = np.array([0, 1, 0, 2], kind), np.array([1, 6, 3, 1], kind)
    M = sm.planar_projection(plane, light4)
    assert M.dtype == np.float64
    np.testing.assert_array_equal(M, sm.planar_projection(plane * 1.0, light4 * 1.0))
    verts = np.array([[1, 0, 6], [3, 2, 7], [0, 1, 5]], kind)
    s = sm.fit_shadow(np.zeros(3, kind), verts, 32)
    assert s.blocker_to_clip.dtype == np.float64


def test_float16_is_promoted_to_float32_documented() -> None:
    # float16 cannot hold a shadow matrix usefully (11-bit mantissa): computed in
    # float32 from the exactly representable float16 values, as the package docstring says.
    h = [a.astype(np.float16) for a in (PLANE, LIGHT4, LIGHT, VERTS)]
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        got = every_function(*h)
    # Each function given only float16 arrays says so (here the first four calls).
    said = [str(w.message) for w in caught if w.category is sm.ShadowFitWarning]
    assert len(said) >= 4
    assert all("float16 is computed and returned in float32" in m for m in said), said
    want = every_function(*(a.astype(np.float32) for a in h))
    for name, value in got.items():
        assert value.dtype == np.float32, name
        np.testing.assert_array_equal(value, want[name], err_msg=name)
    assert "float16 becomes float32" in (sm.__doc__ or "")
    with pytest.warns(sm.ShadowFitWarning, match=r"^plane, light: float16 is computed"):
        assert sm.planar_projection(jnp.asarray(h[0]), jnp.asarray(h[1])).dtype == jnp.float32
    with pytest.warns(sm.ShadowFitWarning, match=r"^light, blocker_vertices: float16 is comp"):
        sm.fit_shadow(h[2], h[3], 64)
    with warnings.catch_warnings():  # float32 or float64 beside float16: computed as given
        warnings.simplefilter("error")
        for other in (np.float32, np.float64):
            sm.planar_projection(PLANE.astype(other), h[1])


def test_read_only_arrays_work() -> None:
    args = [a.copy() for a in (PLANE, LIGHT4, LIGHT, VERTS)]
    for a in args:
        a.flags.writeable = False
    _assert_same(every_function(*args), rtol=0)


def test_non_contiguous_views_give_the_same_results() -> None:
    def strided(a: np.ndarray) -> np.ndarray:
        # Every other element of a twice-as-large buffer, flipped twice: a negative-stride view.
        big = np.zeros((*a.shape[:-1], 2 * a.shape[-1]))
        big[..., ::2] = a[..., ::-1]
        view = big[..., ::2][..., ::-1]
        assert not view.flags.c_contiguous
        return view

    verts_f = np.asfortranarray(VERTS)
    assert not verts_f.flags.c_contiguous
    _assert_same(every_function(strided(PLANE), strided(LIGHT4), strided(LIGHT), verts_f), rtol=0)
    _assert_same(every_function(PLANE, LIGHT4, LIGHT, strided(VERTS)), rtol=0)


@pytest.mark.parametrize("to", [np.asarray, jnp.asarray], ids=["numpy", "jax"])
def test_an_empty_batch_gives_empty_outputs(to: Callable[[Any], Any]) -> None:
    planes, lights4 = to(np.zeros((0, 4))), to(np.zeros((0, 4)))
    lights, verts = to(np.zeros((0, 3))), to(np.zeros((0, 5, 3)))
    assert sm.planar_projection(planes, lights4).shape == (0, 4, 4)
    assert sm.planar_projection(planes, to(LIGHT4)).shape == (0, 4, 4)
    assert sm.mean_direction_vector(lights, verts).shape == (0, 3)
    assert sm.helper_axis(lights).shape == (0, 3)
    frame = sm.light_frame(lights, verts)
    assert all(f.shape == (0, 3) for f in frame)
    assert sm.light_frame_from_direction(lights, lights).z_axis.shape == (0, 3)
    assert sm.world_to_light(frame).shape == (0, 4, 4)
    assert sm.light_to_world(frame).shape == (0, 4, 4)
    frustum = sm.adaptive_frustum(frame, verts, 64)
    assert frustum.rx_max.shape == (0,)
    assert sm.blocker_projection(frustum).shape == (0, 4, 4)
    assert sm.receiver_projection(frustum).shape == (0, 4, 4)
    setup = sm.fit_shadow(lights, verts, 64)
    assert setup.blocker_to_clip.shape == (0, 4, 4)
    assert sm.receiver_texture_matrix(setup, to(np.eye(4))).shape == (0, 4, 4)
    assert sm.column_major_bytes(setup.world_to_texture) == b""


def test_an_empty_batch_still_checks_shapes() -> None:
    with pytest.raises(ValueError, match="vertices: the vertex set is empty"):
        sm.fit_shadow(np.zeros((0, 3)), np.zeros((0, 0, 3)), 64)
    with pytest.raises(ValueError, match=r"plane: expected shape \(\*batch, 4\)"):
        sm.planar_projection(np.zeros((0, 3)), np.zeros((0, 4)))


@pytest.mark.parametrize(
    ("value", "message"),
    [
        (np.ma.masked_array(PLANE, mask=[0, 1, 0, 0]), "masked arrays are not supported"),
        (np.ma.masked_array(PLANE), "masked arrays are not supported"),
        (PLANE.astype(object), "dtype object"),
        (PLANE + 0j, "dtype complex128"),
        (["0", "1", "0", "2"], "dtype <U1"),
        ([[0, 1, 0, 2], [0, 1]], "cannot be read as an array of numbers"),
    ],
    ids=["masked", "masked-no-mask", "object", "complex", "strings", "ragged"],
)
def test_input_without_an_unambiguous_numeric_meaning_is_refused(value: Any, message: str) -> None:
    with pytest.raises(ValueError, match="plane: ") as info:
        sm.planar_projection(value, LIGHT4)
    assert message in str(info.value)


@pytest.mark.parametrize(
    ("map_size", "margins"),
    [
        (np.int64(100), (0.98, 0.98)),
        (np.array([100, 50]), (0.98, 0.96)),
        ([200, 100], (0.99, 0.98)),
    ],
)
def test_map_size_kinds(map_size: Any, margins: tuple[float, float]) -> None:
    assert sm.border_margin(map_size) == margins


@pytest.mark.parametrize("map_size", [True, (64, False), 64.0, np.array([64.5, 32]), "64"])
def test_map_size_that_is_not_an_integer_is_refused(map_size: Any) -> None:
    with pytest.raises(ValueError, match="map_size: "):
        sm.border_margin(map_size)


def test_no_function_writes_into_its_arguments() -> None:
    args = [a.copy() for a in (PLANE, LIGHT4, LIGHT, VERTS)]
    frame = sm.light_frame(args[2], args[3])
    frame_copy = [f.copy() for f in frame]
    every_function(*args)
    frustum = sm.adaptive_frustum(frame, args[3], 64)
    frustum_copy = [np.copy(f) for f in frustum]
    sm.blocker_projection(frustum)
    sm.receiver_projection(frustum)
    sm.world_to_light(frame)
    placement = np.eye(4)
    placement[:3, 3] = [0.1, 0.2, 0.3]
    placement_copy = placement.copy()
    setup = sm.fit_shadow(args[2], args[3], 64, blocker_to_world=placement)
    sm.receiver_texture_matrix(setup, placement)
    sm.column_major_bytes(placement)
    for a, b in zip(args, (PLANE, LIGHT4, LIGHT, VERTS), strict=True):
        np.testing.assert_array_equal(a, b)
    for a, b in [*zip(frame, frame_copy, strict=True), *zip(frustum, frustum_copy, strict=True)]:
        np.testing.assert_array_equal(a, b)
    np.testing.assert_array_equal(placement, placement_copy)
