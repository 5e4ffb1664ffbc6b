"""Pass 1 against the border rule: over random scenes the one-texel border stays empty and the
silhouette still reaches the margin (the frustum is tight, not just safe)."""

from __future__ import annotations

import numpy as np
import pytest

from shadowmath import fit_shadow
from shadowmath.meshes import Mesh, bar, box, sphere, torus
from shadowmath.render import render_shadow_map

MAP_SIZES = [16, 17, 23, 32, (16, 48), (48, 16), (31, 64), 100, (128, 72), 256]
CASES = 240  # random scenes per run (fixed seed), spread over MAP_SIZES


def _rotation(rng: np.random.Generator) -> np.ndarray:
    q, r = np.linalg.qr(rng.normal(size=(3, 3)))
    q = q * np.sign(np.diag(r))
    return q if np.linalg.det(q) > 0 else -q


def _random_blocker(rng: np.random.Generator) -> Mesh:
    kind = rng.integers(4)
    if kind == 0:
        return torus(1.0, rng.uniform(0.1, 0.6), segments=24, sides=12)
    if kind == 1:
        return box(tuple(rng.uniform(0.05, 2.0, size=3)))
    if kind == 2:
        return sphere(rng.uniform(0.2, 2.0), segments=20, rings=10)
    return bar(rng.uniform(2.0, 6.0), rng.uniform(0.02, 0.2))


def _random_case(rng: np.random.Generator) -> tuple[Mesh, np.ndarray, np.ndarray]:
    """A blocker, its local-to-world placement and a light outside twice its bounding radius."""
    mesh = _random_blocker(rng)
    placement = np.eye(4)
    placement[:3, :3] = _rotation(rng) * rng.uniform(0.3, 3.0)
    placement[:3, 3] = rng.uniform(-5, 5, size=3)
    world = mesh.vertices @ placement[:3, :3].T + placement[:3, 3]
    centre = world.mean(axis=0)
    radius = np.linalg.norm(world - centre, axis=1).max()
    direction = rng.normal(size=3)
    light = centre + direction / np.linalg.norm(direction) * radius * rng.uniform(2.0, 12.0)
    return mesh, placement, light


def _case_masks(gl, seed: int):
    """Random scenes; every third one with a two-texel border instead of the article's one."""
    rng = np.random.default_rng(seed)
    for i in range(CASES):
        size = MAP_SIZES[i % len(MAP_SIZES)]
        border = 2 if i % 3 == 2 else 1
        mesh, placement, light = _random_case(rng)
        setup = fit_shadow(
            light, mesh.vertices, size, blocker_to_world=placement, border_texels=border
        )
        mask = render_shadow_map(mesh.vertices, mesh.faces, setup.blocker_to_clip, size, ctx=gl)
        yield size, border, mask


def test_border_never_drawn_and_silhouette_reaches_margin(gl):
    worst_gap = 0
    for size, b, mask in _case_masks(gl, seed=20260521):
        w, h = (size, size) if isinstance(size, int) else size
        assert mask.shape == (h, w)
        drawn = mask > 0.5
        inside = np.zeros_like(drawn)
        inside[b:-b, b:-b] = True
        assert not (drawn & ~inside).any(), f"map {size}: the {b}-texel border was drawn"
        cols = np.flatnonzero(drawn.any(axis=0))
        rows = np.flatnonzero(drawn.any(axis=1))
        assert cols.size, f"map {size}: empty shadow map"
        # Distance in texels from the silhouette's extreme texel to the first texel inside
        # the border, on the nearer side (the frustum is symmetric: one side touches).
        gap_x = min(cols[0] - b, w - 1 - b - cols[-1])
        gap_y = min(rows[0] - b, h - 1 - b - rows[-1])
        worst_gap = max(worst_gap, gap_x, gap_y)
        assert gap_x <= 1, f"map {size}: silhouette {gap_x} texels short of the margin in s"
        assert gap_y <= 1, f"map {size}: silhouette {gap_y} texels short of the margin in t"
    print(f"{CASES} random cases, worst gap to the margin: {worst_gap} texel(s)")


def test_margin_is_what_keeps_the_border_empty(gl):
    """Without the border margin (margin 1.0) the same scenes do draw into the border texels:
    the test above would catch a frustum that forgot the margin."""
    rng = np.random.default_rng(7)
    touched = 0
    for _ in range(20):
        mesh, placement, light = _random_case(rng)
        setup = fit_shadow(light, mesh.vertices, 32, blocker_to_world=placement, margin=1.0)
        mask = render_shadow_map(mesh.vertices, mesh.faces, setup.blocker_to_clip, 32, ctx=gl)
        edge = mask[0].max() + mask[-1].max() + mask[:, 0].max() + mask[:, -1].max()
        touched += edge > 0
    assert touched >= 15


def test_rows_run_along_t_and_columns_along_s(gl):
    """Row 0 is texture t = 0 (GL's bottom row): a triangle in the lower-left NDC quadrant
    appears at low row and column indices."""
    tri = np.array([[-0.9, -0.9, 0.0], [-0.2, -0.9, 0.0], [-0.9, -0.2, 0.0]])
    mask = render_shadow_map(tri, [[0, 1, 2]], np.eye(4), (40, 20), ctx=gl)
    rows, cols = np.nonzero(mask)
    assert mask.shape == (20, 40)
    assert rows.max() < 10
    assert cols.max() < 20
    assert mask[1, 2] == 1.0
    assert mask[18, 37] == 0.0


def test_no_depth_test_and_flat_colour(gl):
    """Overlapping triangles at different depths all draw, with the same flat value."""
    tris = np.array(
        [
            [-0.5, -0.5, 0.9],
            [0.5, -0.5, 0.9],
            [0.0, 0.5, 0.9],
            [-0.5, 0.5, -0.9],
            [0.5, 0.5, -0.9],
            [0.0, -0.5, -0.9],
        ]
    )
    # The first counter-clockwise and near, the second clockwise (a back face) and far.
    mask = render_shadow_map(tris, [[0, 1, 2], [3, 4, 5]], np.eye(4), 32, ctx=gl)
    assert set(np.unique(mask)) == {0.0, 1.0}
    # Both drawn (no culling, no depth test): texels that only one of them covers are set.
    assert mask[8, 8] == 1.0  # near the first's lower-left corner
    assert mask[23, 8] == 1.0  # near the second's upper-left corner


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"vertices": np.zeros((3, 2))}, "vertices"),
        ({"triangles": [[0, 1, 5]]}, "triangles"),
        ({"triangles": [[0.0, 1.0, 2.0]]}, "integer"),
        ({"blocker_to_clip": np.eye(3)}, "blocker_to_clip"),
        ({"blocker_to_clip": np.full((4, 4), np.nan)}, "non-finite"),
        ({"map_size": 0}, "map_size"),
        ({"map_size": (16, 16, 1)}, "map_size"),
    ],
)
def test_bad_input_raises(gl, kwargs, match):
    args = {
        "vertices": np.eye(3),
        "triangles": [[0, 1, 2]],
        "blocker_to_clip": np.eye(4),
        "map_size": 16,
    }
    args.update(kwargs)
    with pytest.raises(ValueError, match=match):
        render_shadow_map(**args, ctx=gl)
