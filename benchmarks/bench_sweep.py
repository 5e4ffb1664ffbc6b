"""Cascades over a sweep of camera poses (issue 27): shadowmath against the engines in every pose.

``python benchmarks/bench_sweep.py [--tiny]`` runs it alone; ``make bench`` runs it as the section
``sweep`` (``--only sweep``).

**The measure** is :mod:`bench_cascades`'s: for every pixel, the ray is cast analytically onto
the receivers, the cascade that serves the hit is picked by view depth, and ``ratio = texel
area / pixel footprint area`` on the surface (``≤ 1``: a texel no larger than the pixel's
footprint, the aliasing limit). Every scheme gets the same scene, shadow distance, 4 cascades
and budget (four 1024² maps; three.js a 2048² atlas of 2 × 2 tiles; Godot's 2048² directional
atlas split in four) and PCF radius 1.

**The poses.** Two scenes of different extents (:data:`EXTENTS`: a 2 km field and a
400 × 600 m town of 60 buildings); in each, every camera height of :data:`HEIGHTS` (1.7, 10,
30, 100 m), pitch of :data:`PITCHES` (-3°: the horizon; -30°; -75°: steeply down) and heading
of :data:`HEADINGS` (0°: facing the sun, 90°, 180°: the sun behind), with the sun's elevation
from :data:`ELEVATIONS` (10°, 40°, 70°) chosen by a Latin square over pitch and heading
(shifted per scene), so that every pitch meets every elevation at every heading in each scene:
72 poses. A pose without a sunlit receiver pixel in the shadow distance is left out.

**The comparisons** (:data:`COMPARISONS`): ``fit_cascades``'s default against three.js's
``SunLightShadow`` and bevy; ``stable=True`` against three.js (stable itself) and the bounding
spheres of Godot and Unreal; ``warp="lispsm"`` and ``orientation="fitted"`` (each map turned
to its body's least-area rectangle) against the default. ``gain`` = their statistic /
shadowmath's (``> 1``: shadowmath finer), at the median and the 90th percentile (p90).
A pixel in a blend band counts the cascade its shader picks, which puts three.js's band
(before its split) in the finer cascade and shadowmath's (after it) in the coarser: the row
``stable / three.js, blended`` gives both schemes' band pixels the texel area the blend reads
(:func:`bench_cascades.blended_ratios`), the same rule whichever side the band lies.

The engines (three.js and bevy: :mod:`bench_cascades`), written here from their sources with
their default settings, the shadow distance the scene's:

* Godot 4, ``servers/rendering/renderer_scene_cull.cpp``
  (``RendererSceneCull::_light_instance_setup_directional_shadow``), 4 splits: the split
  depths ``near + split_offset * (max_distance - near)`` with the default offsets 0.1, 0.2,
  0.5 (``directional_shadow_split_1..3``), blend splits off; per split, the eight corners of
  the camera frustum between its depths, the sphere about their mean with the largest
  distance as radius, ``radius *= texture_size / (texture_size - 2)`` (a texel each side);
  ``x_min``, ``x_max``, ``y_min``, ``y_max`` each ``Math::snapped`` to
  ``unit = 4 radius / texture_size`` (the stable depth-range mode), the map covering
  ``[x_min, x_max] × [y_min, y_max]`` with ``texture_size`` = 1024 texels.
* Unreal Engine 4, ``Engine/Source/Runtime/Engine/Private/Components/
  DirectionalLightComponent.cpp``: ``FDirectionalLightSceneProxy::GetSplitDistance`` (``near +
  ComputeAccumulatedScale(CascadeDistributionExponent = 3, i, 4) * (distance - near)``),
  ``GetShadowSplitBounds`` (every cascade but the last extended by
  ``CascadeTransitionFraction`` = 0.1 of its length) and ``GetShadowSplitBoundsDepthRange``
  (the sphere's centre on the view axis at ``clamp(far - ((d_n² - d_f²) / (2 L) + L / 2),
  near, far)``, ``d_n``, ``d_f`` the half-diagonals of the slice's near and far faces and
  ``L`` its length; its radius the largest distance to the 8 corners, at least 1 cm); the
  map of half-width ``radius`` over ``1024 - 2 SHADOW_BORDER`` (= 1016) texels (the border of
  4 texels cut out of the tile, ``ShadowSetup.cpp``), the centre snapped to whole texels.

Both are drawn in the light frame of :func:`bench_cascades.light_axes` (an engine's own frame
turns the square about the light direction: the same texel size, another snapping phase).

**Split schemes** (:data:`VARIANTS`): ``fit_cascades``'s keyword arguments per candidate
default (or a function of the pose's receiver pixels returning them: the measured depth
range), each fitted tight and with ``stable=True`` in every pose; a new option is one line.
For each, the poses where it is finer than every engine at both statistics, its worst margin
(the smallest gain over poses, engines and statistics), the geometric mean of its p90 and the
poses where its p90 is the smallest of the candidates.

**Stability along camera paths** (:mod:`cascade_paths`): stable cascades with ``state=`` along
paths that climb, dive and turn toward the sun: size changes, split changes, ladder crossings
and the fractional texel motion per path.
"""

