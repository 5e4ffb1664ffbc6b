r"""Many meshes with their world transforms as one world-space :class:`~shadowmath.Mesh`.

A renderer holds its scene as meshes in local coordinates, each placed by a 4 x 4
world matrix; the fits take one set of casters and one of receivers in world
coordinates. :func:`gather_meshes` is that step, for any renderer.
"""

from __future__ import annotations

from collections.abc import Iterable
from typing import Any, NamedTuple

import numpy as np

from ._boundary._shapes import ArrayLike, Real
from ._boundary._validate import (
    Array,
    Checks,
    Context,
    check_faces,
    convert,
    is_tracer,
    non_finite,
)
from ._math._specialize import formulas
from .receivers import Mesh, Triangles


class _Part(NamedTuple):
    """One entry as vertices ``(V, 3)``, NumPy faces ``(F, 3)`` and a transform or None."""

    vertices: Any
    faces: np.ndarray
    transform: Any


def gather_meshes(
    meshes: Iterable[tuple[Mesh | Triangles, Real[ArrayLike, "4 4"] | None]],
) -> Mesh:
    r"""Concatenate meshes placed by world transforms into one world-space mesh.

    Entry ``i`` is a pair ``(mesh, M_i)``; its vertices :math:`v` (local coordinates)
    go to the world by the affine transform once,

    .. math:: w = A_i v + t_i, \qquad M_i = \begin{pmatrix} A_i & t_i \\ 0 & 1 \end{pmatrix},

    and its faces are offset by the number of vertices gathered before it,
    :math:`o_i = \sum_{j < i} V_j`, so that every triangle keeps its corners. The result
    serves as casters (``fit_shadow(light, gathered.vertices, ...)``, or whole triangles
    for ``cube_depth_range`` and ``fit_atlas``) and as ``receivers=``.

    Arguments:
        meshes: pairs ``(mesh, transform)``. ``mesh`` is an :class:`~shadowmath.Mesh`
            (``vertices`` ``(V, 3)``, integer ``faces`` ``(F, 3)``; what the builders of
            :mod:`shadowmath.meshes` return) or :class:`~shadowmath.Triangles` ``(M, 3, 3)``
            (each corner becomes a vertex).
            ``transform`` is its ``(4, 4)`` local-to-world matrix (column vectors,
            ``w = M @ (v, 1)``), affine (last row ``(0, 0, 0, 1)``), or None when the
            vertices are already in world coordinates. No batch dimensions: one scene.

    Returns:
        :class:`~shadowmath.Mesh`: ``vertices`` ``(sum V_i, 3)`` in the promoted float
        dtype of the inputs (JAX in gives JAX out), ``faces`` ``(sum F_i, 3)`` int64
        NumPy. No entries give an empty mesh, ``(0, 3)`` and ``(0, 3)``.

    Raises:
        ValueError: naming ``meshes[i]``: an entry that is not a pair, a mesh of another
            type, vertices not ``(V, 3)``, faces not ``(F, 3)`` or not inside ``[0, V)``
            or not concrete (traced faces cannot be offset), a transform not
            ``(4, 4)``, non-finite vertices or transform, a projective transform (last row
            not ``(0, 0, 0, 1)``). Under JAX transformations the vertices of an entry
            with non-finite values or a projective transform are NaN instead.
        TypeError: ``meshes[i].faces`` not integers (as for any :class:`Mesh`).

    Example:
        >>> quad = Mesh(np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]]),
        ...             np.array([[0, 1, 2], [0, 2, 3]]))
        >>> lift = np.eye(4); lift[2, 3] = 5.0
        >>> scene = gather_meshes([(quad, None), (quad, lift)])
        >>> scene.vertices[4:].tolist()
        [[0.0, 0.0, 5.0], [1.0, 0.0, 5.0], [1.0, 1.0, 5.0], [0.0, 1.0, 5.0]]
        >>> scene.faces.tolist()
        [[0, 1, 2], [0, 2, 3], [4, 5, 6], [4, 6, 7]]
    """
    parts = [_part(i, entry) for i, entry in enumerate(meshes)]
    named: dict[str, Any] = {}
    for i, part in enumerate(parts):
        named[f"meshes[{i}].vertices"] = part.vertices
        named[f"meshes[{i}] transform"] = part.transform
    ctx, arrays = convert(**named)
    xp = ctx.xp
    placed, faces, offset = [], [], 0
    for i, part in enumerate(parts):
        V, M = arrays[2 * i], arrays[2 * i + 1]
        placed.append(_placed(ctx, V, M, f"meshes[{i}]"))
        faces.append(part.faces + offset)
        offset += int(V.shape[0])
    if not parts:
        return Mesh(np.zeros((0, 3)), np.zeros((0, 3), dtype=np.int64))
    return Mesh(xp.concatenate(placed), np.concatenate(faces).astype(np.int64))


