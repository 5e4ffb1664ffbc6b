"""Hypothesis strategies for shadow scenes: planes, lights, blockers, placements, map sizes.

Valid draws span the scales issue 5 asks for: coordinates from 1e-6 to 1e6
scene units, lights very close to the plane, blockers far away (angular sizes
of a fraction of a degree), nearly tied helper-axis components. Invalid draws
come with the fragment of the ``ValueError`` message they must raise, so a
fuzz test can check "either the documented error, or a correct result".

Everything is drawn as float64 NumPy arrays; tests convert to the backend and
dtype under test (a valid float64 scene stays valid in float32 only when its
margins exceed float32's rounding, so the strategies take ``dtype``).
"""

from __future__ import annotations

from typing import Any, NamedTuple

import numpy as np
from hypothesis import strategies as st

FloatArray = np.ndarray


def _eps(dtype: Any) -> float:
    return float(np.finfo(dtype).eps)


#: Scene scales (a typical length): 1e-6 to 1e6 scene units.
scales = st.integers(-6, 6).map(lambda k: 10.0**k)

#: Map sizes: an int or (width, height), with a border that fits.
square_sizes = st.integers(3, 4096)
map_sizes = st.one_of(square_sizes, st.tuples(st.integers(3, 4096), st.integers(3, 4096)))