from __future__ import annotations

import argparse
import math
import os
import sys
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from typing import Any, NamedTuple

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))

from bench_cascades import (
    ASPECT,
    CASCADES,
    F64,
    FAR,
    FOV_Y,
    MAP_SIZE,
    NEAR,
    Fit,
    Hits,
    Scene,
    Stats,
    bevy_fit,
    blended_ratios,
    camera_near_far,
    cast,
    light_axes,
    perspective,
    ratios,
    shadowmath_fit,
    slice_corners,
    stats,
    street_boxes,
    sun_direction,
    threejs_fit,
)
from cascade_paths import path_table
from speed._timing import Config, Section, table

import shadowmath as sm

NAME = "sweep"
TITLE = "Cascades over 72 camera poses: shadowmath against three.js, bevy, Godot, Unreal (issue 27)"

IMAGE = (320, 180)
TINY_IMAGE = (32, 18)
HEIGHTS = (1.7, 10.0, 30.0, 100.0)
PITCHES = (-3.0, -30.0, -75.0)
HEADINGS = (0.0, 90.0, 180.0)  # from the sun's azimuth: 0 faces the sun
ELEVATIONS = (10.0, 40.0, 70.0)


@dataclass(frozen=True)
class Extent:
    """A scene: its box, its receivers besides the ground, its shadow distance, the sun's azimuth
    and where the camera stands (``x``, ``z``)."""

    name: str
    description: str
    bounds: F64
    boxes: F64
    distance: float
    sun_azimuth: float
    eye_xz: tuple[float, float]


EXTENTS = (
    Extent(
        "field",
        "a 2 km ground, casters up to 8 m, shadow distance 300 m",
        np.array([[-1000.0, 0.0, -1000.0], [1000.0, 8.0, 1000.0]]),
        np.zeros((0, 2, 3)),
        300.0,
        60.0,
        (0.0, 0.0),
    ),
    Extent(
        "town",
        "a 400 × 600 m town, a street between 60 buildings (6-18 m), shadow distance 200 m",
        np.array([[-200.0, 0.0, -400.0], [200.0, 18.0, 200.0]]),
        street_boxes(),
        200.0,
        -50.0,
        (0.0, 5.0),
    ),
)


class Pose(NamedTuple):
    extent: Extent
    height: float
    pitch: float
    heading: float
    elevation: float

    @property
    def key(self) -> str:
        return (
            f"{self.extent.name}/h{self.height:g}/p{self.pitch:g}/y{self.heading:g}"
            f"/s{self.elevation:g}"
        )

    @property
    def scene(self) -> Scene:
        e = self.extent
        x, z = e.eye_xz
        return Scene(self.key, self.key, np.array([x, self.height, z]),
                     e.sun_azimuth + self.heading, self.pitch,
                     sun_direction(self.elevation, e.sun_azimuth), e.distance, e.bounds,
                     e.boxes)  # fmt: skip


