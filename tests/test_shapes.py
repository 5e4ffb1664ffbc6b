"""The jaxtyping annotations of the public API are checked in the test suite, and only there.

``shadowmath/_boundary/_shapes.py``: under ``SHADOWMATH_CHECK_SHAPES=1`` (set by the root
``conftest.py``) each public function runs, then its arguments, its result and the result's
NamedTuple fields are checked against the signature in one shape memo. Outside the suite
the functions are the plain ones and jaxtyping is never imported.
"""

from __future__ import annotations

import json
import os
import pathlib
import subprocess
import sys
import types
import typing

import numpy as np
import pytest
from jaxtyping import TypeCheckError

import shadowmath as sm
from shadowmath._boundary._shapes import Array, ArrayLike, Float, MapSize, Real, shapes_checked
from shadowmath._fits.shadow import _driver as _setup
from shadowmath._geometry import _light_frame
from shadowmath._math import _cube, _pcf

BOX = np.array([[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (4, 6)], np.float64)


def test_the_suite_checks_shapes():
    assert os.environ["SHADOWMATH_CHECK_SHAPES"] == "1"
    assert sm.fit_shadow is not _setup.fit_shadow
    assert sm.fit_shadow.__wrapped__ is _setup.fit_shadow  # type: ignore[attr-defined]


def test_a_wrongly_shaped_result_field_is_caught(monkeypatch):
    fit = _setup._fit

    def transposed_texture(*args, **kwargs):  # a core that drops a row of a matrix
        setup = fit(*args, **kwargs)
        return setup._replace(world_to_texture=setup.world_to_texture[..., :3, :])

    monkeypatch.setattr(_setup, "_fit", transposed_texture)
    with pytest.raises(TypeCheckError, match=r"result\.world_to_texture"):
        sm.fit_shadow([0.0, 0.0, 0.0], BOX, 64)


def test_a_result_of_another_batch_than_the_arguments_is_caught(monkeypatch):
    fit = _setup._fit

    def one_entry(*args, **kwargs):  # a core that loses the batch of its light
        setup = fit(*args, **kwargs)
        return setup._replace(blocker_to_clip=setup.blocker_to_clip[:2])

    monkeypatch.setattr(_setup, "_fit", one_entry)
    sm.fit_shadow(np.zeros((2, 3)), BOX, 64)  # two entries: [:2] keeps them
    with pytest.raises(TypeCheckError, match=r"result\.blocker_to_clip"):
        sm.fit_shadow(np.zeros((3, 3)), BOX, 64)


def test_a_result_of_the_wrong_dtype_is_caught(monkeypatch):
    fit = _setup._fit

    def integer_matrices(*args, **kwargs):
        setup = fit(*args, **kwargs)
        return setup._replace(world_to_light=setup.world_to_light.astype(np.int64))

    monkeypatch.setattr(_setup, "_fit", integer_matrices)
    with pytest.raises(TypeCheckError, match=r"result\.world_to_light"):
        sm.fit_shadow([0.0, 0.0, 0.0], BOX, 64)


def _centroid(points: Real[ArrayLike, "*#batch N 3"]) -> Float[Array, "*batch 3"]:
    """A door that lets any array through: the checker catches what it should have refused."""
    p = np.asarray(points, dtype=np.float64)
    return p.mean(axis=-2) if p.ndim >= 2 else p


def test_an_argument_the_door_lets_through_is_caught():
    centroid = shapes_checked(_centroid)
    assert centroid([[0, 0, 0], [2, 4, 6]]).tolist() == [1.0, 2.0, 3.0]  # lists are converted
    assert centroid(np.ones((5, 4, 3))).shape == (5, 3)
    with pytest.raises(TypeCheckError, match="argument points"):
        centroid(np.ones((4, 2)))  # (N, 2): not points in 3D
    with pytest.raises(TypeCheckError, match="argument points"):
        centroid(np.array([[True, False, True]]))  # booleans are not Real


def test_bad_shapes_still_get_the_doors_message():
    with pytest.raises(ValueError, match="light"):
        sm.fit_shadow(np.zeros(5), BOX, 64)
    with pytest.raises(ValueError, match="blocker_vertices"):
        sm.fit_shadow([0.0, 0.0, 0.0], np.zeros((8, 2)), 64)


def test_size_named_by_an_argument():
    assert sm.cascade_splits(1.0, 100.0, 3).shape == (4,)  # "*batch {count}+1"
    assert sm.cascade_splits(np.ones(2), 100.0, 5).shape == (2, 6)


@pytest.mark.parametrize("name", sorted(sm._WHERE))
def test_every_public_annotation_evaluates(name):
    """Every annotation names what its module imports (the checker evaluates them on a call)."""
    value = getattr(sm, name)
    if isinstance(value, (types.FunctionType, type)):
        typing.get_type_hints(value, include_extras=True)


def test_no_checker_and_no_jaxtyping_outside_the_test_suite():
    code = (
        "import json, sys, numpy as np, shadowmath as sm, shadowmath.meshes as meshes\n"
        "from shadowmath._fits.shadow._driver import fit_shadow\n"
        "sm.fit_shadow([0.0, 0, 0], [[-1, -1, 4], [1, 1, 4], [1, -1, 5]], 64)\n"
        "meshes.torus()\n"
        "print(json.dumps([sm.fit_shadow is fit_shadow,\n"
        "                  hasattr(meshes.torus, '__wrapped__'),\n"
        "                  sorted(m for m in ('jaxtyping', 'beartype') if m in sys.modules)]))\n"
    )
    env = {k: v for k, v in os.environ.items() if k != "SHADOWMATH_CHECK_SHAPES"}
    out = subprocess.run(
        [sys.executable, "-c", code],
        capture_output=True,
        text=True,
        check=True,
        env=env,
        cwd=pathlib.Path(sm.__file__).parent.parent,
    ).stdout
    assert json.loads(out.strip().splitlines()[-1]) == [True, False, []]


# The functions of shadowmath._geometry: checked as the fits are. Each test replaces a core with
# one that returns a wrong shape or dtype; with the checking off, the call would return it.


def test_a_wrong_result_of_cube_face_views_is_caught(monkeypatch):
    views = _cube.cube_face_views
    monkeypatch.setattr(_cube, "cube_face_views", lambda xp, p: views(xp, p)[..., :5, :, :])
    with pytest.raises(TypeCheckError, match=r"cube_face_views: result"):
        sm.cube_face_views([0.0, 1.0, 2.0])


def test_a_float_face_of_cube_face_is_caught(monkeypatch):
    face = _cube.cube_face

    def float_face(xp, d):
        f, s, t = face(xp, d)
        return f.astype(np.float64), s, t

    monkeypatch.setattr(_cube, "cube_face", float_face)
    with pytest.raises(TypeCheckError, match=r"cube_face: result\.face"):
        sm.cube_face([[1.0, 0.5, -0.25]])


def test_a_wrong_field_of_light_frame_is_caught(monkeypatch):
    frame_along = _light_frame.frame_along

    def flat_z(*args, **kwargs):
        frame = frame_along(*args, **kwargs)
        return frame._replace(z_axis=frame.z_axis[..., :2])

    monkeypatch.setattr(_light_frame, "frame_along", flat_z)
    with pytest.raises(TypeCheckError, match=r"light_frame: result\.z_axis"):
        sm.light_frame([0.0, 0.0, 0.0], BOX)


def test_a_result_of_pcf_outside_its_batch_is_caught(monkeypatch):
    lookup = _pcf.pcf
    monkeypatch.setattr(_pcf, "pcf", lambda *args, **kwargs: lookup(*args, **kwargs)[..., None])
    depth_map = np.full((8, 8), 0.5)
    with pytest.raises(TypeCheckError, match=r"pcf: result"):
        sm.pcf(depth_map, np.full((3, 2), 0.5), np.full(3, 0.25), pcf_radius=0)


def test_numpy_integers_are_counts_and_sizes():
    """``IntLike``, ``MapSize``: what the doors take as integers, the annotations take too."""
    assert sm.border_margin(np.int64(100), border_texels=np.int32(1)) == (0.98, 0.98)
    assert sm.border_margin(np.array([100, 50])) == sm.border_margin([100, 50]) == (0.98, 0.96)
    samples = sm.area_light_samples(np.zeros(3), np.eye(3)[0], np.eye(3)[1], np.int64(4), seed=0)
    assert samples.shape == (4, 3)  # "*batch {count} 3" with a NumPy count


# Parameters that take anything by design: a value or a NamedTuple of them, a PRNG key.
_UNTYPED = {("check_finite", "value"), ("check_finite", "return"), ("area_light_samples", "key")}
_FUNCTIONS = sorted(n for n in sm._WHERE if isinstance(getattr(sm, n), types.FunctionType))


@pytest.mark.parametrize("name", _FUNCTIONS)
def test_every_public_function_is_annotated_and_checked(name):
    value = getattr(sm, name)
    assert value.__wrapped__.__name__ == name  # shapes_checked's wrapper
    hints = typing.get_type_hints(value.__wrapped__)
    untyped = {k for k, v in hints.items() if v is typing.Any} - {
        k for n, k in _UNTYPED if n == name
    }
    if name == "area_light_samples_jax":  # deprecated: the key comes first
        untyped -= {"key"}
    assert not untyped, f"{name}: {sorted(untyped)} typed Any (annotate the shape)"


def _texels(map_size: MapSize) -> int:
    """A door that lets any map size through."""
    return 0


def test_a_map_size_is_an_integer_or_two():
    texels = shapes_checked(_texels)
    for ok in (64, np.int32(64), (64, np.int64(32)), [64, 32], np.array([64, 32])):
        texels(ok)
    for bad in (64.0, (64.0, 32), (64, 32, 16), np.array([64.0, 32.0]), np.ones((2, 2), int)):
        with pytest.raises(TypeCheckError, match="argument map_size"):
            texels(bad)
