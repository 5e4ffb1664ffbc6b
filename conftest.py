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

# Before JAX is imported: JAX's persistent compilation cache (docs/performance.md), so that
# a program compiled once (by another pytest-xdist worker, a child process the tests start,
# or an earlier run) is loaded from disk instead of compiled again. Entries are keyed by the
# lowered program, so changed code compiles afresh. The environment reaches child processes.
os.environ.setdefault(
    "JAX_COMPILATION_CACHE_DIR",
    os.path.join(os.path.dirname(os.path.abspath(__file__)), ".pytest_cache", "jax-cache"),
)
os.environ.setdefault("JAX_PERSISTENT_CACHE_MIN_COMPILE_TIME_SECS", "0.1")

# Before JAX is imported: XLA's CPU compiler with its former fusion emitters (LLVM IR, not
# MLIR), for a suite of many small programs each compiled once and run on a few entries
# (docs/performance.md, "The test suite"): the compile time falls by a third to a half.
# No fast-math either way (IEEE arithmetic): every check holds the values to the same
# tolerances. (LLVM's optimizations off as well, --xla_backend_optimization_level=0, made
# that emitter give a wrong count in tests/test_scene.py: not used.) A flag already set in
# XLA_FLAGS is kept; the environment reaches child processes. XLA aborts on a flag it does
# not know: a jaxlib without this one fails loudly at the first compile.
os.environ["XLA_FLAGS"] = " ".join(
    [os.environ.get("XLA_FLAGS", "")]
    + [
        flag
        for flag in ("--xla_cpu_use_fusion_emitters=false",)
        if flag.partition("=")[0] not in os.environ.get("XLA_FLAGS", "")
    ]
).strip()

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
