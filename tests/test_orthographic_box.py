"""A perspective :class:`Frustum` and an :class:`OrthographicBox` are two types.

Every fit returns the type of its light, the frustum-taking functions build the matrix
of the type they are given, both are JAX pytrees, and the old spellings (the
``orthographic`` flag, a box read by the frustum's names) still work with a
``DeprecationWarning`` that names the new type or field.
"""

from __future__ import annotations

from typing import Any

import jax
import jax.numpy as jnp
import numpy as np
import pytest

import shadowmath as sm
from shadowmath._backends import _kernels

from .cameras import scene

BOX = np.array([[x, y, z] for x in (-1.0, 1.0) for y in (-2.0, 2.0) for z in (3.0, 5.0)])
SUN = sm.DirectionalLight(np.array([0.3, 1.0, -0.2]))
FIELDS = (2.0, 1.0, 1.0, 5.0, 0.98, 0.96, 0.5, -0.25)


def _ndc(clip: np.ndarray, points: np.ndarray) -> np.ndarray:
    h = np.c_[points, np.ones(len(points))] @ np.asarray(clip).T
    return np.asarray(h[:, :3] / h[:, 3:])


@pytest.mark.parametrize("path", ["compiled", "python loop", "array path", "jax"])
def test_each_fit_returns_the_type_of_its_light(path: str) -> None:
    lights: dict[type, list[Any]] = {
        sm.Frustum: [sm.PointLight([0.5, 9.0, 1.0]), np.array([1.0, 18.0, 2.0, 2.0])],
        sm.OrthographicBox: [SUN, np.array([0.3, 1.0, -0.2, 0.0])],
    }
    ctx = {"python loop": _kernels.disabled, "array path": _kernels.array_path}
    for kind, given in lights.items():
        for light in given:
            if path == "jax":
                if not isinstance(light, sm.DirectionalLight | sm.PointLight):
                    continue  # homogeneous lights are refused under JAX transformations
                fit = jax.jit(lambda v, light=light: sm.fit_shadow(light, v, 64))
                s = fit(jnp.asarray(BOX))
            elif path in ctx:
                with ctx[path]():
                    s = sm.fit_shadow(light, BOX, 64)
            else:
                s = sm.fit_shadow(light, BOX, 64)
            assert type(s.frustum) is kind, (path, light)


def test_a_box_is_the_orthographic_window_of_its_fit() -> None:
    # The box's fields say what they are: the blocker's light x spans
    # [center_x - half_width, center_x + half_width], which the map's margins hold.
    s = sm.fit_shadow(SUN, BOX, (100, 50))
    box = s.frustum
    assert isinstance(box, sm.OrthographicBox)
    light = (np.c_[BOX, np.ones(len(BOX))] @ s.world_to_light.T)[:, :3]
    for axis, half, centre in (
        (0, box.half_width, box.center_x),
        (1, box.half_height, box.center_y),
    ):
        lo, hi = light[:, axis].min(), light[:, axis].max()
        np.testing.assert_allclose([(hi - lo) / 2, (hi + lo) / 2], [half, centre], atol=1e-12)
    assert float(box.near) < light[:, 2].min() and light[:, 2].max() < float(box.far)
    # Its projection, from the public helper, is the fit's: blocker_to_clip = P W.
    P = sm.blocker_projection(box)
    np.testing.assert_allclose(P @ s.world_to_light, s.blocker_to_clip, atol=1e-12)


def test_cascades_are_boxes() -> None:
    sun, view, proj, box = scene(0)
    c = sm.fit_cascades(sun, view, proj, box, 256, count=3)
    assert type(c.frustum) is sm.OrthographicBox
    P = sm.blocker_projection(c.frustum)
    np.testing.assert_allclose(P @ c.world_to_light, c.world_to_clip, atol=1e-12)


