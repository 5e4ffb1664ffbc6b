"""``python -m shadowmath``: render the article's Figure 5.8.1 scene and print its matrices.

A torus (or any mesh) between a light and a wall, above a floor, drawn
offscreen with the reference renderer (:mod:`shadowmath.render`, the
``render`` extra) by one of its shadow systems (``--method``) and saved as a
PNG. Every error about the user's options goes through ``argparse``'s
``parser.error`` (exit status 2) and names the option; a missing OpenGL
context, WebGPU adapter or renderer extra exits with status 1.
"""

from __future__ import annotations

import argparse
import sys
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any, NamedTuple, NoReturn, cast

import numpy as np
from numpy.typing import NDArray

from . import meshes
from ._conventions import api_convention
from ._cube import cube_face_projection, cube_face_views
from ._planar import planar_projection
from ._setup import ShadowSetup, fit_shadow
from ._soft import area_light_samples

WALL_PLANE = (0.0, 0.0, 1.0, 0.0)  # z = 0, facing +z
FLOOR_PLANE = (0.0, 1.0, 0.0, 0.0)  # y = 0, facing +y
BLOCKER_CENTRE = (0.0, 1.6, 2.2)
DEFAULT_LIGHT = (-2.2, 3.6, 6.0)
DEFAULT_MAP_SIZE = 256
DEFAULT_IMAGE_SIZE = (640, 400)
#: The default picture; its folder is the only one the demo creates when missing.
DEFAULT_OUTPUT = Path("out/shadow.png")
EYE, TARGET = (5.4, 3.8, 10.8), (-0.1, 1.5, 1.0)
#: The shading of both APIs' pictures (render_scene's defaults, passed explicitly).
AMBIENT = 0.15
BACKGROUND = (0.06, 0.07, 0.09)

#: ``--method``'s shadow systems, and the options that apply to each.
METHODS = ("texture", "planar", "depth", "omni", "soft", "radiance")
MAP_METHODS = ("texture", "depth", "omni", "soft", "radiance")
DEPTH_BIAS_METHODS = ("depth", "omni", "soft")
PCF_METHODS = ("depth", "soft")
AREA_LIGHT_METHODS = ("soft", "radiance")
DIRECTIONAL_METHODS = ("planar", "depth")
MAP_OUTPUT_METHODS = ("texture", "depth", "omni")
APIS = ("opengl", "webgpu")
DEFAULT_AREA_LIGHT = (1.0, 1.0)
DEFAULT_SAMPLES = 16
DEFAULT_SEED = 0
#: The renderer's default polygon offset of a depth map, ``(2.5 + 2 k, 4)`` for PCF radius k.
DEFAULT_DEPTH_BIAS = (2.5, 4.0)

#: Mesh file types named in messages: OBJ always, the others when trimesh reads them.
MESH_FORMATS = ("obj", "stl", "ply", "off", "glb", "gltf")

#: The built-in blockers, by the name ``--mesh`` takes.
BUILT_IN_MESHES: dict[str, Callable[[], meshes.Mesh]] = {
    "torus": meshes.torus,
    "box": lambda: meshes.box((1.4, 1.0, 0.6)),
    "sphere": lambda: meshes.sphere(0.8),
    "bar": lambda: meshes.bar(2.6, 0.12),
}

DESCRIPTION = """\
Render the scene of Nagy's Figure 5.8.1 offscreen and print the matrices it was
drawn with: a blocker (a torus by default) between a light and a wall, above a
floor, shadowed by one of the reference renderer's shadow systems. The wall is
the plane z = 0 (the scene lies at z > 0), the floor the plane y = 0 (the scene
lies at y > 0). Needs the 'render' extra (moderngl) and an OpenGL 3.3 context
through EGL (Mesa's llvmpipe is enough); --api webgpu needs a WebGPU adapter
through wgpu (Mesa's Vulkan llvmpipe is enough)."""

