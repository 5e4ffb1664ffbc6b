"""Scene helpers for the render tests: placements, and the render-versus-ray-cast comparison."""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
from numpy.lib.stride_tricks import sliding_window_view

from shadowmath.groundtruth import segment_hits_triangles
from shadowmath.render import Body, Frame


def place(rotation=None, translation=(0.0, 0.0, 0.0), scale=1.0) -> np.ndarray:
    m = np.eye(4)
    m[:3, :3] = (np.eye(3) if rotation is None else np.asarray(rotation)) * scale
    m[:3, 3] = translation
    return m


def rotation(axis, degrees) -> np.ndarray:
    """Rodrigues' rotation about ``axis`` by ``degrees`` (right-handed)."""
    k = np.asarray(axis, dtype=float) / np.linalg.norm(axis)
    K = np.array([[0, -k[2], k[1]], [k[2], 0, -k[0]], [-k[1], k[0], 0]])
    a = np.radians(degrees)
    return np.eye(3) + np.sin(a) * K + (1 - np.cos(a)) * K @ K


def world_mesh(body: Body) -> tuple[np.ndarray, np.ndarray]:
    m = np.eye(4) if body.to_world is None else np.asarray(body.to_world)
    v = np.asarray(body.vertices, dtype=float) @ m[:3, :3].T + m[:3, 3]
    return v, np.asarray(body.triangles)


def ray_cast_shadow(frame: Frame, light, blockers, receiver_ids) -> tuple[np.ndarray, np.ndarray]:
    """Ground truth per pixel: (receiver visible, in the shadow of any blocker and facing it)."""
    on = np.isin(frame.body, receiver_ids)
    p = frame.position[on].astype(np.float64)
    n = frame.normal[on].astype(np.float64)
    light = np.asarray(light, dtype=float)
    facing = np.sum(n * (light - p), axis=1) > 0
    blocked = np.zeros(len(p), dtype=bool)
    for b in blockers:
        v, t = world_mesh(b)
        blocked |= segment_hits_triangles(p, light, v, t)
    truth = np.zeros(frame.body.shape, dtype=bool)
    truth[on] = blocked & facing
    return on, truth


def edge_band(image: np.ndarray, radius: int) -> np.ndarray:
    """Pixels within ``radius`` (Chebyshev) of a change of value in a boolean image."""
    padded = np.pad(image, radius, mode="edge")
    windows = sliding_window_view(padded, (2 * radius + 1, 2 * radius + 1))
    return windows.any(axis=(-2, -1)) != windows.all(axis=(-2, -1))


class Agreement(NamedTuple):
    pixels: int  # receiver pixels compared
    shadowed: int  # of them in the ground truth's shadow
    mismatch_all: float  # fraction of receiver pixels that disagree
    mismatch_off_edge: float  # the same, outside the band around the shadow's edges
    excluded: float  # fraction of receiver pixels in that band


def agreement(rendered: np.ndarray, truth: np.ndarray, on: np.ndarray, band: int) -> Agreement:
    edge = edge_band(truth, band)
    wrong = (rendered != truth) & on
    inner = on & ~edge
    return Agreement(
        pixels=int(on.sum()),
        shadowed=int(truth.sum()),
        mismatch_all=float(wrong.sum() / on.sum()),
        mismatch_off_edge=float((wrong & inner).sum() / max(1, inner.sum())),
        excluded=float((on & edge).sum() / on.sum()),
    )