def poses() -> list[Pose]:
    """Every extent × height × pitch × heading, the sun's elevation from a Latin square."""
    return [
        Pose(extent, h, p, y, ELEVATIONS[(i + j + k) % len(ELEVATIONS)])
        for k, extent in enumerate(EXTENTS)
        for h in HEIGHTS
        for i, p in enumerate(PITCHES)
        for j, y in enumerate(HEADINGS)
    ]


# ---------------------------------------------------------------------------
# Godot's and Unreal's bounding spheres
# ---------------------------------------------------------------------------


def to_world(view: F64, points: F64) -> F64:
    inverse = np.linalg.inv(view)
    return np.asarray(points @ inverse[:3, :3].T + inverse[:3, 3], dtype=np.float64)


def square_fit(scene: Scene, splits: F64, lo: F64, hi: F64, texels: float) -> Fit:
    """Maps over light ``[lo, hi]`` (``(n, 2)`` in ``x``, ``y``) of ``texels`` texels a side,
    their depth over the scene box (the engines' depth ranges differ; what they serve does not)."""
    axes = light_axes(scene.sun)
    box = np.array([[scene.bounds[i >> k & 1, k] for k in range(3)] for i in range(8)])
    z = box @ axes[2]
    span = hi - lo
    to_unit = np.zeros((len(lo), 3, 4))
    for k in range(2):
        to_unit[:, k, :3] = axes[k] / span[:, k, None]
        to_unit[:, k, 3] = -lo[:, k] / span[:, k]
    to_unit[:, 2, :3] = axes[2] / (z.max() - z.min())
    to_unit[:, 2, 3] = -z.min() / (z.max() - z.min())
    return Fit(splits, span / texels, to_unit)


GODOT_SPLIT_OFFSETS = (0.1, 0.2, 0.5)


def godot_fit(scene: Scene, projection: F64, texture_size: int = MAP_SIZE) -> Fit:
    """Godot 4's stable directional split (see the module's docstring)."""
    near, _ = camera_near_far(projection)
    far = scene.distance
    d = np.concatenate([[near], near + np.array(GODOT_SPLIT_OFFSETS) * (far - near), [far]])
    corners = to_world(scene.view, slice_corners(projection, d[:-1], d[1:]))  # (n, 8, 3)
    center = corners.mean(axis=1)
    radius = np.linalg.norm(corners - center[:, None], axis=-1).max(axis=1)
    radius = radius * texture_size / (texture_size - 2.0)
    c = center @ light_axes(scene.sun)[:2].T  # (n, 2)
    unit = (radius * 4.0 / texture_size)[:, None]
    lo = np.floor((c - radius[:, None]) / unit + 0.5) * unit  # Math::snapped
    hi = np.floor((c + radius[:, None]) / unit + 0.5) * unit
    return square_fit(scene, d, lo, hi, texture_size)


UNREAL_EXPONENT = 3.0  # CascadeDistributionExponent
UNREAL_TRANSITION = 0.1  # CascadeTransitionFraction
UNREAL_BORDER = 4  # SHADOW_BORDER


def unreal_splits(near: float, far: float, count: int = CASCADES) -> F64:
    """``GetSplitDistance``: ``near + ComputeAccumulatedScale(exponent, i, count) (far - near)``."""
    scale = UNREAL_EXPONENT ** np.arange(count)
    accumulated = np.concatenate([[0.0], np.cumsum(scale)]) / scale.sum()
    return np.asarray(near + accumulated * (far - near), dtype=np.float64)


