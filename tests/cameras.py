"""Camera matrices for the cascades' tests, written from the textbook definitions.

Independent of shadowmath's code: gluLookAt, gluPerspective and glOrtho in OpenGL's
conventions (right-handed view, the camera looking down its -z, NDC depth -1 to 1).
"""

from __future__ import annotations

from typing import Any

import numpy as np


def look_at(eye: Any, target: Any, up: Any = (0.0, 1.0, 0.0)) -> np.ndarray:
    """A right-handed OpenGL view matrix (the camera looks down its -z)."""
    eye, target, up = (np.asarray(v, float) for v in (eye, target, up))
    f = target - eye
    f /= np.linalg.norm(f)
    s = np.cross(f, up)
    s /= np.linalg.norm(s)
    u = np.cross(s, f)
    m = np.eye(4)
    m[0, :3], m[1, :3], m[2, :3] = s, u, -f
    m[:3, 3] = -m[:3, :3] @ eye
    return m


def perspective(fovy: float, aspect: float, near: float, far: float) -> np.ndarray:
    """OpenGL's perspective projection (gluPerspective)."""
    f = 1 / np.tan(fovy / 2)
    return np.array([
        [f / aspect, 0, 0, 0], [0, f, 0, 0],
        [0, 0, (far + near) / (near - far), 2 * far * near / (near - far)], [0, 0, -1, 0],
    ])  # fmt: skip


def orthographic(half_w: float, half_h: float, near: float, far: float) -> np.ndarray:
    return np.array([
        [1 / half_w, 0, 0, 0], [0, 1 / half_h, 0, 0],
        [0, 0, -2 / (far - near), -(far + near) / (far - near)], [0, 0, 0, 1],
    ])  # fmt: skip
