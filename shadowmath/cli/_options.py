"""The demo's command line: the ``argparse`` parser, the option checks, the resolved options.

:func:`build_parser` declares every option with its help text and its value
checks (the ``type=`` functions, whose messages ``argparse`` prefixes with
``argument --option:``). :func:`resolve_options` fills in the defaults and
refuses combinations that the chosen ``--method`` and ``--api`` would ignore
and output paths that cannot be written, raising :class:`OptionError`; the
other layers read the resulting :class:`Options`.
"""

from __future__ import annotations

import argparse
import math
import re
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Literal, cast

import numpy as np
from numpy.typing import NDArray

import shadowmath as sm
from shadowmath import meshes

#: A shadow system of ``--method`` (the ``method`` of ``render_scene``).
Method = Literal[
    "texture", "planar", "depth", "omni", "soft", "radiance", "pcss", "cascades", "atlas"
]

#: ``--method``'s shadow systems, and the options that apply to each.
METHODS: tuple[Method, ...] = (
    "texture", "planar", "depth", "omni", "soft", "radiance", "pcss", "cascades", "atlas",
)  # fmt: skip
DEPTH_BIAS_METHODS = ("depth", "omni", "soft", "pcss", "cascades", "atlas")
PCF_METHODS = ("depth", "soft", "cascades", "atlas")
AREA_LIGHT_METHODS = ("soft", "radiance")
LIGHT_SIZE_METHODS = ("pcss", "cascades")
DIRECTIONAL_METHODS = ("planar", "depth", "pcss", "cascades")
MAP_OUTPUT_METHODS = ("texture", "depth", "omni", "pcss", "atlas")
APIS = ("opengl", "webgpu")