EPILOG = f"""\
shadow systems (--method):
  texture   Nagy's projective shadow texture: the blocker's silhouette map
            projected onto the receivers (fit_shadow, world_to_texture)
  planar    Blinn's planar projection of the blocker onto the wall and the
            floor (planar_projection), no shadow map
  depth     Williams' shadow z-buffer: every body's depth from the light,
            compared per pixel (--pcf, --depth-bias; --api webgpu draws it
            with WebGPU instead of OpenGL)
  omni      a point light shining every way: a cube depth map of six faces
            (cube_face_views, cube_face_projection; --depth-bias)
  soft      an area light (--area-light, --samples, --seed): the average of
            the depth-map shadows of its samples (--pcf, --depth-bias)
  radiance  an area light: Heckbert and Herf's radiance texture per receiver
            (pyramid_to_unit_cube), accumulated over the samples
  --directional X Y Z replaces the point light with a directional one
  (parallel rays, an orthographic depth map) for planar and depth.
  An option that does not apply to the chosen system is refused.

output files:
  The picture goes to --output (default {DEFAULT_OUTPUT}). The default folder
  '{DEFAULT_OUTPUT.parent}' is created when missing; any other folder, of --output
  or --shadow-map-output, must exist already (the demo does not create folders
  you name). Every file written is reported with its full path.

examples:
  python -m shadowmath --mesh bar --light 2 4 6
  python -m shadowmath --mesh model.obj --map-size 512x256 --shadow-map-output map.png
  python -m shadowmath --method planar --output planar.png
  python -m shadowmath --method depth --pcf 1 --map-size 512
  python -m shadowmath --method depth --api webgpu
  python -m shadowmath --method depth --directional -1 2 1.5
  python -m shadowmath --method soft --area-light 1.5 1 --samples 64"""


class _OptionError(ValueError):
    """A problem with the user's options, told in terms of those options."""


def _rotation(axis: Sequence[float], degrees: float) -> NDArray[np.float64]:
    k = np.asarray(axis, dtype=np.float64) / np.linalg.norm(axis)
    K = np.array([[0.0, -k[2], k[1]], [k[2], 0.0, -k[0]], [-k[1], k[0], 0.0]])
    a = np.radians(degrees)
    r: NDArray[np.float64] = np.eye(3) + np.sin(a) * K + (1 - np.cos(a)) * K @ K
    return r


def _placement(
    rotation: NDArray[np.float64], translation: Sequence[float], scale: float = 1.0
) -> NDArray[np.float64]:
    m = np.eye(4)
    m[:3, :3] = rotation * scale
    m[:3, 3] = translation
    return m


def _mesh_formats() -> str:
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


def _blocker_mesh(name: str) -> meshes.Mesh:
    """A built-in mesh by name, or a mesh file centred and scaled to the torus's size.

    Raises:
        _OptionError: neither a built-in name nor a readable mesh file.
    """
    if name in BUILT_IN_MESHES:
        return BUILT_IN_MESHES[name]()
    path = Path(name)
    if not path.is_file():
        raise _OptionError(
            f"--mesh {name!r}: neither a built-in mesh ({', '.join(BUILT_IN_MESHES)}) "
            "nor an existing file"
        )
    suffix = path.suffix.lower()
    formats = _mesh_formats()
    if suffix == "" or (suffix != ".obj" and suffix not in formats.split(", ")):
        raise _OptionError(
            f"--mesh {name}: not a mesh file type the demo reads; it reads {formats}"
        )
    try:
        loaded = meshes.load_mesh(path)
    except (OSError, ValueError) as err:
        raise _OptionError(f"--mesh {name}: cannot read it as a mesh ({err})") from None
    except Exception as err:  # trimesh raises many kinds for files it cannot parse
        raise _OptionError(
            f"--mesh {name}: cannot read it as a {suffix} mesh ({type(err).__name__}: {err})"
        ) from None
    # A user's mesh comes in its own units: centre it and scale it to the torus's size.
    centre = 0.5 * (loaded.vertices.max(axis=0) + loaded.vertices.min(axis=0))
    radius = np.linalg.norm(loaded.vertices - centre, axis=1).max()
    if not radius > 0:
        raise _OptionError(f"--mesh {name}: the mesh has no extent (all vertices coincide)")
    return meshes.Mesh((loaded.vertices - centre) * (1.3 / radius), loaded.triangles)


def _shown(values: Any) -> str:
    return " ".join(f"{float(c):g}" for c in np.ravel(values))


def _point(values: Any) -> str:
    return "(" + ", ".join(f"{float(c):.2f}" for c in np.round(values, 2) + 0.0) + ")"


def _check_light(light: NDArray[np.float64]) -> None:
    """The scene's wall and floor are opaque planes: a light behind one lights nothing real."""
    shown = _shown(light)
    if not np.all(np.isfinite(light)):
        raise _OptionError(f"--light {shown}: coordinates must be finite")
    if light[2] <= 0:
        raise _OptionError(
            f"--light {shown}: z = {light[2]:g} puts the light on or behind the wall "
            "(the plane z = 0); the scene is lit from z > 0"
        )
    if light[1] <= 0:
        raise _OptionError(
            f"--light {shown}: y = {light[1]:g} puts the light on or below the floor "
            "(the plane y = 0); the scene is lit from y > 0"
        )


