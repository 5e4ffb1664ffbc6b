"""Cascaded shadow maps (issue 17): resolution against three.js's and bevy's schemes, and speed.

``python benchmarks/bench_cascades.py [--tiny]`` runs it alone; ``make bench`` runs it as the
section ``cascades`` (``--only cascades``).

**Resolution.** Nothing is rendered: for every pixel of the camera's image, the pixel's ray is
cast analytically onto the receivers (the ground, and the boxes of the street), the cascade
that serves the hit point is picked by its view depth (as a shader does: cascade ``i`` serves
``[splits[i], splits[i + 1])``) and the benchmark computes

    ratio = (world area of one shadow-map texel, projected along the light onto the surface)
            / (world area of the pixel's footprint on the surface)

``≤ 1``: a texel is no larger than a pixel there, no visible aliasing. With the image plane at
view ``z = -1`` and the ray ``r`` through the pixel scaled so that its view ``z`` is ``-1``
(the hit is at ``eye + d r``, ``d`` the view depth), a pixel of ``A`` square units on that
plane covers ``A d² / |n·r|`` of a surface with unit normal ``n``; a texel of ``t_x × t_y``
across the light's direction ``l`` covers ``t_x t_y / (n·l)``. Only the pixels whose receiver
faces the sun (``n·l > 0``) and lies within the shadow distance count; every scheme gets the
same scenes, shadow distance, cascade count (4) and map budget (four 1024² maps: three.js's
2048² atlas of 2 × 2 tiles, bevy's and shadowmath's four layers of 1024²), and the same PCF
radius (1) where the scheme reserves a border for it.

The two engines' schemes are implemented here from their sources:

* three.js, ``src/lights/SunLightShadow.js`` (``updateMatrices``): each tile inset by
  ``(ceil(radius) + 1)`` texels; practical splits ``(uniform + log) / 2`` over
  ``[camera near, min(shadow far, camera far)]``; cascade ``i > 0`` starts at the previous
  cascade's fade start (10 % of its depth range before its end); the bounding sphere of the
  slice's eight corners about their mean, its radius divided by ``1 - 1 / resolution`` (half a
  texel of padding), its centre snapped to texels with ``Math.round`` in the frame of
  ``lookAt(0, direction, up = +Y)``; the casters' ceiling raised by the shadow range.
* bevy, ``crates/bevy_light/src/cascade.rs``: the first cascade's far bound fixed (10, bevy's
  default), the others geometric up to the shadow distance; each cascade starts at 0.8 of the
  previous one's far bound (overlap 0.2); a square cascade of side
  ``ceil(max(|body diagonal|, |far-face diagonal|))`` and texel ``side / size``; the centre of
  the slice's light-space bounding box snapped with ``floor``.

shadowmath's cascades are ``sm.fit_cascades`` with its defaults (``scheme="auto"``: over the
camera's range, practical λ = 0.75; overlap 0.1) and the scene's box, tight and
``stable=True``. Every scheme's map is also checked to contain each point it serves (lateral
and depth): a point outside is counted as uncovered.

**Speed.** Four cascades for one camera and one sun with scene bounds, per call, with NumPy
alone (the compiled loops disabled) and as installed, and a batch of 100 cameras per call
(per camera), against a hand-written NumPy version of three.js's scheme (one camera) timed in
the same process. Nothing is asserted about time.
"""

from __future__ import annotations

import argparse
import contextlib
import math
import os
import sys
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from typing import Any, NamedTuple

import numpy as np
from numpy.typing import NDArray

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))

from speed._timing import Config, Row, Section, Timing, measure, numpy_alone, table

import shadowmath as sm

F64 = NDArray[np.float64]

NAME = "cascades"
TITLE = "Cascaded shadow maps: resolution against three.js and bevy, and speed (issue 17)"

CASCADES = 4
MAP_SIZE = 1024  # per cascade: four 1024² maps = one 2048² atlas
PCF_RADIUS = 1
FOV_Y = 60.0  # degrees
ASPECT = 16.0 / 9.0
NEAR, FAR = 0.1, 1000.0
IMAGE = (960, 540)
TINY_IMAGE = (96, 54)
BATCH = 100
FAST_TARGET = 50e-6  # issue 17: four cascades per frame with the fast extra
NUMPY_TARGET = 0.5e-3  # and with NumPy alone


# ---------------------------------------------------------------------------
# Cameras and scenes
# ---------------------------------------------------------------------------


def unit(v: F64) -> F64:
    return np.asarray(v / np.linalg.norm(v, axis=-1, keepdims=True), dtype=np.float64)


def sun_direction(elevation: float, azimuth: float) -> F64:
    """The unit direction toward the sun: ``elevation`` above the ground, ``azimuth`` from -Z."""
    e, a = math.radians(elevation), math.radians(azimuth)
    return np.array([math.cos(e) * math.sin(a), math.sin(e), -math.cos(e) * math.cos(a)])


