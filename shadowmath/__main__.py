"""``python -m shadowmath``: render the article's Figure 5.8.1 scene and print its matrices.

A torus (or any mesh) between a point light and a wall, above a floor, drawn
offscreen with the reference renderer (:mod:`shadowmath.render`, the
``render`` extra) and saved as a PNG. Every error about the user's options goes
through ``argparse``'s ``parser.error`` (exit status 2) and names the option;
a missing OpenGL context or renderer extra exits with status 1.
"""

from __future__ import annotations

import argparse
import sys
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any, NoReturn, cast

import numpy as np
from numpy.typing import NDArray

from . import meshes
from ._planar import planar_projection
from ._setup import ShadowSetup, fit_shadow

WALL_PLANE = (0.0, 0.0, 1.0, 0.0)  # z = 0, facing +z
FLOOR_PLANE = (0.0, 1.0, 0.0, 0.0)  # y = 0, facing +y
BLOCKER_CENTRE = (0.0, 1.6, 2.2)
DEFAULT_LIGHT = (-2.2, 3.6, 6.0)
DEFAULT_MAP_SIZE = 256
DEFAULT_IMAGE_SIZE = (640, 400)
#: The default picture; its folder is the only one the demo creates when missing.
DEFAULT_OUTPUT = Path("out/shadow.png")
EYE, TARGET = (5.4, 3.8, 10.8), (-0.1, 1.5, 1.0)

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
drawn with: a blocker (a torus by default) between a point light and a wall,
above a floor. The wall is the plane z = 0 (the scene lies at z > 0), the floor
the plane y = 0 (the scene lies at y > 0). Needs the 'render' extra (moderngl)
and an OpenGL 3.3 context through EGL (Mesa's llvmpipe is enough)."""

EPILOG = f"""\
output files:
  The picture goes to --output (default {DEFAULT_OUTPUT}). The default folder
  '{DEFAULT_OUTPUT.parent}' is created when missing; any other folder, of --output
  or --shadow-map-output, must exist already (the demo does not create folders
  you name). Every file written is reported with its full path.

examples:
  python -m shadowmath --mesh bar --light 2 4 6
  python -m shadowmath --mesh model.obj --map-size 512x256 --shadow-map-output map.png
  python -m shadowmath --method planar --output planar.png"""


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


def _check_light(light: NDArray[np.float64]) -> None:
    """The scene's wall and floor are opaque planes: a light behind one lights nothing real."""
    shown = " ".join(f"{c:g}" for c in light)
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


def _texture_setup(
    light: NDArray[np.float64],
    mesh: meshes.Mesh,
    blocker_to_world: NDArray[np.float64],
    map_size: int | tuple[int, int],
) -> ShadowSetup:
    """:func:`fit_shadow`, its failures told in terms of the options."""
    try:
        return fit_shadow(light, mesh.vertices, map_size, blocker_to_world=blocker_to_world)
    except ValueError:
        world = mesh.vertices @ blocker_to_world[:3, :3].T + blocker_to_world[:3, 3]
        centre = 0.5 * (world.max(axis=0) + world.min(axis=0))
        radius = float(np.linalg.norm(world - centre, axis=1).max())
        distance = float(np.linalg.norm(light - centre))
        shown = " ".join(f"{c:g}" for c in light)
        at = ", ".join(f"{c:.2f}" for c in np.round(centre, 2) + 0.0)
        raise _OptionError(
            f"--light {shown}: --method texture needs the whole blocker in front of the "
            f"light (a shadow map sees less than a half-space), but this light is among "
            f"the blocker's vertices ({distance:.2f} from its centre "
            f"({at}), whose bounding radius is "
            f"{radius:.2f}); move the light away from the blocker, or use --method planar"
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
        default=DEFAULT_LIGHT,
        help="the point light's position, with y > 0 (above the floor) and z > 0 (in "
        f"front of the wall) (default: {' '.join(map(str, DEFAULT_LIGHT))})",
    )
    parser.add_argument(
        "--map-size",
        type=_map_size,
        default=None,
        metavar="N_OR_WxH",
        help="the shadow map's size in texels, N (square) or WxH, at most the OpenGL "
        f"driver's maximum texture size; --method texture only (default: {DEFAULT_MAP_SIZE})",
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
        "--method",
        choices=("texture", "planar"),
        default="texture",
        help="texture: Nagy's projective shadow texture (a shadow map); planar: Blinn's "
        "planar projection onto the wall and the floor, no shadow map (default: texture)",
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
        help="also write the shadow map, t upward; --method texture only; its folder "
        "must exist (default: not written)",
    )
    return parser


def _show(matrix: Any) -> NDArray[Any]:
    # Rounding away the last bits, then + 0.0, prints rounding noise and -0 as 0.
    return np.round(np.asarray(matrix, dtype=np.float64), 12) + 0.0


def main(argv: Sequence[str] | None = None) -> int:
    """Run the demo with ``argv`` (default ``sys.argv[1:]``); returns the exit status.

    Errors in the options exit through ``SystemExit(2)`` with a message on stderr.
    """
    parser = _parser()
    args = parser.parse_args(argv)

    def fail(err: Exception) -> NoReturn:
        parser.error(str(err))

    planar = args.method == "planar"
    if planar and args.map_size is not None:
        parser.error("--map-size: --method planar draws no shadow map; leave --map-size out")
    if planar and args.shadow_map_output is not None:
        parser.error("--shadow-map-output: --method planar draws no shadow map to write")
    map_size: int | tuple[int, int] = DEFAULT_MAP_SIZE if args.map_size is None else args.map_size
    width, height = args.size
    light = np.asarray(args.light, dtype=np.float64)
    try:
        output = _png_path("--output", args.output or DEFAULT_OUTPUT, create=args.output is None)
        map_output = (
            None
            if args.shadow_map_output is None
            else _png_path("--shadow-map-output", args.shadow_map_output, create=False)
        )
        _check_light(light)
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
    try:
        setup = (
            _no_map_setup() if planar else _texture_setup(light, mesh, blocker_to_world, map_size)
        )
    except _OptionError as err:
        fail(err)

    try:
        ctx = standalone_context()
    except GLUnavailableError as err:
        parser.exit(1, f"{parser.prog}: {err}\n")
    max_texture = int(ctx.info["GL_MAX_TEXTURE_SIZE"])
    max_image = min(max_texture, int(ctx.info["GL_MAX_RENDERBUFFER_SIZE"]))
    map_w, map_h = (map_size, map_size) if isinstance(map_size, int) else map_size
    if not planar and max(map_w, map_h) > max_texture:
        parser.error(
            f"--map-size {map_w}x{map_h}: larger than this OpenGL driver's maximum "
            f"texture size, {max_texture}x{max_texture} (GL_MAX_TEXTURE_SIZE)"
        )
    if max(width, height) > max_image:
        parser.error(
            f"--size {width} {height}: larger than this OpenGL driver's maximum image "
            f"size, {max_image}x{max_image} (GL_MAX_TEXTURE_SIZE, GL_MAX_RENDERBUFFER_SIZE)"
        )

    camera = perspective(40.0, width / height, 0.1, 60.0) @ look_at(EYE, TARGET)
    try:
        frame = render_scene(
            receivers,
            [blocker],
            [Light(light)],
            camera,
            image_size=(width, height),
            map_size=3 if planar else map_size,
            method=args.method,
            setups=[[setup]],
            ctx=ctx,
        )
    except moderngl.Error as err:
        parser.exit(
            1,
            f"{parser.prog}: OpenGL failed to render a {width}x{height} picture"
            f"{'' if planar else f' with a {map_w}x{map_h} shadow map'}: {err}\n",
        )

    if args.output is None:
        output.parent.mkdir(parents=True, exist_ok=True)
    _save_png(output, frame.color)
    np.set_printoptions(precision=5, suppress=True)
    lit = f"{args.mesh} between a point light at {tuple(float(c) for c in light)} and a wall"
    if planar:
        print(f"wrote {output}: a {width}x{height} PNG, {lit}, Blinn's planar shadows")
    else:
        print(
            f"wrote {output}: a {width}x{height} PNG, {lit}, Nagy's projective shadow "
            f"texture from a {map_w}x{map_h} shadow map"
        )
    if map_output is not None:
        # Row 0 of the map is t = 0 (OpenGL's bottom row): flip it to show t upward.
        _save_png(map_output, frame.shadow_maps[0][0][::-1])
        print(f"wrote {map_output}: the {map_w}x{map_h} shadow map, t upward")
    print("blocker_to_world =", _show(blocker_to_world), sep="\n")
    if not planar:
        print("world_to_light =", _show(setup.world_to_light), sep="\n")
        print("blocker_to_clip (pass 1, the shadow map) =", _show(setup.blocker_to_clip), sep="\n")
        print("world_to_texture (pass 2, the receivers) =", _show(setup.world_to_texture), sep="\n")
    light_h = np.append(light, 1.0)
    for name, plane in (("the wall z = 0", WALL_PLANE), ("the floor y = 0", FLOOR_PLANE)):
        print(
            f"planar_projection onto {name} =", _show(planar_projection(plane, light_h)), sep="\n"
        )
    sys.stdout.flush()
    return 0


if __name__ == "__main__":
    sys.exit(main())
