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

import shadowmath as sm

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


# --- scenes for fit_shadow's options, cube maps, biases, PCF and area lights (issue 16) ------

#: Every graphics API the package supports (docs/conventions.md), in the docs' order.
GRAPHICS_APIS = ("opengl", "vulkan", "direct3d", "metal", "webgpu")
LIGHT_KINDS = ("point", "spot", "directional")
#: Homogeneous ``w`` of a point light: powers of two (either sign), so ``xyz / w`` is exact.
POINT_W = (1.0, 2.0, 0.5, -1.0, -0.25)


def _unit(v: FloatArray) -> FloatArray:
    return np.asarray(v / np.linalg.norm(v), dtype=np.float64)


def _perpendicular(z: FloatArray) -> FloatArray:
    """A unit vector perpendicular to the unit ``z``."""
    helper = np.eye(3)[int(np.argmin(np.abs(z)))]
    return _unit(np.cross(z, helper))


class LightScene(NamedTuple):
    """A light of one kind and a blocker (world coordinates) that it can shadow."""

    kind: str  # "point", "spot" or "directional"
    position: FloatArray  # (3,) point and spot lights; zeros for a directional light
    direction: FloatArray  # (3,) the spot's axis, or toward a directional light; else zeros
    angle: float  # a spot light's half-angle in radians, else 0
    vertices: FloatArray  # (N, 3) the blocker, world coordinates
    kappa: float  # the scene's condition: the fit is known to about eps * kappa
    covers: bool  # a spot's cone holds the whole blocker (always True for the others)
    tan_max: float  # a bound on the fitted frustum's widest ratio |c| + h (0: directional)


@st.composite
def light_scenes(
    draw: st.DrawFn,
    dtype: Any = np.float64,
    kinds: tuple[str, ...] = LIGHT_KINDS,
    max_vertices: int = 16,
) -> LightScene:
    """A point, spot or directional light and a blocker, at the scales of :func:`placements`.

    Spot lights either hold the whole blocker in their cone (``covers``: the cone's
    half-angle exceeds the blocker's angular radius plus the axis' deviation from the
    centroid), or aim at the centroid with a cone narrower than the blocker, which
    the fit clips to the cone's bounding square. The condition ``kappa`` is the
    coordinates' size over the blocker's radius plus the distance ratio (times the
    spread of the ratios over the frustum's width for a clipped spot light).
    """
    kind = draw(st.sampled_from(kinds))
    p = draw(placements(dtype, max_vertices))
    verts = p.vertices
    centroid = verts.mean(axis=0)
    r = float(np.linalg.norm(verts - centroid, axis=-1).max())
    size = float(np.abs(verts).max())
    zero = np.zeros(3)
    if kind == "directional":
        d = draw(unit_vectors()) * 10.0 ** draw(st.floats(-3, 3))
        return LightScene(kind, zero, d, 0.0, verts, size / r + 1.0, True, 0.0)
    kappa = (float(np.abs(p.light).max()) + size) / r + p.distance_ratio
    to_centroid = centroid - p.light
    alpha = float(np.arcsin(min(1.0, r / np.linalg.norm(to_centroid))))
    if kind == "point":  # every vertex within alpha of the mean direction
        return LightScene(kind, p.light, zero, 0.0, verts, kappa, True, float(np.tan(alpha)))
    aim = _unit(to_centroid)
    if alpha < 1.2 and draw(st.booleans()):
        # The cone holds the bounding sphere: the axis may deviate by delta <= alpha.
        delta = draw(st.floats(0, 1)) * min(alpha, (1.5 - alpha) / 2)
        side = _perpendicular(aim)
        twist = draw(st.floats(0, 2 * np.pi))
        side = np.cos(twist) * side + np.sin(twist) * np.cross(aim, side)
        axis = np.cos(delta) * aim + np.sin(delta) * side
        angle = alpha + delta + draw(st.floats(1e-3, 1)) * (1.5 - alpha - delta)
        spread = (np.tan(alpha) + np.tan(delta)) / np.tan(alpha)
        length = 10.0 ** draw(st.floats(-2, 2))
        widest = float(np.tan(alpha + delta))
        return LightScene(kind, p.light, axis * length, angle, verts, kappa * spread, True, widest)
    angle = alpha * draw(st.floats(0.05, 0.9))
    spread = np.tan(alpha) / np.tan(angle)
    widest = float(np.tan(angle))
    return LightScene(kind, p.light, to_centroid, angle, verts, kappa * spread, False, widest)


def aim_direction(scene: LightScene, world: FloatArray | None = None) -> FloatArray:
    """The unit ``Z`` the fit aims along: the mean direction, the spot's axis, or away from
    a directional light."""
    if scene.kind == "directional":
        return _unit(-scene.direction)
    if scene.kind == "spot":
        return _unit(scene.direction)
    verts = scene.vertices if world is None else world
    return _unit((verts - scene.position).mean(axis=0))


