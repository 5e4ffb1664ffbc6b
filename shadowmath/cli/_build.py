"""The demo's scene from the options: the light, the blocker mesh, the bodies, the camera.

The scene is the article's Figure 5.8.1: a wall (the plane ``z = 0``) and a
floor (``y = 0``) receive the shadow of a tilted blocker at
:data:`BLOCKER_CENTRE`. :func:`check_light_and_mesh` checks the light against
those planes and reads the blocker (no renderer needed); :func:`build_scene`
makes the renderer's bodies and camera; :func:`fit_light` fits the shadow maps
that must see the whole blocker in front of the light. Every problem is an
:class:`~shadowmath.cli._options.OptionError` in terms of the options.
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any, NamedTuple, cast

import numpy as np
from numpy.typing import NDArray

import shadowmath as sm
from shadowmath import meshes

from ._options import BUILT_IN_MESHES, OptionError, Options, point, shown

if TYPE_CHECKING:
    from shadowmath.render import Body

WALL_PLANE = (0.0, 0.0, 1.0, 0.0)  # z = 0, facing +z
FLOOR_PLANE = (0.0, 1.0, 0.0, 0.0)  # y = 0, facing +y
BLOCKER_CENTRE = (0.0, 1.6, 2.2)
EYE, TARGET = (5.4, 3.8, 10.8), (-0.1, 1.5, 1.0)
#: Mesh file types named in messages: OBJ always, the others when trimesh reads them.
MESH_FORMATS = ("obj", "stl", "ply", "off", "glb", "gltf")

#: An area light's edges ``(edge_u, edge_v)``.
Edges = tuple[NDArray[np.float64], NDArray[np.float64]]


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
    # A user's mesh comes in its own units: centre it and scale it to the torus's size.
    centre = 0.5 * (loaded.vertices.max(axis=0) + loaded.vertices.min(axis=0))
    radius = np.linalg.norm(loaded.vertices - centre, axis=1).max()
    if not radius > 0:
        raise OptionError(f"--mesh {name}: the mesh has no extent (all vertices coincide)")
    return meshes.Mesh((loaded.vertices - centre) * (1.3 / radius), loaded.triangles)


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
    """A directional light must shine onto the visible faces of the wall and the floor.

    Raises:
        OptionError: ``--directional`` not finite, or with ``z <= 0`` or ``y <= 0``.
    """
    given = shown(direction)
    if not np.all(np.isfinite(direction)):
        raise OptionError(f"--directional {given}: coordinates must be finite")
    for axis, name, plane in ((2, "z", "wall (the plane z = 0)"), (1, "y", "floor (y = 0)")):
        if direction[axis] <= 0:
            raise OptionError(
                f"--directional {given}: the direction points toward the light, and "
                f"{name} = {direction[axis]:g} puts the light on or behind the {plane}; "
                f"give {name} > 0"
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
        OptionError: naming ``--area-light`` and the first corner on the wrong side.
    """
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

    wall = meshes.grid((10.0, 6.0), segments=(10, 6))
    floor = meshes.grid((10.0, 8.0), segments=(10, 8))
    receivers = [
        Body(*wall, placement(np.eye(3), (0.0, 3.0, 0.0)), (0.86, 0.83, 0.76), WALL_PLANE),
        Body(
            *floor,
            placement(rotation((1.0, 0.0, 0.0), -90.0), (0.0, 0.0, 4.0)),
            (0.55, 0.6, 0.66),
            FLOOR_PLANE,
        ),
    ]
    width, height = options.image_size
    camera = perspective(40.0, width / height, 0.1, 60.0) @ look_at(EYE, TARGET)
    return Scene(receivers, Body(*geometry.mesh, geometry.to_world, (0.85, 0.33, 0.18)), camera)


def fit_in_front(
    geometry: Geometry,
    light: NDArray[np.float64],
    map_size: int | tuple[int, int],
    *,
    option: str,
    method: str,
    what: str,
) -> sm.ShadowSetup:
    """:func:`shadowmath.fit_shadow` from ``light``, its failures told in terms of the options.

    Raises:
        OptionError: ``option`` and ``method`` cannot fit a map because ``what``
            (the light, or one of its samples) lies among the blocker's vertices.
    """
    try:
        return sm.fit_shadow(
            light, geometry.mesh.vertices, map_size, blocker_to_world=geometry.to_world
        )
    except ValueError:
        to_world = geometry.to_world
        world = geometry.mesh.vertices @ to_world[:3, :3].T + to_world[:3, 3]
        centre = 0.5 * (world.max(axis=0) + world.min(axis=0))
        radius = float(np.linalg.norm(world - centre, axis=1).max())
        distance = float(np.linalg.norm(light - centre))
        raise OptionError(
            f"{option}: --method {method} needs the whole blocker in front of the "
            f"light (a shadow map sees less than a half-space), but {what} is among "
            f"the blocker's vertices ({distance:.2f} from its centre {point(centre)}, "
            f"whose bounding radius is {radius:.2f}); move the light away from the "
            "blocker, or use --method planar or omni"
        ) from None


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

    Raises:
        OptionError: the point light (texture, depth) or a light sample (soft) lies
            among the blocker's vertices.
    """
    method, light, edges = options.method, options.light, geometry.edges
    setup = no_map_setup()
    if method in ("texture", "depth") and not options.directional:
        setup = fit_in_front(
            geometry,
            light,
            options.map_size,
            option=options.light_option,
            method=method,
            what="this light",
        )
    if edges is None:
        return LightFit(setup, None, None)
    corner = light - 0.5 * (edges[0] + edges[1])
    samples = sm.area_light_samples(corner, edges[0], edges[1], options.samples, seed=options.seed)
    points = np.asarray(samples, np.float64)
    if method == "soft":
        for sample in points:
            fit_in_front(
                geometry,
                sample,
                options.map_size,
                option=f"--area-light {shown(options.area_size)}",
                method=method,
                what=f"the light sample at {point(sample)} (around {options.light_option})",
            )
    return LightFit(setup, points, edges)
