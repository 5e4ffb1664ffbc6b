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


def scene(seed: int, lowest_pitch: float = -0.15) -> tuple[np.ndarray, ...]:
    """A random camera 1 to 8 units above a 300 x 300 scene box looking near the horizon
    (its view tilted down by at most ``-lowest_pitch``), and a sun above the horizon."""
    rng = np.random.default_rng(seed)
    eye = rng.uniform([-30, 1, -30], [30, 8, 30])
    yaw = rng.uniform(0, 2 * np.pi)
    target = eye + [np.cos(yaw), rng.uniform(lowest_pitch, 0.05), np.sin(yaw)]
    view = look_at(eye, target)
    proj = perspective(rng.uniform(0.6, 1.4), rng.uniform(0.8, 2.0), rng.uniform(0.05, 1), 120)
    box = np.array([[-150.0, -0.5, -150.0], [150.0, rng.uniform(10, 20), 150.0]])
    sun = rng.normal(size=3)
    sun[1] = abs(sun[1]) + 0.2
    return sun, view, proj, box


def frustum(l: float, r: float, b: float, t: float, n: float, f: float) -> np.ndarray:  # noqa: E741
    """glFrustum (the OpenGL specification's matrix): an off-axis perspective projection."""
    return np.array([
        [2 * n / (r - l), 0, (r + l) / (r - l), 0], [0, 2 * n / (t - b), (t + b) / (t - b), 0],
        [0, 0, -(f + n) / (f - n), -2 * f * n / (f - n)], [0, 0, -1, 0],
    ])  # fmt: skip


def ortho(l: float, r: float, b: float, t: float, n: float, f: float) -> np.ndarray:  # noqa: E741
    """glOrtho (the OpenGL specification's matrix): an off-centre orthographic projection."""
    return np.array([
        [2 / (r - l), 0, 0, -(r + l) / (r - l)], [0, 2 / (t - b), 0, -(t + b) / (t - b)],
        [0, 0, -2 / (f - n), -(f + n) / (f - n)], [0, 0, 0, 1],
    ])  # fmt: skip
