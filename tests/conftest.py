"""Shared fixtures: every core test runs on each backend and both float dtypes.

JAX runs with float64 enabled so that float64 really means float64 there too.
"""

from __future__ import annotations

import os
from collections.abc import Callable
from typing import Any

import jax
import jax.numpy as jnp
import numpy as np
import pytest
from hypothesis import HealthCheck, settings

jax.config.update("jax_enable_x64", True)

# The converters below are pure, so hypothesis may reuse them across examples.
# `make test` (and so CI) draws the same examples every run (derandomize): a submission
# is judged on the code, not on the draw. `make fuzz` explores with fresh random draws.
settings.register_profile(
    "default",
    max_examples=25,
    derandomize=True,
    deadline=None,
    suppress_health_check=[HealthCheck.function_scoped_fixture],
)
# `make fuzz`: the long run (tests/test_fuzz.py prints how many cases were tried);
# FUZZ_EXAMPLES sets the examples per test (2000 by default).
settings.register_profile(
    "fuzz",
    max_examples=int(os.environ.get("FUZZ_EXAMPLES", "2000")),
    deadline=None,
    suppress_health_check=[HealthCheck.function_scoped_fixture, HealthCheck.too_slow],
)
# HYPOTHESIS_PROFILE=explore: the default profile with fresh random draws every run.
settings.register_profile("explore", settings.get_profile("default"), derandomize=False)
settings.load_profile(os.environ.get("HYPOTHESIS_PROFILE", "default"))

Convert = Callable[[Any], Any]


def _numpy(dtype: Any) -> Convert:
    return lambda x: np.asarray(x, dtype=dtype)


def _numpy_readonly(dtype: Any) -> Convert:
    def convert(x: Any) -> Any:
        arr = np.array(x, dtype=dtype)
        arr.flags.writeable = False
        return arr

    return convert


def _jax(dtype: Any) -> Convert:
    return lambda x: jnp.asarray(x, dtype=dtype)


BACKENDS = {"numpy": _numpy, "numpy-readonly": _numpy_readonly, "jax": _jax}


@pytest.fixture(params=["numpy", "numpy-readonly", "jax"])
def backend(request: pytest.FixtureRequest) -> str:
    return str(request.param)


@pytest.fixture(params=[np.float64, np.float32], ids=["f64", "f32"])
def dtype(request: pytest.FixtureRequest) -> Any:
    return request.param


@pytest.fixture
def to(backend: str, dtype: Any) -> Convert:
    """Convert test data to the backend and dtype under test."""
    return BACKENDS[backend](dtype)


def rtol_for(dtype: Any) -> float:
    """A tolerance a few hundred ulps wide: the formulas are short and well conditioned."""
    return 1e-10 if np.dtype(dtype) == np.float64 else 2e-4