def look(eye: F64, yaw: float, pitch: float) -> F64:
    """World-to-view matrix of a camera at ``eye`` (yaw from -Z toward +X, pitch up, degrees)."""
    y, p = math.radians(yaw), math.radians(pitch)
    forward = np.array([math.sin(y) * math.cos(p), math.sin(p), -math.cos(y) * math.cos(p)])
    right = unit(np.cross(forward, [0.0, 1.0, 0.0]))
    up = np.cross(right, forward)
    view = np.eye(4)
    view[:3, :3] = np.stack([right, up, -forward])
    view[:3, 3] = -view[:3, :3] @ eye
    return view


def perspective(fov_y: float, aspect: float, near: float, far: float) -> F64:
    """OpenGL's perspective projection (view depth ``-z``, NDC depth in ``[-1, 1]``)."""
    f = 1.0 / math.tan(math.radians(fov_y) / 2)
    return np.array(
        [
            [f / aspect, 0.0, 0.0, 0.0],
            [0.0, f, 0.0, 0.0],
            [0.0, 0.0, (far + near) / (near - far), 2 * far * near / (near - far)],
            [0.0, 0.0, -1.0, 0.0],
        ]
    )


@dataclass(frozen=True)
class Scene:
    """A camera over a ground (``y = 0`` within ``bounds``), boxes standing on it, and a sun."""

    name: str
    description: str
    eye: F64
    yaw: float
    pitch: float
    sun: F64  # (3,) unit, toward the sun
    distance: float  # the shadow distance, the same for every scheme
    bounds: F64  # (2, 3) the scene's box: every caster and receiver inside
    boxes: F64  # (k, 2, 3) receivers besides the ground

    @property
    def view(self) -> F64:
        return look(self.eye, self.yaw, self.pitch)


def street_boxes() -> F64:
    """Two rows of 30 buildings (6 to 18 m tall, 8 m deep) along a 12 m street down -Z."""
    rng = np.random.default_rng(17)
    boxes = []
    for side in (-1.0, 1.0):
        for k in range(30):
            z0 = -10.0 * k - 2.0
            h = float(rng.uniform(6.0, 18.0))
            x0, x1 = (6.0, 16.0) if side > 0 else (-16.0, -6.0)
            boxes.append([[x0, 0.0, z0 - 8.0], [x1, h, z0]])
    return np.array(boxes)


SCENES = (
    Scene(
        "horizon",
        "camera 1.7 m above a 2 km ground, 8° below the horizon; trees up to 8 m",
        np.array([0.0, 1.7, 0.0]),
        20.0,
        -8.0,
        sun_direction(40.0, 60.0),
        150.0,
        np.array([[-1000.0, 0.0, -1000.0], [1000.0, 8.0, 1000.0]]),
        np.zeros((0, 2, 3)),
    ),
    Scene(
        "down45",
        "camera 30 m above the ground looking down at 45°; casters up to 10 m",
        np.array([0.0, 30.0, 0.0]),
        0.0,
        -45.0,
        sun_direction(55.0, 135.0),
        100.0,
        np.array([[-500.0, 0.0, -500.0], [500.0, 10.0, 500.0]]),
        np.zeros((0, 2, 3)),
    ),
    Scene(
        "street",
        "camera 1.7 m above a street between two rows of 30 buildings (6-18 m), 5° down",
        np.array([0.0, 1.7, 5.0]),
        3.0,
        -5.0,
        sun_direction(35.0, -50.0),
        150.0,
        np.array([[-200.0, 0.0, -400.0], [200.0, 18.0, 200.0]]),
        street_boxes(),
    ),
)


class Hits(NamedTuple):
    """The visible receiver pixels: hit points, unit normals, rays (view ``z = -1``), depths."""

    point: F64  # (N, 3)
    normal: F64  # (N, 3)
    ray: F64  # (N, 3) world, scaled so that the hit is eye + depth * ray
    depth: F64  # (N,) view depth
    pixel_area: F64  # (N,) world area of each pixel's footprint on its surface


