"""Stable cascades along camera paths (issue 27): how often they change size, and how they move.

Part (d) of the ``sweep`` section (:mod:`bench_sweep`). In each scene of
:data:`bench_sweep.EXTENTS`, three camera paths of :data:`FRAMES` frames (:func:`camera_paths`):
one that *climbs* from 1.7 m to 100 m (geometrically) while pitching from -5° to -45°, one
that *dives* back from 100 m to 1.7 m while levelling from -60° to -3° with the sun behind, and
one 10 m up that *turns toward the sun* (heading 180° to 0°, pitch -15°); every camera moves
:data:`STEP` metres forward per frame, the sun 40° high. Each is fitted with ``stable=True``
and ``state=`` carried from frame to frame, over ``depth_range="visible"`` and over a measured
range (the view depths of last frame's sunlit receiver pixels, a min/max reduction of its depth
buffer, cast at :data:`PATH_IMAGE`).

Per path: the frames in which any cascade's size changed, those in which the splits changed,
the *ladder crossings of the target range* (the frames in which the exact range, visible or
measured, without ``state``, crossed a value of the ladder ``2^(k/4)``: its far end's
``ceil(4 log2 f)`` or its near end's ``floor(4 log2 n)`` changed), those of the range or of a
slice's visible part's half-width (``ceil(4 log2 t)``, ``t`` half the larger side of the
slice's tight box, which a square's ladder value follows): a size can change only in such a
frame (grow at once, shrink only past the margin), so the size changes are at most these
crossings; and the largest fractional
part of a cascade's centre motion in texels between two frames of the same size (0: whole
texels; rounding of the world-anchored grid aside).
"""

from __future__ import annotations

import math
from typing import Any, NamedTuple

import numpy as np
from bench_cascades import CASCADES, F64, MAP_SIZE, PCF_RADIUS, Scene, cast, sun_direction

import shadowmath as sm

FRAMES = 200
TINY_FRAMES = 40
STEP = 0.5  # metres forward per frame
SUN_ELEVATION = 40.0
PATH_IMAGE = (160, 90)
TINY_PATH_IMAGE = (32, 18)


class CameraPath(NamedTuple):
    """Per frame: the camera's height (m), pitch (°) and heading from the sun's azimuth (°)."""

    name: str
    height: F64
    pitch: F64
    heading: F64


def camera_paths(frames: int) -> tuple[CameraPath, ...]:
    """The climb, the dive and the turn toward the sun (see the module's docstring)."""
    t = np.linspace(0.0, 1.0, frames)
    up = 1.7 * (100.0 / 1.7) ** t
    flat = np.ones(frames)
    return (
        CameraPath("climb 1.7→100 m", up, -5.0 - 40.0 * t, 90.0 * flat),
        CameraPath("dive 100→1.7 m", up[::-1], -60.0 + 57.0 * t, 180.0 * flat),
        CameraPath("turn toward the sun", 10.0 * flat, -15.0 * flat, 180.0 - 180.0 * t),
    )


def frame_scene(extent: Any, path: CameraPath, k: int) -> Scene:
    """Frame ``k`` of ``path`` in ``extent`` (a :class:`bench_sweep.Extent`)."""
    yaw = extent.sun_azimuth + float(path.heading[k])
    x, z = extent.eye_xz
    s, y = STEP * k, math.radians(yaw)
    eye = np.array([x + s * math.sin(y), float(path.height[k]), z - s * math.cos(y)])
    sun = sun_direction(SUN_ELEVATION, extent.sun_azimuth)
    return Scene(path.name, path.name, eye, yaw, float(path.pitch[k]), sun, extent.distance,
                 extent.bounds, extent.boxes)  # fmt: skip


class PathCounts(NamedTuple):
    frames: int
    size_changes: int  # frames in which any cascade's size changed
    split_changes: int  # frames in which the splits changed
    crossings: int  # frames in which the target range crossed a ladder value
    all_crossings: int  # ... the range or a slice's visible part's half-width
    fraction: float  # the largest fractional texel motion between frames of the same size


