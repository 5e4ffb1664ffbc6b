"""``--method atlas``: many point, spot and directional lights sharing one shadow atlas.

Not the article's wall and floor: a 24 x 24 ground (the plane ``y = 0``, two triangles,
receiving only), a ring of eight boxes and towers and the ``--mesh`` blocker at the
centre, lit by ``--lights N`` coloured lights laid out on a golden-angle spiral: every
third one a point light (a cube map of six face tiles), every third a spot aimed at a
caster, every third a sun. :func:`shadowmath.render.render_atlas` allocates the atlas
(``--map-size``, a power of two) with :func:`shadowmath.allocate_atlas`, each light's
tile size from its screen coverage (:func:`coverage`, Godot's rule), and fits every tile
with :func:`shadowmath.fit_atlas`.
"""

from __future__ import annotations

import colorsys
import math
from collections.abc import Callable
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import NDArray

import shadowmath as sm

from ._build import ground_and_boxes, tilted_blocker
from ._options import OptionError, Options
from ._run import (
    AMBIENT,
    BACKGROUND,
    UnavailableError,
    check_limits,
    depth_picture,
    open_device,
    output_path,
    print_matrix,
    save_png,
)

if TYPE_CHECKING:
    from shadowmath.render import AtlasFrame, Body

#: The ground's side (it spans ``x, z`` in ``[-12, 12]``).
GROUND_SIZE = 24.0
#: ``(x, z, width, depth, height, turn in degrees)`` of the boxes and towers.
BLOCKS = (
    (6.0, 0.0, 1.2, 1.2, 2.5, 15.0),
    (4.2, 4.2, 1.6, 0.8, 1.2, -20.0),
    (0.0, 6.0, 0.8, 0.8, 3.5, 30.0),
    (-4.2, 4.2, 2.0, 1.0, 1.0, 5.0),
    (-6.0, 0.0, 1.0, 1.0, 2.0, 45.0),
    (-4.2, -4.2, 1.4, 1.4, 1.6, -10.0),
    (0.0, -6.0, 2.2, 0.9, 1.4, 25.0),
    (4.2, -4.2, 0.7, 0.7, 4.0, 0.0),
)
BLOCKER_AT = (0.0, 1.6, 0.0)
EYE, TARGET = (0.0, 16.0, 19.0), (0.0, 0.0, 0.0)
NEAR, FAR, FOV_Y = 0.5, 80.0, 45.0
#: The golden angle: consecutive lights' azimuths spread evenly whatever ``N``.
GOLDEN = math.pi * (3.0 - math.sqrt(5.0))


def atlas_bodies(options: Options) -> tuple[list[Body], list[bool]]:
    """The ground, the blocks and the ``--mesh`` blocker; which of them cast (not the ground)."""
    bodies = ground_and_boxes(GROUND_SIZE, (0.78, 0.78, 0.76), BLOCKS, (0.8, 0.8, 0.8))
    bodies.append(tilted_blocker(options.mesh, BLOCKER_AT, 1.4, (0.85, 0.85, 0.85)))
    return bodies, [False] + [True] * (len(bodies) - 1)


def atlas_lights(count: int) -> tuple[list[Any], NDArray[np.float64]]:
    """``count`` lights and their RGB colours: light ``i`` at azimuth ``i`` golden angles,
    a point light (``i % 3 == 0``), a spot aimed at block ``i % 8`` (``1``) or a sun (``2``);
    hues spread the same way, each light ``2.4 / count`` bright (one more in three)."""
    lights: list[Any] = []
    colors = []
    for i in range(count):
        azimuth = i * GOLDEN
        around = np.array([math.cos(azimuth), 0.0, math.sin(azimuth)])
        kind = i % 3
        if kind == 0:
            radius = 3.0 + 6.0 * ((i * 0.618034) % 1.0)
            lights.append(sm.PointLight(radius * around + [0.0, 3.0 + (i % 4) * 0.8, 0.0]))
        elif kind == 1:
            x, z, _, _, h, _ = BLOCKS[i % len(BLOCKS)]
            target = np.array([x, 0.4 * h, z])
            # steep (about 75 degrees down): every caster in front of the light, which
            # fit_shadow's spot fit needs even for casters outside the cone
            position = target + 2.5 * around + [0.0, 9.5 + (i % 3) * 0.5, 0.0]
            lights.append(sm.SpotLight(position, target - position, np.array(0.45)))
        else:
            elevation = math.radians(35.0 + 30.0 * ((i * 0.381966) % 1.0))
            sun = math.cos(elevation) * around + [0.0, math.sin(elevation), 0.0]
            lights.append(sm.DirectionalLight(sun))
        colors.append(colorsys.hsv_to_rgb((i * 0.618034) % 1.0, 0.55, 1.0))
    return lights, np.asarray(colors) * (2.4 / count)


#: The range of the point and spot lights (world units) whose projection on the screen is
#: their coverage (:func:`coverage`).
LIGHT_RANGE = 4.0


def coverage(lights: list[Any]) -> NDArray[np.float64]:
    """Each light's screen coverage, Godot's rule (``RendererSceneCull``): the diameter of a
    positional light's range sphere (:data:`LIGHT_RANGE`) seen from the camera's eye, over
    the height of the view at that distance, ``r / (d tan(fov_y / 2))``, at most 1; a sun
    covers the whole screen (1)."""
    eye = np.asarray(EYE)
    half = math.tan(math.radians(FOV_Y) / 2)
    out = np.ones(len(lights))
    for i, light in enumerate(lights):
        if not isinstance(light, sm.DirectionalLight):
            distance = float(np.linalg.norm(np.asarray(light.position) - eye))
            out[i] = min(1.0, LIGHT_RANGE / (distance * half))
    return out