def cast(scene: Scene, projection: F64, image: tuple[int, int]) -> Hits:
    """Cast every pixel's ray onto the ground and the boxes; keep the sunlit hits in range."""
    width, height = image
    view = scene.view
    xs = (2 * (np.arange(width) + 0.5) / width - 1) / projection[0, 0]
    ys = (1 - 2 * (np.arange(height) + 0.5) / height) / projection[1, 1]
    gx, gy = np.meshgrid(xs, ys)
    ray_view = np.stack([gx.ravel(), gy.ravel(), -np.ones(gx.size)], axis=-1)
    ray = ray_view @ view[:3, :3]  # view-to-world rotation applied to each ray
    eye = scene.eye
    lo, hi = scene.bounds
    depth = np.full(len(ray), np.inf)
    normal = np.zeros_like(ray)
    with np.errstate(divide="ignore", invalid="ignore"):
        ground = -eye[1] / ray[:, 1]
        at = eye + ground[:, None] * ray
        inside = (ground > 0) & np.all(
            (at[:, [0, 2]] >= lo[[0, 2]]) & (at[:, [0, 2]] <= hi[[0, 2]]), axis=1
        )
        depth = np.where(inside, ground, depth)
        normal[inside] = [0.0, 1.0, 0.0]
        for box in scene.boxes:
            t1 = (box[0] - eye) / ray
            t2 = (box[1] - eye) / ray
            enter = np.minimum(t1, t2)
            t_in = np.max(enter, axis=1)
            t_out = np.min(np.maximum(t1, t2), axis=1)
            hit = (t_out >= t_in) & (t_in > 0) & (t_in < depth)
            axis = np.argmax(enter, axis=1)
            n = np.zeros_like(ray)
            rows = np.arange(len(ray))
            n[rows, axis] = -np.sign(ray[rows, axis])
            depth = np.where(hit, t_in, depth)
            normal[hit] = n[hit]
    keep = (depth >= NEAR) & (depth <= scene.distance) & (normal @ scene.sun > 0)
    point = eye + depth[keep, None] * ray[keep]
    n_k, r_k, d_k = normal[keep], ray[keep], depth[keep]
    area = (2 / (projection[0, 0] * width)) * (2 / (projection[1, 1] * height))
    pixel_area = area * d_k**2 / np.abs(np.sum(n_k * r_k, axis=1))
    return Hits(point, n_k, r_k, d_k, pixel_area)


# ---------------------------------------------------------------------------
# The schemes: what the benchmark needs of a fit
# ---------------------------------------------------------------------------


class Fit(NamedTuple):
    """One scheme's cascades for one camera.

    ``splits`` ``(n + 1,)``: cascade ``i`` serves view depths ``[splits[i], splits[i + 1])``;
    ``texel`` ``(n, 2)``: a texel's world size across the light; ``to_unit`` ``(n, 3, 4)``: world
    to the cascade's usable map (``u``, ``v`` inside the border) and depth range, each in
    ``[0, 1]`` for a point the cascade contains.
    """

    splits: F64
    texel: F64
    to_unit: F64
    texture: F64 | None = None  # (n, 4, 4) a warped map's world_to_texture (LiSPSM)
    bands: F64 | None = None  # (n - 1, 2) the depths over which cascade i blends into i + 1


def light_axes(sun: F64) -> F64:
    """Rows ``X, Y, Z`` (``Z`` toward the sun) of three.js's ``lookAt(0, direction, +Y)``.

    bevy's light transform ``looking_to(direction, Y)`` has the same axes.
    """
    z = unit(sun)
    up = np.array([0.0, 1.0, 0.0]) if abs(z[1]) <= 0.99 else np.array([0.0, 0.0, 1.0])
    x = unit(np.cross(up, z))
    return np.stack([x, np.cross(z, x), z])


def camera_near_far(projection: F64) -> tuple[float, float]:
    """The view depths of an OpenGL perspective projection's near and far planes."""
    a, b = projection[2, 2], projection[2, 3]
    return float(b / (a - 1)), float(b / (a + 1))


class ThreeJs(NamedTuple):
    """three.js's cascades, as its shader and renderer get them (and the benchmark's checks)."""

    splits: F64  # (5,)
    world_to_clip: F64  # (4, 4, 4) OpenGL clip of each cascade's camera
    world_to_texture: F64  # (4, 4, 4) to the atlas's (s, t, depth, 1)
    texel: F64  # (4,) texel size
    to_unit: F64  # (4, 3, 4)