DEFAULT_LIGHT = (-2.2, 3.6, 6.0)
#: The sun of ``--method cascades`` (toward the light; the scene's ground is ``y = 0``).
DEFAULT_SUN = (1.0, 0.4, 0.5)
DEFAULT_MAP_SIZE = 256
#: ``--method cascades``'s default map size, per cascade.
DEFAULT_CASCADE_MAP_SIZE = 1024
#: ``--method atlas``'s default atlas size (``--map-size``), and its default and largest
#: ``--lights``.
DEFAULT_ATLAS_SIZE = 4096
DEFAULT_ATLAS_LIGHTS = 24
MAX_ATLAS_LIGHTS = 256
DEFAULT_IMAGE_SIZE = (640, 400)
#: The default picture; its folder is the only one the demo creates when missing.
DEFAULT_OUTPUT = Path("out/shadow.png")
DEFAULT_AREA_LIGHT = (1.0, 1.0)
DEFAULT_SAMPLES = 16
DEFAULT_SEED = 0
#: The renderer's default polygon offset of a depth map, ``(2.5 + 2 k, 4)`` for PCF radius k.
DEFAULT_DEPTH_BIAS = (2.5, 4.0)
#: ``--method pcss``'s: the renderer's ``PCSS_POLYGON_OFFSET`` (a map of back faces).
DEFAULT_PCSS_BIAS = (0.0, 1.0)
#: ``--light-size``'s defaults: a point light's radius (world units), a sun's angular
#: radius (degrees).
DEFAULT_LIGHT_RADIUS = 0.25
DEFAULT_SUN_DEGREES = 1.0
#: The empty border of ``fit_shadow``'s map (its default ``border_texels``): a
#: ``--map-size`` must leave room inside it, the rule of :func:`shadowmath.border_margin`.
MAP_BORDER_TEXELS = 1
#: The most light samples ``--samples`` takes: each one draws the scene once more.
MAX_SAMPLES = 65536
#: A negative number as a value, not an option: ``-2``, ``-.5``, ``-1e3``, ``-inf``, ``-nan``
#: (Python 3.11's ``argparse`` reads ``-1e3`` as an unknown option).
NEGATIVE_NUMBER = re.compile(
    r"^-(\d+\.?\d*|\.\d+)([eE][-+]?\d+)?$|^-(inf|infinity|nan)$", re.IGNORECASE
)

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
  pcss      percentage-closer soft shadows in one pass: a blocker search and a
            filter as wide as the light (--light-size), the blockers' and the
            receiver's depths make the penumbra (pcss_parameters; --depth-bias,
            --directional for a sun)
  cascades  a sun over a large scene (a 200 x 200 ground, towers, the
            blocker) seen from near the ground toward the horizon: four
            cascaded depth maps fitted to the camera (fit_cascades; --pcf,
            --depth-bias, --directional for the sun, --map-size per cascade,
            --cascade-colors FILE.png for the cascades coloured, --light-size
            DEGREES for PCSS in every cascade)
  atlas     many lights (--lights N, default {DEFAULT_ATLAS_LIGHTS}: point lights with cube
            maps, spots and suns) over a ground with blocks, their shadow maps
            tiles of one atlas (allocate_atlas, fit_atlas; --map-size is the
            atlas's, a power of two, default {DEFAULT_ATLAS_SIZE}; --pcf,
            --depth-bias; --shadow-map-output writes the atlas)
  --directional X Y Z replaces the point light with a directional one
  (parallel rays, an orthographic depth map) for planar, depth and pcss.
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
  python -m shadowmath --method soft --area-light 1.5 1 --samples 64
  python -m shadowmath --method pcss --light-size 0.4
  python -m shadowmath --method pcss --directional -1 2 1.5 --light-size 2
  python -m shadowmath --method cascades --cascade-colors out/cascades.png
  python -m shadowmath --method atlas --lights 48 --shadow-map-output out/atlas.png"""


class OptionError(ValueError):
    """A problem with the user's options, told in terms of those options.

    :func:`shadowmath.cli.main` reports it through ``parser.error`` (exit status 2).
    """


def shown(values: Any) -> str:
    """Numbers as the user typed them: ``-2.2 3.6 6`` (``%g``, space-separated)."""
    return " ".join(f"{float(c):g}" for c in np.ravel(values))


def point(values: Any) -> str:
    """A computed point for messages: ``(0.50, 1.70, -0.52)``, two decimals, no ``-0.00``;
    coordinates of a million or more in three digits, ``(1e+17, 0.57, 1.34)``."""
    return "(" + ", ".join(number(c) for c in np.ravel(values)) + ")"


def number(value: Any) -> str:
    """A computed number for messages: two decimals, or three digits from a million on."""
    v = float(value)
    return f"{v:.3g}" if abs(v) >= 1e6 else f"{round(v, 2) + 0.0:.2f}"


def map_size_arg(text: str) -> int | tuple[int, int]:
    """``--map-size``: ``256`` or ``512x256``, with room inside the map's border.

    The sizes must pass :func:`shadowmath.border_margin` with the border of
    ``fit_shadow`` (:data:`MAP_BORDER_TEXELS`): at least ``2 b + 1 = 3`` texels per axis.
    """
    smallest = 2 * MAP_BORDER_TEXELS + 1
    parts = text.lower().split("x")
    try:
        values = [int(p) for p in parts]
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected N or WxH, got {text!r}") from None
    too_small = argparse.ArgumentTypeError(
        f"expected N or WxH with sizes >= {smallest}, got {text!r}"
    )
    if len(values) not in (1, 2):
        raise too_small
    size = values[0] if len(values) == 1 else (values[0], values[1])
    if not has_room(size, MAP_BORDER_TEXELS):
        raise too_small
    return size


def has_room(size: int | tuple[int, int], border: int) -> bool:
    """A map of ``size`` texels has texels inside ``border`` empty ones on each side
    (:func:`shadowmath.border_margin` accepts it)."""
    try:
        sm.border_margin(size, border_texels=border)
    except ValueError:
        return False
    return True


def _at_least(text: str, least: int, expected: str) -> int:
    """An integer ``>= least``; the message says ``expected`` for anything else."""
    try:
        value = int(text)
    except ValueError:
        value = least - 1
    if value < least:
        raise argparse.ArgumentTypeError(f"expected {expected}, got {text!r}")
    return value


def positive_int(text: str) -> int:
    """``--size``: an integer ``>= 1``."""
    return _at_least(text, 1, "a positive integer")


def _count(text: str, most: int, why: str = "") -> int:
    """An integer from 1 to ``most``; ``why`` follows the range in the message when out of it."""
    expected = f"expected an integer from 1 to {most}"
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{expected}, got {text!r}") from None
    if not 1 <= value <= most:
        raise argparse.ArgumentTypeError(f"{expected}{why}, got {text!r}")
    return value


def sample_count(text: str) -> int:
    """``--samples``: an integer from 1 to :data:`MAX_SAMPLES`."""
    return _count(
        text, MAX_SAMPLES, " (each sample draws the scene once more: a depth map with soft, "
        "the blocker into each receiver's texture with radiance)",
    )  # fmt: skip


def non_negative_int(text: str) -> int:
    """``--pcf``, ``--seed``: an integer ``>= 0``."""
    return _at_least(text, 0, "an integer >= 0")


def finite_float(text: str) -> float:
    """``--depth-bias``: a finite number."""
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a number, got {text!r}") from None
    if not np.isfinite(value):
        raise argparse.ArgumentTypeError(f"expected a finite number, got {text!r}")
    return value


def light_count(text: str) -> int:
    """``--lights``: an integer from 1 to :data:`MAX_ATLAS_LIGHTS`."""
    return _count(text, MAX_ATLAS_LIGHTS)


def positive_float(text: str) -> float:
    """``--area-light``: a finite number ``> 0``."""
    value = finite_float(text)
    if value <= 0:
        raise argparse.ArgumentTypeError(f"expected a number > 0, got {text!r}")
    return value


def non_negative_float(text: str) -> float:
    """``--light-size``: a finite number ``>= 0``."""
    value = finite_float(text)
    if value < 0:
        raise argparse.ArgumentTypeError(f"expected a number >= 0, got {text!r}")
    return value


def build_parser() -> argparse.ArgumentParser:
    """The demo's parser (``prog`` ``python -m shadowmath``), its options in help order."""
    parser = argparse.ArgumentParser(
        prog="python -m shadowmath",
        description=DESCRIPTION,
        epilog=EPILOG,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    parser._negative_number_matcher = NEGATIVE_NUMBER  # --light -1e3 1 1 reads -1e3 as X
    _add_scene_arguments(parser)
    _add_map_arguments(parser)
    _add_area_light_arguments(parser)
    _add_light_size_argument(parser)
    _add_output_arguments(parser)
    return parser


def _add_scene_arguments(parser: argparse.ArgumentParser) -> None:
    """``--mesh``, ``--light``, ``--directional`` and ``--method``."""
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
        "direction toward the light, with y > 0 and z > 0; --method planar, depth, pcss "
        "or cascades only (the sun of cascades: y > 0 only; default for cascades: "
        f"{shown(DEFAULT_SUN)}) "
        "(default: the point light)",
    )
    parser.add_argument(
        "--method",
        choices=METHODS,
        default="texture",
        help="the shadow system, one of texture, planar, depth, omni, soft, radiance, "
        "pcss, cascades, atlas (see 'shadow systems' below) (default: texture)",
    )
    parser.add_argument(
        "--lights",
        type=light_count,
        default=None,
        metavar="N",
        help="--method atlas only: how many lights, from 1 to "
        f"{MAX_ATLAS_LIGHTS} (default: {DEFAULT_ATLAS_LIGHTS})",
    )