def unreal_fit(scene: Scene, projection: F64, map_size: int = MAP_SIZE) -> Fit:
    """Unreal Engine 4's cascade spheres (see the module's docstring)."""
    near, _ = camera_near_far(projection)
    splits = unreal_splits(near, scene.distance)
    a, b = splits[:-1], splits[1:].copy()
    b[:-1] += UNREAL_TRANSITION * (b[:-1] - a[:-1])  # the fade region, all but the last
    diagonal_sq = (1 / projection[0, 0]) ** 2 + (1 / projection[1, 1]) ** 2
    length = b - a
    offset = (diagonal_sq * a**2 - diagonal_sq * b**2) / (2 * length) + length / 2
    centre_z = np.clip(b - offset, a, b)
    corners = slice_corners(projection, a, b)
    centre = np.stack([np.zeros_like(a), np.zeros_like(a), -centre_z], axis=1)
    radius = np.maximum(np.linalg.norm(corners - centre[:, None], axis=-1).max(axis=1), 0.01)
    resolution = map_size - 2 * UNREAL_BORDER
    texel = (2 * radius / resolution)[:, None]
    c = to_world(scene.view, centre) @ light_axes(scene.sun)[:2].T
    c = np.floor(c / texel + 0.5) * texel  # whole texels
    return square_fit(scene, splits, c - radius[:, None], c + radius[:, None], resolution)


# ---------------------------------------------------------------------------
# The sweep
# ---------------------------------------------------------------------------

Options = dict[str, Any] | Callable[[Hits], dict[str, Any]]


def measured_range(**split_options: Any) -> Callable[[Hits], dict[str, Any]]:
    """Practical splits over the view depths of the measured receiver pixels (what a min/max
    reduction of the depth buffer gives, sample distribution shadow maps; here of this frame's
    sunlit receivers in range, not last frame's: a bound on what the measurement can gain);
    ``split_options``: :func:`shadowmath.cascade_splits`'s ``scheme`` and ``lam``."""

    def options(hits: Hits) -> dict[str, Any]:
        near, far = float(hits.depth.min()), float(hits.depth.max())
        far = max(far, near * 1.001)
        return {"splits": np.asarray(sm.cascade_splits(near, far, CASCADES, **split_options))}

    return options


def visible_with_state(**split_options: Any) -> Callable[[Hits], dict[str, Any]]:
    """``depth_range="visible"`` (the camera frustum meets the scene box) from a first frame's
    :class:`shadowmath.CascadeState` (the ladder's range; with ``stable=True`` the squares of
    each slice's visible part)."""

    def options(hits: Hits) -> dict[str, Any]:
        del hits
        return {"depth_range": "visible", "state": sm.CascadeState.initial(), **split_options}

    return options


def measured_with_state(**split_options: Any) -> Callable[[Hits], dict[str, Any]]:
    """``fit_cascades``' own measured range: ``depth_range=(min, max)`` of the receiver
    pixels' view depths (as :func:`measured_range`) with a first frame's state."""

    def options(hits: Hits) -> dict[str, Any]:
        near, far = float(hits.depth.min()), float(hits.depth.max())
        span = np.array([near, max(far, near * 1.001)])
        return {"depth_range": span, "state": sm.CascadeState.initial(), **split_options}

    return options


VARIANTS: dict[str, Options] = {
    "λ=0.9": {"lam": 0.9},
    "default: auto, camera's range (λ=0.75; stable: λ=0.5, bands inside)": {},
    "λ=0.75": {"lam": 0.75},
    "λ=0.6": {"lam": 0.6},
    "λ=0.5": {"lam": 0.5},
    "log": {"scheme": "log"},
    "uniform": {"scheme": "uniform"},
    "λ=0.9, measured range": measured_range(lam=0.9),
    "λ=0.75, measured range": measured_range(lam=0.75),
    "λ=0.5, measured range": measured_range(lam=0.5),
    "log, measured range": measured_range(scheme="log"),
    "λ=0.75, visible range": {"depth_range": "visible", "lam": 0.75},
    "auto, visible range (log)": {"depth_range": "visible"},
    "λ=0.75, visible range, state": visible_with_state(lam=0.75),
    "auto, visible range, state (log)": visible_with_state(),
    "auto, measured range, state (log)": measured_with_state(),
}
"""Candidate defaults: ``fit_cascades``'s keyword arguments, or a function of the pose's
receiver pixels returning them (a new option is one line here). ``scheme="auto"`` (the
default) is λ = 0.75 over the camera's range (with ``stable=True`` three.js's λ = 0.5, each
cascade's blend band inside its split) and the log scheme over a visible or measured range:
the rows without ``lam`` or ``scheme`` are its."""
DEFAULT = "default: auto, camera's range (λ=0.75; stable: λ=0.5, bands inside)"
BLENDED = " blended"
"""The suffix of a fit's statistics with every blend band's pixels given the texel area the
blend reads (:func:`bench_cascades.blended_ratios`)."""
LISPSM = "LiSPSM"
FITTED = "fitted orientation"
ENGINES: dict[str, Callable[[Scene, F64], Fit]] = {
    "three.js": threejs_fit,
    "bevy": bevy_fit,
    "Godot": godot_fit,
    "Unreal": unreal_fit,
}
TIGHT_RIVALS = ("three.js", "bevy")
STABLE_RIVALS = ("three.js", "Godot", "Unreal")
STATS = ("median", "p90")
OURS = {"default": DEFAULT, "stable": f"{DEFAULT} stable", "LiSPSM": LISPSM, "fitted": FITTED}
"""shadowmath's fits whose distance to the aliasing limit is reported."""


