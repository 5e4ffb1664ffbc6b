"""The scene of the PCSS programs: a unit box standing on a floor, as flat triangle lists
(world coordinates, counter-clockwise seen from outside), and a camera."""

from pathlib import Path

import numpy as np

HERE = Path(__file__).parent
Vector = tuple[float, float, float]


def shader(name: str) -> str:
    """The text of a shader file beside this one (pcss.glsl, pcss.wgsl)."""
    return (HERE / name).read_text(encoding="utf-8")


def box(lo: Vector, hi: Vector) -> np.ndarray:
    """``(36, 3)`` the 12 triangles of the box ``[lo, hi]``, outward counter-clockwise."""
    low, high = np.asarray(lo, float), np.asarray(hi, float)
    corner = np.array([[x, y, z] for x in (0, 1) for y in (0, 1) for z in (0, 1)])
    quads = [[0, 1, 3, 2], [4, 6, 7, 5], [0, 4, 5, 1], [2, 3, 7, 6], [0, 2, 6, 4], [1, 5, 7, 3]]
    v = low + corner * (high - low)
    return np.concatenate([v[[a, b, c, a, c, d]] for a, b, c, d in quads])


def floor(half: float) -> np.ndarray:
    """``(6, 3)`` the square ``|x|, |y| <= half`` of the plane ``z = 0``, facing ``+z``."""
    h = float(half)
    return np.array([[-h, -h, 0], [h, -h, 0], [h, h, 0], [-h, -h, 0], [h, h, 0], [-h, h, 0]])


def normals(triangles: np.ndarray) -> np.ndarray:
    """``(3 T, 3)`` each vertex's triangle's unit normal."""
    t = triangles.reshape(-1, 3, 3)
    n = np.cross(t[:, 1] - t[:, 0], t[:, 2] - t[:, 0])
    return np.repeat(n / np.linalg.norm(n, axis=1, keepdims=True), 3, axis=0)


#: The caster (a unit box on the floor) and every triangle (the floor first).
CASTER = box((-1.0, -0.8, 0.0), (0.0, 0.2, 1.0))
TRIANGLES = np.concatenate([floor(5.0), CASTER])


def look_at(eye: Vector, target: Vector, up: Vector = (0.0, 0.0, 1.0)) -> np.ndarray:
    """The world-to-view matrix of a camera at ``eye`` looking at ``target`` (down ``-z``)."""
    e = np.asarray(eye, float)
    f = np.asarray(target, float) - e
    f /= np.linalg.norm(f)
    s = np.cross(f, up)
    s /= np.linalg.norm(s)
    u = np.cross(s, f)
    m = np.eye(4)
    m[0, :3], m[1, :3], m[2, :3] = s, u, -f
    m[:3, 3] = -m[:3, :3] @ e
    return m


def perspective(fovy_degrees: float, aspect: float, near: float, far: float) -> np.ndarray:
    """OpenGL's perspective projection (clip depth in ``[-1, 1]``)."""
    f = 1.0 / np.tan(np.radians(fovy_degrees) / 2)
    return np.array(
        [
            [f / aspect, 0, 0, 0],
            [0, f, 0, 0],
            [0, 0, (far + near) / (near - far), 2 * far * near / (near - far)],
            [0, 0, -1, 0],
        ]
    )


#: The cascades programs' camera: low over the floor, the box's shadow across a split.
CASCADES_VIEW = look_at((2.2, -2.2, 1.6), (-0.2, 0.0, 0.0))
CASCADES_PROJECTION = perspective(60.0, 1.0, 0.3, 12.0)
