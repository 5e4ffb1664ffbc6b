"""``python -m shadowmath``: render the article's Figure 5.8.1 scene and print its matrices.

A torus (or any mesh) between a point light and a wall, above a floor, drawn
offscreen with the reference renderer (:mod:`shadowmath.render`, the
``render`` extra) and saved as a PNG.
"""

from __future__ import annotations

import argparse
import sys
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from . import meshes
from ._planar import planar_projection

WALL_PLANE = (0.0, 0.0, 1.0, 0.0)  # z = 0, facing +z
FLOOR_PLANE = (0.0, 1.0, 0.0, 0.0)  # y = 0, facing +y
BLOCKER_CENTRE = (0.0, 1.6, 2.2)
DEFAULT_LIGHT = (-2.2, 3.6, 6.0)
EYE, TARGET = (5.4, 3.8, 10.8), (-0.1, 1.5, 1.0)


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


def _blocker_mesh(name: str) -> meshes.Mesh:
    procedural: dict[str, Callable[[], meshes.Mesh]] = {
        "torus": meshes.torus,
        "sphere": lambda: meshes.sphere(0.8),
        "box": lambda: meshes.box((1.4, 1.0, 0.6)),
        "bar": lambda: meshes.bar(2.6, 0.12),
    }
    if name in procedural:
        return procedural[name]()
    loaded = meshes.load_mesh(name)
    # A user's mesh comes in its own units: centre it and scale it to the torus's size.
    centre = 0.5 * (loaded.vertices.max(axis=0) + loaded.vertices.min(axis=0))
    radius = np.linalg.norm(loaded.vertices - centre, axis=1).max()
    if not radius > 0:
        raise ValueError(f"{name}: the mesh has no extent")
    return meshes.Mesh((loaded.vertices - centre) * (1.3 / radius), loaded.triangles)


def _save_png(path: Path, image: NDArray[Any]) -> None:
    from PIL import Image

    path.parent.mkdir(parents=True, exist_ok=True)
    Image.fromarray(np.rint(np.clip(image, 0, 1) * 255).astype(np.uint8)).save(path)


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


def main(argv: Sequence[str] | None = None) -> int:
    parser = argparse.ArgumentParser(
        prog="python -m shadowmath",
        description=__doc__,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    parser.add_argument(
        "--mesh",
        default="torus",
        help="the blocker: torus, box, sphere, bar, or a mesh file (.obj; other formats "
        "with the 'mesh' extra); default torus",
    )
    parser.add_argument(
        "--light",
        type=float,
        nargs=3,
        metavar=("X", "Y", "Z"),
        default=DEFAULT_LIGHT,
        help=f"point light position (default {' '.join(map(str, DEFAULT_LIGHT))})",
    )
    parser.add_argument(
        "--map-size", type=_map_size, default=256, help="shadow map size, N or WxH (default 256)"
    )
    parser.add_argument(
        "--size", type=int, nargs=2, metavar=("W", "H"), default=(640, 400), help="image size"
    )
    parser.add_argument(
        "--method",
        choices=("texture", "planar"),
        default="texture",
        help="Nagy's projective shadow texture (default) or Blinn's planar projection",
    )
    parser.add_argument(
        "--output", type=Path, default=Path("out/shadow.png"), help="the PNG to write"
    )
    parser.add_argument(
        "--shadow-map-output", type=Path, default=None, help="also save the shadow map as a PNG"
    )
    args = parser.parse_args(argv)

    try:
        from .render import Body, GLUnavailableError, Light, look_at, perspective, render_scene
    except ImportError as err:
        parser.exit(1, f"shadowmath: the demo needs the 'render' extra ({err})\n")

    try:
        mesh = _blocker_mesh(args.mesh)
    except (OSError, ValueError) as err:
        parser.error(f"--mesh: {err}")
    light = np.asarray(args.light, dtype=np.float64)
    width, height = args.size
    if width < 1 or height < 1:
        parser.error("--size: width and height must be positive")

    wall = meshes.grid((10.0, 6.0), segments=(10, 6))
    floor = meshes.grid((10.0, 8.0), segments=(10, 8))
    tilt = _rotation((0.0, 1.0, 0.0), -35.0) @ _rotation((1.0, 0.0, 0.0), -25.0)
    receivers = [
        Body(*wall, _placement(np.eye(3), (0.0, 3.0, 0.0)), (0.86, 0.83, 0.76), WALL_PLANE),
        Body(
            *floor,
            _placement(_rotation((1.0, 0.0, 0.0), -90.0), (0.0, 0.0, 4.0)),
            (0.55, 0.6, 0.66),
            FLOOR_PLANE,
        ),
    ]
    blocker = Body(*mesh, _placement(tilt, BLOCKER_CENTRE), (0.85, 0.33, 0.18))
    camera = perspective(40.0, width / height, 0.1, 60.0) @ look_at(EYE, TARGET)
    try:
        frame = render_scene(
            receivers,
            [blocker],
            [Light(light)],
            camera,
            image_size=(width, height),
            map_size=args.map_size,
            method=args.method,
        )
    except GLUnavailableError as err:
        parser.exit(1, f"shadowmath: {err}\n")
    except ValueError as err:
        parser.error(str(err))

    _save_png(args.output, frame.color)
    setup = frame.setups[0][0]
    np.set_printoptions(precision=5, suppress=True)

    def show(matrix: Any) -> NDArray[Any]:
        # Rounding away the last bits, then + 0.0, prints rounding noise and -0 as 0.
        return np.round(np.asarray(matrix, dtype=np.float64), 12) + 0.0

    map_w, map_h = frame.shadow_maps[0][0].shape[::-1]
    print(
        f"wrote {args.output} ({width}x{height}): {args.mesh} between a point light at "
        f"{tuple(float(c) for c in light)} and a wall, {map_w}x{map_h} shadow map, "
        f"{args.method} method"
    )
    if args.shadow_map_output is not None:
        # Row 0 of the map is t = 0 (OpenGL's bottom row): flip it to show t upward.
        _save_png(args.shadow_map_output, frame.shadow_maps[0][0][::-1])
        print(f"wrote {args.shadow_map_output}: the shadow map, t upward")
    print("blocker_to_world =", show(setup.blocker_to_world), sep="\n")
    print("world_to_light =", show(setup.world_to_light), sep="\n")
    print("blocker_to_clip (pass 1, the shadow map) =", show(setup.blocker_to_clip), sep="\n")
    print("world_to_texture (pass 2, the receivers) =", show(setup.world_to_texture), sep="\n")
    light_h = np.append(light, 1.0)
    print(
        "planar_projection onto the wall z = 0 =",
        show(planar_projection(WALL_PLANE, light_h)),
        sep="\n",
    )
    print(
        "planar_projection onto the floor y = 0 =",
        show(planar_projection(FLOOR_PLANE, light_h)),
        sep="\n",
    )
    sys.stdout.flush()
    return 0


if __name__ == "__main__":
    sys.exit(main())