class Comparison(NamedTuple):
    label: str
    ours: str
    theirs: str


COMPARISONS = (
    Comparison("default / three.js", DEFAULT, "three.js"),
    Comparison("default / bevy", DEFAULT, "bevy"),
    Comparison("stable / three.js", f"{DEFAULT} stable", "three.js"),
    Comparison("stable / three.js, blended", f"{DEFAULT} stable{BLENDED}", f"three.js{BLENDED}"),
    Comparison("stable / Godot", f"{DEFAULT} stable", "Godot"),
    Comparison("stable / Unreal", f"{DEFAULT} stable", "Unreal"),
    Comparison("LiSPSM / no warp", LISPSM, DEFAULT),
    Comparison("fitted / light orientation", FITTED, DEFAULT),
)


def measure_pose(
    pose: Pose, projection: F64, image: tuple[int, int], variants: Mapping[str, Options]
) -> dict[str, Stats] | None:
    """Every scheme's statistics in one pose (``None``: no sunlit receiver pixel in range)."""
    scene = pose.scene
    hits = cast(scene, projection, image)
    if len(hits.depth) == 0:
        return None
    fits = {name: fit(scene, projection) for name, fit in ENGINES.items()}
    for name, variant in variants.items():
        options = variant(hits) if callable(variant) else variant
        for stable in (False, True):
            fits[name + " stable" * stable] = shadowmath_fit(
                scene, projection, stable=stable, splits=None, options=options
            )
    plain = variants[DEFAULT]
    plain = plain(hits) if callable(plain) else plain
    fits[LISPSM] = shadowmath_fit(
        scene, projection, stable=False, splits=None, warp=True, options=plain
    )
    fits[FITTED] = shadowmath_fit(
        scene, projection, stable=False, splits=None, options={**plain, "orientation": "fitted"}
    )
    per = {name: stats(ratios(fit, hits, scene.sun)) for name, fit in fits.items()}
    for name in ("three.js", f"{DEFAULT} stable"):
        per[name + BLENDED] = stats(blended_ratios(fits[name], hits, scene.sun))
    return per


def gain(theirs: Stats, ours: Stats, stat: str) -> float:
    """Their statistic over ours: ``> 1`` where ours is finer."""
    return float(getattr(theirs, stat) / getattr(ours, stat))


def margin(per: dict[str, Stats], ours: str, rivals: tuple[str, ...]) -> float:
    """The smallest gain of ``ours`` over the rivals, at either statistic."""
    return min(gain(per[r], per[ours], s) for r in rivals for s in STATS)


Results = list[tuple[Pose, dict[str, Stats]]]