def _add_map_arguments(parser: argparse.ArgumentParser) -> None:
    """``--map-size``, ``--pcf`` and ``--depth-bias``."""
    parser.add_argument(
        "--map-size",
        type=map_size_arg,
        default=None,
        metavar="N_OR_WxH",
        help="the shadow map's size in texels, N (square) or WxH, at most the driver's "
        "maximum texture size: the silhouette map (texture), the depth map (depth, and "
        "each sample's in soft), each cube face (omni: square only), each receiver's "
        f"radiance texture (radiance), each cascade's map (cascades, default "
        f"{DEFAULT_CASCADE_MAP_SIZE}); not with planar (default: {DEFAULT_MAP_SIZE})",
    )
    parser.add_argument(
        "--pcf",
        type=non_negative_int,
        default=None,
        metavar="K",
        help="percentage-closer filtering: each depth comparison averaged over a "
        "(2K+1)x(2K+1) box of texels; --method depth, soft, cascades or atlas only (the omni pass "
        "samples one cube-map texel) (default: 0, no filtering)",
    )
    parser.add_argument(
        "--depth-bias",
        type=finite_float,
        nargs=2,
        metavar=("FACTOR", "UNITS"),
        default=None,
        help="the depth map's polygon offset against shadow acne, glPolygonOffset(FACTOR, "
        "UNITS): FACTOR times each caster triangle's depth slope plus UNITS depth steps; "
        "--method depth, omni, soft, pcss, cascades or atlas (WebGPU rounds UNITS to an "
        "integer; cascades apply the same FACTOR and UNITS to each receiver's slope in the "
        f"shader) (default: {DEFAULT_DEPTH_BIAS[0]:g}+2K {DEFAULT_DEPTH_BIAS[1]:g}, "
        f"K the --pcf radius; pcss: {shown(DEFAULT_PCSS_BIAS)})",
    )


