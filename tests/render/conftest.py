"""The GL and WebGPU fixtures: a missing context or adapter fails under
SHADOWMATH_REQUIRE_GL=1 (CI, which requires both graphics APIs), skips elsewhere."""

from __future__ import annotations

import os
from typing import Any

import pytest


def unavailable(message: str) -> None:
    """A missing graphics API: a failure under SHADOWMATH_REQUIRE_GL=1 (CI), else a skip."""
    if os.environ.get("SHADOWMATH_REQUIRE_GL") == "1":
        pytest.fail(f"SHADOWMATH_REQUIRE_GL=1: {message}")
    pytest.skip(message)


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
        unavailable(message)


@pytest.fixture(scope="session")
def wgpu_device() -> Any:
    """The shared WebGPU device (wgpu over Vulkan; Mesa's llvmpipe without a GPU)."""
    try:
        from shadowmath.render.webgpu import wgpu_device

        return wgpu_device()
    except Exception as err:  # ImportError (no wgpu) or WgpuUnavailableError
        message = f"no WebGPU adapter for the reference render: {err}"
        if "mesa-vulkan-drivers" not in message:
            message += (
                "; install the 'render' extra (wgpu) and the Debian package "
                "mesa-vulkan-drivers (apt-get install -y mesa-vulkan-drivers)"
            )
        unavailable(message)
