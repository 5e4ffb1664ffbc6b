"""The ray caster itself, against analytic shadows (no GL needed)."""

from __future__ import annotations

import numpy as np
import pytest

from shadowmath.groundtruth import segment_hits_triangles
from shadowmath.meshes import sphere


def test_triangle_cases():
    tri = np.array([[-1.0, -1.0, 1.0], [1.0, -1.0, 1.0], [0.0, 1.0, 1.0]])
    t = [[0, 1, 2]]
    light = [0.0, 0.0, 2.0]
    points = np.array(
        [
            [0.0, 0.0, 0.0],  # below its centre
            [3.0, 0.0, 0.0],  # off to the side
            [0.0, 0.0, 1.5],  # between the triangle and the light: the segment misses it
            [0.0, 0.0, 3.0],  # beyond the light
            [0.0, 0.0, 1.0],  # on the triangle: touching is not a shadow
            [0.0, 0.9, 0.0],  # below, but its segment leaves through the triangle's tip region
        ]
    )
    hits = segment_hits_triangles(points, light, tri, t)
    # (0, 0.9, 0) -> light: crosses z = 1 at (0, 0.45): inside the triangle (y <= 1 - 2|x|).
    assert hits.tolist() == [True, False, False, False, False, True]
    # Winding does not matter: both faces block.
    assert segment_hits_triangles(points, light, tri, [[0, 2, 1]]).tolist() == hits.tolist()


def test_sphere_shadow_is_the_analytic_cone():
    """A point's segment to the light hits a sphere iff its distance to the centre is < r."""
    rng = np.random.default_rng(3)
    centre, r = np.array([0.2, -0.1, 3.0]), 1.0
    mesh = sphere(r, segments=96, rings=48)
    light = np.array([0.0, 0.0, 8.0])
    points = np.c_[rng.uniform(-4, 4, size=(4000, 2)), np.zeros(4000)]
    seg = light - points
    along = np.clip(np.sum((centre - points) * seg, axis=1) / np.sum(seg * seg, axis=1), 0, 1)
    distance = np.linalg.norm(points + along[:, None] * seg - centre, axis=1)
    hits = segment_hits_triangles(points, light, mesh.vertices + centre, mesh.faces)
    # The tessellation is inscribed: its radius lies within r cos(pi / 48) and r.
    clear = (distance < 0.99 * r) | (distance > r)
    assert clear.sum() > 3500
    assert np.array_equal(hits[clear], distance[clear] < r)


def test_directional_light_casts_the_unbounded_ray():
    """w = 0: the ray from each point toward the light's direction, however far away the
    triangle is; its shadow is the triangle translated along the direction (a prism)."""
    tri = np.array([[-1.0, -1.0, 1.0], [1.0, -1.0, 1.0], [0.0, 1.0, 1.0]])
    direction = np.array([1.0, 0.0, 2.0])  # toward the light: up and toward +x
    points = np.array(
        [
            [-0.5, 0.0, 0.0],  # (0, 0, 1) at t = 1/2: inside
            [0.0, 0.0, 0.0],  # (0.5, 0, 1): inside (y <= 1 - 2|x| = 0)
            [1.0, 0.0, 0.0],  # (1.5, 0, 1): outside
            [-0.5, 0.0, 1.5],  # above the triangle: the ray leaves upward, misses
            [-100.5, 0.0, -200.0],  # far below: (0, 0, 1) at t = 100.5
        ]
    )
    hits = segment_hits_triangles(points, np.append(direction, 0.0), tri, [[0, 1, 2]])
    assert hits.tolist() == [True, True, False, False, True]
    # Scaling the direction changes nothing; a point light far along it agrees nearby.
    scaled = segment_hits_triangles(points, np.append(3 * direction, 0.0), tri, [[0, 1, 2]])
    assert scaled.tolist() == hits.tolist()
    far = segment_hits_triangles(points[:4], 1e6 * direction, tri, [[0, 1, 2]])
    assert far.tolist() == hits[:4].tolist()
    # A homogeneous point (w != 0) is the point xyz / w.
    point = segment_hits_triangles(points, [0.0, 0.0, 4.0, 2.0], tri, [[0, 1, 2]])
    assert point.tolist() == segment_hits_triangles(points, [0, 0, 2], tri, [[0, 1, 2]]).tolist()


def test_directional_sphere_shadow_is_the_analytic_cylinder():
    rng = np.random.default_rng(4)
    centre, r = np.array([0.3, -0.2, 3.0]), 1.0
    mesh = sphere(r, segments=96, rings=48)
    d = np.array([0.4, -0.3, 1.0])
    u = d / np.linalg.norm(d)
    points = np.c_[rng.uniform(-4, 4, size=(3000, 2)), np.zeros(3000)]
    rel = centre - points
    distance = np.linalg.norm(rel - np.sum(rel * u, axis=1)[:, None] * u, axis=1)
    hits = segment_hits_triangles(points, np.append(d, 0), mesh.vertices + centre, mesh.faces)
    clear = (distance < 0.99 * r) | (distance > r)
    assert clear.sum() > 2500
    assert np.array_equal(hits[clear], distance[clear] < r)


def test_batch_shape_and_empty():
    tri = [[-1.0, -1.0, 1.0], [1.0, -1.0, 1.0], [0.0, 1.0, 1.0]]
    points = np.zeros((2, 3, 3))
    assert segment_hits_triangles(points, [0, 0, 2], tri, [[0, 1, 2]]).shape == (2, 3)
    assert segment_hits_triangles(np.zeros((0, 3)), [0, 0, 2], tri, [[0, 1, 2]]).shape == (0,)


@pytest.mark.parametrize(
    ("args", "match"),
    [
        (([[0, 0]], [0, 0, 1], [[0, 0, 0]], [[0, 0, 0]]), "points"),
        (([[0, 0, 0]], [0, 0, 1, 1, 1], [[0, 0, 0]], [[0, 0, 0]]), "light_position"),
        (([[0, 0, 0]], [0, 0, 0, 0], [[0, 0, 0]], [[0, 0, 0]]), "direction"),
        (([[0, 0, 0]], [0, 0, np.nan], [[0, 0, 0]], [[0, 0, 0]]), "non-finite"),
        (([[0, 0, 0]], [0, 0, 1], [[0, 0, 0]], [[0, 0, 1]]), "indices"),
        (([[0, 0, 0]], [0, 0, 1], [[0, 0, 0]], [[0.0, 0, 0]]), "integer"),
    ],
)
def test_bad_input(args, match):
    with pytest.raises(ValueError, match=match):
        segment_hits_triangles(*args)
