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
from shadowmath._boundary._shapes import Array, ArrayLike, Float, Real, shapes_checked
from shadowmath._fits import _setup

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
        "from shadowmath._fits._setup import fit_shadow\n"
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
