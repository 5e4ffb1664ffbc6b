"""The demo's scene from the options: the light, the blocker mesh, the bodies, the camera.

The scene is the article's Figure 5.8.1: a wall (the plane ``z = 0``) and a
floor (``y = 0``) receive the shadow of a tilted blocker at
:data:`BLOCKER_CENTRE`. :func:`check_light_and_mesh` checks the light against
those planes and reads the blocker (no renderer needed); :func:`build_scene`
makes the renderer's bodies and camera; :func:`fit_light` fits the shadow maps
that must see the whole blocker in front of the light, and checks that the
light is not so far (or so close to a plane) that rounding erases what a
method needs: the blocker's silhouette, a radiance pyramid, Blinn's projection.
Every problem is an :class:`~shadowmath.cli._options.OptionError` in terms of
the options.
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any, NamedTuple, cast

import numpy as np
from numpy.typing import NDArray

import shadowmath as sm
from shadowmath import meshes

from ._options import (
    BUILT_IN_MESHES,
    MAP_BORDER_TEXELS,
    PCF_METHODS,
    OptionError,
    Options,
    depth_border_texels,
    number,
    point,
    shown,
)

if TYPE_CHECKING:
    from shadowmath.render import Body

WALL_PLANE = (0.0, 0.0, 1.0, 0.0)  # z = 0, facing +z
FLOOR_PLANE = (0.0, 1.0, 0.0, 0.0)  # y = 0, facing +y
#: The wall's (width along x, height along y) and the floor's (width along x, depth along
#: z): the wall spans x in [-5, 5], y in [0, 6], the floor x in [-5, 5], z in [0, 8].
WALL_SIZE = (10.0, 6.0)
FLOOR_SIZE = (10.0, 8.0)
#: Every receiver point lies within this distance of the origin.
SCENE_RADIUS = 10.0
BLOCKER_CENTRE = (0.0, 1.6, 2.2)
EYE, TARGET = (5.4, 3.8, 10.8), (-0.1, 1.5, 1.0)
#: Mesh file types named in messages: OBJ always, the others when trimesh reads them.
MESH_FORMATS = ("obj", "stl", "ply", "off", "glb", "gltf")

#: An area light's edges ``(edge_u, edge_v)``.
Edges = tuple[NDArray[np.float64], NDArray[np.float64]]
#: A receiver's rectangle ``(corner, edge_u, edge_v)``.
Rectangle = tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]

_FLOAT = np.finfo(np.float64)
#: :func:`shadowmath.planar_projection`'s rounding test: a light whose height above a
#: plane through the origin is at most this fraction of its distance from the origin
#: (``16 eps`` of the terms of ``plane . light``) lies in the plane as far as the
#: rounding of its coordinates can tell.
PLANAR_ROUNDING = 16 * float(_FLOAT.eps)
#: :func:`shadowmath.pyramid_to_unit_cube`'s: an apex (a light sample) whose height above
#: the receiver is at most this fraction of the pyramid's size (the receiver's edges plus
#: the apex's distance from its corner) lies in the receiver's plane.
PYRAMID_ROUNDING = 64 * float(_FLOAT.eps)
#: The shortest and longest lengths whose squares are normal floats: the library
#: squares a direction's or an edge's length to normalize it.
TINY_LENGTH = float(np.sqrt(_FLOAT.tiny))
HUGE_LENGTH = float(np.sqrt(_FLOAT.max))
#: The receivers' planes as ``(coordinate, its name, the receiver, the plane)``.
RECEIVER_SIDES = ((2, "z", "wall", "the plane z = 0"), (1, "y", "floor", "the plane y = 0"))
#: What a light too far from the scene should be instead.
USE_DIRECTIONAL = (
    "for a light that far use a directional one (--directional X Y Z, the direction "
    "toward the light, with --method planar or depth)"
)


def length(vector: NDArray[np.float64]) -> float:
    """The Euclidean length of ``vector``, without overflow or underflow in its squares."""
    scale = float(np.abs(vector).max())
    if not 0 < scale < np.inf:
        return scale
    return scale * float(np.linalg.norm(vector / scale))


def rotation(axis: Sequence[float], degrees: float) -> NDArray[np.float64]:
    """The ``(3, 3)`` rotation by ``degrees`` about ``axis`` (Rodrigues' formula)."""
    k = np.asarray(axis, dtype=np.float64) / np.linalg.norm(axis)
    K = np.array([[0.0, -k[2], k[1]], [k[2], 0.0, -k[0]], [-k[1], k[0], 0.0]])
    a = np.radians(degrees)
    r: NDArray[np.float64] = np.eye(3) + np.sin(a) * K + (1 - np.cos(a)) * K @ K
    return r


def placement(
    turn: NDArray[np.float64], translation: Sequence[float], scale: float = 1.0
) -> NDArray[np.float64]:
    """The ``(4, 4)`` placement: ``turn`` scaled by ``scale``, then moved by ``translation``."""
    m = np.eye(4)
    m[:3, :3] = turn * scale
    m[:3, 3] = translation
    return m


def ground_and_boxes(
    size: float,
    color: tuple[float, float, float],
    boxes: Sequence[tuple[float, float, float, float, float, float]],
    box_color: tuple[float, float, float],
) -> list[Body]:
    """A ``size`` x ``size`` ground in the plane ``y = 0`` (two triangles, facing ``+y``) and
    a box standing on it per ``(x, z, width, depth, height, turn in degrees about y)``: the
    large scenes of ``--method cascades`` and ``atlas`` (needs :mod:`shadowmath.render`)."""
    from shadowmath.render import Body

    flat = placement(rotation((1.0, 0.0, 0.0), -90.0), (0.0, 0.0, 0.0))
    bodies = [Body(*meshes.grid((size, size), segments=(1, 1)), flat, color)]
    for x, z, w, d, h, turn in boxes:
        turned = placement(rotation((0.0, 1.0, 0.0), turn), (x, 0.5 * h, z))
        bodies.append(Body(*meshes.box((w, h, d)), turned, box_color))
    return bodies


def tilted_blocker(
    name: str, at: Sequence[float], scale: float, color: tuple[float, float, float]
) -> Body:
    """The ``--mesh`` blocker ``name`` turned -25 degrees about ``x`` then -35 about ``y``,
    scaled by ``scale`` and centred at ``at`` (needs :mod:`shadowmath.render`)."""
    from shadowmath.render import Body

    tilt = rotation((0.0, 1.0, 0.0), -35.0) @ rotation((1.0, 0.0, 0.0), -25.0)
    return Body(*blocker_mesh(name), placement(tilt, at, scale), color)


def mesh_formats() -> str:
    """The file types ``--mesh`` reads here, for messages."""
    try:
        import trimesh
    except ImportError:
        return (
            ".obj (other formats, e.g. .stl, .ply, .glb, .off, need the 'mesh' extra: "
            "pip install 'shadowmath[mesh]')"
        )
    readable = set(trimesh.available_formats()) | {"obj"}
    return ", ".join(f".{f}" for f in MESH_FORMATS if f in readable)


def blocker_mesh(name: str) -> meshes.Mesh:
    """A built-in mesh by name, or a mesh file centred and scaled to the torus's size.

    Raises:
        OptionError: neither a built-in name nor a readable mesh file.
    """
    if name in BUILT_IN_MESHES:
        return BUILT_IN_MESHES[name]()
    loaded = _read_mesh_file(name)
    # A user's mesh comes in its own units: centre it and scale it to the torus's size,
    # in units of its largest coordinate so that no difference or square overflows.
    vertices = loaded.vertices / max(float(np.abs(loaded.vertices).max()), _FLOAT.tiny)
    centre = 0.5 * vertices.max(axis=0) + 0.5 * vertices.min(axis=0)
    radius = np.linalg.norm(vertices - centre, axis=1).max()
    if not radius > 0:
        raise OptionError(f"--mesh {name}: the mesh has no extent (all vertices coincide)")
    return meshes.Mesh((vertices - centre) * (1.3 / radius), loaded.faces)


def _read_mesh_file(name: str) -> meshes.Mesh:
    """The mesh file ``--mesh name`` as stored (:func:`shadowmath.meshes.load_mesh`).

    Raises:
        OptionError: no such file, a file type the demo does not read, or a file
            that does not parse as a mesh.
    """
    path = Path(name)
    if not path.is_file():
        raise OptionError(
            f"--mesh {name!r}: neither a built-in mesh ({', '.join(BUILT_IN_MESHES)}) "
            "nor an existing file"
        )
    suffix = path.suffix.lower()
    formats = mesh_formats()
    if suffix == "" or (suffix != ".obj" and suffix not in formats.split(", ")):
        raise OptionError(f"--mesh {name}: not a mesh file type the demo reads; it reads {formats}")
    try:
        return meshes.load_mesh(path)
    except (OSError, ValueError) as err:
        raise OptionError(f"--mesh {name}: cannot read it as a mesh ({err})") from None
    except Exception as err:  # trimesh raises many kinds for files it cannot parse
        raise OptionError(
            f"--mesh {name}: cannot read it as a {suffix} mesh ({type(err).__name__}: {err})"
        ) from None


def check_light(light: NDArray[np.float64]) -> None:
    """The scene's wall and floor are opaque planes: a light behind one lights nothing real.

    Raises:
        OptionError: ``--light`` not finite, on or behind the wall, on or below the floor.
    """
    given = shown(light)
    if not np.all(np.isfinite(light)):
        raise OptionError(f"--light {given}: coordinates must be finite")
    if light[2] <= 0:
        raise OptionError(
            f"--light {given}: z = {light[2]:g} puts the light on or behind the wall "
            "(the plane z = 0); the scene is lit from z > 0"
        )
    if light[1] <= 0:
        raise OptionError(
            f"--light {given}: y = {light[1]:g} puts the light on or below the floor "
            "(the plane y = 0); the scene is lit from y > 0"
        )


def check_direction(direction: NDArray[np.float64]) -> None:
    """A directional light must shine onto the visible faces of the wall and the floor,
    clear of both planes by more than rounding, with a length the library can normalize.

    Raises:
        OptionError: ``--directional`` not finite, with ``z <= 0`` or ``y <= 0``, a
            length whose square overflows or underflows, or parallel to the wall or
            the floor within rounding (Blinn's projection onto it is undefined).
    """
    size = check_direction_sides(
        direction,
        (
            (2, "z", "on or behind the wall (the plane z = 0)"),
            (1, "y", "on or behind the floor (y = 0)"),
        ),
    )
    given = shown(direction)
    axis, name, receiver, plane = min(RECEIVER_SIDES, key=lambda side: direction[side[0]])
    if direction[axis] <= PLANAR_ROUNDING * size:
        raise OptionError(
            f"--directional {given}: the light shines parallel to the {receiver} ({plane}) "
            f"within rounding: {name} = {direction[axis]:g} is at most {PLANAR_ROUNDING:.2g} "
            f"of the direction's length {size:.3g}, so Blinn's projection onto the "
            f"{receiver} (drawn by --method planar, printed with depth) is undefined; tilt "
            f"the light away from the {receiver}'s plane, {name} > "
            f"{PLANAR_ROUNDING * size:.3g}"
        )


def check_direction_sides(
    direction: NDArray[np.float64], sides: Sequence[tuple[int, str, str]]
) -> float:
    """``--directional``'s checks shared by every scene: finite, on the lit side of each
    plane ``(axis, its name, where a direction <= 0 puts the light)``, and of a length
    whose square floating point holds; returns the length.

    Raises:
        OptionError: not finite, ``direction[axis] <= 0`` for a side, a length whose square
            overflows or underflows.
    """
    given = shown(direction)
    if not np.all(np.isfinite(direction)):
        raise OptionError(f"--directional {given}: coordinates must be finite")
    for axis, name, where in sides:
        if direction[axis] <= 0:
            raise OptionError(
                f"--directional {given}: the direction points toward the light, and "
                f"{name} = {direction[axis]:g} puts the light {where}; give {name} > 0"
            )
    size = length(direction)
    if not TINY_LENGTH <= size <= HUGE_LENGTH:
        how = "small" if size < TINY_LENGTH else "large"
        raise OptionError(
            f"--directional {given}: the direction's length {size:.3g} is too {how} for "
            f"floating point: the library normalizes it, and its square "
            f"{'underflows' if how == 'small' else 'overflows'} (lengths from "
            f"{TINY_LENGTH:.2g} to {HUGE_LENGTH:.2g} work); only the direction matters, "
            f"e.g. --directional {shown(direction / size)}"
        )
    return size


def check_planar_rounding(light: NDArray[np.float64]) -> None:
    """The point light clear of the wall and the floor by more than the rounding of its
    coordinates: Blinn's projections onto both, which the demo draws (planar) or prints
    (every method), need it (:func:`shadowmath.planar_projection`'s test).

    Raises:
        OptionError: ``--light`` too far for its height above a receiver (or, when even
            a light inside the scene would be that close, too close to the receiver).
    """
    given = shown(light)
    distance = length(light)
    axis, name, receiver, plane = min(RECEIVER_SIDES, key=lambda side: light[side[0]])
    height = float(light[axis])
    if height > PLANAR_ROUNDING * distance:
        return
    limit = height / PLANAR_ROUNDING
    projection = (
        f"Blinn's projection onto the {receiver} (drawn by --method planar, printed by every "
        "method)"
    )
    if limit > SCENE_RADIUS:
        raise OptionError(
            f"--light {given}: too far for a point light of this scene: {distance:.3g} from "
            f"the origin, beyond {limit:.3g}, where its height above the {receiver} "
            f"({name} = {height:g}) falls below the rounding of its coordinates "
            f"({PLANAR_ROUNDING:.2g} of the distance) and {projection} cannot tell the "
            f"light from the {receiver}'s plane; bring the light within {limit:.3g} of the "
            f"origin, or {USE_DIRECTIONAL}"
        )
    raise OptionError(
        f"--light {given}: {name} = {height:g} puts the light within rounding of the "
        f"{receiver} ({plane}): {distance:.3g} from the origin, its height must exceed "
        f"{PLANAR_ROUNDING * distance:.3g} ({PLANAR_ROUNDING:.2g} of the distance) for "
        f"{projection}; move the light away from the {receiver}"
    )


def area_light_edges(light: NDArray[np.float64], size: Sequence[float]) -> Edges:
    """``(edge_u, edge_v)`` of a ``W x H`` light centred on ``light``, facing the blocker.

    Both edges are perpendicular to the direction ``d`` from the light to the
    blocker's centre: ``edge_u`` (length ``W``) is horizontal, ``d x (0, 1, 0)``,
    and ``edge_v`` (length ``H``) points upward, ``edge_u x d``. A light straight
    above or below the blocker takes ``edge_u`` along ``x``.
    """
    d = np.asarray(BLOCKER_CENTRE) - light
    distance = float(np.linalg.norm(d))
    d = d / distance if distance > 0 else np.array([0.0, 0.0, -1.0])
    across = np.cross(d, (0.0, 1.0, 0.0))
    if np.linalg.norm(across) < 1e-9:
        across = np.array([1.0, 0.0, 0.0])
    across = across / np.linalg.norm(across)
    up = np.cross(across, d)
    return size[0] * across, size[1] * up


def check_area_light(light: NDArray[np.float64], size: Sequence[float], edges: Edges) -> None:
    """Every corner of the area light, like the point light, above the floor and before the wall.

    Raises:
        OptionError: naming ``--area-light`` and the first corner on the wrong side, or
            sizes whose squares (or whose area's square) leave floating point's range.
    """
    w, h = size
    if not TINY_LENGTH <= min(w, h, w * h) <= max(w, h, w * h) <= HUGE_LENGTH:
        raise OptionError(
            f"--area-light {shown(size)}: sizes and an area W x H = {w * h:.3g} beyond "
            "floating point's range: the library squares the edges' lengths and the "
            f"area, which must lie from {TINY_LENGTH:.2g} to {HUGE_LENGTH:.2g} for the "
            "squares to be told from zero and infinity; give W, H and W x H in that range"
        )
    for su in (-0.5, 0.5):
        for sv in (-0.5, 0.5):
            corner = light + su * edges[0] + sv * edges[1]
            where = (
                "on or behind the wall (the plane z = 0)"
                if corner[2] <= 0
                else "on or below the floor (the plane y = 0)"
                if corner[1] <= 0
                else None
            )
            if where is not None:
                raise OptionError(
                    f"--area-light {shown(size)}: the light's corner {point(corner)} lies "
                    f"{where}; make the light smaller or move --light {shown(light)} away"
                )


class Geometry(NamedTuple):
    """The checked geometry: the blocker's mesh and placement, the area light's edges.

    Attributes:
        mesh: the blocker's mesh, centred at the origin.
        to_world: ``(4, 4)`` its placement at :data:`BLOCKER_CENTRE`, tilted.
        edges: ``(edge_u, edge_v)`` of the area light (soft, radiance), else None.
    """

    mesh: meshes.Mesh
    to_world: NDArray[np.float64]
    edges: Edges | None


def check_light_and_mesh(options: Options) -> Geometry:
    """The light checked against the wall and floor, then the blocker read and placed.

    Raises:
        OptionError: the first problem: the light (or direction), the area light's
            corners, then ``--mesh``.
    """
    light = options.light
    if options.directional:
        check_direction(light)
    else:
        check_light(light)
    edges = area_light_edges(light, options.area_size) if options.area else None
    if edges is not None:
        check_area_light(light, options.area_size, edges)
    mesh = blocker_mesh(options.mesh)
    tilt = rotation((0.0, 1.0, 0.0), -35.0) @ rotation((1.0, 0.0, 0.0), -25.0)
    return Geometry(mesh, placement(tilt, BLOCKER_CENTRE), edges)


class Scene(NamedTuple):
    """The renderer's bodies and camera.

    Attributes:
        receivers: the wall and the floor (``shadowmath.render.Body``, with planes).
        blocker: the blocker's ``Body``.
        camera: ``(4, 4)`` world to clip.
    """

    receivers: list[Body]
    blocker: Body
    camera: NDArray[np.float64]

    def world_vertices(self) -> NDArray[np.float64]:
        """Every body's vertices in world coordinates, ``(N, 3)``."""
        parts = []
        for body in (*self.receivers, self.blocker):
            to_world = np.asarray(body.to_world, dtype=np.float64)
            parts.append(np.asarray(body.vertices) @ to_world[:3, :3].T + to_world[:3, 3])
        return np.concatenate(parts)


def build_scene(options: Options, geometry: Geometry) -> Scene:
    """The wall, the floor, the blocker and the camera (needs :mod:`shadowmath.render`)."""
    from shadowmath.render import Body, look_at, perspective

    wall = meshes.grid(WALL_SIZE, segments=(10, 6))
    floor = meshes.grid(FLOOR_SIZE, segments=(10, 8))
    wall_at, floor_at = (0.0, 0.5 * WALL_SIZE[1], 0.0), (0.0, 0.0, 0.5 * FLOOR_SIZE[1])
    receivers = [
        Body(*wall, placement(np.eye(3), wall_at), (0.86, 0.83, 0.76), WALL_PLANE),
        Body(
            *floor,
            placement(rotation((1.0, 0.0, 0.0), -90.0), floor_at),
            (0.55, 0.6, 0.66),
            FLOOR_PLANE,
        ),
    ]
    width, height = options.image_size
    camera = perspective(40.0, width / height, 0.1, 60.0) @ look_at(EYE, TARGET)
    return Scene(receivers, Body(*geometry.mesh, geometry.to_world, (0.85, 0.33, 0.18)), camera)


def blocker_sphere(geometry: Geometry) -> tuple[NDArray[np.float64], float]:
    """The placed blocker's bounding-box centre and its bounding radius about it."""
    to_world = geometry.to_world
    world = geometry.mesh.vertices @ to_world[:3, :3].T + to_world[:3, 3]
    centre = 0.5 * (world.max(axis=0) + world.min(axis=0))
    return centre, float(np.linalg.norm(world - centre, axis=1).max())


def fit_blocker(
    geometry: Geometry,
    light: NDArray[np.float64],
    map_size: int | tuple[int, int],
    border: int = MAP_BORDER_TEXELS,
) -> sm.ShadowSetup:
    """:func:`shadowmath.fit_shadow`'s map of the placed blocker from ``light``."""
    return sm.fit_shadow(
        light,
        geometry.mesh.vertices,
        map_size,
        blocker_to_world=geometry.to_world,
        border_texels=border,
    )


def _fits(
    geometry: Geometry,
    light: NDArray[np.float64],
    map_size: int | tuple[int, int],
    border: int = MAP_BORDER_TEXELS,
) -> bool:
    """Whether :func:`fit_blocker` fits a map from ``light``."""
    try:
        fit_blocker(geometry, light, map_size, border)
    except ValueError:
        return False
    return True


def farthest_fit(
    geometry: Geometry, light: NDArray[np.float64], map_size: int | tuple[int, int]
) -> float | None:
    """About how far from the blocker's centre, on the ray through ``light``, a map still fits.

    Bisects the distance (to 0.1 %) between twice the blocker's bounding radius and
    ``light``'s distance, where the fit fails. None when it fails at twice the radius
    too: then the distance is not what stops it.
    """
    centre, radius = blocker_sphere(geometry)
    offset = light - centre
    hi = min(length(offset), float(_FLOAT.max))
    lo = 2.0 * radius
    direction = offset / hi
    if not lo < hi or not _fits(geometry, centre + lo * direction, map_size):
        return None
    while hi > lo * 1.001:
        mid = float(np.exp(0.5 * (np.log(lo) + np.log(hi))))
        if _fits(geometry, centre + mid * direction, map_size):
            lo = mid
        else:
            hi = mid
    return lo


def fit_in_front(
    options: Options,
    geometry: Geometry,
    light: NDArray[np.float64],
    *,
    option: str,
    what: str,
) -> sm.ShadowSetup:
    """:func:`shadowmath.fit_shadow` from ``light``, its failures told in terms of the options.

    ``light`` is the point light or one of the area light's samples (``what`` says
    which), ``option`` the option that placed it.

    The map keeps the border the renderer gives it: ``max(1, K)`` texels for ``--pcf K``
    (depth, soft; :func:`~shadowmath.cli._options.depth_border_texels`), else one.

    Raises:
        OptionError: no map can be fitted because the ``--pcf`` border leaves too few
            texels in ``--map-size`` (a map with a one-texel border fits), because
            ``light`` is among or beside the blocker's vertices (naming ``option``),
            because it is so far that the blocker's silhouette falls below rounding
            (naming the light's option, the distance and the farthest distance that
            fits), or for another reason the library gives (naming ``option`` and
            ``--mesh``).
    """
    method, map_size = options.method, options.map_size
    border = depth_border_texels(options.pcf) if method in PCF_METHODS else MAP_BORDER_TEXELS
    try:
        return fit_blocker(geometry, light, map_size, border)
    except ValueError as err:
        if border > MAP_BORDER_TEXELS and _fits(geometry, light, map_size):
            map_w, map_h = options.map_texels
            raise OptionError(
                f"--pcf {options.pcf} with --map-size {map_w}x{map_h}: the {border}-texel "
                f"border that a PCF radius of {options.pcf} keeps on each side of the depth "
                f"map leaves {map_w - 2 * border}x{map_h - 2 * border} texels for the "
                f"blocker's silhouette, too few to fit one from {what} (a map with a "
                "1-texel border fits); use a larger --map-size or a smaller --pcf"
            ) from None
        centre, radius = blocker_sphere(geometry)
        distance = length(light - centre)
        where = f"{number(distance)} from its centre {point(centre)}, whose bounding radius is"
        if distance <= 2.0 * radius:
            beside = "among" if distance <= radius else "beside"
            raise OptionError(
                f"{option}: --method {method} needs the whole blocker in front of the "
                f"light (a shadow map sees less than a half-space), but {what} is {beside} "
                f"the blocker's vertices ({where} {radius:.2f}); move the light away from "
                "the blocker, or use --method planar or omni"
            ) from None
        limit = farthest_fit(geometry, light, map_size)
        if limit is None or distance <= limit:
            raise OptionError(
                f"{option} with --mesh {options.mesh}: --method {method} cannot fit a shadow "
                f"map to the blocker from {what} ({where} {radius:.2f}): {err}"
            ) from None
        kind = "an area light" if options.area else "a point light"
        raise OptionError(
            f"{options.light_option}: too far for {kind} of this scene: {what} is "
            f"{distance:.3g} from the blocker's centre {point(centre)}, beyond about "
            f"{limit:.3g}, where the blocker's silhouette (bounding radius {radius:.2f}, "
            f"{radius / distance:.2g} of the distance) falls below rounding and --method "
            f"{method} cannot fit a shadow map to it; bring the light within {limit:.3g} "
            f"of the blocker, or {USE_DIRECTIONAL}"
        ) from None


def receiver_rectangles() -> tuple[Rectangle, Rectangle]:
    """``(corner, edge_u, edge_v)`` of the wall and the floor, in :data:`RECEIVER_SIDES` order:
    the rectangles that ``method="radiance"`` projects the blocker onto."""
    (wall_w, wall_h), (floor_w, floor_d) = WALL_SIZE, FLOOR_SIZE
    wall = (np.array([-0.5 * wall_w, 0, 0]), np.array([wall_w, 0, 0]), np.array([0, wall_h, 0]))
    floor = (
        np.array([-0.5 * floor_w, 0, 0]),
        np.array([floor_w, 0, 0]),
        np.array([0, 0, floor_d]),
    )
    return wall, floor


def check_radiance_rounding(options: Options, points: NDArray[np.float64]) -> None:
    """Each light sample clear of the wall and the floor by more than the rounding of the
    pyramid it spans with the receiver (:func:`shadowmath.pyramid_to_unit_cube`'s test).

    Raises:
        OptionError: ``--light`` too far for a sample's height above a receiver (or,
            when even a sample inside the scene would be that close, ``--area-light``
            too close to the receiver).
    """
    rectangles = receiver_rectangles()
    sizes = [
        float(np.linalg.norm(edge_u) + np.linalg.norm(edge_v))
        # An overflowing distance (a light beyond 1e154) makes the ratio 0: refused, rightly.
        + np.linalg.norm(points - corner, axis=1)
        for corner, edge_u, edge_v in rectangles
    ]
    ratios = np.stack([points[:, s[0]] for s in RECEIVER_SIDES]) / np.stack(sizes)
    side, worst = divmod(int(np.argmin(ratios)), len(points))
    if ratios[side, worst] > PYRAMID_ROUNDING:
        return
    (axis, name, receiver, plane), (corner, edge_u, edge_v) = RECEIVER_SIDES[side], rectangles[side]
    sample = points[worst]
    edges = float(np.linalg.norm(edge_u) + np.linalg.norm(edge_v))
    height, distance = float(sample[axis]), length(sample - corner)
    limit = height / PYRAMID_ROUNDING - edges
    rounding = (
        f"the rounding of the pyramid from the sample to the {receiver} "
        f"({PYRAMID_ROUNDING:.2g} of its size)"
    )
    projection = "the radiance texture's projection (pyramid_to_unit_cube)"
    if limit > SCENE_RADIUS:
        raise OptionError(
            f"{options.light_option}: too far for an area light of this scene with --method "
            f"radiance: its sample at {point(sample)} is {distance:.3g} from the "
            f"{receiver}'s corner {point(corner)}, beyond {limit:.3g}, where its height "
            f"above the {receiver} ({name} = {height:.3g}) falls below {rounding} and "
            f"{projection} cannot tell the sample from the {receiver}'s plane; bring the "
            f"light within {limit:.3g} of that corner, or {USE_DIRECTIONAL}"
        )
    raise OptionError(
        f"--area-light {shown(options.area_size)}: the light's sample at {point(sample)} "
        f"lies within rounding of the {receiver} ({plane}): its height {name} = "
        f"{height:.3g} must exceed {rounding}, {PYRAMID_ROUNDING * (edges + distance):.3g}, "
        f"for {projection}; make the light smaller or move {options.light_option} away "
        f"from the {receiver}"
    )


def no_map_setup() -> sm.ShadowSetup:
    """What ``render_scene`` gets for planar shadows, which read no shadow map.

    ``render_scene`` draws a shadow map per blocker whatever the method; with a
    zero ``blocker_to_clip`` every vertex lands on ``w = 0`` and nothing is drawn,
    and planar shadows need no light frame, so no light-frame check can refuse
    a light (e.g. one inside the blocker).
    """
    zero = np.zeros((4, 4))
    nothing = cast(Any, None)
    return sm.ShadowSetup(
        frame=nothing,
        frustum=nothing,
        world_to_light=zero,
        blocker_to_world=zero,
        blocker_to_clip=zero,
        world_to_texture=zero,
    )


class LightFit(NamedTuple):
    """The light's shadow-map fit, checked before anything is drawn.

    Attributes:
        setup: ``fit_shadow``'s setup of a point light under texture or depth; for
            the other systems the empty :func:`no_map_setup`.
        points: ``(samples, 3)`` the area light's samples (soft, radiance), else None.
        edges: ``(edge_u, edge_v)`` of the area light (soft, radiance), else None.
    """

    setup: sm.ShadowSetup
    points: NDArray[np.float64] | None
    edges: Edges | None


def fit_light(options: Options, geometry: Geometry) -> LightFit:
    """The setup of the light and the area light's samples, each seeing the whole blocker.

    Checks, in this order, the method's own fits (the point light's map for texture
    and depth, each sample's for soft), the samples' radiance pyramids (radiance),
    then the point light's Blinn projections (every method but directional ones,
    checked by :func:`check_direction`).

    Raises:
        OptionError: the point light (texture, depth) or a light sample (soft) lies
            among the blocker's vertices or too far from it, a sample too close to or
            too far from a receiver (radiance), or the light too close to or too far
            from a receiver for Blinn's projection.
    """
    method, light, edges = options.method, options.light, geometry.edges
    setup = no_map_setup()
    if method in ("texture", "depth", "pcss") and not options.directional:
        setup = fit_in_front(
            options, geometry, light, option=options.light_option, what="this light"
        )
    points = None
    if edges is not None:
        corner = light - 0.5 * (edges[0] + edges[1])
        samples = sm.area_light_samples(
            corner, edges[0], edges[1], options.samples, seed=options.seed
        )
        points = np.asarray(samples, np.float64)
    if method == "soft" and points is not None:
        for sample in points:
            fit_in_front(
                options,
                geometry,
                sample,
                option=f"--area-light {shown(options.area_size)}",
                what=f"the light sample at {point(sample)} (around {options.light_option})",
            )
    if method == "radiance" and points is not None:
        check_radiance_rounding(options, points)
    if not options.directional:
        check_planar_rounding(light)
    return LightFit(setup, points, edges)
