"""Triangle meshes to cast and receive shadows: procedural shapes and an OBJ loader.

Every function returns a :class:`shadowmath.Mesh` (the one mesh type: what
``receivers=``, ``cube_depth_range`` and ``fit_atlas`` take): ``vertices``
``(N, 3)`` float64 and ``faces`` ``(M, 3)`` int64 indices into them, wound
counter-clockwise seen from outside (the right-hand rule gives the outward normal), so closed meshes
have a positive signed volume. Plain NumPy: no GL, no JAX, no optional
dependency except for :func:`load_mesh` on formats other than OBJ.
"""

from __future__ import annotations

import os

import numpy as np
from numpy.typing import NDArray

from ._boundary._shapes import shapes_checked
from ._boundary._validate import integer, real
from .receivers import Mesh as Mesh

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.int64]


def _grid_triangles(rows: int, cols: int, *, wrap_cols: bool, wrap_rows: bool) -> IntArray:
    """Two triangles per cell of a ``rows x cols`` vertex grid (vertex ``r * cols + c``).

    Cell ``(r, c)`` spans vertices ``r, r+1`` and ``c, c+1`` (mod the size when
    wrapping); the winding is counter-clockwise when ``r`` runs along the first
    tangent and ``c`` along the second of a right-handed (tangent, tangent, normal).
    """
    r_cells = rows if wrap_rows else rows - 1
    c_cells = cols if wrap_cols else cols - 1
    r = np.arange(r_cells)[:, None]
    c = np.arange(c_cells)[None, :]
    r1 = (r + 1) % rows
    c1 = (c + 1) % cols
    a = r * cols + c
    b = r1 * cols + c
    d = r * cols + c1
    e = r1 * cols + c1
    first = np.stack(np.broadcast_arrays(a, b, e), axis=-1).reshape(-1, 3)
    second = np.stack(np.broadcast_arrays(a, e, d), axis=-1).reshape(-1, 3)
    return np.concatenate([first, second]).astype(np.int64)


def _positive(name: str, value: float) -> float:
    number = real(name, value)
    if not (np.isfinite(number) and number > 0):
        raise ValueError(f"{name}: must be a positive finite number, got {value!r}")
    return number


def _count(name: str, value: int, minimum: int) -> int:
    return integer(name, value, minimum)


@shapes_checked
def torus(
    major_radius: float = 1.0,
    minor_radius: float = 0.35,
    *,
    segments: int = 48,
    sides: int = 24,
) -> Mesh:
    r"""A torus around the ``z`` axis, centred at the origin (the article's blocker).

    .. math::

        p(u, v) = \big((R + r\cos v)\cos u,\; (R + r\cos v)\sin u,\; r \sin v\big)

    Arguments:
        major_radius: ``R``, from the centre to the tube's centre line.
        minor_radius: ``r``, the tube's radius (``< R``).
        segments: vertices around the ``z`` axis.
        sides: vertices around the tube.

    Returns:
        :class:`Mesh` with ``segments * sides`` vertices and twice as many triangles.

    Raises:
        ValueError: non-positive radii, ``r >= R``, fewer than 3 segments or sides.

    Example:
        >>> m = torus(segments=8, sides=4)
        >>> m.vertices.shape, m.faces.shape
        ((32, 3), (64, 3))
    """
    R = _positive("major_radius", major_radius)
    r = _positive("minor_radius", minor_radius)
    if r >= R:
        raise ValueError(f"minor_radius: must be smaller than major_radius ({r} >= {R})")
    n = _count("segments", segments, 3)
    m = _count("sides", sides, 3)
    u = np.linspace(0, 2 * np.pi, n, endpoint=False)[:, None]
    v = np.linspace(0, 2 * np.pi, m, endpoint=False)[None, :]
    ring = R + r * np.cos(v)
    vertices = np.stack(
        np.broadcast_arrays(ring * np.cos(u), ring * np.sin(u), r * np.sin(v)), axis=-1
    ).reshape(-1, 3)
    # u grows counter-clockwise about +z and v about the tube's tangent: (d/du, d/dv)
    # is right-handed with the outward normal, so (row=u, col=v) cells wind outward.
    return Mesh(vertices, _grid_triangles(n, m, wrap_cols=True, wrap_rows=True))


