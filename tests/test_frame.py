"""The light frame: MDV, helper axis, axes, world-to-light."""

from __future__ import annotations

from typing import Any

import numpy as np
import pytest
from hypothesis import assume, given
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays

from shadowmath import (
    helper_axis,
    light_frame,
    light_frame_from_direction,
    light_to_world,
    mean_direction_vector,
    world_to_light,
)

from .conftest import rtol_for

coords = st.floats(-10, 10, allow_nan=False, width=32)
directions = arrays(np.float64, 3, elements=st.floats(-1, 1, width=32)).filter(
    lambda v: np.linalg.norm(v) > 0.1
)


@st.composite
def light_and_blocker(draw: st.DrawFn) -> tuple[np.ndarray, np.ndarray]:
    """A blocker inside a ball of radius r around its centroid, the light farther than 1.5 r."""
    centre = draw(arrays(np.float64, 3, elements=coords))
    r = draw(st.floats(0.1, 3))
    n = draw(st.integers(1, 12))
    offsets = draw(arrays(np.float64, (n, 3), elements=st.floats(-1, 1, width=32)))
    offsets -= offsets.mean(axis=0)
    offsets *= r / max(np.linalg.norm(offsets, axis=-1).max(), 1.0)
    direction = draw(directions)
    light = centre + direction / np.linalg.norm(direction) * r * draw(st.floats(1.5, 20))
    return light, centre + offsets


def test_helper_axis_article_examples() -> None:
    np.testing.assert_array_equal(helper_axis([0.381, 0.889, 0.254]), [0, 0, 1])
    np.testing.assert_array_equal(helper_axis([-0.889, 0.254, 0.381]), [0, 1, 0])


@pytest.mark.parametrize(
    ("z", "expected"),
    [
        ([1, 1, 1], [1, 0, 0]),  # three-way tie: lowest index
        ([0.9, -0.3, 0.3], [0, 1, 0]),  # tie in size with opposite signs
        ([0.0, 0.0, 1.0], [1, 0, 0]),
        ([0.5, 0.7, -0.1], [0, 0, 1]),
    ],
)
def test_helper_axis_ties_go_to_the_lowest_index(z: list[float], expected: list[int]) -> None:
    np.testing.assert_array_equal(helper_axis(z), expected)


@given(directions)
def test_helper_axis_keeps_the_cross_product_long(to: Any, dtype: Any, d: np.ndarray) -> None:
    z = to(d / np.linalg.norm(d))
    v = np.asarray(helper_axis(z), dtype=np.float64)
    assert v.sum() == 1 and set(np.unique(v)) <= {0.0, 1.0}
    assert np.linalg.norm(np.cross(np.asarray(z, np.float64), v)) >= np.sqrt(2 / 3) * (
        1 - rtol_for(dtype)
    )


@given(light_and_blocker())
def test_mdv_is_the_mean_offset(to: Any, dtype: Any, scene: Any) -> None:
    light, verts = scene
    mdv = mean_direction_vector(to(light), to(verts))
    assert mdv.dtype == dtype and mdv.shape == (3,)
    expected = np.mean([v - light for v in verts], axis=0)
    np.testing.assert_allclose(mdv, expected, rtol=rtol_for(dtype), atol=rtol_for(dtype) * 30)


@given(light_and_blocker(), st.sampled_from(["mean", "bbox"]))
def test_frame_is_orthonormal_left_handed_and_aims_at_the_blocker(
    to: Any, dtype: Any, scene: Any, aim: Any
) -> None:
    light, verts = scene
    f = light_frame(to(light), to(verts), aim=aim)
    X, Y, Z = (np.asarray(a, np.float64) for a in f[1:])
    R = np.stack([X, Y, Z])
    tol = 10 * rtol_for(dtype)
    np.testing.assert_allclose(R @ R.T, np.eye(3), atol=tol)
    np.testing.assert_allclose(np.cross(X, Y), -Z, atol=tol)  # left-handed
    target = verts.mean(0) if aim == "mean" else (verts.max(0) + verts.min(0)) / 2
    aim_dir = (target - light) / np.linalg.norm(target - light)
    np.testing.assert_allclose(Z, aim_dir, atol=tol)
    # X is the normalized Z x V for the helper axis V
    V = np.asarray(helper_axis(Z))
    np.testing.assert_allclose(X, np.cross(Z, V) / np.linalg.norm(np.cross(Z, V)), atol=tol)
    np.testing.assert_allclose(np.asarray(f.origin), light, rtol=tol, atol=tol)


@given(light_and_blocker())
def test_world_to_light_sends_light_to_origin_and_blocker_to_positive_z(
    to: Any, dtype: Any, scene: Any
) -> None:
    light, verts = scene
    W = np.asarray(world_to_light(light_frame(to(light), to(verts))), np.float64)
    scale = 10 * rtol_for(dtype) * (1 + np.abs(light).max())
    np.testing.assert_allclose(W @ np.append(light, 1), [0, 0, 0, 1], atol=scale)
    p = (W @ np.c_[verts, np.ones(len(verts))].T).T
    assert np.all(p[:, 2] > 0)
    # a rigid motion with a reflection: the frame is left-handed
    np.testing.assert_allclose(np.linalg.det(W[:3, :3]), -1, atol=10 * rtol_for(dtype))
    np.testing.assert_array_equal(W[3], [0, 0, 0, 1])
    # distances are preserved
    np.testing.assert_allclose(
        np.linalg.norm(p[:, :3], axis=-1), np.linalg.norm(verts - light, axis=-1), rtol=scale
    )


@given(light_and_blocker())
def test_light_to_world_inverts_world_to_light(scene: Any) -> None:
    light, verts = scene
    f = light_frame(light, verts)
    np.testing.assert_allclose(light_to_world(f) @ world_to_light(f), np.eye(4), atol=1e-12 * 30)


@given(arrays(np.float64, 3, elements=coords), directions)
def test_frame_from_direction(light: np.ndarray, d: np.ndarray) -> None:
    f = light_frame_from_direction(light, d)
    np.testing.assert_allclose(f.z_axis, d / np.linalg.norm(d), rtol=1e-12, atol=1e-15)
    # same as the MDV frame of a blocker centred along d (when light + d - light is
    # exactly d: otherwise a rounded direction may fall on the other side of a
    # helper-axis tie, where the frame legitimately jumps)
    assume(np.array_equal((light + d) - light, d))
    g = light_frame(light, (light + d)[None, :])
    for a, b in zip(f, g, strict=True):
        np.testing.assert_allclose(a, b, rtol=1e-12, atol=1e-14)


def test_batched_frames_equal_a_loop() -> None:
    rng = np.random.default_rng(3)
    lights = rng.normal(size=(3, 1, 3)) * 5 + [0, 0, -20]
    verts = rng.normal(size=(2, 7, 3))
    f = light_frame(lights, verts)
    W = world_to_light(f)
    assert f.x_axis.shape == (3, 2, 3) and W.shape == (3, 2, 4, 4)
    for i in range(3):
        for j in range(2):
            g = light_frame(lights[i, 0], verts[j])
            for a, b in zip(f, g, strict=True):
                np.testing.assert_allclose(a[i, j], b, rtol=1e-14)
            np.testing.assert_allclose(W[i, j], world_to_light(g), rtol=1e-14)