@st.composite
def receiver_points(draw: st.DrawFn, scene: LightScene, count: int | None = None) -> FloatArray:
    """Receiver points around a scene: behind the blocker, between it and the light, beside
    the map (outside its sides) and, for point lights, behind the light."""
    n = count if count is not None else draw(st.integers(1, 8))
    verts = scene.vertices
    centroid = verts.mean(axis=0)
    r = float(np.linalg.norm(verts - centroid, axis=-1).max())
    t = np.array(draw(st.lists(st.floats(-1.5, 6), min_size=n, max_size=n)))
    lateral = np.array(
        draw(st.lists(st.lists(st.floats(-4, 4), min_size=3, max_size=3), min_size=n, max_size=n))
    )
    if scene.kind == "directional":
        away = _unit(-scene.direction)
        return np.asarray(centroid + 4 * r * t[:, None] * away + r * lateral)
    along = centroid - scene.position
    return np.asarray(scene.position + t[:, None] * along + r * lateral)


@st.composite
def receiver_surfaces(
    draw: st.DrawFn, scene: LightScene, points: FloatArray
) -> tuple[FloatArray, np.ndarray]:
    """A receiver mesh ``(vertices, faces)``: triangles over the drawn points, and a floor of
    two triangles larger than the map (its corners all outside the map's sides)."""
    verts = scene.vertices
    centroid = verts.mean(axis=0)
    r = float(np.linalg.norm(verts - centroid, axis=-1).max())
    if scene.kind == "directional":
        normal = _unit(scene.direction)
        origin = centroid - normal * 4 * r * draw(st.floats(0.5, 5))
    else:
        normal = _unit(scene.position - centroid)
        origin = scene.position + (centroid - scene.position) * draw(st.floats(1.2, 6))
    u = _perpendicular(normal)
    v = np.cross(normal, u)
    big = r * 10.0 ** draw(st.floats(1, 3))
    floor = origin + big * np.array([-u - v, u - v, u + v, -u + v])
    vertices = np.concatenate([points, floor])
    n = len(points)
    faces = [[n, n + 1, n + 2], [n, n + 2, n + 3]]
    for _ in range(draw(st.integers(0, 4))):
        faces.append([draw(st.integers(0, len(vertices) - 1)) for _ in range(3)])
    return vertices, np.array(faces)


@st.composite
def up_hints(draw: st.DrawFn, z: FloatArray) -> FloatArray:
    """An up hint at least 0.05 radians away from the unit aim ``z``, of any length."""
    u = draw(unit_vectors())
    if np.linalg.norm(np.cross(u, z)) < 0.05:
        u = _perpendicular(z)
    return np.asarray(u * 10.0 ** draw(st.floats(-2, 2)))


