"""Receivers as surfaces: triangles, or an indexed mesh, for ``fit_shadow(receivers=)``.

A plain ``(*batch, M, 3)`` array passed as ``receivers=`` is a set of points, always;
these types say that the receivers are surfaces, whose every point that the map covers
the depth range must hold (a floor whose corners all lie outside the map still
crosses it). Receivers never add batch dimensions to a fit: a raw ``(M, 3, 3)`` array
of triangles, read as ``M`` point sets, is refused beside one light and caster set.
Like the lights they are NamedTuples of arrays, so JAX pytrees, and the kind is the
type: static for ``jit``.
"""

from __future__ import annotations

from typing import NamedTuple

from ._boundary._shapes import ArrayLike, Integer, Real


class Triangles(NamedTuple):
    """Receiver triangles, each given by its three corners.

    Attributes:
        corners: ``(*batch, M, 3, 3)``: ``M`` triangles, three corners ``(x, y, z)``
            each, in world coordinates.

    Example:
        >>> import numpy as np
        >>> a, b, c, d = [-9, 0, -9], [9, 0, -9], [9, 0, 9], [-9, 0, 9]
        >>> Triangles(np.array([[a, b, c], [a, c, d]])).corners.shape
        (2, 3, 3)
    """

    corners: Real[ArrayLike, "*#batch _ 3 3"]


class Mesh(NamedTuple):
    """An indexed triangle mesh: shared vertices and the triangles that index them.

    The one mesh type of shadowmath: what :mod:`shadowmath.meshes` builds and loads
    (float64 vertices, int64 faces wound counter-clockwise seen from outside), and
    what ``receivers=``, :func:`cube_depth_range`'s and :func:`fit_atlas`'s casters take.

    Attributes:
        vertices: ``(*batch, V, 3)`` in world coordinates.
        faces: ``(F, 3)`` integer indices into ``vertices``, one row per triangle
            (the same faces for every batch entry). Under JAX transformations an
            index outside ``[0, V)`` cannot raise: that triangle is NaN, and so is
            the fit.

    Example:
        >>> import numpy as np
        >>> quad = np.array([[-9, 0, -9], [9, 0, -9], [9, 0, 9], [-9, 0, 9]])
        >>> Mesh(quad, np.array([[0, 1, 2], [0, 2, 3]])).faces.shape
        (2, 3)
    """

    vertices: Real[ArrayLike, "*#batch _ 3"]
    faces: Integer[ArrayLike, "_ 3"]