def summary(results: Results, section: Section) -> list[str]:
    """(a) per comparison: poses finer at both statistics, the worst pose and its margin; and
    the distance to the aliasing limit (p90 over 1)."""
    lines = [
        "| comparison | poses finer at median and p90 | worst pose | its gain, median / p90 |",
        "|---|---|---|---|",
    ]
    for c in COMPARISONS:
        m = [(margin(per, c.ours, (c.theirs,)), pose, per) for pose, per in results]
        worst, pose, per = min(m, key=lambda t: t[0])
        finer = sum(v > 1 for v, _, _ in m)
        g = [gain(per[c.theirs], per[c.ours], s) for s in STATS]
        lines.append(f"| {c.label} | {finer} of {len(m)} | `{pose.key}` | "
                     f"{g[0]:.2f} / {g[1]:.2f} |")  # fmt: skip
        key = c.label.replace(" / ", "_vs_").replace(" ", "_")
        section.figures[f"summary.{key}.finer_poses"] = float(finer)
        section.figures[f"summary.{key}.worst_margin"] = worst
    lines += ["", "| shadowmath | poses at the aliasing limit (p90 ≤ 1) | worst p90 | worst pose |",
              "|---|---|---|---|"]  # fmt: skip
    for label, name in OURS.items():
        p90 = [(per[name].p90, pose) for pose, per in results]
        worst, pose = max(p90, key=lambda t: t[0])
        at_limit = sum(v <= 1 for v, _ in p90)
        lines.append(f"| {label} | {at_limit} of {len(p90)} | {worst:.3g} | `{pose.key}` |")
        section.figures[f"summary.{label}.aliasing_free_poses"] = float(at_limit)
        section.figures[f"summary.{label}.worst_p90"] = worst
    return lines


def candidates(results: Results, variants: Mapping[str, Options], section: Section) -> list[str]:
    """(b) each candidate default, tight against three.js and bevy, stable against three.js,
    Godot and Unreal."""
    lines = [
        "| candidate | fit | poses finer than every engine (both statistics) | worst margin "
        "| worst pose | geometric mean of p90 | poses with the finest p90 |",
        "|---|---|---|---|---|---|---|",
    ]
    for suffix, rivals in (("", TIGHT_RIVALS), (" stable", STABLE_RIVALS)):
        fit = "stable" if suffix else "tight"
        names = [v + suffix for v in variants]
        best = [min(per[n].p90 for n in names) for _, per in results]
        margins = {n: [margin(per, n, rivals) for _, per in results] for n in names}
        for v, name in zip(variants, names, strict=True):
            m = margins[name]
            worst = min(m)
            gmean = math.exp(np.mean([math.log(per[name].p90) for _, per in results]))
            wins = sum(per[name].p90 <= b for (_, per), b in zip(results, best, strict=True))
            row = [v, fit, f"{sum(x > 1 for x in m)} of {len(m)}", f"{worst:.2f}",
                   f"`{results[m.index(worst)][0].key}`", f"{gmean:.3g}", str(wins)]  # fmt: skip
            lines.append("| " + " | ".join(row) + " |")
            key = f"candidates.{v}.{fit}"
            section.figures[f"{key}.finer_poses"] = float(sum(x > 1 for x in m))
            section.figures[f"{key}.worst_margin"] = worst
            section.figures[f"{key}.gmean_p90"] = gmean
            section.figures[f"{key}.wins"] = float(wins)
        oracle = [max(margins[n][k] for n in names) for k in range(len(results))]
        worst = min(oracle)
        where = results[oracle.index(worst)][0].key
        lines.append(f"| the best of these per pose | {fit} | {sum(x > 1 for x in oracle)} of "
                     f"{len(oracle)} | {worst:.2f} | `{where}` | | |")  # fmt: skip
        section.figures[f"candidates.best_per_pose.{fit}.worst_margin"] = worst
    return lines


def cell(g_median: float, g_p90: float) -> str:
    """A heat-map cell: 🟩 finer at both statistics, 🟨 at least 0.8 of the rival's, 🟥 worse."""
    low = min(g_median, g_p90)
    mark = "🟩" if low > 1 else "🟨" if low >= 0.8 else "🟥"
    return f"{mark} {g_median:.2f} / {g_p90:.2f}"