def test_the_projection_follows_the_type() -> None:
    # x_ndc = m_x (x / z - c_x) / R_x for a Frustum, m_x (x - c_x) / R_x for a box.
    point = np.array([[1.5, 0.5, 4.0]])
    x, y, z = point[0]
    R_x, R_y, _, _, m_x, m_y, c_x, c_y = FIELDS
    perspective = _ndc(sm.blocker_projection(sm.Frustum(*FIELDS)), point)[0]
    orthographic = _ndc(sm.blocker_projection(sm.OrthographicBox(*FIELDS)), point)[0]
    np.testing.assert_allclose(
        perspective[:2], [m_x * (x / z - c_x) / R_x, m_y * (y / z - c_y) / R_y], rtol=1e-15
    )
    np.testing.assert_allclose(
        orthographic[:2], [m_x * (x - c_x) / R_x, m_y * (y - c_y) / R_y], rtol=1e-15
    )


def test_both_types_are_pytrees_under_jit() -> None:
    for kind in (sm.Frustum, sm.OrthographicBox):
        value = kind(*(jnp.asarray(v) for v in FIELDS))
        doubled = jax.tree_util.tree_map(lambda v: 2 * v, value)
        assert type(doubled) is kind
        np.testing.assert_allclose(doubled, 2 * np.array(FIELDS))
        got = jax.jit(sm.blocker_projection)(value)
        np.testing.assert_allclose(got, sm.blocker_projection(kind(*FIELDS)), rtol=1e-6)


def test_a_box_refuses_a_bad_box_but_not_a_near_plane_behind_its_origin() -> None:
    with pytest.raises(ValueError, match="half_width and half_height must be > 0"):
        sm.blocker_projection(sm.OrthographicBox(0.0, *FIELDS[1:]))
    with pytest.raises(ValueError, match="near must be < far"):
        sm.receiver_projection(sm.OrthographicBox(2.0, 1.0, 5.0, 5.0, 0.98, 0.98))
    with pytest.raises(ValueError, match=r"frustum\.near: must be > 0"):
        sm.blocker_projection(sm.Frustum(2.0, 1.0, -1.0, 5.0, 0.98, 0.98))
    P = sm.blocker_projection(sm.OrthographicBox(2.0, 1.0, -1.0, 5.0, 0.98, 0.98))
    np.testing.assert_allclose(_ndc(P, np.array([[0.0, 0.0, -1.0]]))[0, 2], -1.0)


# --- the old spellings, for one release -----------------------------------------------------


def test_the_orthographic_flag_gives_the_type_with_a_warning() -> None:
    with pytest.warns(DeprecationWarning, match=r"Frustum\(orthographic=\.\.\.\).*OrthographicBox"):
        box = sm.Frustum(*FIELDS, True)  # positional, as before
    assert type(box) is sm.OrthographicBox and tuple(box) == FIELDS
    with pytest.warns(DeprecationWarning, match="OrthographicBox"):
        fr = sm.Frustum(*FIELDS[:6], orthographic=np.array([False, False]))
    assert type(fr) is sm.Frustum and fr.x_offset == 0.0
    with (
        pytest.warns(DeprecationWarning, match="OrthographicBox"),
        pytest.raises(ValueError, match="mixes perspective"),
    ):
        sm.Frustum(*FIELDS[:6], orthographic=np.array([False, True]))
    # A plain tuple with the flag, as blocker_projection took it: the box's matrix.
    with pytest.warns(DeprecationWarning, match="OrthographicBox"):
        old = sm.blocker_projection((*FIELDS, True))
    np.testing.assert_array_equal(old, sm.blocker_projection(sm.OrthographicBox(*FIELDS)))


@pytest.mark.parametrize(
    ("old", "new"),
    [("rx_max", "half_width"), ("ry_max", "half_height"), ("x_offset", "center_x"),
     ("y_offset", "center_y")],
)  # fmt: skip
def test_a_box_read_by_the_old_names_warns_and_reads_the_new_field(old: str, new: str) -> None:
    box = sm.fit_shadow(SUN, BOX, 64).frustum
    with pytest.warns(DeprecationWarning, match=rf"OrthographicBox\.{old} is deprecated.*{new}"):
        value = getattr(box, old)
    assert value is getattr(box, new)


def test_the_orthographic_attribute_warns_and_names_the_type() -> None:
    box, fr = sm.OrthographicBox(*FIELDS), sm.Frustum(*FIELDS)
    with pytest.warns(DeprecationWarning, match=r"isinstance\(box, OrthographicBox\)"):
        assert box.orthographic is True
    with pytest.warns(DeprecationWarning, match=r"isinstance\(frustum, OrthographicBox\)"):
        assert fr.orthographic is False
