"""Procedural meshes and the OBJ reader (no GL needed)."""

from __future__ import annotations

import sys
from collections import Counter

import numpy as np
import pytest

from shadowmath.meshes import (
    Mesh,
    bar,
    box,
    grid,
    load_mesh,
    load_obj,
    signed_volume,
    sphere,
    torus,
)


def _directed_edges(mesh: Mesh) -> Counter:
    t = mesh.faces
    return Counter(map(tuple, np.concatenate([t[:, [0, 1]], t[:, [1, 2]], t[:, [2, 0]]])))


@pytest.mark.parametrize(
    "mesh", [torus(), torus(2.0, 0.5, segments=7, sides=3), sphere(), sphere(segments=3, rings=2)]
)
def test_closed_and_consistently_wound(mesh):
    """Every edge is used once in each direction: a closed, consistently oriented surface."""
    edges = _directed_edges(mesh)
    assert all(count == 1 for count in edges.values())
    assert all((b, a) in edges for a, b in edges)


def test_volumes_are_positive_and_match_the_solids():
    assert signed_volume(box((1.0, 2.0, 3.0))) == pytest.approx(6.0)
    assert signed_volume(bar(4.0, 0.1)) == pytest.approx(0.04)
    # Inscribed polyhedra: slightly less than the smooth solid, converging with resolution.
    coarse, fine = (
        signed_volume(sphere(1.5, segments=16, rings=8)),
        signed_volume(sphere(1.5, segments=128, rings=64)),
    )
    exact = 4 / 3 * np.pi * 1.5**3
    assert 0 < coarse < fine < exact
    assert fine == pytest.approx(exact, rel=2e-3)
    t = signed_volume(torus(1.0, 0.25, segments=256, sides=128))
    assert t == pytest.approx(2 * np.pi**2 * 1.0 * 0.25**2, rel=2e-3)


def test_face_normals_point_outward():
    for mesh, centre_of in (
        (sphere(2.0), lambda c: np.zeros_like(c)),
        (box((1.0, 2.0, 0.5)), lambda c: np.zeros_like(c)),
        # for a torus: away from the tube's centre line
        (
            torus(1.0, 0.3),
            lambda c: np.c_[
                c[:, :2] / np.linalg.norm(c[:, :2], axis=1, keepdims=True), np.zeros(len(c))
            ],
        ),
    ):
        a, b, c = (mesh.vertices[mesh.faces[:, i]] for i in range(3))
        normal = np.cross(b - a, c - a)
        centroid = (a + b + c) / 3
        assert np.all(np.sum(normal * (centroid - centre_of(centroid)), axis=1) > 0)


def test_grid_faces_plus_z_and_spans_its_size():
    g = grid((4.0, 2.0), segments=(4, 3))
    a, b, c = (g.vertices[g.faces[:, i]] for i in range(3))
    n = np.cross(b - a, c - a)
    assert np.all(n[:, 2] > 0)
    assert np.allclose(n[:, :2], 0)
    assert np.sum(n[:, 2]) / 2 == pytest.approx(8.0)  # total area
    assert np.ptp(g.vertices, axis=0) == pytest.approx([4.0, 2.0, 0.0])


def test_bar_is_long_and_thin():
    extent = np.ptp(bar(5.0, 0.05).vertices, axis=0)
    assert extent == pytest.approx([5.0, 0.05, 0.05])


@pytest.mark.parametrize(
    ("make", "match"),
    [
        (lambda: torus(1.0, 1.0), "minor_radius"),
        (lambda: torus(-1.0, 0.2), "major_radius"),
        (lambda: torus(segments=2), "segments"),
        (lambda: sphere(0.0), "radius"),
        (lambda: sphere(rings=1), "rings"),
        (lambda: box((1.0, 0.0, 1.0)), r"size\[1\]"),
        (lambda: grid(segments=(0, 2)), r"segments\[0\]"),
        (lambda: bar(np.inf), "size"),
    ],
)
def test_bad_parameters_raise(make, match):
    with pytest.raises(ValueError, match=match):
        make()


def test_obj_reader(tmp_path):
    path = tmp_path / "m.obj"
    path.write_text(
        "# a comment\n"
        "o thing\n"
        "v 0 0 0\n"
        "v 2 0 0 2\n"  # w = 2: the point (1, 0, 0)
        "v 1 1 0\n"
        "vt 0 0\n"
        "vn 0 0 1\n"
        "v 0 1 0  # trailing comment\n"
        "f 1/1/1 2/1/1 3/1/1 4/1/1\n"  # a quad, fanned
        "f -4//1 -3//1 -1//1\n"  # negative indices count back from the last vertex
        "usemtl red\n"
    )
    mesh = load_obj(path)
    assert mesh.vertices.tolist() == [[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]]
    assert mesh.faces.tolist() == [[0, 1, 2], [0, 2, 3], [0, 1, 3]]
    assert mesh.faces.dtype == np.int64
    assert load_mesh(str(path)).faces.shape == (3, 3)


@pytest.mark.parametrize(
    ("text", "match"),
    [
        ("v 0 0 0\nv 1 0 0\nv 0 1 0\n", "no faces"),
        ("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 4\n", "out of range"),
        ("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 0 1 2\n", "out of range"),
        ("v 0 0 0\nv 1 0 0\nf 1 2\n", "at least 3"),
        ("v 0 zero 0\n", "bad vertex"),
        ("v 0 0\n", "bad vertex"),
        ("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 x\n", "bad face index"),
        ("v nan 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n", "non-finite"),
    ],
)
def test_obj_reader_errors(tmp_path, text, match):
    path = tmp_path / "bad.obj"
    path.write_text(text)
    with pytest.raises(ValueError, match=match):
        load_obj(path)


def test_other_formats_through_trimesh(tmp_path):
    trimesh = pytest.importorskip("trimesh")
    path = tmp_path / "box.stl"
    trimesh.creation.box(extents=(1.0, 2.0, 3.0)).export(path)
    mesh = load_mesh(path)
    assert signed_volume(mesh) == pytest.approx(6.0)


def test_other_formats_without_trimesh_name_the_extra(tmp_path, monkeypatch):
    monkeypatch.setitem(sys.modules, "trimesh", None)  # import trimesh -> ImportError
    with pytest.raises(ValueError, match=r"shadowmath\[mesh\]"):
        load_mesh(tmp_path / "box.stl")
