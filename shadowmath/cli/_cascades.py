"""``--method cascades``: a sun over a large scene, seen from near the ground to the horizon.

Not the article's wall and floor: a 200 x 200 ground (the plane ``y = 0``, two
triangles), towers and boxes spread over it and the ``--mesh`` blocker, three
times the torus's size, in front of the camera, which stands 5 units above the
ground and looks along ``-z`` toward the horizon. The sun (``--directional``, or
:data:`~shadowmath.cli._options.DEFAULT_SUN`) is drawn by
:func:`shadowmath.render.render_cascades` with four cascades fitted to the camera
by :func:`shadowmath.fit_cascades`.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import NDArray

from ._build import check_direction_sides, ground_and_boxes, tilted_blocker
from ._options import Options
from ._run import (
    AMBIENT,
    BACKGROUND,
    UnavailableError,
    check_limits,
    open_device,
    output_path,
    print_matrix,
    save_png,
)

if TYPE_CHECKING:
    from shadowmath.render import Body, CascadeFrame

#: The ground's side (it spans ``x, z`` in ``[-100, 100]``).
GROUND_SIZE = 200.0
#: ``(x, z, width, depth, height, turn in degrees)`` of the towers and boxes.
TOWERS = (
    (14.0, 30.0, 1.5, 1.5, 7.0, 0.0),
    (24.0, 8.0, 3.0, 3.0, 16.0, 10.0),
    (-8.0, 12.0, 2.0, 2.0, 5.0, 20.0),
    (12.0, 0.0, 4.0, 2.0, 4.0, -15.0),
    (-14.0, -5.0, 5.0, 5.0, 14.0, 10.0),
    (16.0, -20.0, 4.0, 6.0, 10.0, 30.0),
    (-4.0, -40.0, 8.0, 4.0, 6.0, -20.0),
    (-35.0, -55.0, 6.0, 6.0, 22.0, 5.0),
    (30.0, -70.0, 10.0, 5.0, 12.0, 15.0),
    (0.0, -90.0, 12.0, 8.0, 18.0, -10.0),
)
BLOCKER_AT = (5.0, 2.6, 14.0)
EYE, TARGET = (0.0, 5.0, 40.0), (0.0, 0.0, -60.0)
NEAR, FAR, FOV_Y = 0.5, 250.0, 50.0


def check_sun(direction: NDArray[np.float64]) -> None:
    """The sun must shine onto the ground's top, with a length the library can normalize.

    Raises:
        OptionError: ``--directional`` not finite, with ``y <= 0``, or of a length whose
            square leaves floating point's range.
    """
    check_direction_sides(direction, ((1, "y", "on or below the ground (the plane y = 0)"),))


def cascade_bodies(options: Options) -> list[Body]:
    """The ground, the towers and the ``--mesh`` blocker (needs :mod:`shadowmath.render`)."""
    bodies = ground_and_boxes(GROUND_SIZE, (0.55, 0.62, 0.5), TOWERS, (0.82, 0.78, 0.7))
    bodies.append(tilted_blocker(options.mesh, BLOCKER_AT, 2.0, (0.85, 0.33, 0.18)))
    return bodies


def draw_cascades(options: Options) -> Callable[[], None]:
    """Check the sun, draw the picture (and the cascade-coloured one), write the files.

    Returns:
        the printout of the matrices, to run after the notes.

    Raises:
        OptionError: a bad sun, a size beyond the driver's limits, a file not written.
        UnavailableError: no OpenGL context, or OpenGL failed to draw.
    """
    import moderngl

    from shadowmath.render import Light, look_at, perspective, render_cascades

    check_sun(options.light)
    bodies = cascade_bodies(options)
    device = open_device(options)
    check_limits(options, device)
    width, height = options.image_size
    view = look_at(EYE, TARGET)
    projection = perspective(FOV_Y, width / height, NEAR, FAR)
    try:
        frame = render_cascades(
            bodies, Light(direction=options.light), view, projection,
            image_size=options.image_size, map_size=options.map_size, pcf_radius=options.pcf,
            depth_bias=options.bias, cascade_colors=options.cascade_output is not None,
            ambient=AMBIENT, background=BACKGROUND, light_size=options.light_size,
            ctx=device.ctx,
        )  # fmt: skip
    except moderngl.Error as err:
        raise UnavailableError(f"OpenGL failed to render the cascades: {err}") from None
    _write(options, frame)
    return lambda: print_cascades(frame)


def _write(options: Options, frame: CascadeFrame) -> None:
    """Save the picture and the cascade-coloured one, a line for each file."""
    output = output_path(options)
    save_png("--output", output, frame.color)
    print(f"wrote {output}: {summary(options)}")
    if options.cascade_output is not None and frame.cascade_color is not None:
        save_png("--cascade-colors", options.cascade_output, frame.cascade_color)
        print(
            f"wrote {options.cascade_output}: the same picture with its cascades coloured, "
            "red, green, blue, yellow from near to far"
        )


def summary(options: Options) -> str:
    """What the picture shows: its size, the scene, the sun, the maps."""
    width, height = options.image_size
    map_w, map_h = options.map_texels
    sun = tuple(float(c) for c in options.light)
    soft = ""
    if options.light_size > 0:
        degrees = np.degrees(options.light_size)
        soft = f", percentage-closer soft shadows of angular radius {degrees:g} degrees"
    return (
        f"a {width}x{height} PNG, a 200x200 ground with towers and a {options.mesh} under a sun "
        f"toward {sun}, seen from near the ground toward the horizon, cascaded shadow maps "
        f"(4 cascades of {map_w}x{map_h}, PCF radius {options.pcf}, depth bias "
        f"{options.bias[0]:g} {options.bias[1]:g}{soft}) drawn with OpenGL"
    )


def print_cascades(frame: CascadeFrame) -> None:
    """The splits, the bands and each cascade's matrices."""
    c = frame.cascades
    print_matrix("splits (view depths bounding the cascades)", np.asarray(c.splits))
    print_matrix("band_end (cascade i blends into i + 1 up to here)", np.asarray(c.band_end))
    clip: Any = np.asarray(c.world_to_clip)
    texture: Any = np.asarray(c.world_to_texture)
    for i in range(len(clip)):
        print_matrix(f"world_to_clip[{i}] (cascade {i}'s depth map)", clip[i])
        print_matrix(f"world_to_texture[{i}] ((s, t, r, 1) in cascade {i})", texture[i])