def _add_area_light_arguments(parser: argparse.ArgumentParser) -> None:
    """``--area-light``, ``--samples`` and ``--seed``."""
    parser.add_argument(
        "--area-light",
        type=positive_float,
        nargs=2,
        metavar=("W", "H"),
        default=None,
        help="a W x H rectangular light centred on --light and facing the blocker: both "
        "edges perpendicular to the direction from the light to the blocker, W horizontal "
        "and H upward; --method soft or radiance only (default: "
        f"{shown(DEFAULT_AREA_LIGHT)} with those methods)",
    )
    parser.add_argument(
        "--samples",
        type=sample_count,
        default=None,
        metavar="N",
        help="how many points of the area light cast hard shadows, stratified and "
        f"jittered (area_light_samples), at most {MAX_SAMPLES}; --method soft or radiance "
        f"only (default: {DEFAULT_SAMPLES})",
    )
    parser.add_argument(
        "--seed",
        type=non_negative_int,
        default=None,
        metavar="S",
        help="the seed of the samples' jitter; --method soft or radiance only "
        f"(default: {DEFAULT_SEED})",
    )


def _add_light_size_argument(parser: argparse.ArgumentParser) -> None:
    """``--light-size``."""
    parser.add_argument(
        "--light-size",
        type=non_negative_float,
        default=None,
        metavar="SIZE",
        help="the light's radius (world units), or with --directional the sun's angular "
        "radius in degrees (below 90); --method pcss, or cascades (the sun's: PCSS in "
        f"every cascade) (default: {DEFAULT_LIGHT_RADIUS:g}, a sun {DEFAULT_SUN_DEGREES:g} "
        "degree; cascades: 0, hard shadows)",
    )


def _add_output_arguments(parser: argparse.ArgumentParser) -> None:
    """``--api``, ``--size``, ``--output`` and ``--shadow-map-output``."""
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
        type=positive_int,
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
        "map (depth, pcss; near dark, far light, white where nothing was drawn) or the six "
        "cube faces +X -X +Y -Y +Z -Z side by side (omni); its folder must exist "
        "(default: not written)",
    )
    parser.add_argument(
        "--cascade-colors",
        type=Path,
        default=None,
        metavar="FILE.png",
        help="--method cascades: also write the picture with each cascade coloured (red, "
        "green, blue, yellow from near to far, mixed across the blend bands); its folder "
        "must exist (default: not written)",
    )


def check_combinations(args: argparse.Namespace) -> None:
    """Refuse every option that the chosen ``--method`` and ``--api`` would ignore, and a
    ``--pcf`` whose border leaves no texel inside ``--map-size``.

    Raises:
        OptionError: naming the option, the method, and the methods it applies to (or
            ``--pcf`` and ``--map-size`` with their numbers).
    """
    _check_atlas(args)
    _check_directional(args)
    _check_cascades(args)
    _check_api_and_map(args)
    _check_method_options(args)
    _check_pcf_border(args)


def _check_directional(args: argparse.Namespace) -> None:
    """``--directional``: not with ``--light``, only for planar, depth and pcss (and the
    cascades' sun), only on OpenGL."""
    if args.directional is None:
        return
    given = f"--directional {shown(args.directional)}"
    if args.light is not None:
        raise OptionError(f"{given}: give a point light (--light) or a directional one, not both")
    if args.method not in DIRECTIONAL_METHODS:
        raise OptionError(
            f"{given}: --method {args.method} takes a point light; directional lights "
            "are drawn by --method planar, depth, pcss or cascades"
        )
    if args.api == "webgpu":
        raise OptionError(
            f"{given}: the demo's WebGPU renderer takes a point light; use --api opengl "
            "(the default) for a directional light"
        )