def threejs_cascades(
    sun: F64,
    view: F64,
    projection: F64,
    shadow_far: float,
    map_size: int = MAP_SIZE,
    radius: float = PCF_RADIUS,
    shadow_near: float = 0.5,
) -> ThreeJs:
    """``SunLightShadow.updateMatrices`` in NumPy, for one camera (the speed baseline too).

    ``map_size`` is ``shadow.mapSize``: one tile of the 2 × 2 atlas; ``shadow_far`` is the
    shadow camera's ``far`` (the shadow distance); ``radius`` the PCF radius.
    """
    inset = min(0.25, (math.ceil(radius) + 1) / map_size)
    resolution = map_size * (1 - 2 * inset)
    near, camera_far = camera_near_far(projection)
    far = max(near + 1e-6, min(shadow_far, camera_far))
    amount = np.arange(1, CASCADES) / CASCADES
    uniform = near + (far - near) * amount
    log = near * (far / near) ** amount
    splits = np.concatenate([[near], (uniform + log) * 0.5, [far]])
    axes = light_axes(sun)
    view_to_light = axes @ np.linalg.inv(view)[:3]  # (3, 4)
    ndc = np.array([[1.0, 1.0, -1.0, 1.0], [1.0, -1.0, -1.0, 1.0], [-1.0, -1.0, -1.0, 1.0],
                    [-1.0, 1.0, -1.0, 1.0]])  # fmt: skip
    h = ndc @ np.linalg.inv(projection).T
    near_corners = h[:, :3] / h[:, 3:]
    far_corners = near_corners * (far / near)
    nl = near_corners @ view_to_light[:, :3].T + view_to_light[:, 3]
    fl = far_corners @ view_to_light[:, :3].T + view_to_light[:, 3]
    ceiling = max(nl[:, 2].max(), fl[:, 2].max()) + far
    # cascade i > 0 starts at the previous one's fade start
    starts = np.concatenate([[splits[0]], splits[1:-1] - 0.1 * (splits[1:-1] - splits[:-2])])
    alpha = (np.stack([starts, splits[1:]], axis=1) - near) / (far - near)  # (4, 2)
    corners = nl + alpha[:, :, None, None] * (fl - nl)  # (4, 2, 4, 3)
    corners = corners.reshape(CASCADES, 8, 3)
    center = corners.mean(axis=1)
    r = np.sqrt(np.max(np.sum((corners - center[:, None]) ** 2, axis=-1), axis=1))
    min_z = corners[:, :, 2].min(axis=1)
    r = r / (1 - 1 / resolution)
    texel = 2 * r / resolution
    cxy = np.floor(center[:, :2] / texel[:, None] + 0.5) * texel[:, None]  # Math.round
    depth = ceiling - min_z + shadow_near  # from the near plane (the ceiling) to the far plane
    # world -> cascade camera: x, y about the centre, eye depth from the camera at
    # ceiling + shadow_near looking along -Z
    n = CASCADES
    clip = np.zeros((n, 4, 4))
    clip[:, 0, :3] = axes[0] / r[:, None]
    clip[:, 0, 3] = -cxy[:, 0] / r
    clip[:, 1, :3] = axes[1] / r[:, None]
    clip[:, 1, 3] = -cxy[:, 1] / r
    # eye depth e = ceiling + shadow_near - Z.p; ndc z = (2 e - (far_s + near_s)) / (far_s - near_s)
    far_s = depth + shadow_near
    scale = 2 / (far_s - shadow_near)
    clip[:, 2, :3] = -axes[2] * scale[:, None]
    clip[:, 2, 3] = (ceiling + shadow_near) * scale - (far_s + shadow_near) / (far_s - shadow_near)
    clip[:, 3, 3] = 1.0
    cells = np.array([[i % 2, i // 2] for i in range(n)], dtype=float)
    tex = clip.copy()
    for k in range(2):  # s = (cell + inset + (1 - 2 inset) (x_ndc + 1) / 2) / 2
        s = (1 - 2 * inset) / 4
        tex[:, k] = clip[:, k] * s
        tex[:, k, 3] += s + (cells[:, k] + inset) / 2
    tex[:, 2] = 0.5 * clip[:, 2]
    tex[:, 2, 3] += 0.5
    to_unit = np.empty((n, 3, 4))
    to_unit[:, :2] = 0.5 * clip[:, :2]
    to_unit[:, :2, 3] += 0.5
    to_unit[:, 2] = tex[:, 2]
    return ThreeJs(splits, clip, tex, texel, to_unit)


def threejs_fit(scene: Scene, projection: F64) -> Fit:
    t = threejs_cascades(scene.sun, scene.view, projection, scene.distance)
    s = t.splits  # cascade i fades into i + 1 over the last 10 % of [s_i, s_{i+1}]
    bands = np.stack([s[1:-1] - 0.1 * (s[1:-1] - s[:-2]), s[1:-1]], axis=1)
    return Fit(s, np.stack([t.texel, t.texel], axis=1), t.to_unit, bands=bands)


def slice_corners(projection: F64, near: F64, far: F64) -> F64:
    """``(n, 8, 3)`` view-space corners of the slices ``[near[i], far[i]]`` of a symmetric
    perspective frustum: the near face's bottom-right, top-right, top-left, bottom-left (bevy's
    order), then the far face's."""
    tx, ty = 1 / projection[0, 0], 1 / projection[1, 1]
    signs = np.array([[1.0, -1.0], [1.0, 1.0], [-1.0, 1.0], [-1.0, -1.0]])  # BR, TR, TL, BL
    z = np.stack([near, far], axis=1)[:, :, None, None]  # (n, 2, 1, 1)
    xy = signs * np.array([tx, ty]) * z  # (n, 2, 4, 2)
    corners = np.concatenate([xy, np.broadcast_to(-z, (*xy.shape[:3], 1))], axis=-1)
    return np.asarray(corners.reshape(len(near), 8, 3), dtype=np.float64)


def bevy_bounds(distance: float, first_bound: float = 10.0) -> F64:
    """bevy's far bounds: the first fixed, the others geometric up to the shadow distance."""
    return np.asarray(
        first_bound * (distance / first_bound) ** (np.arange(CASCADES) / (CASCADES - 1)),
        dtype=np.float64,
    )


def bevy_fit(
    scene: Scene,
    projection: F64,
    map_size: int = MAP_SIZE,
    first_bound: float = 10.0,
    overlap: float = 0.2,
) -> Fit:
    """``build_directional_light_cascades`` and ``calculate_cascade`` (bevy) in NumPy."""
    near, _ = camera_near_far(projection)
    n = CASCADES
    bounds = bevy_bounds(scene.distance, first_bound)
    near_bounds = np.concatenate([[near], (1 - overlap) * bounds[:-1]])
    corners = slice_corners(projection, near_bounds, bounds)
    axes = light_axes(scene.sun)
    view_to_light = axes @ np.linalg.inv(scene.view)[:3]
    light = corners @ view_to_light[:, :3].T + view_to_light[:, 3]
    lo, hi = light.min(axis=1), light.max(axis=1)
    body = np.linalg.norm(corners[:, 0] - corners[:, 6], axis=1)
    far_face = np.linalg.norm(corners[:, 4] - corners[:, 6], axis=1)
    diameter = np.ceil(np.maximum(body, far_face))
    texel = diameter / map_size
    center = np.floor(0.5 * (lo[:, :2] + hi[:, :2]) / texel[:, None]) * texel[:, None]
    to_unit = np.zeros((n, 3, 4))
    for k in range(2):
        to_unit[:, k, :3] = axes[k] / diameter[:, None]
        to_unit[:, k, 3] = 0.5 - center[:, k] / diameter
    # reversed Z: 1 at the near plane (max z), 0 at min z
    span = hi[:, 2] - lo[:, 2]
    to_unit[:, 2, :3] = axes[2] / span[:, None]
    to_unit[:, 2, 3] = 1 - hi[:, 2] / span
    splits = np.concatenate([[near], bounds])
    return Fit(splits, np.stack([texel, texel], axis=1), to_unit)


def shadowmath_fit(
    scene: Scene,
    projection: F64,
    *,
    stable: bool,
    splits: F64 | None,
    warp: bool = False,
    options: Mapping[str, Any] | None = None,
) -> Fit:
    """``sm.fit_cascades`` for the scene; ``options``: more keyword arguments (they win)."""
    kwargs: dict[str, Any] = {
        "count": CASCADES,
        "splits": splits,
        "max_distance": None if splits is not None else scene.distance,
        "pcf_radius": PCF_RADIUS,
        "stable": stable,
        "warp": "lispsm" if warp else None,
        **(options or {}),
    }
    c = sm.fit_cascades(scene.sun, scene.view, projection, scene.bounds, MAP_SIZE, **kwargs)
    if warp:
        return Fit(np.asarray(c.splits), np.asarray(c.texel_size), np.zeros((CASCADES, 3, 4)),
                   np.asarray(c.world_to_texture))  # fmt: skip
    tex = np.asarray(c.world_to_texture)[:, :3]  # (n, 3, 4): s, t, r (orthographic: q = 1)
    to_unit = tex.copy()
    for k, margin in enumerate((c.frustum.margin_x, c.frustum.margin_y)):
        m = np.asarray(margin)[:, None]
        to_unit[:, k] = tex[:, k] / m
        to_unit[:, k, 3] -= (1 - m[:, 0]) / (2 * m[:, 0])
    splits, band_end = np.asarray(c.splits), np.asarray(c.band_end)
    bands = np.stack([splits[1:-1], band_end[:-1]], axis=1)
    return Fit(splits, np.asarray(c.texel_size), to_unit, bands=bands)


BEVY_SPLITS = "shadowmath, bevy's splits"
LISPSM = "shadowmath LiSPSM"
SCHEMES = ("three.js", "bevy", "shadowmath", "shadowmath stable", BEVY_SPLITS, LISPSM)
KEYS = dict(
    zip(SCHEMES, ("threejs", "bevy", "shadowmath", "stable", "bevy_splits", "lispsm"), strict=True)
)
"""The schemes compared. shadowmath's default splits (``scheme="auto"`` over the camera's range)
are practical with λ = 0.75 (three.js: 0.5), from the camera's near plane;
:data:`BEVY_SPLITS` is shadowmath's fit on bevy's split depths, to tell the fit's gain from the
splits'."""


def fit_scheme(name: str, scene: Scene, projection: F64) -> Fit:
    if name == "three.js":
        return threejs_fit(scene, projection)
    if name == "bevy":
        return bevy_fit(scene, projection)
    if name == BEVY_SPLITS:
        near, _ = camera_near_far(projection)
        splits = np.concatenate([[near], bevy_bounds(scene.distance)])
        return shadowmath_fit(scene, projection, stable=False, splits=splits)
    if name == LISPSM:
        return shadowmath_fit(scene, projection, stable=False, splits=None, warp=True)
    return shadowmath_fit(scene, projection, stable=name.endswith("stable"), splits=None)


# ---------------------------------------------------------------------------
# Resolution
# ---------------------------------------------------------------------------


class Ratios(NamedTuple):
    ratio: F64  # (N,) texel area / pixel area on the surface, per visible receiver pixel
    uncovered: int  # pixels whose point lies outside the cascade that serves it


def ratios(fit: Fit, hits: Hits, sun: F64) -> Ratios:
    n = len(fit.texel)
    index = np.clip(np.searchsorted(fit.splits, hits.depth, side="right") - 1, 0, n - 1)
    if fit.texture is not None:
        return warped_ratios(fit.texture[index], hits)
    texel_area = fit.texel[index, 0] * fit.texel[index, 1] / (hits.normal @ sun)
    m = fit.to_unit[index]  # (N, 3, 4)
    uvw = np.einsum("nij,nj->ni", m[:, :, :3], hits.point) + m[:, :, 3]
    tol = 1e-9
    inside = np.all((uvw >= -tol) & (uvw <= 1 + tol), axis=1)
    return Ratios(texel_area / hits.pixel_area, int(np.count_nonzero(~inside)))


def blended_ratios(fit: Fit, hits: Hits, sun: F64) -> Ratios:
    """:func:`ratios` with each blend band's pixels given the texel area the blend reads,
    ``w A_i + (1 - w) A_{i+1}`` (``w``: cascade ``i``'s weight, 1 to 0 across the band),
    whichever side of the split the scheme puts its band (three.js before it, shadowmath
    after it): the same for both."""
    r = ratios(fit, hits, sun)
    if fit.bands is None:
        return r
    area = fit.texel[:, 0] * fit.texel[:, 1]
    out = r.ratio.copy()
    for i, (a, b) in enumerate(fit.bands):
        inside = (hits.depth >= a) & (hits.depth < b)
        w = (b - hits.depth[inside]) / (b - a)
        blend = w * area[i] + (1 - w) * area[i + 1]
        out[inside] = blend / (hits.normal[inside] @ sun) / hits.pixel_area[inside]
    return Ratios(out, r.uncovered)


def warped_ratios(M: F64, hits: Hits) -> Ratios:
    """A projective map's texel area on the surface, per pixel: ``1 / (W H |det J|)``.

    ``J``: the derivatives of ``(s, t) = (M p)_{xy} / (M p)_w`` along two orthonormal
    tangents of the surface at the hit; for an orthographic map this is the texel's
    area projected on the surface along the light, as :func:`ratios` computes it.
    """
    p = np.c_[hits.point, np.ones(len(hits.point))]
    h = np.einsum("nij,nj->ni", M, p)
    q = h[:, 3:]
    uvw = h[:, :3] / q
    grads = (M[:, :3, :3] - uvw[:, :, None] * M[:, 3:, :3]) / q[:, :, None]  # (N, 3, 3)
    helper = np.where(np.abs(hits.normal[:, :1]) < 0.9, [[1.0, 0, 0]], [[0, 1.0, 0]])
    t1 = np.cross(hits.normal, helper)
    t1 /= np.linalg.norm(t1, axis=1, keepdims=True)
    t2 = np.cross(hits.normal, t1)
    J = np.stack([np.einsum("nj,nj->n", grads[:, k], t) for k in (0, 1) for t in (t1, t2)])
    det = np.abs(J[0] * J[3] - J[1] * J[2])
    texel_area = 1.0 / (MAP_SIZE * MAP_SIZE * det)
    tol = 1e-9
    inside = np.all((uvw >= -tol) & (uvw <= 1 + tol), axis=1)
    return Ratios(texel_area / hits.pixel_area, int(np.count_nonzero(~inside)))


@dataclass
class Stats:
    pixels: int
    median: float
    p90: float
    aliasing_free: float  # share of pixels with ratio <= 1
    uncovered: int


def stats(r: Ratios) -> Stats:
    v = r.ratio
    return Stats(
        len(v),
        float(np.median(v)),
        float(np.percentile(v, 90)),
        float(np.mean(v <= 1)),
        r.uncovered,
    )


def resolution(cfg: Config, section: Section) -> str:
    """The resolution table (Markdown) and its figures in ``section.figures``."""
    image = TINY_IMAGE if cfg.tiny else IMAGE
    projection = perspective(FOV_Y, ASPECT, NEAR, FAR)
    pooled: dict[str, list[Ratios]] = {s: [] for s in SCHEMES}
    results: list[tuple[str, dict[str, Stats]]] = []
    for scene in SCENES:
        hits = cast(scene, projection, image)
        per: dict[str, Stats] = {}
        for name in SCHEMES:
            r = ratios(fit_scheme(name, scene, projection), hits, scene.sun)
            pooled[name].append(r)
            per[name] = stats(r)
        results.append((scene.name, per))
    merged = {
        name: Ratios(np.concatenate([r.ratio for r in rs]), sum(r.uncovered for r in rs))
        for name, rs in pooled.items()
    }
    results.append(("all", {name: stats(r) for name, r in merged.items()}))

    lines = [
        f"Image {image[0]}×{image[1]}, vertical field of view {FOV_Y:g}°, near {NEAR:g}; "
        f"{CASCADES} cascades, {MAP_SIZE}² each (three.js: one {2 * MAP_SIZE}² atlas), "
        f"PCF radius {PCF_RADIUS}. Scenes:",
        "",
    ]
    for scene in SCENES:
        lines.append(
            f"* `{scene.name}`: {scene.description}; shadow distance {scene.distance:g} m, "
            f"sun {math.degrees(math.asin(scene.sun[1])):.0f}° high"
        )
    lines += [
        "",
        "Ratio = shadow-map texel area / pixel footprint area on the receiver (≤ 1: no visible "
        "aliasing), over the sunlit receiver pixels within the shadow distance; *uncovered*: "
        "pixels outside the map of the cascade that serves them. *× smaller* = the engine's "
        "figure / shadowmath's: its default fit / `stable=True` / its fit on the engine's "
        "split depths.",
        "",
        "| scene | scheme | pixels | median | p90 | share ≤ 1 | uncovered "
        "| × smaller, median | × smaller, p90 |",
        "|---|---|---|---|---|---|---|---|---|",
    ]
    for scene_name, per in results:
        for name in SCHEMES:
            s = per[name]
            key = f"{scene_name}.{KEYS[name]}"
            section.figures[f"{key}.median"] = s.median
            section.figures[f"{key}.p90"] = s.p90
            section.figures[f"{key}.uncovered"] = float(s.uncovered)
            cells = ["", ""]
            if name in ("three.js", "bevy"):
                same = per["shadowmath" if name == "three.js" else BEVY_SPLITS]
                ours = (per["shadowmath"], per["shadowmath stable"], same)
                for k, stat in enumerate(("median", "p90")):
                    mine = getattr(s, stat)
                    gains = [mine / getattr(o, stat) for o in ours]
                    cells[k] = " / ".join(f"{g:.2f}" for g in gains)
                    for label, g in zip(("", "_stable", "_same_splits"), gains, strict=True):
                        section.figures[f"{key}.gain_{stat}{label}"] = g
            lines.append(
                f"| {scene_name} | {name} | {s.pixels} | {s.median:.3g} | {s.p90:.3g} | "
                f"{100 * s.aliasing_free:.1f} % | {s.uncovered} | {cells[0]} | {cells[1]} |"
            )
    return "\n".join(lines)


# ---------------------------------------------------------------------------
# Speed
# ---------------------------------------------------------------------------


def cameras(count: int, seed: int) -> F64:
    """``(count, 4, 4)`` views: eyes over the horizon scene's ground, yaw and pitch varied."""
    rng = np.random.default_rng(seed)
    views = [
        look(
            np.array([rng.uniform(-50, 50), rng.uniform(1.5, 20.0), rng.uniform(-50, 50)]),
            float(rng.uniform(-180, 180)),
            float(rng.uniform(-40, 0)),
        )
        for _ in range(count)
    ]
    return np.stack(views)


def speed(cfg: Config, section: Section) -> None:
    scene = SCENES[0]
    projection = perspective(FOV_Y, ASPECT, NEAR, FAR)
    view = scene.view
    views = cameras(cfg.size(BATCH, 4), cfg.seed)
    repeats = cfg.repeats(15)
    min_time = cfg.min_time

    def one() -> object:
        return sm.fit_cascades(scene.sun, view, projection, scene.bounds, MAP_SIZE,
                               max_distance=scene.distance, pcf_radius=PCF_RADIUS)  # fmt: skip

    def one_stable() -> object:
        return sm.fit_cascades(scene.sun, view, projection, scene.bounds, MAP_SIZE,
                               max_distance=scene.distance, pcf_radius=PCF_RADIUS,
                               stable=True)  # fmt: skip

    def ranged(depth_range: object) -> Callable[[], object]:
        """Stable, over ``depth_range``, with the state of the frame before (the same view)."""
        args = (scene.sun, view, projection, scene.bounds, MAP_SIZE)
        options = {"max_distance": scene.distance, "pcf_radius": PCF_RADIUS, "stable": True,
                   "depth_range": depth_range}  # fmt: skip
        state = sm.fit_cascades(*args, **options, state=sm.CascadeState.initial()).state
        return lambda: sm.fit_cascades(*args, **options, state=state)

    visible_range = sm.fit_cascades(
        scene.sun,
        view,
        projection,
        scene.bounds,
        MAP_SIZE,
        max_distance=scene.distance,
        depth_range="visible",
    ).splits
    measured = np.array([visible_range[0], visible_range[-1]])  # as a depth buffer's min/max

    def batch() -> object:
        return sm.fit_cascades(scene.sun, views, projection, scene.bounds, MAP_SIZE,
                               max_distance=scene.distance, pcf_radius=PCF_RADIUS)  # fmt: skip

    def baseline() -> object:
        return threejs_cascades(scene.sun, view, projection, scene.distance)

    def per_camera(t: Timing) -> Timing:
        return Timing(t.median / len(views), t.repeats, t.number)

    base_label = "three.js's scheme, hand-written NumPy (1 camera)"
    base = measure(baseline, repeats=repeats, min_time=min_time)
    installed = measure(one, repeats=repeats, min_time=min_time)
    installed_stable = measure(one_stable, repeats=repeats, min_time=min_time)
    installed_batch = per_camera(measure(batch, repeats=repeats, min_time=min_time))
    ranges = {"visible range": "visible", "measured range": measured}
    installed_ranged = {k: measure(ranged(v), repeats=repeats, min_time=min_time)
                        for k, v in ranges.items()}  # fmt: skip
    with numpy_alone():
        alone = measure(one, repeats=repeats, min_time=min_time)
        alone_stable = measure(one_stable, repeats=repeats, min_time=min_time)
        alone_ranged = {k: measure(ranged(v), repeats=repeats, min_time=min_time)
                        for k, v in ranges.items()}  # fmt: skip
        alone_batch = per_camera(measure(batch, repeats=repeats, min_time=min_time))
    bevy = measure(lambda: bevy_fit(scene, projection), repeats=repeats, min_time=min_time)
    fast = f"≤ {FAST_TARGET * 1e6:g} µs"
    slow = f"≤ {NUMPY_TARGET * 1e3:g} ms"
    section.rows += [
        Row("fit_cascades, 4 cascades, 1 camera (as installed)", installed, base_label, base,
            fast, FAST_TARGET, "seconds"),
        Row("fit_cascades stable=True, 1 camera (as installed)", installed_stable, base_label,
            base),
        Row(f"fit_cascades, {len(views)} cameras per call, per camera (as installed)",
            installed_batch, base_label, base),
        Row("fit_cascades, 1 camera (NumPy alone)", alone, base_label, base, slow,
            NUMPY_TARGET, "seconds"),
        Row("fit_cascades stable=True, 1 camera (NumPy alone)", alone_stable, base_label, base),
        Row(f"fit_cascades, {len(views)} cameras per call, per camera (NumPy alone)",
            alone_batch, base_label, base),
        Row("bevy's scheme, hand-written NumPy (1 camera, for reference)", bevy, base_label,
            base),
    ]  # fmt: skip
    for k in ranges:
        section.rows += [
            Row(f"fit_cascades stable=True, {k} + state, 1 camera (as installed)",
                installed_ranged[k], base_label, base, fast, FAST_TARGET, "seconds"),
            Row(f"fit_cascades stable=True, {k} + state, 1 camera (NumPy alone)",
                alone_ranged[k], base_label, base, slow, NUMPY_TARGET, "seconds"),
        ]  # fmt: skip
    section.notes.append(
        "Speed: the horizon scene's camera and sun with its scene box, 4 cascades of 1024², "
        "PCF radius 1; the batch varies the camera (position, yaw, pitch); the range rows "
        "are stable with the state of the frame before (the same view), the measured range "
        "the visible one. The baselines return "
        "their matrices (three.js: each cascade's clip and atlas texture matrix). 'NumPy alone' "
        "disables the compiled loops (`_kernels.disabled()`), as without the `fast` extra; where "
        "fit_cascades has no compiled path, both run the same array driver."
    )


#: The warp's and the fitted orientation's targets with the fast extra: at most this many
#: times the default fit's time (the same camera, in the same run).
OPTION_TARGET = 2.0


def option_speed(cfg: Config, section: Section) -> None:
    """``warp="lispsm"`` and ``orientation="fitted"`` against the default fit, both as
    installed (compiled with the fast extra) and with NumPy alone: ratios to the default."""
    scene = SCENES[0]
    args = (scene.sun, scene.view, perspective(FOV_Y, ASPECT, NEAR, FAR), scene.bounds, MAP_SIZE)
    repeats, min_time = cfg.repeats(15), cfg.min_time

    def fit(**options: object) -> Callable[[], object]:
        return lambda: sm.fit_cascades(*args, max_distance=scene.distance,
                                       pcf_radius=PCF_RADIUS, **options)  # fmt: skip

    options = {
        "warp='lispsm'": {"warp": "lispsm"},
        "orientation='fitted'": {"orientation": "fitted"},
    }
    for where, context in (("as installed", contextlib.nullcontext), ("NumPy alone", numpy_alone)):
        with context():
            default = measure(fit(), repeats=repeats, min_time=min_time)
            timed = {k: measure(fit(**v), repeats=repeats, min_time=min_time)
                     for k, v in options.items()}  # fmt: skip
        label = f"fit_cascades default, 1 camera ({where})"
        for k, t in timed.items():
            target = (
                (f"≤ {OPTION_TARGET:g}× default", OPTION_TARGET)
                if where[0] == "a"
                else (None, None)
            )
            section.rows.append(Row(f"fit_cascades {k}, 1 camera ({where})", t, label, default,
                                    *target))  # fmt: skip


def run(cfg: Config) -> Section:
    section = Section(NAME, TITLE)
    section.text = resolution(cfg, section)
    speed(cfg, section)
    option_speed(cfg, section)
    return section


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=(__doc__ or "").splitlines()[0])
    parser.add_argument("--tiny", action="store_true", help="tiny image, each timing once")
    args = parser.parse_args(argv)
    print(table(run(Config(tiny=args.tiny))))
    return 0


if __name__ == "__main__":
    sys.exit(main())