def _check_direction(direction: NDArray[np.float64]) -> None:
    """A directional light must shine onto the visible faces of the wall and the floor."""
    shown = _shown(direction)
    if not np.all(np.isfinite(direction)):
        raise _OptionError(f"--directional {shown}: coordinates must be finite")
    for axis, name, plane in ((2, "z", "wall (the plane z = 0)"), (1, "y", "floor (y = 0)")):
        if direction[axis] <= 0:
            raise _OptionError(
                f"--directional {shown}: the direction points toward the light, and "
                f"{name} = {direction[axis]:g} puts the light on or behind the {plane}; "
                f"give {name} > 0"
            )


def _area_light_edges(
    light: NDArray[np.float64], size: Sequence[float]
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
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


def _check_area_light(
    light: NDArray[np.float64],
    size: Sequence[float],
    edges: tuple[NDArray[np.float64], NDArray[np.float64]],
) -> None:
    """Every corner of the area light, like the point light, above the floor and before the wall."""
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
                raise _OptionError(
                    f"--area-light {_shown(size)}: the light's corner {_point(corner)} lies "
                    f"{where}; make the light smaller or move --light {_shown(light)} away"
                )


def _fit_in_front(
    option: str,
    method: str,
    what: str,
    point: NDArray[np.float64],
    mesh: meshes.Mesh,
    blocker_to_world: NDArray[np.float64],
    map_size: int | tuple[int, int],
) -> ShadowSetup:
    """:func:`fit_shadow` from ``point``, its failures told in terms of the options."""
    try:
        return fit_shadow(point, mesh.vertices, map_size, blocker_to_world=blocker_to_world)
    except ValueError:
        world = mesh.vertices @ blocker_to_world[:3, :3].T + blocker_to_world[:3, 3]
        centre = 0.5 * (world.max(axis=0) + world.min(axis=0))
        radius = float(np.linalg.norm(world - centre, axis=1).max())
        distance = float(np.linalg.norm(point - centre))
        raise _OptionError(
            f"{option}: --method {method} needs the whole blocker in front of the "
            f"light (a shadow map sees less than a half-space), but {what} is among "
            f"the blocker's vertices ({distance:.2f} from its centre {_point(centre)}, "
            f"whose bounding radius is {radius:.2f}); move the light away from the "
            "blocker, or use --method planar or omni"
        ) from None


def _no_map_setup() -> ShadowSetup:
    """What ``render_scene`` gets for planar shadows, which read no shadow map.

    ``render_scene`` draws a shadow map per blocker whatever the method; with a
    zero ``blocker_to_clip`` every vertex lands on ``w = 0`` and nothing is drawn,
    and planar shadows need no light frame, so no light-frame check can refuse
    a light (e.g. one inside the blocker).
    """
    zero = np.zeros((4, 4))
    nothing = cast(Any, None)
    return ShadowSetup(nothing, nothing, zero, zero, zero, zero)


def _map_size(text: str) -> int | tuple[int, int]:
    """``256`` or ``512x256``."""
    parts = text.lower().split("x")
    try:
        values = [int(p) for p in parts]
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected N or WxH, got {text!r}") from None
    if len(values) not in (1, 2) or min(values) < 3:
        raise argparse.ArgumentTypeError(f"expected N or WxH with sizes >= 3, got {text!r}")
    return values[0] if len(values) == 1 else (values[0], values[1])


def _positive_int(text: str) -> int:
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a positive integer, got {text!r}") from None
    if value < 1:
        raise argparse.ArgumentTypeError(f"expected a positive integer, got {text!r}")
    return value


def _non_negative_int(text: str) -> int:
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected an integer >= 0, got {text!r}") from None
    if value < 0:
        raise argparse.ArgumentTypeError(f"expected an integer >= 0, got {text!r}")
    return value


def _finite_float(text: str) -> float:
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a number, got {text!r}") from None
    if not np.isfinite(value):
        raise argparse.ArgumentTypeError(f"expected a finite number, got {text!r}")
    return value


def _positive_float(text: str) -> float:
    value = _finite_float(text)
    if value <= 0:
        raise argparse.ArgumentTypeError(f"expected a number > 0, got {text!r}")
    return value


def _png_path(option: str, path: Path, *, create: bool) -> Path:
    """``path`` resolved, after checking that a PNG can be written there.

    Raises:
        _OptionError: not a ``.png`` name, a folder, or in a folder that does not
            exist (and may not be created).
    """
    if path.suffix.lower() != ".png":
        raise _OptionError(f"{option} {path}: expected a file name ending in .png")
    if path.is_dir():
        raise _OptionError(f"{option} {path}: is a folder; give a file name ending in .png")
    folder = path.parent
    if not folder.is_dir() and not create:
        raise _OptionError(
            f"{option} {path}: the folder {folder} does not exist; create it first "
            "(the demo creates only its default folder)"
        )
    return path.resolve()


def _save_png(path: Path, image: NDArray[Any]) -> None:
    from PIL import Image

    Image.fromarray(np.rint(np.clip(image, 0, 1) * 255).astype(np.uint8)).save(path)


def _parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="python -m shadowmath",
        description=DESCRIPTION,
        epilog=EPILOG,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    parser.add_argument(
        "--mesh",
        default="torus",
        metavar="NAME_OR_FILE",
        help=f"the blocker: a built-in mesh ({', '.join(BUILT_IN_MESHES)}) or a mesh "
        "file (.obj; .stl, .ply, .glb, .off and more with the 'mesh' extra), centred "
        "and scaled to the torus's size (default: torus)",
    )
    parser.add_argument(
        "--light",
        type=float,
        nargs=3,
        metavar=("X", "Y", "Z"),
        default=None,
        help="the point light's position (an area light's centre), with y > 0 (above "
        "the floor) and z > 0 (in front of the wall) "
        f"(default: {' '.join(map(str, DEFAULT_LIGHT))})",
    )
    parser.add_argument(
        "--directional",
        type=float,
        nargs=3,
        metavar=("X", "Y", "Z"),
        default=None,
        help="a directional light instead of --light (parallel rays, like sunlight): the "
        "direction toward the light, with y > 0 and z > 0; --method planar or depth only "
        "(default: the point light)",
    )
    parser.add_argument(
        "--method",
        choices=METHODS,
        default="texture",
        help="the shadow system, one of texture, planar, depth, omni, soft, radiance "
        "(see 'shadow systems' below) (default: texture)",
    )
    parser.add_argument(
        "--map-size",
        type=_map_size,
        default=None,
        metavar="N_OR_WxH",
        help="the shadow map's size in texels, N (square) or WxH, at most the driver's "
        "maximum texture size: the silhouette map (texture), the depth map (depth, and "
        "each sample's in soft), each cube face (omni: square only), each receiver's "
        f"radiance texture (radiance); not with planar (default: {DEFAULT_MAP_SIZE})",
    )
    parser.add_argument(
        "--pcf",
        type=_non_negative_int,
        default=None,
        metavar="K",
        help="percentage-closer filtering: each depth comparison averaged over a "
        "(2K+1)x(2K+1) box of texels; --method depth or soft only (the omni pass "
        "samples one cube-map texel) (default: 0, no filtering)",
    )
    parser.add_argument(
        "--depth-bias",
        type=_finite_float,
        nargs=2,
        metavar=("FACTOR", "UNITS"),
        default=None,
        help="the depth map's polygon offset against shadow acne, glPolygonOffset(FACTOR, "
        "UNITS): FACTOR times each caster triangle's depth slope plus UNITS depth steps; "
        "--method depth, omni or soft (WebGPU rounds UNITS to an integer) "
        f"(default: {DEFAULT_DEPTH_BIAS[0]:g}+2K {DEFAULT_DEPTH_BIAS[1]:g}, "
        "K the --pcf radius)",
    )
    parser.add_argument(
        "--area-light",
        type=_positive_float,
        nargs=2,
        metavar=("W", "H"),
        default=None,
        help="a W x H rectangular light centred on --light and facing the blocker: both "
        "edges perpendicular to the direction from the light to the blocker, W horizontal "
        "and H upward; --method soft or radiance only (default: "
        f"{_shown(DEFAULT_AREA_LIGHT)} with those methods)",
    )
    parser.add_argument(
        "--samples",
        type=_positive_int,
        default=None,
        metavar="N",
        help="how many points of the area light cast hard shadows, stratified and "
        "jittered (area_light_samples); --method soft or radiance only "
        f"(default: {DEFAULT_SAMPLES})",
    )
    parser.add_argument(
        "--seed",
        type=_non_negative_int,
        default=None,
        metavar="S",
        help="the seed of the samples' jitter; --method soft or radiance only "
        f"(default: {DEFAULT_SEED})",
    )
    parser.add_argument(
        "--api",
        choices=APIS,
        default="opengl",
        help="the graphics API that draws the shadows: opengl (moderngl through EGL) or "
        "webgpu (wgpu; --method depth only, with WebGPU's depth and texture conventions) "
        "(default: opengl)",
    )
    parser.add_argument(
        "--size",
        type=_positive_int,
        nargs=2,
        metavar=("W", "H"),
        default=DEFAULT_IMAGE_SIZE,
        help="the picture's size in pixels (default: "
        f"{DEFAULT_IMAGE_SIZE[0]} {DEFAULT_IMAGE_SIZE[1]})",
    )
    parser.add_argument(
        "--output",
        type=Path,
        default=None,
        metavar="FILE.png",
        help=f"the picture to write (default: {DEFAULT_OUTPUT}); its folder must exist",
    )
    parser.add_argument(
        "--shadow-map-output",
        type=Path,
        default=None,
        metavar="FILE.png",
        help="also write the shadow map, t upward: the silhouette (texture), the depth "
        "map (depth; near dark, far light, white where nothing was drawn) or the six "
        "cube faces +X -X +Y -Y +Z -Z side by side (omni); its folder must exist "
        "(default: not written)",
    )
    return parser


def _check_combinations(args: argparse.Namespace) -> None:
    """Refuse every option that the chosen ``--method`` and ``--api`` would ignore.

    Raises:
        _OptionError: naming the option, the method, and the methods it applies to.
    """
    method = args.method
    if args.directional is not None:
        shown = f"--directional {_shown(args.directional)}"
        if args.light is not None:
            raise _OptionError(
                f"{shown}: give a point light (--light) or a directional one, not both"
            )
        if method not in DIRECTIONAL_METHODS:
            raise _OptionError(
                f"{shown}: --method {method} takes a point light; directional lights "
                "are drawn by --method planar or depth"
            )
        if args.api == "webgpu":
            raise _OptionError(
                f"{shown}: the demo's WebGPU renderer takes a point light; use --api opengl "
                "(the default) for a directional light"
            )
    if args.api == "webgpu" and method != "depth":
        raise _OptionError(
            f"--api webgpu: the demo's WebGPU renderer draws --method depth only, not "
            f"--method {method}; use --api opengl (the default) for {method}"
        )
    if method == "planar" and args.map_size is not None:
        raise _OptionError("--map-size: --method planar draws no shadow map; leave --map-size out")
    if method == "omni" and isinstance(args.map_size, tuple) and len(set(args.map_size)) > 1:
        w, h = args.map_size
        raise _OptionError(
            f"--map-size {w}x{h}: --method omni's cube faces are square; give one size, "
            f"e.g. --map-size {max(w, h)}"
        )
    if args.shadow_map_output is not None and method not in MAP_OUTPUT_METHODS:
        why = {
            "planar": "--method planar draws no shadow map to write",
            "soft": "--method soft draws one depth map per light sample and writes none",
            "radiance": "--method radiance draws a texture per receiver and writes none",
        }[method]
        raise _OptionError(
            f"--shadow-map-output: {why} (it writes the map of --method texture, depth or omni)"
        )
    if args.pcf is not None and method not in PCF_METHODS:
        why = (
            "the omni pass samples one cube-map texel per comparison"
            if method == "omni"
            else f"--method {method} compares no depths"
        )
        raise _OptionError(
            f"--pcf {args.pcf}: {why}; percentage-closer filtering applies to "
            "--method depth or soft"
        )
    if args.depth_bias is not None and method not in DEPTH_BIAS_METHODS:
        raise _OptionError(
            f"--depth-bias {_shown(args.depth_bias)}: --method {method} draws no depth "
            "map; the bias applies to --method depth, omni or soft"
        )
    for option, value in (
        ("--area-light", args.area_light),
        ("--samples", args.samples),
        ("--seed", args.seed),
    ):
        if value is not None and method not in AREA_LIGHT_METHODS:
            raise _OptionError(
                f"{option} {_shown(value)}: --method {method} lights from a point; an area "
                "light and its samples need --method soft or radiance"
            )


def _depth_picture(depth: NDArray[Any]) -> NDArray[np.float64]:
    """Window depths as grey: the drawn range stretched from black (near) to light grey
    (far), white where nothing was drawn (depth 1)."""
    d = np.asarray(depth, dtype=np.float64)
    drawn = d < 1.0
    if not drawn.any():
        return np.ones_like(d)
    lo, hi = float(d[drawn].min()), float(d[drawn].max())
    scaled = 0.8 * (d - lo) / (hi - lo if hi > lo else 1.0)
    return np.where(drawn, scaled, 1.0)


class _Scene(NamedTuple):
    receivers: list[Any]
    blocker: Any
    camera: NDArray[np.float64]

    def world_vertices(self) -> NDArray[np.float64]:
        parts = []
        for body in (*self.receivers, self.blocker):
            to_world = np.asarray(body.to_world, dtype=np.float64)
            parts.append(np.asarray(body.vertices) @ to_world[:3, :3].T + to_world[:3, 3])
        return np.concatenate(parts)


def _webgpu_color(
    frame: Any, albedo: Sequence[Sequence[float]], light: NDArray[np.float64]
) -> NDArray[np.float64]:
    """The picture from a WebGPU frame's record: ``render_scene``'s shading (ambient plus
    Lambert, the diffuse term removed by the shadow mask) with the face normals."""
    body = frame.body
    colors = np.asarray(albedo, dtype=np.float64)[np.clip(body, 0, None)]
    to_light = light - frame.position
    to_light /= np.linalg.norm(to_light, axis=-1, keepdims=True)
    diffuse = np.clip(np.sum(frame.normal * to_light, axis=-1), 0.0, None)
    shade = AMBIENT + diffuse * (1.0 - frame.shadow)
    color = colors * shade[..., None]
    return np.where((body >= 0)[..., None], np.nan_to_num(color), np.asarray(BACKGROUND))


def _show(matrix: Any) -> NDArray[Any]:
    # Rounding away the last bits, then + 0.0, prints rounding noise and -0 as 0.
    return np.round(np.asarray(matrix, dtype=np.float64), 12) + 0.0


def _print_matrix(name: str, matrix: Any) -> None:
    # Local print options: main() runs in-process in tests and must not change NumPy's.
    with np.printoptions(precision=5, suppress=True):
        print(f"{name} =", _show(matrix), sep="\n")


def main(argv: Sequence[str] | None = None) -> int:
    """Run the demo with ``argv`` (default ``sys.argv[1:]``); returns the exit status.

    Errors in the options exit through ``SystemExit(2)`` with a message on stderr.
    """
    parser = _parser()
    args = parser.parse_args(argv)

    def fail(err: Exception) -> NoReturn:
        parser.error(str(err))

    method: str = args.method
    webgpu = args.api == "webgpu"
    area = method in AREA_LIGHT_METHODS
    map_size: int | tuple[int, int] = DEFAULT_MAP_SIZE if args.map_size is None else args.map_size
    map_w, map_h = (map_size, map_size) if isinstance(map_size, int) else map_size
    width, height = args.size
    directional = args.directional is not None
    light = np.asarray(
        args.directional if directional else (args.light or DEFAULT_LIGHT), dtype=np.float64
    )
    pcf = 0 if args.pcf is None else args.pcf
    bias = (
        (DEFAULT_DEPTH_BIAS[0] + 2.0 * pcf, DEFAULT_DEPTH_BIAS[1])
        if args.depth_bias is None
        else (float(args.depth_bias[0]), float(args.depth_bias[1]))
    )
    area_size = tuple(args.area_light or DEFAULT_AREA_LIGHT)
    samples = DEFAULT_SAMPLES if args.samples is None else args.samples
    seed = DEFAULT_SEED if args.seed is None else args.seed
    try:
        _check_combinations(args)
        output = _png_path("--output", args.output or DEFAULT_OUTPUT, create=args.output is None)
        map_output = (
            None
            if args.shadow_map_output is None
            else _png_path("--shadow-map-output", args.shadow_map_output, create=False)
        )
        if directional:
            _check_direction(light)
        else:
            _check_light(light)
        edges = _area_light_edges(light, area_size) if area else None
        if edges is not None:
            _check_area_light(light, area_size, edges)
        mesh = _blocker_mesh(args.mesh)
    except _OptionError as err:
        fail(err)

    try:
        import moderngl

        from .render import (
            Body,
            GLUnavailableError,
            Light,
            look_at,
            perspective,
            render_scene,
            standalone_context,
        )
    except ImportError as err:
        parser.exit(
            1,
            f"{parser.prog}: the demo needs the 'render' extra, "
            f"pip install 'shadowmath[render]' ({err})\n",
        )

    wall = meshes.grid((10.0, 6.0), segments=(10, 6))
    floor = meshes.grid((10.0, 8.0), segments=(10, 8))
    tilt = _rotation((0.0, 1.0, 0.0), -35.0) @ _rotation((1.0, 0.0, 0.0), -25.0)
    blocker_to_world = _placement(tilt, BLOCKER_CENTRE)
    receivers = [
        Body(*wall, _placement(np.eye(3), (0.0, 3.0, 0.0)), (0.86, 0.83, 0.76), WALL_PLANE),
        Body(
            *floor,
            _placement(_rotation((1.0, 0.0, 0.0), -90.0), (0.0, 0.0, 4.0)),
            (0.55, 0.6, 0.66),
            FLOOR_PLANE,
        ),
    ]
    blocker = Body(*mesh, blocker_to_world, (0.85, 0.33, 0.18))
    camera = perspective(40.0, width / height, 0.1, 60.0) @ look_at(EYE, TARGET)
    scene = _Scene(receivers, blocker, camera)

    # The light's points that fit a shadow map must see the whole blocker in front.
    light_text = f"--{'directional' if directional else 'light'} {_shown(light)}"
    points: NDArray[np.float64] | None = None
    try:
        setup = _no_map_setup()
        if method in ("texture", "depth") and not directional:
            setup = _fit_in_front(
                light_text, method, "this light", light, mesh, blocker_to_world, map_size
            )
        if edges is not None:
            corner = light - 0.5 * (edges[0] + edges[1])
            points = np.asarray(
                area_light_samples(corner, edges[0], edges[1], samples, seed=seed), np.float64
            )
            if method == "soft":
                for point in points:
                    _fit_in_front(
                        f"--area-light {_shown(area_size)}",
                        method,
                        f"the light sample at {_point(point)} (around {light_text})",
                        point,
                        mesh,
                        blocker_to_world,
                        map_size,
                    )
    except _OptionError as err:
        fail(err)

    map_picture: NDArray[Any] | None = None
    if webgpu:
        try:
            from .render.webgpu import WgpuUnavailableError, render_depth_wgpu, wgpu_device

            device = wgpu_device()
        except ImportError as err:
            parser.exit(1, f"{parser.prog}: --api webgpu needs wgpu (the 'render' extra): {err}\n")
        except WgpuUnavailableError as err:
            parser.exit(1, f"{parser.prog}: --api webgpu: {err}\n")
        max_texture = int(device.limits["max-texture-dimension-2d"])
        limit_name = "max-texture-dimension-2d"
        max_image = max_texture
    else:
        try:
            ctx = standalone_context()
        except GLUnavailableError as err:
            parser.exit(1, f"{parser.prog}: {err}\n")
        max_texture = int(ctx.info["GL_MAX_TEXTURE_SIZE"])
        limit_name = "GL_MAX_TEXTURE_SIZE"
        max_image = min(max_texture, int(ctx.info["GL_MAX_RENDERBUFFER_SIZE"]))
    driver = "WebGPU adapter" if webgpu else "OpenGL driver"
    if method != "planar" and max(map_w, map_h) > max_texture:
        parser.error(
            f"--map-size {map_w}x{map_h}: larger than this {driver}'s maximum "
            f"texture size, {max_texture}x{max_texture} ({limit_name})"
        )
    if max(width, height) > max_image:
        image_limits = limit_name if webgpu else "GL_MAX_TEXTURE_SIZE, GL_MAX_RENDERBUFFER_SIZE"
        parser.error(
            f"--size {width} {height}: larger than this {driver}'s maximum image "
            f"size, {max_image}x{max_image} ({image_limits})"
        )

    if webgpu:
        wframe = render_depth_wgpu(
            receivers,
            [blocker],
            Light(light),
            camera,
            image_size=(width, height),
            map_size=map_size,
            pcf_radius=pcf,
            depth_bias=bias,
        )
        albedo = [body.color for body in (*receivers, blocker)]
        color: NDArray[Any] = _webgpu_color(wframe, albedo, light)
        setups: tuple[ShadowSetup, ...] = (wframe.setup,)
        # WebGPU's first row is t = 0, the top of the light's view: already t upward.
        map_picture = _depth_picture(wframe.depth_map)
        adapter = wframe.adapter
    else:
        area_light = (
            Light(direction=light)
            if directional
            else Light(light)
            if edges is None
            else Light(light, edge_u=edges[0], edge_v=edges[1])
        )
        try:
            frame = render_scene(
                receivers,
                [blocker],
                [area_light],
                camera,
                image_size=(width, height),
                map_size=3 if method == "planar" else map_size,
                method=cast(Any, method),
                ambient=AMBIENT,
                background=BACKGROUND,
                setups=[[setup]] if method in ("texture", "planar") else None,
                pcf_radius=pcf,
                depth_bias=bias if method in DEPTH_BIAS_METHODS else None,
                samples=samples,
                seed=seed,
                ctx=ctx,
            )
        except moderngl.Error as err:
            with_map = "" if method == "planar" else f" with {map_w}x{map_h} maps"
            parser.exit(
                1,
                f"{parser.prog}: OpenGL failed to render a {width}x{height} picture"
                f"{with_map}: {err}\n",
            )
        except ValueError as err:  # the checks above should leave the renderer nothing
            fail(_OptionError(f"{light_text}: the renderer refused this scene ({err})"))
        color = frame.color
        setups = frame.setups[0]
        # Row 0 of a GL map is t = 0 (its bottom row): flip it to show t upward.
        if method == "texture":
            map_picture = frame.shadow_maps[0][0][::-1]
        elif method == "depth":
            map_picture = _depth_picture(frame.shadow_maps[0][0][::-1])
        elif method == "omni":
            faces = np.stack(frame.shadow_maps[0])[:, ::-1]
            map_picture = np.concatenate(list(_depth_picture(faces)), axis=1)
        adapter = ""

    if args.output is None:
        output.parent.mkdir(parents=True, exist_ok=True)
    _save_png(output, color)
    where = tuple(float(c) for c in light)
    lit = (
        f"{args.mesh} between a {area_size[0]:g}x{area_size[1]:g} area light centred at "
        f"{where} and a wall"
        if area
        else f"{args.mesh} between a directional light toward {where} and a wall"
        if directional
        else f"{args.mesh} between a point light at {where} and a wall"
    )
    bias_text = f"depth bias {bias[0]:g} {bias[1]:g}"
    drawn = {
        "texture": f"Nagy's projective shadow texture from a {map_w}x{map_h} shadow map",
        "planar": "Blinn's planar shadows",
        "depth": f"Williams' depth shadow map ({map_w}x{map_h}"
        + (", orthographic" if directional else "")
        + f", PCF radius {pcf}, "
        f"{bias_text}) drawn with "
        + (f"WebGPU on {adapter}, shading composed in NumPy" if webgpu else "OpenGL"),
        "omni": f"an omnidirectional cube depth map (six {map_w}x{map_h} faces, {bias_text})",
        "soft": f"soft shadows, the average of {samples} samples' depth shadow maps "
        f"({map_w}x{map_h}, PCF radius {pcf}, {bias_text}; seed {seed})",
        "radiance": f"soft shadows, Heckbert and Herf's radiance textures ({map_w}x{map_h} "
        f"per receiver) accumulated over {samples} samples (seed {seed})",
    }[method]
    print(f"wrote {output}: a {width}x{height} PNG, {lit}, {drawn}")
    if map_output is not None and map_picture is not None:
        _save_png(map_output, map_picture)
        what = {
            "texture": f"the {map_w}x{map_h} shadow map, t upward",
            "depth": f"the {map_w}x{map_h} depth map, t upward, near dark, far light, "
            "white where nothing was drawn",
            "omni": f"the six {map_w}x{map_h} cube faces +X -X +Y -Y +Z -Z, t upward, "
            "near dark, far light",
        }[method]
        print(f"wrote {map_output}: {what}")
    _print_matrix("blocker_to_world", blocker_to_world)
    if method == "texture":
        _print_matrix("world_to_light", setup.world_to_light)
        _print_matrix("blocker_to_clip (pass 1, the shadow map)", setup.blocker_to_clip)
        _print_matrix("world_to_texture (pass 2, the receivers)", setup.world_to_texture)
    elif method == "depth":
        (light_setup,) = setups
        # The depth setup is fitted to the blocker's world vertices: its "blocker" is the world.
        _print_matrix("world_to_light", light_setup.world_to_light)
        _print_matrix(
            "world_to_clip of the light (pass 1, every body's depth; OpenGL conventions)",
            light_setup.blocker_to_clip,
        )
        _print_matrix(
            "world_to_texture (pass 2, (s q, t q, r q, q) compared with the map)",
            light_setup.world_to_texture,
        )
        if webgpu:
            _print_matrix(
                "gl_clip_to_clip (api_convention(api='webgpu'), applied to both)",
                api_convention(api="webgpu").gl_clip_to_clip,
            )
    elif method == "omni":
        # The pass's depth range: far just beyond the farthest vertex along a face axis.
        far = 1.001 * float(np.abs(scene.world_vertices() - light).max())
        near = 1e-3 * far
        _print_matrix(
            f"cube_face_projection(near={near:.5g}, far={far:.5g}, map_size={map_w})",
            cube_face_projection(near, far, map_size=map_w),
        )
        _print_matrix("cube_face_views(light), faces +X -X +Y -Y +Z -Z", cube_face_views(light))
    elif points is not None:
        assert edges is not None
        _print_matrix("area light edge_u (W, horizontal)", edges[0])
        _print_matrix("area light edge_v (H, upward)", edges[1])
        _print_matrix(f"area_light_samples (the {samples} light samples)", points)
    light_h = np.append(light, 0.0 if directional else 1.0)
    for name, plane in (("the wall z = 0", WALL_PLANE), ("the floor y = 0", FLOOR_PLANE)):
        _print_matrix(f"planar_projection onto {name}", planar_projection(plane, light_h))
    sys.stdout.flush()
    return 0


if __name__ == "__main__":
    sys.exit(main())