def _check_atlas(args: argparse.Namespace) -> None:
    """``--lights`` only with atlas; atlas places its own lights; its map size is the
    atlas's, one power of two."""
    if args.lights is not None and args.method != "atlas":
        raise OptionError(
            f"--lights {args.lights}: --method {args.method} draws one light; --lights "
            "applies to --method atlas"
        )
    if args.method != "atlas":
        return
    for option, value in (("--light", args.light), ("--directional", args.directional)):
        if value is not None:
            raise OptionError(
                f"{option} {shown(value)}: --method atlas places its own lights (point, spot "
                "and directional, --lights N); leave it out"
            )
    size = args.map_size
    if size is not None:
        w, h = (size, size) if isinstance(size, int) else size
        if w != h or w & (w - 1):
            given = f"{w}" if w == h else f"{w}x{h}"
            raise OptionError(
                f"--map-size {given}: --method atlas's map is the atlas, one power of two "
                f"(square), e.g. --map-size {1 << max(w, h).bit_length() - 1}"
            )


def _check_cascades(args: argparse.Namespace) -> None:
    """``--cascade-colors`` only with cascades; cascades light with a sun, not ``--light``."""
    if args.cascade_colors is not None and args.method != "cascades":
        raise OptionError(
            f"--cascade-colors {args.cascade_colors}: --method {args.method} has no cascades; "
            "it applies to --method cascades"
        )
    if args.method == "cascades" and args.light is not None:
        raise OptionError(
            f"--light {shown(args.light)}: --method cascades lights the scene with a sun; "
            "give its direction with --directional X Y Z"
        )


def _check_api_and_map(args: argparse.Namespace) -> None:
    """``--api webgpu`` draws depth only; ``--map-size`` and ``--shadow-map-output`` need a map."""
    method = args.method
    if args.api == "webgpu" and method != "depth":
        raise OptionError(
            f"--api webgpu: the demo's WebGPU renderer draws --method depth only, not "
            f"--method {method}; use --api opengl (the default) for {method}"
        )
    if method == "planar" and args.map_size is not None:
        raise OptionError("--map-size: --method planar draws no shadow map; leave --map-size out")
    if method == "omni" and isinstance(args.map_size, tuple) and len(set(args.map_size)) > 1:
        w, h = args.map_size
        raise OptionError(
            f"--map-size {w}x{h}: --method omni's cube faces are square; give one size, "
            f"e.g. --map-size {max(w, h)}"
        )
    if args.shadow_map_output is not None and method not in MAP_OUTPUT_METHODS:
        why = {
            "planar": "--method planar draws no shadow map to write",
            "soft": "--method soft draws one depth map per light sample and writes none",
            "radiance": "--method radiance draws a texture per receiver and writes none",
            "cascades": "--method cascades draws four maps; --cascade-colors writes the "
            "picture with its cascades coloured",
        }[method]
        raise OptionError(
            f"--shadow-map-output: {why} (it writes the map of --method texture, depth, omni "
            "or atlas)"
        )


def _check_method_options(args: argparse.Namespace) -> None:
    """``--pcf``, ``--depth-bias`` and the area light's options, each with its methods."""
    method = args.method
    if args.pcf is not None and method not in PCF_METHODS:
        why = (
            "the omni pass samples one cube-map texel per comparison"
            if method == "omni"
            else f"--method {method} compares no depths"
        )
        raise OptionError(
            f"--pcf {args.pcf}: {why}; percentage-closer filtering applies to "
            "--method depth, soft, cascades or atlas"
        )
    if args.depth_bias is not None and method not in DEPTH_BIAS_METHODS:
        raise OptionError(
            f"--depth-bias {shown(args.depth_bias)}: --method {method} draws no depth "
            "map; the bias applies to --method depth, omni, soft, pcss, cascades or atlas"
        )
    if args.light_size is not None and method not in LIGHT_SIZE_METHODS:
        raise OptionError(
            f"--light-size {shown(args.light_size)}: --method {method} does not read it; "
            "the light's size applies to --method pcss and cascades (soft and radiance "
            "take --area-light)"
        )
    sun = args.directional is not None or method == "cascades"
    if args.light_size is not None and sun and args.light_size >= 90:
        raise OptionError(
            f"--light-size {shown(args.light_size)}: a sun's angular radius in degrees "
            "must be below 90"
        )
    for option, value in (
        ("--area-light", args.area_light),
        ("--samples", args.samples),
        ("--seed", args.seed),
    ):
        if value is not None and method not in AREA_LIGHT_METHODS:
            raise OptionError(
                f"{option} {shown(value)}: --method {method} lights from a point; an area "
                "light and its samples need --method soft or radiance"
            )