def draw_atlas(options: Options) -> Callable[[], None]:
    """Draw the scene through one atlas, write the picture (and the atlas), return the
    printout.

    Raises:
        OptionError: a size beyond the driver's limits, an atlas too small for the lights'
            borders, a file not written.
        UnavailableError: no OpenGL context, or OpenGL failed to draw.
    """
    import moderngl

    from shadowmath.render import look_at, perspective, render_atlas

    bodies, casters = atlas_bodies(options)
    lights, colors = atlas_lights(options.lights)
    device = open_device(options)
    check_limits(options, device)
    width, height = options.image_size
    try:
        frame = render_atlas(
            bodies, lights, look_at(EYE, TARGET), perspective(FOV_Y, width / height, NEAR, FAR),
            casters=casters, colors=colors, coverage=coverage(lights),
            atlas_size=options.map_texels[0],
            pcf_radius=options.pcf, depth_bias=options.bias, image_size=options.image_size,
            ambient=AMBIENT, background=BACKGROUND, ctx=device.ctx,
        )  # fmt: skip
    except ValueError as err:
        raise _refusal(options, err) from None
    except moderngl.Error as err:
        raise UnavailableError(f"OpenGL failed to render the atlas: {err}") from None
    _write(options, frame)
    return lambda: print_atlas(frame, lights)


def _refusal(options: Options, err: ValueError) -> OptionError:
    """The renderer's ``ValueError`` told as the option behind the argument it names."""
    text = str(err)
    size = options.map_texels[0]
    if text.startswith(("atlas_size", "border_texels", "min_tile", "pcf_radius")):
        option = f"--map-size {size} with --pcf {options.pcf}"
    elif text.startswith("lights"):
        option = f"--lights {options.lights}"
    else:
        option = "--method atlas"
    return OptionError(f"{option}: the renderer refused this scene ({text})")


def _write(options: Options, frame: AtlasFrame) -> None:
    output = output_path(options)
    save_png("--output", output, frame.color)
    print(f"wrote {output}: {summary(options, frame)}")
    if options.map_output is not None:
        save_png("--shadow-map-output", options.map_output, atlas_picture(frame))
        width, height = frame.fit.texture_size
        print(
            f"wrote {options.map_output}: the {width}x{height} atlas, t upward, each tile's "
            "depths from black (near) to light grey (far), white where nothing was drawn, "
            "each tile outlined in orange"
        )


def summary(options: Options, frame: AtlasFrame) -> str:
    """What the picture shows: its size, the scene, the lights, the atlas."""
    width, height = options.image_size
    atlas, texels = frame.atlas, frame.fit.texture_size
    kinds = [sum(1 for i in range(options.lights) if i % 3 == k) for k in range(3)]
    sizes = sorted({int(s) for s in atlas.light_size if s > 0}, reverse=True)
    return (
        f"a {width}x{height} PNG, a 24x24 ground with eight blocks and a {options.mesh} under "
        f"{options.lights} lights ({kinds[0]} point lights with cube maps, {kinds[1]} spots, "
        f"{kinds[2]} suns), their shadow maps in one {texels[0]}x{texels[1]} "
        f"atlas ({len(atlas.tile_light)} tiles of {', '.join(map(str, sizes))} texels, "
        f"{100 * atlas.used:.1f}% used; PCF radius {options.pcf}, depth bias "
        f"{options.bias[0]:g} {options.bias[1]:g}) drawn with OpenGL"
    )


def atlas_picture(frame: AtlasFrame) -> NDArray[np.float64]:
    """The atlas as an RGB picture, ``t`` upward: each tile's depths stretched on their own
    (:func:`depth_picture`), its outline one texel wide; at most 2048 pixels square (the
    nearest depth of each block of texels: casters stay visible)."""
    depth = frame.shadow_map
    picture = np.ones((*depth.shape, 3))
    for x, y, n in frame.atlas.tile_rect:
        tile = depth_picture(depth[y : y + n, x : x + n])
        picture[y : y + n, x : x + n] = tile[..., None]
        edge = (0.9, 0.35, 0.2)
        picture[y, x : x + n] = picture[y + n - 1, x : x + n] = edge
        picture[y : y + n, x] = picture[y : y + n, x + n - 1] = edge
    step = max(1, depth.shape[0] // 2048)
    if step > 1:
        h = depth.shape[0] // step
        picture = picture.reshape(h, step, h, step, 3).min(axis=(1, 3))
    return np.asarray(picture[::-1])


def print_atlas(frame: AtlasFrame, lights: list[Any]) -> None:
    """Each light's tiles, and the matrices of the first light of each kind."""
    atlas = frame.atlas
    print("light  kind         tile size  tiles (x, y) in the atlas")
    for i, light in enumerate(lights):
        tiles = [int(t) for t in atlas.light_tiles[i] if t >= 0]
        places = " ".join(f"({atlas.tile_rect[t][0]}, {atlas.tile_rect[t][1]})" for t in tiles)
        print(f"{i:5d}  {type(light).__name__:<16s} {int(atlas.light_size[i]):5d}  {places}")
    shown: set[type] = set()
    for i, light in enumerate(lights):
        if type(light) in shown or atlas.light_tiles[i, 0] < 0:
            continue
        shown.add(type(light))
        t = int(atlas.light_tiles[i, 0])
        name = type(light).__name__
        print_matrix(f"world_to_clip[{t}] (light {i}, a {name}, its first tile)",
                     np.asarray(frame.fit.world_to_clip[t]))  # fmt: skip
        print_matrix(f"world_to_texture[{t}] ((s q, t q, r q, q) in the atlas)",
                     np.asarray(frame.fit.world_to_texture[t]))  # fmt: skip