@st.composite
def sized_maps(draw: st.DrawFn) -> tuple[int | tuple[int, int], int]:
    """``(map_size, border_texels)`` with room inside the border."""
    size = draw(map_sizes)
    smallest = min(size) if isinstance(size, tuple) else size
    border = draw(st.integers(0, min(4, (smallest - 1) // 2)))
    return size, border


@st.composite
def unit_vectors(draw: st.DrawFn) -> FloatArray:
    """Unit vectors, including axis-aligned ones and nearly tied components."""
    kind = draw(st.sampled_from(["random", "axis", "tie"]))
    if kind == "axis":
        v = np.zeros(3)
        v[draw(st.integers(0, 2))] = draw(st.sampled_from([-1.0, 1.0]))
        return v
    if kind == "tie":
        # |components| equal up to a few ulps: the helper axis' decision is knife-edge.
        signs = np.array(draw(st.lists(st.sampled_from([-1.0, 1.0]), min_size=3, max_size=3)))
        ulps = np.array(draw(st.lists(st.integers(-4, 4), min_size=3, max_size=3)), float)
        v = signs * (1 + ulps * 2.0**-23)
        return v / np.linalg.norm(v)
    v = np.array(draw(st.lists(st.floats(-1, 1), min_size=3, max_size=3)))
    n = np.linalg.norm(v)
    return v / n if n > 0.1 else np.array([0.0, 0.0, 1.0])


class PlanarScene(NamedTuple):
    plane: FloatArray  # (4,)
    light: FloatArray  # (4,)
    scale: float


@st.composite
def planar_scenes(draw: st.DrawFn, dtype: Any = np.float64) -> PlanarScene:
    """A plane and a light clearly off it (point or directional), at any scale.

    The light's distance from the plane is down to 1e-5 of the scene's scale
    (float64) or 1e-3 (float32): near-degenerate but well above rounding.
    """
    scale = draw(scales)
    n = draw(unit_vectors()) * draw(st.floats(0.1, 10))
    anchor = np.array(draw(st.lists(st.floats(-1, 1), min_size=3, max_size=3))) * scale
    plane = np.append(n, -n @ anchor)
    min_rel = 1e-5 if np.dtype(dtype) == np.float64 else 1e-3
    rel = draw(st.floats(np.log10(min_rel), 0)).__rpow__(10.0)
    side = draw(st.sampled_from([-1.0, 1.0]))
    if draw(st.booleans()):  # point light: off the plane by rel * scale
        lateral = np.array(draw(st.lists(st.floats(-1, 1), min_size=3, max_size=3))) * scale
        pos = anchor + lateral
        pos = (
            pos - ((n @ pos + plane[3]) / (n @ n)) * n + side * rel * scale * n / np.linalg.norm(n)
        )
        w = draw(st.sampled_from([1.0, 2.0, 0.5]))
        light = np.append(pos * w, w)
    else:  # directional: at an angle of at least rel radians to the plane
        t = draw(unit_vectors())
        t = t - (t @ n) / (n @ n) * n
        if np.linalg.norm(t) < 1e-3:
            t = (
                np.cross(n, [1.0, 0.0, 0.0])
                if abs(n[0]) < 0.9 * np.linalg.norm(n)
                else np.cross(n, [0.0, 1.0, 0.0])
            )
        t = t / np.linalg.norm(t)
        d = t + side * rel * n / np.linalg.norm(n)
        light = np.append(d * draw(st.floats(0.1, 10)), 0.0)
    return PlanarScene(plane, light, scale)


class Placement(NamedTuple):
    light: FloatArray  # (3,)
    vertices: FloatArray  # (N, 3)
    scale: float
    distance_ratio: float  # |centroid - light| / blocker radius (> 1)


@st.composite
def blockers(draw: st.DrawFn, scale: float = 1.0, max_vertices: int = 16) -> FloatArray:
    """A vertex set around the origin within radius ``scale``, with a nonzero silhouette."""
    n = draw(st.integers(3, max_vertices))
    pts = np.array(
        draw(st.lists(st.lists(st.floats(-1, 1), min_size=3, max_size=3), min_size=n, max_size=n))
    )
    # Three fixed points keep the set from being a single point or a segment.
    pts = np.concatenate([pts, np.eye(3) * 0.5])
    pts -= pts.mean(axis=0)
    pts /= np.linalg.norm(pts, axis=-1).max()
    return pts * scale


@st.composite
def placements(draw: st.DrawFn, dtype: Any = np.float64, max_vertices: int = 16) -> Placement:
    """A point light and a blocker entirely in front of it, at any scale and distance.

    The blocker lies within radius ``r`` of its centroid; the light is at
    distance ``D = ratio * r`` from the centroid along a unit direction, with
    ``ratio`` from just above 1 (the light almost touching the blocker) to
    1e4 in float64 (an angular size of about 0.01 degrees) or 1e3 in float32.
    The whole scene is offset from the origin by up to 1e3 of its size.
    """
    scale = draw(scales)
    verts = draw(blockers(scale, max_vertices))
    r = float(np.linalg.norm(verts, axis=-1).max())
    top = 4.0 if np.dtype(dtype) == np.float64 else 3.0
    ratio = 1.0 + draw(st.floats(-2, top)).__rpow__(10.0)
    offset = np.array(draw(st.lists(st.floats(-1, 1), min_size=3, max_size=3)))
    offset *= scale * draw(st.sampled_from([0.0, 1.0, 1e3]))
    light = offset + draw(unit_vectors()) * ratio * r
    return Placement(light, verts + offset, scale, ratio)


class Invalid(NamedTuple):
    args: tuple[Any, ...]
    message: str  # a fragment the ValueError's message must contain


@st.composite
def invalid_planar(draw: st.DrawFn) -> Invalid:
    """Plane/light pairs that planar_projection must refuse."""
    scene = draw(planar_scenes())
    plane, light = scene.plane.copy(), scene.light.copy()
    kind = draw(
        st.sampled_from(["nan_plane", "inf_light", "zero_normal", "zero_light", "in_plane"])
    )
    if kind == "nan_plane":
        plane[draw(st.integers(0, 3))] = np.nan
        return Invalid((plane, light), "plane: contains non-finite values")
    if kind == "inf_light":
        light[draw(st.integers(0, 3))] = draw(st.sampled_from([np.inf, -np.inf, np.nan]))
        return Invalid((plane, light), "light: contains non-finite values")
    if kind == "zero_normal":
        plane[:3] = 0.0
        return Invalid((plane, light), "the normal (a, b, c) is zero")
    if kind == "zero_light":
        return Invalid((plane, np.zeros(4)), "light: all components are zero")
    # In the plane: the plane moved through a point light, or a direction parallel to it.
    n = plane[:3]
    if light[3] != 0:
        # Move the plane through the light (d = -n . pos): pi . L is then the rounding
        # error of one dot product, within a few ulps of the terms, at any scale.
        pos = light[:3] / light[3]
        light = np.append(pos, 1.0)
        plane = np.append(n, -(n @ pos))
    else:
        # A cross product with n, kept long: a short one's rounding would tilt it off the plane.
        c = np.cross(n, draw(unit_vectors()))
        if np.linalg.norm(c) < 0.5 * np.linalg.norm(n):
            c = np.cross(n, np.eye(3)[int(np.argmin(np.abs(n)))])
        light = np.append(c, 0.0)
    return Invalid((plane, light), "light lies in the plane")


@st.composite
def invalid_placements(draw: st.DrawFn) -> Invalid:
    """Light/vertex pairs that light_frame, adaptive_frustum or fit_shadow must refuse."""
    p = draw(placements())
    light, verts = p.light.copy(), p.vertices.copy()
    kind = draw(
        st.sampled_from(
            ["nan_light", "nan_vertex", "empty", "centroid", "behind", "at_light", "point"]
        )
    )
    if kind == "nan_light":
        light[draw(st.integers(0, 2))] = np.nan
        return Invalid((light, verts), "light_position: contains non-finite values")
    if kind == "nan_vertex":
        verts[draw(st.integers(0, len(verts) - 1)), draw(st.integers(0, 2))] = np.inf
        return Invalid((light, verts), "contains non-finite values")
    if kind == "empty":
        return Invalid((light, verts[:0]), "the vertex set is empty")
    if kind == "centroid":
        # The light at the centroid as floating point computes it: MDV is rounding noise.
        return Invalid((verts.mean(axis=0), verts), "viewing direction is zero")
    if kind == "behind":
        # A vertex mirrored to the far side of the light: the MDV still points at the blocker.
        mirrored = 2 * light - verts[0]
        return Invalid((light, np.concatenate([verts, mirrored[None]])), "not strictly in front")
    if kind == "at_light":
        return Invalid((light, np.concatenate([verts, light[None]])), "not strictly in front")
    # A single point (repeated): zero silhouette.
    return Invalid((light, np.repeat(verts[:1], 3, axis=0)), "zero width or height")