def depth_border_texels(pcf: int) -> int:
    """The empty border on each side of the reference renderer's depth maps (depth, soft):
    :func:`shadowmath.pcf_border_texels` of its box kernel, ``max(1, K)`` texels for PCF
    radius ``K``, so that no kernel reads past the silhouette."""
    return sm.pcf_border_texels(pcf)


def _check_pcf_border(args: argparse.Namespace) -> None:
    """``--pcf K`` (depth, soft): the depth map must have texels inside its ``max(1, K)`` border.

    The rule of :func:`shadowmath.border_margin` with :func:`depth_border_texels`.
    """
    if args.pcf is None or args.method not in PCF_METHODS or args.method == "atlas":
        return  # the atlas's tiles get their sizes (and room for the border) from the rule
    size = DEFAULT_MAP_SIZE if args.map_size is None else args.map_size
    border = depth_border_texels(args.pcf)
    if has_room(size, border):
        return
    w, h = (size, size) if isinstance(size, int) else size
    given = f"{w}" if isinstance(size, int) else f"{w}x{h}"
    fitting = (min(w, h) - 1) // 2  # the widest K with 2 max(1, K) + 1 texels: >= 1 (size >= 3)
    if args.map_size is None:
        given += " (the default)"
    raise OptionError(
        f"--pcf {args.pcf} with --map-size {given}: a PCF radius of {args.pcf} keeps "
        f"{border} empty texels on each side of the depth map (max(1, K), so that no "
        f"{2 * args.pcf + 1}x{2 * args.pcf + 1} kernel reads past the silhouette), which "
        f"leaves no texel inside a {w}x{h} map; use --map-size {2 * border + 1} or more, "
        f"or --pcf {fitting} or less"
    )


def png_path(option: str, path: Path, *, create: bool) -> Path:
    """``path`` resolved, after checking that a PNG can be written there.

    Raises:
        OptionError: not a ``.png`` name, a folder, or in a folder that is a file or
            does not exist (and may not be created).
    """
    if path.suffix.lower() != ".png":
        raise OptionError(f"{option} {path}: expected a file name ending in .png")
    if path.is_dir():
        raise OptionError(f"{option} {path}: is a folder; give a file name ending in .png")
    folder = path.parent
    if folder.exists() and not folder.is_dir():
        raise OptionError(f"{option} {path}: {folder} is a file, not a folder")
    if not folder.is_dir() and not create:
        raise OptionError(
            f"{option} {path}: the folder {folder} does not exist; create it first "
            "(the demo creates only its default folder)"
        )
    return path.resolve()


@dataclass(frozen=True, eq=False)
class Options:
    """The parsed options with their defaults filled in and their combinations checked.

    Attributes:
        method: the shadow system (``--method``).
        webgpu: ``--api webgpu`` (else OpenGL).
        mesh: ``--mesh`` as given: a built-in name or a file.
        light: ``(3,)`` the point light's position or area light's centre, or the
            direction toward a directional light.
        directional: ``light`` is ``--directional``'s direction.
        map_size: ``--map-size`` as parsed: ``N`` or ``(W, H)``.
        image_size: ``--size``, ``(W, H)`` in pixels.
        pcf: the PCF radius ``K``.
        bias: the depth map's polygon offset ``(factor, units)``.
        area_size: the area light's ``(W, H)`` (read by soft and radiance only).
        samples, seed: the area light's samples and their jitter seed.
        output: the picture's resolved path.
        map_output: the shadow map's resolved path, or None.
        cascade_output: ``--cascade-colors``'s resolved path, or None.
        lights: ``--lights``, the atlas's light count (read by atlas only).
        light_size: ``--light-size`` as ``render_scene`` and ``render_cascades`` take
            it: the radius, or a sun's angular radius in radians (read by pcss and
            cascades only).
        default_output: ``--output`` was not given: create its folder if missing.
    """

    method: Method
    webgpu: bool
    mesh: str
    light: NDArray[np.float64]
    directional: bool
    map_size: int | tuple[int, int]
    image_size: tuple[int, int]
    pcf: int
    bias: tuple[float, float]
    area_size: tuple[float, float]
    samples: int
    seed: int
    output: Path
    map_output: Path | None
    cascade_output: Path | None
    default_output: bool
    lights: int = DEFAULT_ATLAS_LIGHTS
    light_size: float = 0.0

    @property
    def map_texels(self) -> tuple[int, int]:
        """The shadow map's ``(width, height)`` in texels."""
        size = self.map_size
        return (size, size) if isinstance(size, int) else size

    @property
    def area(self) -> bool:
        """The method lights from an area light (soft, radiance)."""
        return self.method in AREA_LIGHT_METHODS

    @property
    def light_option(self) -> str:
        """The light as an option, for messages: ``--light X Y Z`` or ``--directional X Y Z``."""
        return f"--{'directional' if self.directional else 'light'} {shown(self.light)}"


