"""The viewer's camera: an OpenGL look-at view and a perspective projection (plain NumPy)."""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import NDArray


def look_at(eye: Any, target: Any, up: Any = (0.0, 1.0, 0.0)) -> NDArray[np.float64]:
    r"""World to view coordinates of a right-handed OpenGL camera (it looks down ``-z``).

    .. math::

        f = \frac{t - e}{|t - e|}, \quad r = \frac{f \times u}{|f \times u|}, \quad
        u' = r \times f, \qquad
        M = \begin{bmatrix} r^{\mathsf T} & -r \cdot e \\ u'^{\mathsf T} & -u' \cdot e \\
        -f^{\mathsf T} & f \cdot e \\ 0 & 1 \end{bmatrix}

    Arguments:
        eye: ``(3,)`` the camera position.
        target: ``(3,)`` the point it looks at.
        up: ``(3,)`` the world direction that appears upward.

    Returns:
        ``(4, 4)`` column-vector matrix.

    Raises:
        ValueError: ``eye == target``, or ``up`` parallel to the viewing direction.

    Example:
        >>> look_at([0, 0, 5], [0, 0, 0]) @ np.array([0, 0, 0, 1.0])  # 5 in front
        array([ 0.,  0., -5.,  1.])
    """
    e, t, u = (np.asarray(x, dtype=np.float64) for x in (eye, target, up))
    f = t - e
    if not np.linalg.norm(f) > 0:
        raise ValueError("eye, target: the camera must not sit on its target")
    f = f / np.linalg.norm(f)
    r = np.cross(f, u)
    if not np.linalg.norm(r) > 1e-9:
        raise ValueError("up: parallel to the viewing direction; choose another up vector")
    r = r / np.linalg.norm(r)
    u2 = np.cross(r, f)
    rows = np.stack([r, u2, -f])
    return np.block([[rows, -(rows @ e)[:, None]], [np.zeros((1, 3)), np.ones((1, 1))]])


def perspective(
    fov_y_degrees: float, aspect: float, near: float, far: float
) -> NDArray[np.float64]:
    r"""OpenGL's perspective projection (``gluPerspective``): view to clip coordinates.

    .. math::

        \begin{bmatrix} c / a & 0 & 0 & 0 \\ 0 & c & 0 & 0 \\
        0 & 0 & \frac{f + n}{n - f} & \frac{2 f n}{n - f} \\ 0 & 0 & -1 & 0 \end{bmatrix},
        \qquad c = \cot(\mathrm{fov}_y / 2)

    Arguments:
        fov_y_degrees: vertical field of view in ``(0, 180)`` degrees.
        aspect: width over height.
        near, far: clip distances, ``0 < near < far``.

    Returns:
        ``(4, 4)`` column-vector matrix.

    Raises:
        ValueError: values out of range.

    Example:
        >>> P = perspective(90.0, 1.0, 1.0, 10.0)
        >>> clip = P @ np.array([0, 0, -1.0, 1])  # on the near plane: NDC depth -1
        >>> float(clip[2] / clip[3])
        -1.0
    """
    if not 0 < fov_y_degrees < 180:
        raise ValueError(f"fov_y_degrees: must lie in (0, 180), got {fov_y_degrees}")
    if not aspect > 0:
        raise ValueError(f"aspect: must be > 0, got {aspect}")
    if not 0 < near < far:
        raise ValueError(f"near, far: need 0 < near < far, got {near}, {far}")
    c = 1.0 / np.tan(np.radians(fov_y_degrees) / 2)
    return np.array(
        [
            [c / aspect, 0.0, 0.0, 0.0],
            [0.0, c, 0.0, 0.0],
            [0.0, 0.0, (far + near) / (near - far), 2 * far * near / (near - far)],
            [0.0, 0.0, -1.0, 0.0],
        ]
    )
