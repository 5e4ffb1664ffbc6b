"""sm.gather_meshes: many placed meshes as one world-space mesh.

The reference is each mesh transformed by hand, point by point in homogeneous
coordinates (``M @ (v, 1)``, then the division by ``w``, which is 1 for an affine
placement), and each triangle's world corners compared one by one.
"""

from __future__ import annotations

import jax
import jax.numpy as jnp
import numpy as np
import pytest

import shadowmath as sm
from shadowmath.meshes import box, grid, torus


def _placement(rng: np.random.Generator) -> np.ndarray:
    m = np.eye(4)
    turn, _ = np.linalg.qr(rng.normal(size=(3, 3)))  # an orthogonal matrix
    m[:3, :3] = turn @ np.diag(rng.uniform(0.5, 2, 3))
    m[:3, 3] = rng.uniform(-5, 5, 3)
    return m


def _by_hand(vertices: np.ndarray, m: np.ndarray) -> np.ndarray:
    out = []
    for v in np.asarray(vertices, dtype=float):
        p = m @ np.append(v, 1.0)
        out.append(p[:3] / p[3])
    return np.array(out)


def test_gathering_is_each_mesh_placed_by_hand():
    rng = np.random.default_rng(3)
    parts = [box((1.0, 2.0, 0.5)), torus(1.0, 0.3, segments=8, sides=6), grid((4.0, 4.0))]
    placements = [_placement(rng) for _ in parts]
    soup = sm.Triangles(rng.normal(size=(5, 3, 3)))
    gathered = sm.gather_meshes(
        [*zip(parts, placements, strict=True), (soup, None), (sm.Mesh(*parts[0]), placements[0])]
    )
    corners = []
    for mesh, m in zip(parts, placements, strict=True):
        corners.append(_by_hand(mesh.vertices, m)[mesh.faces])
    corners.append(soup.corners)
    corners.append(corners[0])
    expected = np.concatenate(corners)
    assert gathered.faces.dtype == np.int64
    assert gathered.faces.shape == (len(expected), 3)
    assert np.allclose(gathered.vertices[gathered.faces], expected, rtol=0, atol=1e-12)
    # The faces of entry i index only its own vertices, offset by those before it.
    sizes = [len(p.vertices) for p in parts] + [15, len(parts[0].vertices)]
    starts = np.cumsum([0, *sizes])
    counts = [len(p.faces) for p in parts] + [5, len(parts[0].faces)]
    first = np.cumsum([0, *counts])
    for i in range(len(sizes)):
        f = gathered.faces[first[i] : first[i + 1]]
        assert f.min() >= starts[i] and f.max() < starts[i + 1]
    assert len(gathered.vertices) == starts[-1]


def test_gathered_mesh_fits_as_the_hand_placed_one():
    """The gathered mesh is what the fits take: the same receiver far plane as by hand."""
    rng = np.random.default_rng(5)
    floor, m = grid((10.0, 10.0)), _placement(rng)
    gathered = sm.gather_meshes([(floor, m)])
    by_hand = sm.Triangles(_by_hand(floor.vertices, m)[floor.faces])
    light = sm.PointLight(m[:3, 3] + 20 * m[:3, 2])
    blocker = _by_hand(box().vertices, m) + 3 * m[:3, 2]
    a = sm.fit_shadow(light, blocker, 512, receivers=gathered)
    b = sm.fit_shadow(light, blocker, 512, receivers=by_hand)
    assert np.allclose(a.blocker_to_clip, b.blocker_to_clip, rtol=1e-12, atol=1e-12)


def test_no_meshes_give_an_empty_mesh():
    empty = sm.gather_meshes([])
    assert empty.vertices.shape == (0, 3) and empty.faces.shape == (0, 3)


def test_gather_under_jax_jit():
    quad = grid((2.0, 2.0))
    m = _placement(np.random.default_rng(1))

    @jax.jit
    def gathered(placement):
        return sm.gather_meshes([(quad, placement), (quad, None)]).vertices

    with jax.enable_x64():
        out = gathered(jnp.asarray(m))
        assert isinstance(out, jax.Array)
        assert np.allclose(out[:4], _by_hand(quad.vertices, m), atol=1e-12)
        bad = m.copy()
        bad[3] = [0.0, 0.0, 0.5, 1.0]
        poisoned = np.asarray(gathered(jnp.asarray(bad)))
        assert np.isnan(poisoned[:4]).all() and np.isfinite(poisoned[4:]).all()


def test_gather_refusals():
    quad = grid()
    v, f = quad.vertices, quad.faces
    projective = np.eye(4)
    projective[3, 2] = 1.0
    cases = [
        ([(quad, projective)], r"meshes\[0\]: its transform's last row is not \(0, 0, 0, 1\)"),
        ([(quad, None), (quad, np.full((4, 4), np.nan))], r"meshes\[1\] transform: .*non-finite"),
        ([(quad, np.eye(3))], r"meshes\[0\]: expected a \(4, 4\) transform, got \(3, 3\)"),
        ([quad], r"meshes\[0\]: expected a pair \(mesh, transform\)"),
        ([(np.zeros((3, 3)), None)], r"meshes\[0\]: expected an sm.Mesh"),
        ([(sm.Mesh(v, f + 1), None)], r"meshes\[0\]\.faces: indices must lie in \[0, 4\)"),
        ([(sm.Mesh(v[None], f), None)], r"meshes\[0\]: expected vertices \(V, 3\)"),
        ([(sm.Triangles(np.zeros((2, 3))), None)], r"meshes\[0\]: expected Triangles of shape"),
        ([(sm.Mesh(v * np.nan, f), None)], r"meshes\[0\].vertices: .*non-finite"),
    ]  # fmt: skip
    for meshes, message in cases:
        with pytest.raises(ValueError, match=message):
            sm.gather_meshes(meshes)
    with pytest.raises(TypeError, match=r"meshes\[0\]\.faces: expected integer indices"):
        sm.gather_meshes([(sm.Mesh(v, f * 1.0), None)])
