"""The GL fixture: a missing context fails under SHADOWMATH_REQUIRE_GL=1 (CI), skips elsewhere."""

from __future__ import annotations

import os
from typing import Any

import pytest


@pytest.fixture(scope="session")
def gl() -> Any:
    """The shared offscreen moderngl context (EGL; Mesa llvmpipe without a GPU)."""
    try:
        from shadowmath.render import standalone_context

        return standalone_context()
    except Exception as err:  # ImportError (no moderngl) or GLUnavailableError
        message = f"no OpenGL context for the reference render: {err}"
        if "libegl1" not in message:
            message += (
                "; install the 'render' extra and the Debian packages libegl1, libgl1 and "
                "libgl1-mesa-dri (apt-get install -y libegl1 libgl1 libgl1-mesa-dri)"
            )
        if os.environ.get("SHADOWMATH_REQUIRE_GL") == "1":
            pytest.fail(f"SHADOWMATH_REQUIRE_GL=1: {message}")
        pytest.skip(message)