@st.composite
def affine_placements(draw: st.DrawFn) -> FloatArray:
    """``blocker_to_world``: a rotation times an axis scaling of 1/3 to 3, and a translation
    of up to 3 units (the local coordinates keep the scene's scale and offset).

    Placements far from the origin, or of a large scale, are the target of
    ``test_fuzz_fit_shadow_placement_far_from_the_origin`` (a known bug: such invertible
    placements are refused as singular)."""
    q = np.array(draw(st.lists(st.floats(-1, 1), min_size=4, max_size=4)))
    if np.linalg.norm(q) < 0.1:
        q = np.array([1.0, 0.0, 0.0, 0.0])
    w, x, y, z = _unit(q)
    R = np.array(
        [
            [1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
            [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
            [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)],
        ]
    )
    S = np.diag([10.0 ** draw(st.floats(-0.5, 0.5)) for _ in range(3)])
    B = np.eye(4)
    B[:3, :3] = R @ S
    B[:3, 3] = np.array(draw(st.lists(st.floats(-3, 3), min_size=3, max_size=3)))
    return B


def spread_apart(vertices: FloatArray, gap: float = 0.02) -> FloatArray:
    """``vertices`` with any two closer than ``gap`` times the blocker's size moved apart.

    (Repeated or nearly repeated vertices far from the origin break a stable map's
    sphere: the target of ``test_fuzz_stable_map_with_a_repeated_vertex``, a known bug.)"""
    out = np.array(vertices, dtype=np.float64)
    size = float(np.linalg.norm(out - out.mean(axis=0), axis=-1).max()) or 1.0
    directions = np.array([[1.0, -0.5, 0.25], [-0.25, 1.0, 0.5], [0.5, 0.25, -1.0]])
    for i in range(1, len(out)):
        for k in range(len(out) * 3):
            if np.linalg.norm(out[:i] - out[i], axis=-1).min() >= gap * size:
                break
            out[i] += 2 * gap * size * directions[k % 3] * (1 + k // 3)
    return out


class FitCall(NamedTuple):
    """One call of ``fit_shadow`` with scene options; ``None`` options are not passed."""

    scene: LightScene
    form: str  # "xyz", "xyzw" (homogeneous) or "typed"
    w: float  # the homogeneous w of a point light given as (x, y, z, w)
    local: FloatArray  # (N, 3) the vertices as passed (local when placement is given)
    placement: FloatArray | None  # (4, 4) blocker_to_world
    receivers: FloatArray | None  # (M, 3) points or mesh vertices, or (M, 3, 3) triangles
    up: FloatArray | None  # (3,)
    near: float | None
    far: float | None
    aim: str
    map_size: int | tuple[int, int]
    map_options: dict[str, Any]  # border_texels, pcf_radius and pcf_filter, or margin
    api: str
    reversed_z: bool
    stable: bool
    as_spec: bool  # the map options in a ShadowMapSpec, or as keywords
    receiver_kind: str = "points"  # "points", "triangles" (sm.Triangles) or "mesh" (sm.Mesh)
    faces: np.ndarray | None = None  # (F, 3) a mesh's vertex indices


def _map_options(draw: st.DrawFn, smallest: int) -> dict[str, Any]:
    """Border options that leave room inside the map: a border, a PCF kernel, a margin."""
    room = (smallest - 1) // 2  # the largest border that leaves a texel inside
    kind = draw(st.sampled_from(["default", "border", "pcf", "margin"]))
    if kind == "border":
        return {"border_texels": draw(st.integers(0, min(4, room)))}
    if kind == "pcf":
        filt = draw(st.sampled_from(["box", "bilinear"]))
        k = draw(st.integers(0, 4))
        need = k + 1 if filt == "bilinear" else max(1, k)
        if need > room:
            return {}
        return {"pcf_radius": k, "pcf_filter": filt}
    if kind == "margin":
        m = st.floats(0.05, 1.0)
        return {"margin": draw(st.one_of(m, st.tuples(m, m)))}
    return {} if room >= 1 else {"border_texels": 0}


def _depths(scene: LightScene, world: FloatArray) -> tuple[float, float]:
    """``(z_min, z_max)`` of the blocker along the fit's ``Z`` from the light."""
    z = (world - scene.position) @ aim_direction(scene, world)
    return float(z.min()), float(z.max())


def _inverse_place(B: FloatArray | None, world: FloatArray) -> FloatArray:
    if B is None:
        return world
    h = np.c_[world, np.ones(len(world))] @ np.linalg.inv(B).T
    return np.asarray(h[:, :3] / h[:, 3:])


@st.composite
def fit_calls(
    draw: st.DrawFn,
    dtype: Any = np.float64,
    kinds: tuple[str, ...] = LIGHT_KINDS,
    max_vertices: int = 16,
    vertex_count: int | None = None,
    receiver_count: int | None = None,
    forms: tuple[str, ...] = ("xyz", "xyzw", "typed"),
    receiver_kinds: tuple[str, ...] = ("points", "triangles", "mesh"),
) -> FitCall:
    """A valid ``fit_shadow`` call drawing every scene option.

    ``vertex_count`` and ``receiver_count`` fix the arrays' shapes (vertices repeat
    cyclically; for JAX, so that ``jit`` compiles once per option set); whether
    receivers are given is drawn either way.
    """
    scene = draw(light_scenes(dtype, kinds, max_vertices))
    if vertex_count is not None:
        scene = scene._replace(vertices=np.resize(scene.vertices, (vertex_count, 3)))
    world = scene.vertices
    eps = _eps(dtype)
    coords = float(np.abs(world).max() + np.abs(scene.position).max())
    form = "typed" if scene.kind == "spot" else draw(st.sampled_from(forms))
    if scene.kind == "directional" and form == "xyz":
        form = "xyzw"
    w = draw(st.sampled_from(POINT_W)) if scene.kind == "point" and form == "xyzw" else 1.0
    placement = draw(affine_placements()) if draw(st.booleans()) else None
    receivers = draw(receiver_points(scene, receiver_count)) if draw(st.booleans()) else None
    receiver_kind, faces = "points", None
    if receivers is not None:
        receiver_kind = draw(st.sampled_from(receiver_kinds))
        if receiver_kind != "points":
            receivers, faces = draw(receiver_surfaces(scene, receivers))
            if receiver_kind == "triangles":
                receivers, faces = receivers[faces], None
    aim = "mean"
    z_aim = aim_direction(scene, world)
    if scene.kind == "point" and draw(st.integers(0, 3)) == 0:
        # Aimed at the bounding box's centre: valid while every vertex stays in front.
        z_box = _unit(0.5 * (world.max(axis=0) + world.min(axis=0)) - scene.position)
        off = world - scene.position
        z = off @ z_box
        if z.min() > 0.1 * np.linalg.norm(off, axis=-1).max():
            aim, z_aim = "bbox", z_box
            lateral = np.sqrt(np.maximum(np.sum(off * off, axis=-1) - z * z, 0.0))
            scene = scene._replace(tan_max=float((lateral / z).max()))
    up = draw(up_hints(z_aim)) if draw(st.booleans()) else None
    near = far = None
    if scene.kind != "directional" and aim == "mean" and draw(st.booleans()):
        z_min, z_max = _depths(scene, world)
        noise = 64 * eps * coords * (1 if placement is None else 16)
        if draw(st.booleans()) and z_min * 0.1 > noise:
            near = z_min * draw(st.floats(1e-3, 0.9))
        if draw(st.booleans()) and z_max * 0.1 > noise:
            far = z_max * (1.1 + draw(st.floats(0, 10)))
    map_size = draw(map_sizes)
    smallest = min(map_size) if isinstance(map_size, tuple) else map_size
    map_options = _map_options(draw, smallest)
    # Valid fits stay inside the widest frustum fitted (170 degrees, tan 85 deg = 11.43 at
    # the map's edge |c| + h / m): no border when the margin would push it past 10.
    if scene.tan_max / min(_spec_margins(map_size, map_options)) > 10:
        map_options = {"border_texels": 0}
    stable = draw(st.booleans()) and (scene.kind == "directional" or up is not None)
    if stable and scene.kind == "directional":
        scene = scene._replace(vertices=spread_apart(scene.vertices))
        world = scene.vertices
    if stable:
        spec = _spec_margins(map_size, map_options)
        sizes = map_size if isinstance(map_size, tuple) else (map_size, map_size)
        stable = all(m * n > 1 for m, n in zip(spec, sizes, strict=True))
    return FitCall(
        scene=scene,
        form=form,
        w=w,
        local=_inverse_place(placement, world),
        placement=placement,
        receivers=receivers,
        receiver_kind=receiver_kind,
        faces=faces,
        up=up,
        near=near,
        far=far,
        aim=aim,
        map_size=map_size,
        map_options=map_options,
        api=draw(st.sampled_from(GRAPHICS_APIS)),
        reversed_z=draw(st.booleans()),
        stable=stable,
        as_spec=draw(st.booleans()),
    )


def _spec_margins(map_size: Any, options: dict[str, Any]) -> tuple[float, float]:
    """The margins a spec of these options has (computed here, not by the package)."""
    sizes = map_size if isinstance(map_size, tuple) else (map_size, map_size)
    if "margin" in options:
        m = options["margin"]
        return (m, m) if not isinstance(m, tuple) else m
    if "border_texels" in options:
        b = options["border_texels"]
    elif "pcf_radius" in options:
        k = options["pcf_radius"]
        b = k + 1 if options.get("pcf_filter", "box") == "bilinear" else max(1, k)
    else:
        b = 1
    return (sizes[0] - 2 * b) / sizes[0], (sizes[1] - 2 * b) / sizes[1]


class InvalidFit(NamedTuple):
    """A ``fit_shadow`` call that must fail: the error, and a fragment of its message."""

    call: FitCall
    kwargs: dict[str, Any]  # extra keywords (bad options), passed as they are
    message: str
    error: type[Exception]
    lazy: bool  # a bad value: NaN under jax.jit instead of the error
    light: Any  # replaces the light argument when not None (a bad light)


#: The invalid twins of a fit call, by name; the ones that keep every shape come first.
VALUE_MUTATIONS = (
    "nan_light",
    "nan_vertex",
    "nan_placement",
    "projective",
    "nan_receiver",
    "nan_up",
    "zero_up",
    "parallel_up",
    "zero_light",
    "spot_angle",
    "at_light",
    "near_nonpositive",
    "near_nan",
    "far_inf",
    "near_ge_far",
    "near_clips",
    "far_clips",
)
STATIC_MUTATIONS = (
    "directional_near",
    "stable_without_up",
    "mixed_batch",
    "spec_and_keyword",
    "bad_api",
    "bad_reversed_z",
    "bad_stable",
    "bad_pcf_radius",
    "bad_pcf_filter",
    "bad_margin",
    "bad_border",
    "border_too_wide",
    "two_borders",
    "bad_map_size",
    "stable_tiny_map",
    "bad_method",
    "bad_aim",
    "light_shape",
    "vertices_shape",
    "receivers_shape",
    "mesh_faces",
    "placement_shape",
    "up_shape",
    "batch_mismatch",
    "typed_shape",
    "unknown_keyword",
    "optimized_with_options",
    "not_numbers",
)

NON_FINITE = "contains non-finite values"


@st.composite
def invalid_fit_calls(
    draw: st.DrawFn,
    dtype: Any = np.float64,
    mutations: tuple[str, ...] = VALUE_MUTATIONS + STATIC_MUTATIONS,
    call: FitCall | None = None,
    **fit_call_options: Any,
) -> InvalidFit:
    """A valid :func:`fit_calls` draw (or ``call``) with one thing made invalid.

    Mutations that do not apply to the drawn call (a spot angle for a point light)
    fall back to a non-finite vertex, which applies to every call and keeps shapes.
    """
    if call is None:
        call = draw(fit_calls(dtype, **fit_call_options))
    scene = call.scene
    kind = draw(st.sampled_from(mutations))
    world = scene.vertices
    eps = _eps(dtype)
    kw: dict[str, Any] = {}

    def bad(c: FitCall, message: str, lazy: bool = True, **extra: Any) -> InvalidFit:
        return InvalidFit(c, {**kw, **extra}, message, ValueError, lazy, None)

    def with_scene(**fields: Any) -> FitCall:
        return call._replace(scene=scene._replace(**fields))

    index = draw(st.integers(0, len(world) - 1)), draw(st.integers(0, 2))
    point_like = scene.kind != "directional"
    if kind == "nan_light":
        field = "position" if point_like else "direction"
        value = getattr(scene, field).copy()
        value[index[1]] = draw(st.sampled_from([np.nan, np.inf, -np.inf]))
        return bad(with_scene(**{field: value}), "light: " + NON_FINITE)
    if kind == "nan_placement":
        B = np.eye(4) if call.placement is None else call.placement.copy()
        B[draw(st.integers(0, 2)), draw(st.integers(0, 3))] = np.nan
        return bad(call._replace(placement=B), "blocker_to_world: " + NON_FINITE)
    if kind == "projective":
        B = np.eye(4) if call.placement is None else call.placement.copy()
        B[3] = [0.0, 0.0, 0.0, -1.0]
        return bad(call._replace(placement=B), "blocker_to_world: its last row is not (0, 0, 0, 1)")
    if kind == "nan_receiver" and call.receivers is not None:
        R = call.receivers.copy()
        R[draw(st.integers(0, len(R) - 1)), index[1]] = np.nan
        return bad(call._replace(receivers=R), "receivers: " + NON_FINITE)
    # (With receivers as surfaces a non-finite up is blamed on the receivers: a known bug,
    # test_fuzz_non_finite_up_beside_surface_receivers.)
    if kind == "nan_up" and call.up is not None and call.receiver_kind == "points":
        up = call.up.copy()
        up[index[1]] = np.inf
        return bad(call._replace(up=up), "up: " + NON_FINITE)
    if kind == "zero_up":
        return bad(call._replace(up=np.zeros(3)), "up: the up hint is zero or parallel")
    if kind == "parallel_up" and call.aim == "mean":
        z = aim_direction(scene, world)
        if scene.kind == "directional":
            up = scene.direction * -2.0  # exactly parallel in every dtype
        elif scene.kind == "spot":
            up = scene.direction * 2.0
        else:
            # The mean direction as the fit computes it is known to eps * its condition.
            off = world - scene.position
            cond = float(np.linalg.norm(off, axis=-1).mean() / np.linalg.norm(off.mean(0)))
            coords = float(np.abs(world).max() + np.abs(scene.position).max())
            reach = float(np.linalg.norm(off, axis=-1).max())
            if call.placement is not None or 8 * cond * (coords / reach) > 64:
                return bad(call._replace(up=np.zeros(3)), "up: the up hint is zero or parallel")
            up = z * 3.0
        return bad(call._replace(up=up), "up: the up hint is zero or parallel")
    if kind == "zero_light" and scene.kind != "point":
        message = (
            "light: zero directional light"
            if scene.kind == "directional"
            else "light: the spot light's direction is zero"
        )
        return bad(with_scene(direction=np.zeros(3)), message)
    if kind == "spot_angle" and scene.kind == "spot":
        angle = draw(st.sampled_from([0.0, -0.3, np.pi / 2, 2.0, 3.5]))
        return bad(with_scene(angle=angle), "light: a spot light's angle is the half-angle")
    if kind == "at_light" and point_like and call.placement is None and call.aim == "mean":
        # Exactly at the light (a placement's rounding would move it off; a bounding box's
        # centre would move the aim).
        local = call.local.copy()
        local[-1] = scene.position
        return bad(call._replace(local=local), "vertices: a blocker vertex is not strictly")
    if point_like and call.aim == "mean" and kind.startswith(("near", "far")):
        z_min, z_max = _depths(scene, world)
        coords = float(np.abs(world).max() + np.abs(scene.position).max())
        noise = 64 * eps * coords * (1 if call.placement is None else 16)
        c = call._replace(near=None, far=None)
        if kind == "near_nonpositive":
            return bad(c._replace(near=-z_min * draw(st.floats(0, 2))), "near: the near plane")
        if kind == "near_nan":
            return bad(c._replace(near=np.nan), "near: must be finite")
        if kind == "far_inf":
            return bad(c._replace(far=np.inf), "far: must be finite")
        if kind == "near_ge_far":
            far = z_min * draw(st.floats(0.01, 0.99))
            return bad(c._replace(near=far * draw(st.floats(1, 2)), far=far), "near/far:")
        if kind == "near_clips" and z_max - z_min > 8 * noise:
            near = z_min + (z_max - z_min) * draw(st.floats(0.1, 0.9))
            return bad(c._replace(near=near), "near: the near plane cuts into the blocker")
        if kind == "far_clips" and z_max - z_min > 8 * noise:
            far = z_min + (z_max - z_min) * draw(st.floats(0.1, 0.9))
            return bad(c._replace(far=far), "far: the far plane cuts into the blocker")
    # The static ones: whatever the values, and under jax.jit too.
    if kind == "directional_near" and scene.kind == "directional":
        return bad(call._replace(near=1.0), "near/far: a directional light's depth", False)
    if kind == "stable_without_up" and scene.kind != "directional":
        c = call._replace(up=None, stable=True, map_size=64, map_options={})
        return bad(c, "up: stable=True needs an up hint", False)
    if kind == "mixed_batch" and call.form == "xyzw":
        if scene.kind == "point":
            first = np.append(scene.position * call.w, call.w)
            other = np.array([0.3, 1.0, -0.2, 0.0])
        else:
            first, other = np.append(scene.direction, 0.0), np.ones(4)
        light = np.stack([first, other])
        return InvalidFit(call, kw, "light: a batch mixes", ValueError, False, light)
    if kind == "spec_and_keyword":
        option = draw(
            st.sampled_from(
                [
                    {"api": "vulkan"},
                    {"reversed_z": True},
                    {"border_texels": 0},
                    {"stable": True},
                    {"pcf_radius": 1},
                    {"margin": 0.5},
                ]
            )
        )
        name = next(iter(option))
        return bad(call._replace(as_spec=True), f"{name}: given both", False, **option)
    if kind == "bad_api":
        api = draw(
            st.one_of(st.text(max_size=8), st.sampled_from(["OpenGL", "d3d", "gl", 3, None]))
        )
        if api not in GRAPHICS_APIS:
            return bad(call._replace(as_spec=False), "api: unknown graphics API", False, api=api)
    if kind == "bad_reversed_z":
        value = draw(st.sampled_from([1, 0, "yes", None, 0.0]))
        c = call._replace(as_spec=False)
        return bad(c, "reversed_z: expected True or False", False, reversed_z=value)
    if kind == "bad_stable":
        value = draw(st.sampled_from([1, "no", None, 1.0]))
        c = call._replace(as_spec=False)
        return bad(c, "stable: expected True or False", False, stable=value)
    c = call._replace(as_spec=False, map_options={})
    if kind == "bad_pcf_radius":
        value = draw(st.sampled_from([-1, -3, 1.5, True, "2"]))
        return bad(c, "pcf_radius: expected an integer >= 0", False, pcf_radius=value)
    if kind == "bad_pcf_filter":
        value = draw(st.sampled_from(["gauss", "Box", "", None, 1]))
        return bad(c, "pcf_filter: expected 'box' or 'bilinear'", False, pcf_filter=value)
    if kind == "bad_margin":
        value = draw(st.sampled_from([0.0, -0.5, 1.5, np.nan, np.inf, (0.5,), (0.5, 0.5, 0.5)]))
        return bad(c, "margin: ", False, margin=value)
    if kind == "bad_border":
        value = draw(st.sampled_from([-1, -4, 1.5, "1"]))
        return bad(c, "border_texels: ", False, border_texels=value)
    if kind == "border_too_wide":
        smallest = min(call.map_size) if isinstance(call.map_size, tuple) else call.map_size
        border = (smallest + 1) // 2 + draw(st.integers(0, 3))
        return bad(c, "map_size: ", False, border_texels=border)
    if kind == "two_borders":
        options = draw(
            st.sampled_from(
                [
                    {"border_texels": 1, "pcf_radius": 1},
                    {"border_texels": 1, "margin": 0.5},
                    {"pcf_radius": 0, "margin": 0.9},
                ]
            )
        )
        return bad(c, " and ", False, **options)
    if kind == "bad_map_size":
        size = draw(st.sampled_from([0, -5, 2.5, True, (64,), (64, 0), (3, 4, 5), "64", None]))
        return bad(c._replace(map_size=size), "map_size: ", False)
    if kind == "stable_tiny_map" and scene.kind == "directional":
        c = c._replace(map_size=draw(st.sampled_from([3, (3, 40), (40, 3)])), stable=True)
        return bad(c, "map_size: stable=True needs more than one texel", False, border_texels=1)
    if kind == "bad_method":
        method = draw(st.sampled_from(["fast", "MDV", "", None]))
        return bad(call, "method: expected 'mdv' or 'optimized'", False, method=method)
    if kind == "bad_aim":
        aim = draw(st.sampled_from(["center", "Mean", "", None]))
        return bad(call._replace(aim=aim), "aim: expected 'mean' or 'bbox'", False)
    if kind == "light_shape":
        light = np.zeros(draw(st.sampled_from([(2,), (5,), (), (3, 2)])))
        return InvalidFit(call, kw, "light: expected shape", ValueError, False, light)
    if kind == "vertices_shape":
        local = call.local[:, : draw(st.sampled_from([1, 2]))]
        return bad(call._replace(local=local), "blocker_vertices: expected shape", False)
    if kind == "receivers_shape" and call.receivers is not None:
        R = call.receivers[..., :2]
        name = "receivers.vertices" if call.receiver_kind == "mesh" else "receivers"
        return bad(call._replace(receivers=R), f"{name}: expected shape", False)
    if kind == "mesh_faces" and call.receiver_kind == "mesh" and call.faces is not None:
        faces = call.faces.copy()
        if draw(st.booleans()):
            faces[draw(st.integers(0, len(faces) - 1)), 0] = len(call.receivers)
            return bad(call._replace(faces=faces), "receivers.faces: indices must lie in", False)
        c = call._replace(faces=faces.astype(float))
        return InvalidFit(c, kw, "receivers.faces: expected integer", TypeError, False, None)
    if kind == "placement_shape":
        B = np.eye(4) if call.placement is None else call.placement
        return bad(call._replace(placement=B[:3]), "blocker_to_world: expected shape", False)
    if kind == "up_shape" and call.up is not None:
        return bad(call._replace(up=call.up[:2]), "up: expected shape", False)
    if kind == "batch_mismatch" and scene.kind == "point":
        local = np.broadcast_to(call.local, (3, *call.local.shape))
        light = np.broadcast_to(scene.position, (2, 3))
        c = call._replace(local=local)
        return InvalidFit(c, kw, "batch dimensions do not broadcast", ValueError, False, light)
    if kind == "typed_shape":
        light = draw(
            st.sampled_from(
                [
                    sm.PointLight(np.zeros(4)),
                    sm.DirectionalLight(np.ones(2)),
                    sm.SpotLight(np.zeros(2), np.ones(3), np.array(0.5)),
                    sm.SpotLight(np.zeros(3), np.ones(4), np.array(0.5)),
                ]
            )
        )
        return InvalidFit(call, kw, "expected shape", ValueError, False, light)
    if kind == "unknown_keyword":
        name = draw(st.sampled_from(["rceivers", "upp", "border", "apis", "far_plane"]))
        return InvalidFit(call, {name: 1}, name, TypeError, False, None)
    if kind == "optimized_with_options":
        c = call._replace(api="vulkan", as_spec=False, near=None, far=None, aim="mean")
        return bad(c, "method: 'optimized' fits point lights without", False, method="optimized")
    if kind == "not_numbers" and scene.kind == "point" and call.form != "typed":
        light = draw(st.sampled_from([["a", "b", "c"], [1 + 2j, 0, 0], [[0, 0], [0]]]))
        return InvalidFit(call, kw, "light: ", ValueError, False, light)
    # Every call has vertices: a non-finite one is always invalid.
    local = call.local.copy()
    local[index] = draw(st.sampled_from([np.nan, np.inf, -np.inf]))
    return bad(call._replace(local=local), "blocker_vertices: " + NON_FINITE)


def given_options(call: FitCall) -> tuple[str, ...]:
    """The names of the array options ``call`` passes (what a jitted fit is compiled for)."""
    named = {
        "blocker_to_world": call.placement,
        "receivers": call.receivers,
        "up": call.up,
        "near": call.near,
        "far": call.far,
    }
    return tuple(name for name, value in named.items() if value is not None)


# --- cube maps ------------------------------------------------------------------------------


@st.composite
def cube_directions(draw: st.DrawFn, dtype: Any = np.float64, count: int = 8) -> FloatArray:
    """``(count, 3)`` nonzero directions: random, along an axis, on a cube edge (two tied
    largest magnitudes) or corner (three), scaled from 1e-20 to 1e20 (1e-30 to 1e30 in
    float64); every entry exactly representable in ``dtype``."""
    top = 30 if np.dtype(dtype) == np.float64 else 20
    rows = []
    for _ in range(count):
        kind = draw(st.sampled_from(["random", "axis", "edge", "corner"]))
        signs = np.array(draw(st.lists(st.sampled_from([-1.0, 1.0]), min_size=3, max_size=3)))
        if kind == "random":
            v = np.array(draw(st.lists(st.floats(-1, 1), min_size=3, max_size=3)))
            v = v / np.abs(v).max() if np.any(v) else np.array([0.0, 0.0, 1.0])
        elif kind == "axis":
            v = np.eye(3)[draw(st.integers(0, 2))] * signs
        elif kind == "edge":
            v = np.array([1.0, 1.0, draw(st.floats(0, 0.999))]) * signs
            v = v[list(draw(st.permutations([0, 1, 2])))]
        else:
            v = signs
        scale = 10.0 ** draw(st.integers(-top, top))
        rows.append(np.asarray(v * scale, dtype=dtype).astype(np.float64))
    return np.array(rows)


class CubeSetup(NamedTuple):
    light: FloatArray  # (3,)
    near: float
    far: float
    map_size: int
    border: int
    api: str
    reversed_z: bool


@st.composite
def cube_setups(draw: st.DrawFn) -> CubeSetup:
    """A point light's cube map: near from 1e-3 to 1e3, far up to 1e4 times near."""
    scale = draw(scales)
    light = np.array(draw(st.lists(st.floats(-1, 1), min_size=3, max_size=3))) * scale
    near = 10.0 ** draw(st.floats(-3, 3))
    far = near * (1 + 10.0 ** draw(st.floats(-2, 4)))
    size = draw(st.integers(1, 4096))
    border = draw(st.integers(0, (size - 1) // 2))
    return CubeSetup(
        light,
        near,
        far,
        size,
        border,
        draw(st.sampled_from(GRAPHICS_APIS)),
        draw(st.booleans()),
    )


# --- PCF ------------------------------------------------------------------------------------


class PcfCase(NamedTuple):
    depth_map: FloatArray  # (H, W)
    coords: FloatArray  # (N, 2)
    depths: FloatArray  # (N,)
    radius: int
    filter: str
    reversed_z: bool
    softness: float


@st.composite
def pcf_cases(draw: st.DrawFn, count: int = 6, shape: tuple[int, int] | None = None) -> PcfCase:
    """A depth map of dyadic depths (so ``1 - z`` is exact), lookups on and off the map."""
    filt = draw(st.sampled_from(["box", "bilinear"]))
    k = draw(st.integers(0, 3))
    border = k + 1 if filt == "bilinear" else max(1, k)
    if shape is None:
        H = draw(st.integers(2 * border + 1, 2 * border + 9))
        W = draw(st.integers(2 * border + 1, 2 * border + 9))
    else:
        H, W = shape
    levels = st.integers(0, 64).map(lambda i: i / 64)
    flat = draw(st.lists(levels, min_size=H * W, max_size=H * W))
    depth_map = np.array(flat).reshape(H, W)
    coords = np.array(
        draw(
            st.lists(
                st.lists(st.floats(-0.3, 1.3), min_size=2, max_size=2),
                min_size=count,
                max_size=count,
            )
        )
    )
    depths = np.array(draw(st.lists(levels, min_size=count, max_size=count)))
    softness = draw(st.sampled_from([0.0, 0.0, 1 / 64, 0.25]))
    return PcfCase(depth_map, coords, depths, k, filt, draw(st.booleans()), softness)


# --- area lights ----------------------------------------------------------------------------


class AreaLight(NamedTuple):
    corner: FloatArray  # (3,)
    edge_u: FloatArray  # (3,)
    edge_v: FloatArray  # (3,)
    apex: FloatArray  # (3,) a point off the light's plane (a pyramid's apex)
    kappa: float  # the parallelogram's and pyramid's condition


@st.composite
def area_lights(draw: st.DrawFn) -> AreaLight:
    """A parallelogram light at any scale, edges of aspect up to 1e3 and at least 0.05 rad
    apart, and an apex at a height of 1e-3 to 1e3 of its size above or below its plane."""
    scale = draw(scales)
    corner = np.array(draw(st.lists(st.floats(-1, 1), min_size=3, max_size=3))) * scale
    corner *= draw(st.sampled_from([0.0, 1.0, 100.0]))
    eu = draw(unit_vectors())
    side = _perpendicular(eu)
    turn = draw(st.floats(0.05, np.pi - 0.05))
    normal_twist = draw(st.floats(0, 2 * np.pi))
    side = np.cos(normal_twist) * side + np.sin(normal_twist) * np.cross(eu, side)
    ev = np.cos(turn) * eu + np.sin(turn) * side
    eu = eu * scale * 10.0 ** draw(st.floats(-1.5, 1.5))
    ev = ev * scale * 10.0 ** draw(st.floats(-1.5, 1.5))
    normal = _unit(np.cross(eu, ev))
    size = float(np.linalg.norm(eu) + np.linalg.norm(ev))
    height = size * 10.0 ** draw(st.floats(-3, 3)) * draw(st.sampled_from([-1.0, 1.0]))
    inside = corner + draw(st.floats(-1, 2)) * eu + draw(st.floats(-1, 2)) * ev
    apex = inside + height * normal
    area = float(np.linalg.norm(np.cross(eu, ev)))
    total = size + float(np.linalg.norm(corner - apex))
    aspect = size * size / area
    kappa = aspect * (total / abs(height)) * (1 + float(np.abs(corner).max()) / size)
    return AreaLight(corner, eu, ev, apex, kappa)
