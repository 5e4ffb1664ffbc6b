"""The optimized fit against the article's set-up, on rendered shadow maps.

The coverage of the usable map is measured on masks drawn by the reference
renderer. On blockers whose article frame leaves the map visibly empty (a bar or
a flat box seen diagonally, a torus with the light off its axis) the optimized
set-up must cover more, and it must never draw into the border.
"""

from __future__ import annotations

from typing import Any

import numpy as np
import pytest

from shadowmath import fit_shadow, silhouette_coverage
from shadowmath.meshes import Mesh, bar, box, torus
from shadowmath.render import render_shadow_map

MAP = 128


def _turn(angle: float, axis: int) -> np.ndarray:
    c, s = np.cos(angle), np.sin(angle)
    i, j = [k for k in range(3) if k != axis]
    B = np.eye(4)
    B[i, i], B[i, j], B[j, i], B[j, j] = c, -s, s, c
    return B


CASES: dict[str, tuple[Mesh, np.ndarray, list[float]]] = {
    "bar": (bar(3.0, 0.1), _turn(0.7, 2) @ _turn(0.3, 0), [0.5, 1.0, 9.0]),
    "box": (box((2.0, 0.3, 1.0)), _turn(0.5, 1) @ _turn(0.9, 2), [-6.0, 2.0, 5.0]),
    "torus": (torus(1.0, 0.3, segments=32, sides=12), _turn(1.1, 0), [2.0, -3.0, 4.0]),
}


@pytest.mark.parametrize("name", sorted(CASES))
def test_optimized_fit_covers_more_without_clipping(gl: Any, name: str) -> None:
    mesh, B, light = CASES[name]
    cover = {}
    for method in ("mdv", "optimized"):
        s = fit_shadow(light, mesh.vertices, MAP, blocker_to_world=B, method=method)  # type: ignore[arg-type]
        mask = render_shadow_map(mesh.vertices, mesh.faces, s.blocker_to_clip, MAP, ctx=gl)
        border = np.concatenate([mask[0], mask[-1], mask[:, 0], mask[:, -1]])
        assert border.max() == 0, f"{method} drew into the border"
        # The silhouette reaches the margin on all four sides for the off-centre frustum.
        if method == "optimized":
            assert mask[1].max() == 1 and mask[-2].max() == 1
            assert mask[:, 1].max() == 1 and mask[:, -2].max() == 1
        cover[method] = float(silhouette_coverage(mask))
    assert cover["optimized"] > 1.05 * cover["mdv"], cover
