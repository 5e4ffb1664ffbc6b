"""Doctests see NumPy and the public API, as a user after ``from shadowmath import *`` would.

The examples of :mod:`shadowmath.render` draw with OpenGL: without a context they
are skipped with the packages to install, except under ``SHADOWMATH_REQUIRE_GL=1``
(set by CI), where a missing context fails them.
"""

import os
from typing import Any

import numpy as np
import pytest

# Before shadowmath is imported: its public functions check their jaxtyping annotations
# after every call in the test suite (shadowmath/_boundary/_shapes.py).
os.environ["SHADOWMATH_CHECK_SHAPES"] = "1"

import shadowmath


@pytest.fixture(autouse=True)
def _doctest_names(doctest_namespace: dict[str, Any], request: pytest.FixtureRequest) -> None:
    doctest_namespace["np"] = np
    for name in shadowmath.__all__:
        doctest_namespace[name] = getattr(shadowmath, name)
    if "shadowmath.render" in request.node.name:
        from shadowmath.render import GLUnavailableError, standalone_context

        try:
            standalone_context()
        except GLUnavailableError as err:
            if os.environ.get("SHADOWMATH_REQUIRE_GL") == "1":
                raise
            pytest.skip(str(err))