def _part(i: int, entry: Any) -> _Part:
    """Entry ``i`` as vertices, checked NumPy faces and its transform (shapes checked)."""
    name = f"meshes[{i}]"
    if not (isinstance(entry, tuple) and len(entry) == 2) or hasattr(entry, "_fields"):
        raise ValueError(
            f"{name}: expected a pair (mesh, transform), the transform a (4, 4) matrix or "
            f"None, got {type(entry).__name__}"
        )
    mesh, transform = entry
    if isinstance(mesh, Triangles):
        corners = np.shape(mesh.corners)
        if len(corners) != 3 or corners[1:] != (3, 3):
            raise ValueError(f"{name}: expected Triangles of shape (M, 3, 3), got {corners}")
        vertices: Any = _reshaped(mesh.corners, (corners[0] * 3, 3))
        faces = np.arange(3 * corners[0], dtype=np.int64).reshape(-1, 3)
    else:
        indices = getattr(mesh, "faces", None)
        vertices = getattr(mesh, "vertices", None)
        if vertices is None or indices is None:
            raise ValueError(
                f"{name}: expected an sm.Mesh (vertices, faces) or sm.Triangles, "
                f"got {type(mesh).__name__}"
            )
        if np.ndim(vertices) != 2 or np.shape(vertices)[1] != 3:
            raise ValueError(f"{name}: expected vertices (V, 3), got {np.shape(vertices)}")
        faces = _faces(name, indices, int(np.shape(vertices)[0]))
    if transform is not None and np.shape(transform) != (4, 4):
        raise ValueError(f"{name}: expected a (4, 4) transform, got {np.shape(transform)}")
    return _Part(vertices, faces, transform)


def _reshaped(a: Any, shape: tuple[int, ...]) -> Any:
    return a.reshape(shape) if hasattr(a, "reshape") else np.reshape(a, shape)


def _faces(name: str, faces: Any, count: int) -> np.ndarray:
    """Concrete integer faces ``(F, 3)`` inside ``[0, count)``, as NumPy int64."""
    if is_tracer(faces):
        raise ValueError(f"{name}: its faces must be concrete indices, not traced")
    f = np.asarray(faces)
    check_faces(f"{name}.faces", f, count)
    return f.astype(np.int64)


def _placed(ctx: Context, V: Array, M: Array | None, name: str) -> Array:
    """``V`` through the affine ``M`` (checked: NaN under tracing where it fails)."""
    xp, checks = ctx.xp, Checks(ctx)
    checks.require(xp.all(xp.isfinite(V)), non_finite(f"{name}.vertices"))
    if M is None:
        return checks.poison(V, 2)
    checks.require(xp.all(xp.isfinite(M)), non_finite(f"{name} transform"))
    entries = tuple(M[i // 4, i % 4] for i in range(16))
    checks.require(
        formulas(xp).placement_affine(entries, ctx.eps),
        f"{name}: its transform's last row is not (0, 0, 0, 1) (a projective transform); "
        "give an affine local-to-world matrix",
    )
    return checks.poison(V @ xp.matrix_transpose(M[:3, :3]) + M[:3, 3], 2)