def ladder_indices(near: float, far: float) -> tuple[int, int]:
    """The ladder steps ``2^(k/4)`` just inside ``near`` and just outside ``far``."""
    return math.floor(4 * math.log2(near)), math.ceil(4 * math.log2(far))


def texel_fraction(c: Any, prev: Any) -> float:
    """The largest fractional part of the centre motion in texels of the cascades that kept
    their size (0 where none did)."""
    same = np.asarray(c.frustum.half_width) == np.asarray(prev.frustum.half_width)
    worst = 0.0
    for k, centre in enumerate(("center_x", "center_y")):
        move = (getattr(c.frustum, centre) - getattr(prev.frustum, centre)) / c.texel_size[:, k]
        worst = max(worst, float(np.max(np.abs(move - np.rint(move))[same], initial=0.0)))
    return worst


def follow(
    extent: Any, path: CameraPath, projection: F64, image: tuple[int, int] | None
) -> PathCounts:
    """Fit every frame of ``path`` stable with ``state``: over the visible range (``image``
    None) or over the range measured in the last frame at ``image``."""
    state, prev, target_prev = sm.CascadeState.initial(), None, None
    sizes = splits = crossings = all_crossings = 0
    fraction, measured = 0.0, None
    for k in range(len(path.height)):
        scene = frame_scene(extent, path, k)
        if image is not None:
            depth = cast(frame_scene(extent, path, max(k - 1, 0)), projection, image).depth
            measured = measured if len(depth) == 0 else np.array([depth.min(), depth.max()])
        rng: Any = "visible" if image is None else measured
        fit = _fitter(scene, projection)
        c = fit(stable=True, state=state, depth_range=rng)
        ends = fit(depth_range=rng).splits[[0, -1]]
        need = fit(splits=c.splits).frustum  # the tight box of each slice's visible part
        half = np.maximum(need.half_width * need.margin_x, need.half_height * need.margin_y)
        target = (ladder_indices(float(ends[0]), float(ends[1])),
                  tuple(math.ceil(4 * math.log2(h)) for h in half))  # fmt: skip
        if prev is not None:
            sizes += bool(np.any(c.frustum.half_width != prev.frustum.half_width))
            splits += bool(np.any(c.splits != prev.splits))
            crossings += target[0] != target_prev[0]
            all_crossings += target != target_prev
            fraction = max(fraction, texel_fraction(c, prev))
        state, prev, target_prev = c.state, c, target
    return PathCounts(len(path.height), sizes, splits, crossings, all_crossings, fraction)


def _fitter(scene: Scene, projection: F64) -> Any:
    def fit(**options: Any) -> Any:
        dmax = None if "splits" in options else scene.distance
        return sm.fit_cascades(scene.sun, scene.view, projection, scene.bounds, MAP_SIZE,
                               count=CASCADES, max_distance=dmax, pcf_radius=PCF_RADIUS,
                               **options)  # fmt: skip

    return fit


def path_table(extents: Any, projection: F64, tiny: bool, figures: dict[str, float]) -> list[str]:
    """(d) every extent × path × range: the counts of :class:`PathCounts` as a table."""
    frames = TINY_FRAMES if tiny else FRAMES
    image = TINY_PATH_IMAGE if tiny else PATH_IMAGE
    lines = [
        "| scene | path | range (stable, state) | frames | size changes | split changes "
        "| target range's ladder crossings | ... of the range or a half-width "
        "| largest fractional texel motion |",
        "|---|---|---|---|---|---|---|---|---|",
    ]
    for extent in extents:
        for path in camera_paths(frames):
            for label, img in (("visible", None), ("measured", image)):
                n = follow(extent, path, projection, img)
                lines.append(f"| `{extent.name}` | {path.name} | {label} | {n.frames} | "
                             f"{n.size_changes} | {n.split_changes} | {n.crossings} | "
                             f"{n.all_crossings} | {n.fraction:.1e} |")  # fmt: skip
                key = f"paths.{extent.name}.{path.name.split()[0]}.{label}"
                for field in PathCounts._fields[1:]:
                    figures[f"{key}.{field}"] = float(getattr(n, field))
    return lines