def heat_map(results: Results, section: Section) -> list[str]:
    """(c) every pose × comparison: the gains at the median / p90, and the default's p90."""
    head = " | ".join(c.label for c in COMPARISONS)
    lines = [
        f"| pose | pixels | {head} | default's p90 (≤ 1: aliasing limit) |",
        "|---" * (len(COMPARISONS) + 3) + "|",
    ]
    for pose, per in results:
        cells = []
        for c in COMPARISONS:
            g = [gain(per[c.theirs], per[c.ours], s) for s in STATS]
            cells.append(cell(*g))
            key = c.label.replace(" / ", "_vs_").replace(" ", "_")
            for s, v in zip(STATS, g, strict=True):
                section.figures[f"{pose.key}.{key}.gain_{s}"] = v
        p90 = per[DEFAULT].p90
        for label, name in OURS.items():
            section.figures[f"{pose.key}.{label}.p90"] = per[name].p90
        lines.append(f"| `{pose.key}` | {per[DEFAULT].pixels} | " + " | ".join(cells)
                     + f" | {p90:.3g} |")  # fmt: skip
    return lines


def measure_all(
    image: tuple[int, int], variants: Mapping[str, Options]
) -> tuple[Results, list[str]]:
    """Every pose's statistics, and the keys of the poses left out (no sunlit receiver)."""
    projection = perspective(FOV_Y, ASPECT, NEAR, FAR)
    results: Results = []
    skipped = []
    for pose in poses():
        per = measure_pose(pose, projection, image, variants)
        if per is None:
            skipped.append(pose.key)
        else:
            results.append((pose, per))
    return results, skipped


def sweep(cfg: Config, section: Section, variants: Mapping[str, Options]) -> str:
    image = TINY_IMAGE if cfg.tiny else IMAGE
    projection = perspective(FOV_Y, ASPECT, NEAR, FAR)
    results, skipped = measure_all(image, variants)
    names = [name for name in results[0][1] if not name.endswith(BLENDED)]
    uncovered = {name: sum(per[name].uncovered for _, per in results) for name in names}
    for name, count in uncovered.items():
        section.figures[f"uncovered.{name}"] = float(count)
    left_out = f", {len(skipped)} without a sunlit receiver left out: {', '.join(skipped)}"
    lines = [
        f"Image {image[0]}×{image[1]}, vertical field of view {FOV_Y:g}°, near {NEAR:g}; "
        f"{CASCADES} cascades of {MAP_SIZE}², PCF radius 1. Poses `scene/h<height m>/p<pitch°>/"
        f"y<heading from the sun°>/s<sun elevation°>`: "
        + "; ".join(f"`{e.name}`: {e.description}" for e in EXTENTS)
        + f". {len(results)} poses measured{left_out if skipped else ''}. Gain = the rival's "
        "figure / shadowmath's (> 1: shadowmath finer). Pixels outside the map that serves "
        "them: " + ", ".join(f"{n} {c}" for n, c in uncovered.items()) + ".",
        "",
        "**(a) Per comparison** (shadowmath's default: `scheme=\"auto\"` over the camera's "
        "range, λ = 0.75; stable: λ = 0.5, each band ending at its split):",
        "",
        *summary(results, section),
        "",
        "**(b) Candidate defaults** (tight: against three.js and bevy; stable: against "
        "three.js, Godot and Unreal; worst margin = the smallest gain over poses, rivals and "
        "both statistics):",
        "",
        *candidates(results, variants, section),
        "",
        "**(c) Every pose**: gain at the median / p90 (🟩 finer at both, 🟨 at least 0.8 of the "
        "rival's, 🟥 coarser):",
        "",
        *heat_map(results, section),
        "",
        "**(d) Stable cascades along camera paths** (`cascade_paths.py`; `stable=True` with "
        "`state=` carried from frame to frame; a size may change only in a frame where the "
        "range or a slice's visible half-width crosses a ladder value):",
        "",
        *path_table(EXTENTS, projection, cfg.tiny, section.figures),
    ]
    return "\n".join(lines)


def run(cfg: Config) -> Section:
    section = Section(NAME, TITLE)
    section.text = sweep(cfg, section, VARIANTS)
    return section


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=(__doc__ or "").splitlines()[0])
    parser.add_argument("--tiny", action="store_true", help="tiny image")
    args = parser.parse_args(argv)
    print(table(run(Config(tiny=args.tiny))))
    return 0


if __name__ == "__main__":
    sys.exit(main())