@shapes_checked
def sphere(radius: float = 1.0, *, segments: int = 32, rings: int = 16) -> Mesh:
    """A UV sphere centred at the origin, poles on the ``z`` axis.

    Arguments:
        radius: the sphere's radius.
        segments: vertices around each ring of latitude.
        rings: bands of latitude between the poles.

    Returns:
        :class:`Mesh`: ``segments * (rings - 1) + 2`` vertices (one per pole).

    Raises:
        ValueError: a non-positive radius, fewer than 3 segments or 2 rings.

    Example:
        >>> m = sphere(segments=6, rings=3)
        >>> m.vertices.shape, m.faces.shape
        ((14, 3), (24, 3))
    """
    rad = _positive("radius", radius)
    n = _count("segments", segments, 3)
    k = _count("rings", rings, 2)
    theta = np.linspace(0, np.pi, k + 1)[1:-1, None]  # polar angle of the inner rings
    phi = np.linspace(0, 2 * np.pi, n, endpoint=False)[None, :]
    ring_vertices = np.stack(
        np.broadcast_arrays(
            np.sin(theta) * np.cos(phi), np.sin(theta) * np.sin(phi), np.cos(theta)
        ),
        axis=-1,
    ).reshape(-1, 3)
    vertices = rad * np.concatenate([[[0.0, 0.0, 1.0]], ring_vertices, [[0.0, 0.0, -1.0]]])
    # Rows run from north to south (along -d/dtheta... i.e. +theta) and columns along
    # +phi: (d/dtheta, d/dphi) is right-handed with the outward normal.
    body = _grid_triangles(k - 1, n, wrap_cols=True, wrap_rows=False) + 1
    c = np.arange(n)
    c1 = (c + 1) % n
    north = np.stack([np.zeros(n, dtype=np.int64), c + 1, c1 + 1], axis=-1)
    south_pole = len(vertices) - 1
    last = 1 + (k - 2) * n
    south = np.stack([np.full(n, south_pole), last + c1, last + c], axis=-1)
    return Mesh(vertices, np.concatenate([north, body, south]).astype(np.int64))


@shapes_checked
def box(size: tuple[float, float, float] = (1.0, 1.0, 1.0)) -> Mesh:
    """An axis-aligned box centred at the origin, four vertices per face (flat normals).

    Arguments:
        size: ``(sx, sy, sz)`` edge lengths.

    Returns:
        :class:`Mesh` with 24 vertices and 12 triangles.

    Raises:
        ValueError: a non-positive edge length.

    Example:
        >>> m = box((2.0, 1.0, 1.0))
        >>> float(m.vertices[:, 0].max()), m.faces.shape
        (1.0, (12, 3))
    """
    half = np.array([_positive(f"size[{i}]", s) for i, s in enumerate(size)]) / 2
    faces = []
    for axis in range(3):
        for sign in (1.0, -1.0):
            # (t1, t2, normal) right-handed: corners in counter-clockwise order.
            n = np.zeros(3)
            n[axis] = sign
            t1 = np.zeros(3)
            t1[(axis + 1) % 3] = 1.0
            t2 = np.cross(n, t1)
            corners = [n + a * t1 + b * t2 for a, b in ((-1, -1), (1, -1), (1, 1), (-1, 1))]
            faces.append(np.array(corners))
    vertices = np.concatenate(faces) * half
    quads = np.arange(24).reshape(6, 4)
    triangles = np.concatenate([quads[:, [0, 1, 2]], quads[:, [0, 2, 3]]])
    return Mesh(vertices, triangles.astype(np.int64))


@shapes_checked
def bar(length: float = 3.0, thickness: float = 0.08) -> Mesh:
    """A long thin bar along ``x``: a hard case for the frustum (a very wide silhouette).

    Arguments:
        length: extent along ``x``.
        thickness: extent along ``y`` and ``z``.

    Returns:
        :class:`Mesh` (a :func:`box`).

    Example:
        >>> float(bar(4.0, 0.1).vertices[:, 0].max())
        2.0
    """
    return box((length, thickness, thickness))


@shapes_checked
def grid(size: tuple[float, float] = (1.0, 1.0), *, segments: tuple[int, int] = (1, 1)) -> Mesh:
    """A flat rectangle in the ``z = 0`` plane, centred at the origin, facing ``+z``.

    Displace its ``z`` to make a bumpy surface (a height field), or place it with
    a matrix to make a floor or a wall.

    Arguments:
        size: ``(sx, sy)`` extents along ``x`` and ``y``.
        segments: ``(nx, ny)`` cells along ``x`` and ``y``.

    Returns:
        :class:`Mesh` with ``(nx + 1) (ny + 1)`` vertices and ``2 nx ny`` triangles.

    Raises:
        ValueError: non-positive sizes or segment counts.

    Example:
        >>> m = grid((2.0, 2.0), segments=(2, 3))
        >>> m.vertices.shape, m.faces.shape
        ((12, 3), (12, 3))
    """
    sx, sy = (_positive(f"size[{i}]", s) for i, s in enumerate(size))
    nx, ny = (_count(f"segments[{i}]", s, 1) for i, s in enumerate(segments))
    x = np.linspace(-sx / 2, sx / 2, nx + 1)[:, None]
    y = np.linspace(-sy / 2, sy / 2, ny + 1)[None, :]
    vertices = np.stack(np.broadcast_arrays(x, y, np.zeros_like(x * y)), axis=-1).reshape(-1, 3)
    # Rows along +x, columns along +y: (x, y, +z) is right-handed.
    return Mesh(vertices, _grid_triangles(nx + 1, ny + 1, wrap_cols=False, wrap_rows=False))