def _light_of(args: argparse.Namespace) -> Any:
    """The light's vector: ``--directional``, the cascades' default sun, or ``--light``."""
    if args.directional is not None:
        return args.directional
    if args.method == "cascades":
        return DEFAULT_SUN
    return args.light or DEFAULT_LIGHT


def _map_size_of(args: argparse.Namespace) -> int | tuple[int, int]:
    """``--map-size``, or the method's default."""
    if args.map_size is not None:
        return cast(int | tuple[int, int], args.map_size)
    defaults = {"cascades": DEFAULT_CASCADE_MAP_SIZE, "atlas": DEFAULT_ATLAS_SIZE}
    return defaults.get(args.method, DEFAULT_MAP_SIZE)


def resolve_options(args: argparse.Namespace) -> Options:
    """The :class:`Options` of ``parser.parse_args``'s result, defaults filled in.

    Checks, in this order, the combinations (:func:`check_combinations`), then
    ``--output`` and ``--shadow-map-output`` (:func:`png_path`), which must differ.

    Raises:
        OptionError: the first problem found.
    """
    directional = args.directional is not None
    pcf = 0 if args.pcf is None else args.pcf
    bias = (
        (DEFAULT_DEPTH_BIAS[0] + 2.0 * pcf, DEFAULT_DEPTH_BIAS[1])
        if args.depth_bias is None
        else (float(args.depth_bias[0]), float(args.depth_bias[1]))
    )
    if args.method == "pcss" and args.depth_bias is None:
        bias = DEFAULT_PCSS_BIAS
    area_w, area_h = args.area_light or DEFAULT_AREA_LIGHT
    check_combinations(args)
    output = png_path("--output", args.output or DEFAULT_OUTPUT, create=args.output is None)
    map_output = (
        None
        if args.shadow_map_output is None
        else png_path("--shadow-map-output", args.shadow_map_output, create=False)
    )
    if map_output == output:
        raise OptionError(
            f"--shadow-map-output {args.shadow_map_output}: the same file as --output "
            f"{args.output or DEFAULT_OUTPUT}; the map would overwrite the picture, give "
            "another name"
        )
    cascade_output = (
        None
        if args.cascade_colors is None
        else png_path("--cascade-colors", args.cascade_colors, create=False)
    )
    if cascade_output is not None and cascade_output == output:
        raise OptionError(
            f"--cascade-colors {args.cascade_colors}: the same file as --output "
            f"{args.output or DEFAULT_OUTPUT}; give another name"
        )
    width, height = args.size
    return Options(
        method=cast(Method, args.method),
        webgpu=args.api == "webgpu",
        mesh=args.mesh,
        light=np.asarray(_light_of(args), dtype=np.float64),
        directional=directional or args.method == "cascades",
        map_size=_map_size_of(args),
        image_size=(width, height),
        pcf=pcf,
        bias=bias,
        area_size=(area_w, area_h),
        samples=DEFAULT_SAMPLES if args.samples is None else args.samples,
        seed=DEFAULT_SEED if args.seed is None else args.seed,
        output=output,
        map_output=map_output,
        cascade_output=cascade_output,
        default_output=args.output is None,
        lights=DEFAULT_ATLAS_LIGHTS if args.lights is None else args.lights,
        light_size=_light_size_of(args, directional),
    )


def _light_size_of(args: argparse.Namespace, directional: bool) -> float:
    """``--light-size`` or its default (none for cascades; 0 for the methods that do not
    read it, so ``--method omni`` stays the hard cube-map shadow), a sun's degrees in
    radians."""
    if args.method not in LIGHT_SIZE_METHODS:
        return 0.0
    if args.method == "cascades":
        return 0.0 if args.light_size is None else math.radians(args.light_size)
    if directional:
        degrees = DEFAULT_SUN_DEGREES if args.light_size is None else args.light_size
        return math.radians(degrees)
    return DEFAULT_LIGHT_RADIUS if args.light_size is None else float(args.light_size)