@shapes_checked
def signed_volume(mesh: Mesh) -> float:
    r"""The signed volume enclosed by a closed mesh (divergence theorem).

    .. math:: V = \frac16 \sum_{(a, b, c)} a \cdot (b \times c)

    Positive when the triangles wind counter-clockwise seen from outside.

    Example:
        >>> round(signed_volume(box((1.0, 2.0, 3.0))), 12)
        6.0
    """
    a, b, c = (mesh.vertices[mesh.faces[:, i]] for i in range(3))
    return float(np.sum(a * np.cross(b, c)) / 6.0)


def _parse_index(token: str, count: int, path: str, line_number: int) -> int:
    text = token.split("/")[0]
    try:
        index = int(text)
    except ValueError:
        raise ValueError(f"{path}:{line_number}: bad face index {token!r}") from None
    # OBJ indices are 1-based; negative ones count back from the last vertex read.
    resolved = index - 1 if index > 0 else count + index
    if index == 0 or not 0 <= resolved < count:
        raise ValueError(f"{path}:{line_number}: face index {index} out of range (1..{count})")
    return resolved


@shapes_checked
def load_obj(path: str | os.PathLike[str]) -> Mesh:
    """Read the vertices and faces of a Wavefront OBJ file (no dependency).

    Reads ``v x y z [w]`` and ``f`` lines (``i``, ``i/t``, ``i//n``, ``i/t/n``
    index forms, negative indices, polygons fanned into triangles); ignores
    normals, texture coordinates, groups and materials.

    Arguments:
        path: the ``.obj`` file.

    Returns:
        :class:`Mesh`.

    Raises:
        ValueError: a malformed vertex or face, an index out of range, or a file
            without faces.
        OSError: the file cannot be read.

    Example:
        >>> import pathlib, tempfile
        >>> p = pathlib.Path(tempfile.mkdtemp()) / "quad.obj"
        >>> _ = p.write_text("v 0 0 0\\nv 1 0 0\\nv 1 1 0\\nv 0 1 0\\nf 1 2 3 4\\n")
        >>> load_obj(p).faces
        array([[0, 1, 2],
               [0, 2, 3]])
    """
    name = os.fspath(path)
    vertices: list[list[float]] = []
    triangles: list[list[int]] = []
    with open(name, encoding="utf-8", errors="replace") as f:
        for line_number, line in enumerate(f, start=1):
            parts = line.split("#", 1)[0].split()
            if not parts:
                continue
            if parts[0] == "v":
                try:
                    xyz = [float(t) for t in parts[1:4]]
                    w = float(parts[4]) if len(parts) > 4 else 1.0
                except ValueError:
                    raise ValueError(f"{name}:{line_number}: bad vertex {line.strip()!r}") from None
                if len(xyz) != 3 or w == 0:
                    raise ValueError(f"{name}:{line_number}: bad vertex {line.strip()!r}")
                vertices.append([c / w for c in xyz])
            elif parts[0] == "f":
                idx = [_parse_index(t, len(vertices), name, line_number) for t in parts[1:]]
                if len(idx) < 3:
                    raise ValueError(f"{name}:{line_number}: a face needs at least 3 vertices")
                triangles.extend([idx[0], idx[i], idx[i + 1]] for i in range(1, len(idx) - 1))
    if not triangles:
        raise ValueError(f"{name}: no faces found (an OBJ mesh needs 'f' lines)")
    v = np.asarray(vertices, dtype=np.float64)
    if not np.all(np.isfinite(v)):
        raise ValueError(f"{name}: contains non-finite vertex coordinates")
    return Mesh(v, np.asarray(triangles, dtype=np.int64))


@shapes_checked
def load_mesh(path: str | os.PathLike[str]) -> Mesh:
    """Read a mesh file: OBJ with the built-in reader, other formats through trimesh.

    trimesh is the optional ``mesh`` extra (``pip install 'shadowmath[mesh]'``);
    it reads STL, PLY, GLB/glTF, OFF and more. Scenes are merged into one mesh.

    Arguments:
        path: the file.

    Returns:
        :class:`Mesh`.

    Raises:
        ValueError: an unreadable mesh, or a non-OBJ file without trimesh installed.
        OSError: the file cannot be read.

    Example:
        >>> import pathlib, tempfile
        >>> p = pathlib.Path(tempfile.mkdtemp()) / "tri.obj"
        >>> _ = p.write_text("v 0 0 0\\nv 1 0 0\\nv 0 1 0\\nf 1 2 3\\n")
        >>> load_mesh(p).vertices.shape
        (3, 3)
    """
    name = os.fspath(path)
    if name.lower().endswith(".obj"):
        return load_obj(name)
    try:
        import trimesh
    except ImportError:
        raise ValueError(
            f"{name}: only .obj files are read without trimesh; install the 'mesh' extra "
            "(pip install 'shadowmath[mesh]') for other formats"
        ) from None
    loaded = trimesh.load(name, force="mesh")
    faces = np.asarray(getattr(loaded, "faces", np.empty((0, 3))), dtype=np.int64)
    if faces.ndim != 2 or faces.shape[0] == 0:
        raise ValueError(f"{name}: no triangles found")
    return Mesh(np.asarray(getattr(loaded, "vertices", None), dtype=np.float64), faces)
