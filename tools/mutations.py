"""A small mutation runner for shadowmath's formulas, module by module.

Each entry of :data:`ALL` (the fits' :data:`MUTATIONS`, then :data:`MODULES`: cascades,
atlas, shadow cameras, cube depth, bias, PCF, spot caster selection, soft shadows,
gather and the pygfx integration, then :data:`NEWEST`: the scene and its culling, the
spot light's clipping loop, the atlas redraw, ``pcss_parameters``' recorded map size,
the placement check and the float32 warning, and the array forms that keep the traced
programs small) changes one piece of exact source text into a
plausible mistake (a sign, a factor, a rounding mode, a bound, a swapped axis). For
each, the runner copies the repository's ``shadowmath/``, ``tests/``, ``docs/`` (whose
examples tests run), ``conftest.py`` and ``pyproject.toml`` into a temporary folder,
applies the one mutation there, and runs the entry's test files with ``pytest -x``: a
mutation is *killed* when a test fails, and *SURVIVED* when they all pass, which means
the tests do not pin that piece of the formula down.

The tests run with ``SHADOWMATH_NUMBA=0`` (the array path: no compiled code cached
from the unmutated source can hide a mutation), ``SHADOWMATH_REQUIRE_GL=1`` (a render
test fails instead of skipping) and ``PYTHONPATH`` set to the
temporary folder (checked: ``shadowmath`` must be imported from there), with a
fixed hypothesis seed (``--seed``, default 0) so that a run can be repeated. First the
listed test files run once unmutated (the baseline): a test that fails without any
mutation would "kill" every mutation, so a failing baseline stops the run.

Usage::

    python tools/mutations.py             # every mutation; exit status 1 if one survived
    python tools/mutations.py --list      # the table, without running anything
    python tools/mutations.py --only b-directional-pad --only stable-floor
    python tools/mutations.py --repo /path/to/checkout

Exit status: 0 every mutation killed, 1 some mutation survived, 2 the run itself
failed (the baseline, a mutation's text not found exactly once, a timeout or a
pytest error other than failing tests).
"""

from __future__ import annotations

import argparse
import os
import shutil
import subprocess
import sys
import tempfile
import time
from collections.abc import Iterable, Sequence
from dataclasses import dataclass
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
COPIED = ("shadowmath", "tests", "docs", "conftest.py", "pyproject.toml")
IGNORED = shutil.ignore_patterns("__pycache__", "*.pyc", "*.nbi", "*.nbc", ".hypothesis")
TIMEOUT_S = 1800.0

STABLE = ("tests/test_fit_mutations.py", "tests/test_directional.py")


@dataclass(frozen=True)
class Mutation:
    """One source change and the test files that must kill it."""

    id: str
    file: str  # relative to the repository
    original: str  # exact text, found exactly once in ``file``
    mutated: str
    description: str
    tests: tuple[str, ...]  # test files (or pytest node ids), relative to the repository


MUTATIONS: tuple[Mutation, ...] = (
    Mutation(
        "a-stable-half-texel",
        "shadowmath/_math/_fit_formulas.py",
        "half_x = radius / (1.0 - 1.0 / (mx * width))\n"
        "    half_y = radius / (1.0 - 1.0 / (my * height))",
        "half_x = radius / (1.0 - 0.5 / (mx * width))\n"
        "    half_y = radius / (1.0 - 0.5 / (my * height))",
        "stable map enlarged by a quarter texel instead of half a texel",
        STABLE,
    ),
    Mutation(
        "b-directional-pad",
        "shadowmath/_math/_fit_formulas.py",
        "pad = (z_hi - z_lo) + where(half_x >= half_y, half_x, half_y)",
        "pad = (z_hi - z_lo)",
        "directional origin padded by the depth range only, not the box size",
        STABLE,
    ),
    Mutation(
        "stable-floor",
        "shadowmath/_math/_fit_formulas.py",
        "cx = rint(ax / safe_tx) * tx - ax\n    cy = rint(ay / safe_ty) * ty - ay",
        "cx = rint(ax / safe_tx - 0.5) * tx - ax\n    cy = rint(ay / safe_ty - 0.5) * ty - ay",
        "stable centre snapped down (a floor) instead of to the nearest texel",
        STABLE,
    ),
    Mutation(
        "welzl-three-levels",
        "shadowmath/_math/_vertex_passes.py",
        "                    if _outside(pr, ball):",
        "                    if False:",
        "Welzl's algorithm without its fourth level (spheres of four support points)",
        ("tests/test_stable_sphere.py",),
    ),
    Mutation(
        "ball-support-unchecked",
        "shadowmath/_math/_ball_support.py",
        "r2 = np.where(outside.any(axis=0), np.inf, cand[3])",
        "r2 = np.where(False, np.inf, cand[3])",
        "the batched support takes the smallest candidate sphere, whether it holds S + p or not",
        ("tests/test_stable_sphere.py",),
    ),
    Mutation(
        "receivers-outside-counted",
        "shadowmath/_math/_fit_formulas.py",
        "return inside & ((z > 0) | directional)",
        "return (z > 0) | directional",
        "receiver points outside the map's sides widen the depth range",
        ("tests/test_receivers.py",),
    ),
    Mutation(
        "fit-far-slack",
        "shadowmath/_math/_fit_formulas.py",
        "far = z_hi * (1.0 + slack)",
        "far = z_hi * (1.0 - slack)",
        "fit_shadow's default far plane inside the blocker (slack subtracted)",
        ("tests/test_directional.py",),
    ),
    Mutation(
        "frustum-near-slack",
        "shadowmath/_geometry/_adaptive_frustum.py",
        "near = z_min * (1 - NEAR_FAR_SLACK) if given_near is None else given_near",
        "near = z_min * (1 + NEAR_FAR_SLACK) if given_near is None else given_near",
        "adaptive_frustum's default near plane behind the nearest vertex (slack added)",
        ("tests/test_setup.py",),
    ),
    Mutation(
        "axes-cross-sign",
        "shadowmath/_math/_formulas.py",
        "normalize3(zy * vz - zz * vy, zz * vx - zx * vz, zx * vy - zy * vx)",
        "normalize3(zy * vz + zz * vy, zz * vx - zx * vz, zx * vy - zy * vx)",
        "axes_from_z: a sign in X = Z x V",
        ("tests/test_frame.py",),
    ),
    Mutation(
        "helper-axis-tie",
        "shadowmath/_math/_formulas.py",
        "pick_x = (ax <= ay) & (ax <= az)",
        "pick_x = (ax < ay) & (ax <= az)",
        "helper_axis3: a tie between |z_x| and |z_y| goes to Y instead of the lowest index",
        ("tests/test_frame.py",),
    ),
    Mutation(
        "light-translation",
        "shadowmath/_math/_formulas.py",
        "ty = -(yx * ox + yy * oy + yz * oz)",
        "ty = -(yx * ox + yy * oy + yz * ox)",
        "light_rows: Y's translation uses the origin's x for its z",
        ("tests/test_frame.py",),
    ),
    Mutation(
        "texture-half",
        "shadowmath/_math/_formulas.py",
        "0.5 * (c[0] + c[12]), 0.5 * (c[1] + c[13])",
        "1.0 * (c[0] + c[12]), 0.5 * (c[1] + c[13])",
        "texture_rows: s's x entry not halved (the 0.5 of (clip + w) / 2)",
        ("tests/test_setup.py",),
    ),
    Mutation(
        "projection-depth",
        "shadowmath/_math/_formulas.py",
        "-2.0 * near * ratio",
        "-1.0 * near * ratio",
        "projection_rows: -n f / (f - n) instead of -2 n f / (f - n) (near off -1)",
        ("tests/test_setup.py",),
    ),
    Mutation(
        "triangle-no-map-edges",
        "shadowmath/_math/_fit_formulas.py",
        "        best = _corner_far((g0, g1, g2), z, (k // 2, 2 + k % 2), best, tau)",
        "        best = best",
        "triangle_far: the map's edges piercing a triangle not considered",
        ("tests/test_receivers.py",),
    ),
    Mutation(
        "triangle-no-edge-crossings",
        "shadowmath/_math/_fit_formulas.py",
        "    best = _edge_far((g1, g2), (z[1], z[2]), best, tau)",
        "    best = best",
        "triangle_far: one edge's crossings of the side planes not considered",
        ("tests/test_receivers.py",),
    ),
    Mutation(
        "receivers-pull-near",
        "shadowmath/_math/_fit_entry.py",
        "        (zb_min, z_hi, zb_min, zb_max),",
        "        (0.5 * zb_min, z_hi, zb_min, zb_max),",
        "a point light's near pulled toward the light (as receivers in front used to)",
        ("tests/test_receivers.py",),
    ),
    Mutation(
        "sphere-diameter-as-radius",
        "shadowmath/_math/_fit_formulas.py",
        "    return q[0] + ox, q[1] + oy, q[2] + oz, ox * ox + oy * oy + oz * oz",
        "    return q[0] + ox, q[1] + oy, q[2] + oz, 1.0001 * (ox * ox + oy * oy + oz * oz)",
        "sphere_through: the radius 0.005 % too large (not the minimal sphere)",
        ("tests/test_stable_sphere.py",),
    ),
    Mutation(
        "fov-limit-on-half-width",
        "shadowmath/_math/_fit_formulas.py",
        "    tx = fabs(cx) + half_x / margins[0]",
        "    tx = fabs(cx) + half_x",
        "fov_ok: the map's edge without the margin (a frustum a border too narrow judged)",
        ("tests/test_degenerate.py",),
    ),
)

# --- every module beyond the fits (issue 26): cascades, atlas, cameras, cube depth, bias,
# PCF, spot caster selection, soft shadows, gather and the pygfx integration.

CASCADES = ("tests/test_cascades.py",)
SURVIVORS = ("tests/test_mutation_survivors.py",)
CASCADE_F = "shadowmath/_math/_cascade_formulas.py"
SPLITS_F = "shadowmath/_fits/cascades/_splits.py"
LISPSM_F = "shadowmath/_fits/cascades/_lispsm.py"
TILES_F = "shadowmath/_math/_atlas_tiles.py"
ATLAS_F = "shadowmath/_fits/atlas/_allocate.py"
ATLAS = ("tests/test_atlas.py",)
CAMERA_F = "shadowmath/_fits/camera/_shadow_camera.py"
CAMERA = ("tests/test_shadow_camera.py",)
CUBE_DEPTH_F = "shadowmath/_fits/cube/_driver.py"
CUBE_DEPTH = ("tests/test_cube_depth.py",)
CUBE_F = "shadowmath/_math/_cube.py"
CUBE = ("tests/test_cube.py",)
BIAS_F = "shadowmath/_math/_bias.py"
BIAS = ("tests/test_bias.py",)
PCF_F = "shadowmath/_math/_pcf.py"
PCF = ("tests/test_pcf.py",)
SPOT_F = "shadowmath/_math/_spot_casters.py"
SPOT = ("tests/test_caster_selection.py",)
SOFT_F = "shadowmath/_math/_soft.py"
SOFT = ("tests/test_soft.py",)
GATHER_F = "shadowmath/gather.py"
GATHER = ("tests/test_gather.py",)
PYGFX_F = "shadowmath/integrations/pygfx.py"
PYGFX = ("tests/render/test_pygfx.py",)

MODULES: tuple[Mutation, ...] = (
    # cascades: formulas, splits, LiSPSM
    Mutation(
        "cascade-pad-min",
        CASCADE_F,
        "pad = (z_hi - z_lo) + where(hx >= hy, hx, hy)",
        "pad = (z_hi - z_lo) + where(hx >= hy, hy, hx)",
        "cascade_box: the origin padded by the map's smaller half-size (max replaced by min)",
        SURVIVORS,
    ),
    Mutation(
        "cascade-flat-box",
        CASCADE_F,
        "return t0, t1, ok & (t0 <= t1)",
        "return t0, t1, ok & (t0 < t1)",
        "clip_segment: a single point (t0 = t1) counted empty (a flat scene box loses its points)",
        SURVIVORS,
    ),
    Mutation(
        "cascade-ladder-margin",
        CASCADE_F,
        "keep = (p >= t) & (p <= q * margin)",
        "keep = (p >= t) & (p <= q)",
        "ladder_hold: a laddered value shrinks at the first ladder step (no margin)",
        ("tests/test_cascade_range.py::test_the_ladder_with_hysteresis_along_a_path",),
    ),
    Mutation(
        "cascade-near-mirror",
        CASCADE_F,
        "lo = 1.0 / ladder_hold(inv_t, inv_p)",
        "lo = 1.0 / ladder_hold(inv_t, 1.0 / inv_p)",
        "depth_hysteresis: the near end's last value not mirrored (1 / p), so never kept",
        ("tests/test_cascade_range.py::test_the_ladder_with_hysteresis_along_a_path",),
    ),
    Mutation(
        "cascade-stable-part-centre",
        "shadowmath/_math/_cascade_steps.py",
        "c = (mx * a[0] + my * a[3], mx * a[1] + my * a[4], mx * a[2] + my * a[5])",
        "c = (mx * a[0] + my * a[3], mx * a[1] + my * a[4], c[2])",
        "stable_box: the visible part's square centred with the sphere's world z kept",
        ("tests/test_cascade_range.py::test_stable_squares_along_a_path",),
    ),
    Mutation(
        "cascade-visible-near",
        "shadowmath/_math/_cascade_steps.py",
        "    return b.lo_x, b.hi_x\n",
        "    return near, b.hi_x\n",
        "visible_range: the camera's near plane kept as the range's near end",
        ("tests/test_cascade_range.py",),
    ),
    Mutation(
        "cascade-split-uniform",
        CASCADE_F,
        "(1.0 - lam) * (near + (far - near) * frac)",
        "(1.0 - lam) * (near + far * frac)",
        "split_depth: the uniform part n + f i/N instead of n + (f - n) i/N",
        CASCADES,
    ),
    Mutation(
        "cascade-edge-infinite-far",
        CASCADE_F,
        "u = (d - s * n[2]) / (s * (f[2] - n[2]) + d * (1.0 - f[3]))",
        "u = (d - s * n[2]) / (s * (f[2] - n[2]))",
        "edge_point: the far corner's w ignored (an infinite far plane's edges)",
        CASCADES,
    ),
    Mutation(
        "cascade-clip-entering",
        CASCADE_F,
        "t0 = where(entering & (t > t0), t, t0)",
        "t0 = where(entering & (t < t0), t, t0)",
        "clip_plane: a plane entered does not raise t0 (Liang-Barsky's comparison reversed)",
        CASCADES,
    ),
    Mutation(
        "cascade-sphere-centre",
        CASCADE_F,
        "t = 0.5 + (rf2 - rn2) / (2.0 * where(length2 > 0, length2, 1.0))",
        "t = 0.5 + (rf2 - rn2) / (4.0 * where(length2 > 0, length2, 1.0))",
        "slice_sphere: the centre half-way to the equidistant point (not the minimal sphere)",
        CASCADES,
    ),
    Mutation(
        "cascade-box-values",
        CASCADE_F,
        "return x - lo[0], hi[0] - x, y - lo[1], hi[1] - y, z - lo[2], hi[2] - z",
        "return x - lo[0], hi[0] - x, y - lo[1], hi[1] - y, z - lo[2], hi[2] - y",
        "box_values: the box's top plane reads y for z",
        CASCADES,
    ),
    Mutation(
        "cascade-camera-sides",
        CASCADE_F,
        "return cw - cx, cw + cx, cw - cy, cw + cy, cw",
        "return cw - cx, cw + cx, cw - cy, cw + cx, cw",
        "camera_values: the bottom side plane w + x instead of w + y",
        SURVIVORS,
    ),
    Mutation(
        "splits-far-equals-near",
        SPLITS_F,
        'checks.require(f > n, "far: the split range must end beyond near (far > near)")',
        'checks.require(f >= n, "far: the split range must end beyond near (far > near)")',
        "cascade_splits: far == near accepted (an empty range of cascades)",
        SURVIVORS,
    ),
    Mutation(
        "splits-log-near-zero",
        SPLITS_F,
        "(n > 0) | (lm == 0),",
        "(n >= 0) | (lm == 0),",
        "cascade_splits: near = 0 accepted with a logarithmic part",
        CASCADES,
    ),
    Mutation(
        "splits-fraction",
        SPLITS_F,
        "i = xp.asarray(np.arange(count + 1) / count, dtype=n.dtype)",
        "i = xp.asarray(np.arange(count + 1) / (count + 1), dtype=n.dtype)",
        "cascade_splits: the fractions i / (N + 1) instead of i / N",
        CASCADES,
    ),
    Mutation(
        "lispsm-y-row",
        LISPSM_F,
        "sy * ((wp.f + wp.n) * t_row[3] - 2.0 * wp.f * wp.n),",
        "sy * ((wp.f + wp.n) * t_row[3] - 1.0 * wp.f * wp.n),",
        "LiSPSM: the warp's y row -(f + n) t + f n instead of 2 f n (y' leaves [-1, 1])",
        ("tests/test_lispsm.py",),
    ),
    Mutation(
        "lispsm-x-centre",
        LISPSM_F,
        "h, c = 0.5 * (hi - lo), 0.5 * (hi + lo)",
        "h, c = 0.5 * (hi - lo), 0.5 * (hi - lo)",
        "LiSPSM: the window's centre (hi - lo) / 2 instead of (hi + lo) / 2",
        ("tests/test_lispsm.py",),
    ),
    Mutation(
        "lispsm-texel-size",
        LISPSM_F,
        "size_u = wp.f * (wp.f - wp.n) / (spec.margins[1] * spec.size[1] * wp.n)",
        "size_u = (wp.f - wp.n) / (spec.margins[1] * spec.size[1])",
        "LiSPSM: the texel size along u without the perspective's f / n",
        ("tests/test_lispsm.py",),
    ),
    Mutation(
        "lispsm-fade-cap",
        LISPSM_F,
        "return g * k**3, dg * k**3 + 3.0 * g * k * k * dk",
        "return g * k**2, dg * k**2 + 2.0 * g * k * dk",
        "LiSPSM: the strength's cap with texel areas growing like t^2 instead of t^3 along u",
        ("tests/test_lispsm_fade.py",),
    ),
    # the atlas: allocation rule (integer arrays) and tile geometry
    Mutation(
        "atlas-hysteresis-upper",
        TILES_F,
        "(raw <= previous * (1 + hysteresis))",
        "(raw < previous * (1 + hysteresis))",
        "size_classes: a coverage exactly at p (1 + h) changes class (the bound is inclusive)",
        SURVIVORS,
    ),
    Mutation(
        "atlas-hysteresis-lower",
        TILES_F,
        "keep &= (raw > previous * ((1 - hysteresis) / 2))",
        "keep &= (raw >= previous * ((1 - hysteresis) / 2))",
        "size_classes: a coverage exactly at p (1 - h) / 2 keeps its class (the bound is strict)",
        SURVIVORS,
    ),
    Mutation(
        "atlas-power-of-two-class",
        TILES_F,
        "exponent -= mantissa == 0.5",
        "exponent -= mantissa == 0.25",
        "size_classes: an exact power of two wishes the next class up",
        ATLAS,
    ),
    Mutation(
        "atlas-budget-order",
        TILES_F,
        "last_first = order[::-1]",
        "last_first = order",
        "shrink_to_budget: the most covering light halved first",
        ATLAS,
    ),
    Mutation(
        "atlas-worst-fit",
        TILES_F,
        "k = int(candidates[np.argmin(rank)])",
        "k = int(candidates[np.argmax(rank)])",
        "place: a new tile in the free node with the largest free ancestor (worst fit)",
        ATLAS,
    ),
    Mutation(
        "atlas-pack-smallest-first",
        TILES_F,
        "order = np.lexsort((rank, -side))",
        "order = np.lexsort((rank, side))",
        "pack: tiles laid smallest first (misaligned along the Morton curve)",
        ATLAS,
    ),
    Mutation(
        "atlas-morton-mask",
        TILES_F,
        "v = (v | (v << 2)) & 0x33333333\n    return",
        "v = (v | (v << 2)) & 0x55555555\n    return",
        "morton_encode: a wrong mask spreading the bits",
        ATLAS,
    ),
    Mutation(
        "atlas-tile-transform-xy",
        "shadowmath/_math/_rows.py",
        "    x, y, w, h = rect\n",
        "    y, x, w, h = rect\n",
        "atlas_tile_transforms: a tile's column and row swapped",
        ATLAS,
    ),
    Mutation(
        "atlas-border-fills-tile",
        ATLAS_F,
        "if lo <= 2 * border:",
        "if lo < 2 * border:",
        "allocate_atlas: a border of min_tile / 2 accepted (no inner texel left)",
        ATLAS,
    ),
    # shadow cameras
    Mutation(
        "camera-ortho-window-symmetric",
        CAMERA_F,
        "shift_x, shift_y = (cx, cy) if ortho else (0.0 * cx, 0.0 * cy)",
        "shift_x, shift_y = (0.0 * cx, 0.0 * cy) if ortho else (0.0 * cx, 0.0 * cy)",
        "shadow_camera: an orthographic eye left at the origin with an off-centre window",
        SURVIVORS,
    ),
    Mutation(
        "camera-margin-y",
        CAMERA_F,
        "hx, hy = half_x / margin_x, half_y / margin_y",
        "hx, hy = half_x / margin_x, half_y / margin_x",
        "shadow_camera: the window's height divided by the x margin",
        CAMERA,
    ),
    Mutation(
        "camera-look-plus-z",
        CAMERA_F,
        '"+z": (-r, u, f)}[look]',
        '"+z": (r, u, f)}[look]',
        "camera_to_world: look '+z' with right instead of -right (a reflection)",
        CAMERA,
    ),
    Mutation(
        "camera-cascade-origin",
        CAMERA_F,
        "origin = -xp.sum(R * t[..., :, None], axis=-2)",
        "origin = -xp.sum(R * t[..., :, None], axis=-1)",
        "shadow_camera of cascades: the eye -R t instead of -R^T t",
        CAMERA,
    ),
    # the map's volume: a perspective Frustum or an OrthographicBox, by type
    Mutation(
        "volume-always-frustum",
        "shadowmath/_math/_frustum.py",
        "return OrthographicBox._make(fields) if directional else Frustum._make(fields)",
        "return Frustum._make(fields)",
        "a directional light's fit returns a perspective Frustum instead of its box",
        ("tests/test_orthographic_box.py::test_each_fit_returns_the_type_of_its_light",),
    ),
    Mutation(
        "projection-ignores-box",
        "shadowmath/_math/_frustum.py",
        "    if not isinstance(fr, OrthographicBox):",
        "    if isinstance(fr, Frustum | OrthographicBox):",
        "blocker_projection of an OrthographicBox gives the perspective matrix",
        ("tests/test_orthographic_box.py::test_the_projection_follows_the_type",),
    ),
    # cube depth ranges
    Mutation(
        "cube-depth-border-scale",
        CUBE_DEPTH_F,
        "return k * d_min * (1 - NEAR_FAR_SLACK), d_max * (1 + NEAR_FAR_SLACK), ok",
        "return d_min * (1 - NEAR_FAR_SLACK), d_max * (1 + NEAR_FAR_SLACK), ok",
        "cube_depth_core: near not scaled by the border ring's window k",
        CUBE_DEPTH,
    ),
    Mutation(
        "cube-depth-receivers-signed",
        CUBE_DEPTH_F,
        "xp.max(xp.abs(corners - light[..., None, :]), axis=(-2, -1))",
        "xp.max(corners - light[..., None, :], axis=(-2, -1))",
        "cube_depth_core: receivers' distance without |.| (those below the light missed)",
        CUBE_DEPTH,
    ),
    Mutation(
        "cube-depth-edge-beyond-end",
        CUBE_DEPTH_F,
        "inside = ok & (s >= 0) & (s <= 1)",
        "inside = ok & (s >= 0)",
        "triangle_min_chebyshev: edge candidates past the edge's end counted",
        CUBE_DEPTH,
    ),
    Mutation(
        "cube-depth-diagonal-outside",
        CUBE_DEPTH_F,
        "inside = ok & (t > 0) & xp.all(side >= 0, axis=0)",
        "inside = ok & (t > 0)",
        "triangle_min_chebyshev: a diagonal crossing the triangle's plane outside it counted",
        CUBE_DEPTH,
    ),
    Mutation(
        "cube-depth-candidates",
        CUBE_DEPTH_F,
        "(gap != bound) & (gap <= bound + _KEEP_ULPS * eps * size)",
        "(gap != bound) & (gap <= 0.5 * bound)",
        "nearest_triangle: triangles whose box comes within twice the bound skipped",
        CUBE_DEPTH,
    ),
    Mutation(
        "cube-tie-y-over-x",
        CUBE_F,
        "use_y = xp.logical_not(use_z) & (ay >= ax)",
        "use_y = xp.logical_not(use_z) & (ay > ax)",
        "_major_face: a tie |y| = |x| goes to x (Vulkan: y wins over x)",
        CUBE,
    ),
    Mutation(
        "cube-depth-reversed",
        CUBE_F,
        "return near * (far - D) / (span * D)",
        "return far * (far - D) / (span * D)",
        "cube_face_depth: reversed depth f (f - D) / ((f - n) D) instead of n (f - D) / ...",
        ("tests/test_cube.py::test_cube_face_depth_is_the_depth_the_face_projection_stores",),
    ),
    Mutation(
        "cube-projection-zero-to-one-reversed",
        CUBE_F,
        "return n / span, f * n / span",
        "return f / span, f * n / span",
        "cube_face_projection: [0, 1] reversed depth's a = f / (f - n) instead of n / (f - n)",
        ("tests/test_cube.py::test_depth_range_of_each_api",),
    ),
    Mutation(
        "cube-face-scale",
        "shadowmath/_geometry/_cube_faces.py",
        "return (size - 2 * border) / size",
        "return (size - border) / size",
        "face_scale: (N - b) / N instead of (N - 2 b) / N (one side's ring only)",
        ("tests/test_cube.py::test_the_texel_drawn_for_p_is_the_texel_sampled_with_p_minus_light",),
    ),
    Mutation(
        "cube-face-st-swapped",
        CUBE_F,
        "return face, (sc / ma + 1) / 2, (tc / ma + 1) / 2",
        "return face, (tc / ma + 1) / 2, (sc / ma + 1) / 2",
        "cube_face: s and t swapped",
        CUBE,
    ),
    # bias
    Mutation(
        "bias-reach-bilinear",
        BIAS_F,
        'return radius + (1.0 if filter == "bilinear" else 0.5)',
        "return radius + 0.5",
        "_reach: a bilinear kernel's reach k + 1/2 instead of k + 1",
        BIAS,
    ),
    Mutation(
        "bias-gradient-perspective",
        BIAS_F,
        "grads = (M[..., :3, :3] - uvw[..., :, None] * M[..., 3:, :3]) / q[..., None]",
        "grads = M[..., :3, :3] / q[..., None]",
        "_texture_gradients: the quotient rule's q-gradient term dropped",
        BIAS,
    ),
    Mutation(
        "bias-slope-height",
        BIAS_F,
        "y = xp.where(edge_on, inf, xp.abs(dr_dt / (safe * H)))",
        "y = xp.where(edge_on, inf, xp.abs(dr_dt / (safe * W)))",
        "_depth_slope: the slope along t per texel of the width W instead of the height H",
        BIAS,
    ),
    Mutation(
        "bias-texel-across-ray",
        BIAS_F,
        "det = xp.abs(dot(xp, cross(xp, gs, gt), n))",
        "det = norm(xp, cross(xp, gs, gt))",
        "texel_world_size on a surface: the texel across the ray (surface tilt ignored)",
        BIAS,
    ),
    Mutation(
        "bias-normal-offset-unnormalised",
        BIAS_F,
        "along_ray = xp.abs(dot(xp, gr, D)) / length",
        "along_ray = xp.abs(dot(xp, gr, D))",
        "_normal_offset: grad r . D not divided by |D|",
        BIAS,
    ),
    Mutation(
        "bias-depth-bits",
        "shadowmath/_geometry/_depth_bias.py",
        "r_min = 1.0 / (2.0**depth_bits - 1)",
        "r_min = 1.0 / 2.0**depth_bits",
        "slope_scaled_bias: a fixed-point depth step 1 / 2^b instead of 1 / (2^b - 1)",
        BIAS,
    ),
    # PCF
    Mutation(
        "pcf-border",
        PCF_F,
        "return max(1, math.ceil(kernel_reach(radius, filter) - 0.5))",
        "return max(1, math.ceil(kernel_reach(radius, filter) - 1.0))",
        "pcf_border_texels: a bilinear kernel's border a texel short",
        PCF,
    ),
    Mutation(
        "pcf-bilinear-centre",
        PCF_F,
        "u = coords[..., 0] * W - 0.5",
        "u = coords[..., 0] * W",
        "pcf bilinear: the weights measured from texel corners, not centres",
        PCF,
    ),
    Mutation(
        "pcf-compare-reversed",
        PCF_F,
        "margin = depths - stored if reversed_z else stored - depths",
        "margin = stored - depths",
        "pcf: reversed-z compares as if not reversed",
        PCF,
    ),
    Mutation(
        "pcf-smoothstep",
        PCF_F,
        "return x * x * (3 - 2 * x)",
        "return x * x",
        "pcf softness: x^2 instead of the smoothstep 3x^2 - 2x^3",
        ("tests/test_pcf.py::test_softness_is_exact_away_from_the_stored_depth",),
    ),
    Mutation(
        "pcf-box-normalise",
        PCF_F,
        "fraction = xp.clip(total / (2 * radius + 1) ** 2, 0.0, 1.0)",
        "fraction = xp.clip(total / (2 * radius + 2) ** 2, 0.0, 1.0)",
        "pcf: the sum divided by (2k + 2)^2 taps instead of (2k + 1)^2",
        PCF,
    ),
    Mutation(
        "pcf-rows-bound",
        PCF_F,
        "(rows >= 0) & (rows <= H - 1)",
        "(rows >= 0) & (rows <= W - 1)",
        "pcf: rows past the map's height read when the map is wider than high",
        PCF,
    ),
    # spot light caster selection
    Mutation(
        "spot-side-plane",
        SPOT_F,
        "n = xp.stack([tz - X, tz + X, tz - Y, tz + Y, Z], axis=-2)",
        "n = xp.stack([tz - X, tz + X, tz - Y, tz - Y, Z], axis=-2)",
        "pyramid_planes: the -y side plane is the +y side's",
        SPOT,
    ),
    Mutation(
        "spot-drop-any-side",
        SPOT_F,
        "reaches = xp.all(xp.any(front & (g[..., :4] > -tau[..., :4]), axis=-2), axis=-1)",
        "reaches = xp.any(xp.any(front & (g[..., :4] > -tau[..., :4]), axis=-2), axis=-1)",
        "points_kept: a set outside one side plane kept if it reaches another",
        SPOT,
    ),
    Mutation(
        "spot-empty-square-wide",
        SPOT_F,
        "s = xp.minimum(t, 1.0)[..., None, None]",
        "s = xp.maximum(t, 1.0)[..., None, None]",
        "empty_square: the empty fit's square wider than a narrow cone",
        SPOT,
    ),
    Mutation(
        "spot-clip-outside-kept",
        SPOT_F,
        "inside = exists & xp.all(values >= -tau, axis=-1)",
        "inside = exists",
        "clip_triangles: candidate points outside the pyramid kept",
        SPOT,
    ),
    Mutation(
        "spot-caster-depth-min",
        SPOT_F,
        "depth = xp.max(xp.abs(z), axis=-1)",
        "depth = xp.min(xp.abs(z), axis=-1)",
        "caster_depth: the nearest caster's depth instead of the farthest",
        SURVIVORS,
    ),
    # soft shadows
    Mutation(
        "soft-grid-columns-rows",
        SOFT_F,
        "u = (col + jitter[..., 0]) / cols",
        "u = (col + jitter[..., 0]) / rows",
        "area light samples: u divided by the rows instead of the columns",
        SOFT,
    ),
    Mutation(
        "soft-grid-not-square",
        SOFT_F,
        "rows = max(d for d in range(1, math.isqrt(count) + 1) if count % d == 0)",
        "rows = min(d for d in range(1, math.isqrt(count) + 1) if count % d == 0)",
        "area light samples: a 1 x count strip instead of the most nearly square grid",
        ("tests/test_soft.py::test_one_sample_in_each_cell_of_the_most_nearly_square_grid",),
    ),
    Mutation(
        "soft-z-row-sign",
        SOFT_F,
        "row_z = e4 - row_w",
        "row_z = row_w - e4",
        "pyramid_to_unit_cube: z = 1 - 1/w instead of 1/w - 1",
        ("tests/test_soft.py::test_points_on_a_ray_from_the_apex_share_x_y",),
    ),
    Mutation(
        "soft-w-through-base",
        SOFT_F,
        "row_w = _row(xp, n_w, a, dot(xp, n_w, ew))",
        "row_w = _row(xp, n_w, b, dot(xp, n_w, ew))",
        "pyramid_to_unit_cube: W = 0 on the base instead of at the apex",
        SOFT,
    ),
    # gather
    Mutation(
        "gather-face-offset",
        GATHER_F,
        "offset += int(V.shape[0])",
        "offset += int(V.shape[0]) - 1",
        "gather_meshes: faces of later meshes offset one vertex short",
        GATHER,
    ),
    Mutation(
        "gather-transform-transpose",
        GATHER_F,
        "V @ xp.matrix_transpose(M[:3, :3]) + M[:3, 3]",
        "V @ M[:3, :3] + M[:3, 3]",
        "gather_meshes: vertices multiplied by A^T instead of A",
        GATHER,
    ),
    Mutation(
        "gather-triangle-faces",
        GATHER_F,
        "faces = np.arange(3 * corners[0], dtype=np.int64).reshape(-1, 3)",
        "faces = np.arange(3 * corners[0], dtype=np.int64).reshape(3, -1).T",
        "gather_meshes: Triangles' faces read column-wise (corners of different triangles)",
        GATHER,
    ),
    # the pygfx integration
    Mutation(
        "pygfx-view-offset-top",
        PYGFX_F,
        "camera.set_view_offset(2.0 * X, 2.0 * Y, lo + X, Y - t, r - lo, t - b)",
        "camera.set_view_offset(2.0 * X, 2.0 * Y, lo + X, b + Y, r - lo, t - b)",
        "set_shadow_camera: the view offset's y from the bottom, not the top-left corner",
        PYGFX,
    ),
    Mutation(
        "pygfx-up-face-as-pygfx-aims-it",
        PYGFX_F,
        "        _turn_up_face(shadow, light)",
        "        pass",
        "point light's +Y face left as pygfx 0.17 aims it (looking away from +Y)",
        ("tests/render/test_pygfx.py::test_pygfx_point_light_faces_as_the_shader_reads_them",),
    ),
    Mutation(
        "pygfx-fov",
        PYGFX_F,
        "half_tan = 0.5 * (X + Y)",
        "half_tan = max(X, Y)",
        "set_shadow_camera: pygfx's fov from max(X, Y) instead of (X + Y) / 2",
        PYGFX,
    ),
)


# --- the survivors of issue 35 and the newest modules: the scene (scene.py, _scene/), the
# spot light's clipping loop, the atlas redraw, pcss_parameters' recorded map size, the
# placement check and the float32-precision warning.

PYGFX_RULES = ("tests/render/test_pygfx_fit_rules.py",)
SCENE_F = "shadowmath/scene.py"
SCENE = ("tests/test_scene.py",)
CULL_F = "shadowmath/_scene/_cull.py"
SUMMARY_F = "shadowmath/_scene/_summary.py"
SPOT_LOOP_F = "shadowmath/_math/_spot_loop.py"
SPOT_LOOP = ("tests/test_spot_clip_paths.py",)
REDRAW_F = "shadowmath/_fits/atlas/_redraw.py"
REDRAW = ("tests/test_scene.py", "tests/test_atlas_identity.py")
PCSS_MAPS_F = "shadowmath/_fits/pcss/_maps.py"
PCSS = ("tests/test_pcss.py",)
DOOR_F = "shadowmath/_fits/shadow/_door.py"
PRECISION = ("tests/test_degenerate.py", "tests/test_input_kinds.py")
PLACEMENT = ("tests/test_refusals.py", "tests/test_errors.py")

# Equivalent mutants left out (tried on 2026-11-29, no result can change): in a sun's
# scene fit a caster that is not a candidate lies inside the candidates' box on every
# axis (a candidate lies wholly beyond it both ways), so a caster's corners are never
# past the box's far or near plane ("a summary's corners past far judged inside",
# "inside_box: a caster before near judged inside"), and casters left out of the
# candidates are refitted in by the loop ("sun_candidates one way only": slower, same fit).
NEWEST: tuple[Mutation, ...] = (
    # the ten survivors of issue 35 (the three older ones are cascade-pad-min,
    # splits-far-equals-near and atlas-hysteresis-upper above)
    Mutation(
        "pcss-array-radius-zero",
        "shadowmath/_fits/pcss/_driver.py",
        "return xp.isfinite(R) & (R >= 0)",
        "return xp.isfinite(R) & (R > 0)",
        "pcss_parameters (its one radius check): a light radius of 0 (a point light) refused",
        SURVIVORS,
    ),
    Mutation(
        "spot-casters-used-axis",
        "shadowmath/_fits/shadow/_spot_select.py",
        "np.full(shape, casters.shape[-2], dtype=np.int64)",
        "np.full(shape, casters.shape[0], dtype=np.int64)",
        "spot selection: casters_used of points all kept counted along the batch axis",
        SURVIVORS,
    ),
    Mutation(
        "optimized-spot-by-name",
        DOOR_F,
        "options = key.directional or key.spot or key.has_receivers",
        "options = key.directional or key.has_receivers",
        "fit_shadow(SpotLight, method='optimized') not refused by name",
        SURVIVORS,
    ),
    Mutation(
        "fitter-shape-unchecked",
        "shadowmath/_fits/shadow/_prepared.py",
        "if door.key != self._door.key or door.shape != self._door.shape or (",
        "if door.key != self._door.key or (",
        "ShadowFitter.fit: another batch shape taken for the prepared one",
        SURVIVORS,
    ),
    Mutation(
        "pygfx-receivers-dropped",
        PYGFX_F,
        "receives=receive)  # fmt: skip",
        "receives=False)  # fmt: skip",
        "fit_scene_shadows: the receivers left out of the fits (the floor clipped)",
        PYGFX_RULES,
    ),
    Mutation(
        "pygfx-self-aimed-up",
        PYGFX_F,
        "\n        aim = np.array([0.0, 0.0, -1.0])",
        "\n        aim = np.array([0.0, 1.0, 0.0])",
        "fit_scene_shadows: a light aimed at its own position fitted up +y, not down -z",
        PYGFX_RULES,
    ),
    Mutation(
        "pygfx-box-border",
        PYGFX_F,
        'PYGFX_SHADOW_MAP_SIZE, pcf_radius=pcf_radius, pcf_filter="bilinear", api="webgpu"',
        'PYGFX_SHADOW_MAP_SIZE, pcf_radius=pcf_radius, pcf_filter="box", api="webgpu"',
        "fit_scene_shadows: the box filter's border (2 texels) for pygfx's bilinear taps (3)",
        PYGFX_RULES,
    ),
    # the scene: ShadowScene's sun loop and triangles, the culling, the summaries
    Mutation(
        "scene-sun-no-refit",
        SCENE_F,
        "if not (out_c.any() or out_r.any()):",
        "if True:",
        "ShadowScene sun: objects sticking out of the candidates' box not refitted",
        SCENE,
    ),
    Mutation(
        "cull-box-receiver-far-end",
        CULL_F,
        "before_far = hi[:, 2] <= float(box.far)",
        "before_far = lo[:, 2] <= float(box.far)",
        "inside_box: a receiver straddling the far plane judged inside (not refitted)",
        SCENE,
    ),
    Mutation(
        "scene-sun-used-objects",
        SCENE_F,
        "used = np.asarray(np.count_nonzero(casts[self._owner]))",
        "used = np.asarray(np.count_nonzero(casts))",
        "ShadowScene sun: casters_used counts objects, not their summaries' triangles",
        SCENE,
    ),
    Mutation(
        "scene-around-light-summary",
        SCENE_F,
        "around = objects & (np.linalg.norm(self._center - light, axis=1) <= self._radius)",
        "around = objects & (np.linalg.norm(self._center - light, axis=1) < 0.0)",
        "ShadowScene spot: an object around the light fitted by its summary (holding the light)",
        (*SCENE, "tests/render/test_pygfx_scene.py"),
    ),
    Mutation(
        "cull-world-radius-unscaled",
        CULL_F,
        "return c, radius * stretch * (1 + 1e-12)",
        "return c, radius * (1 + 1e-12)",
        "world_spheres: the radius not stretched by the placement's largest singular value",
        SCENE,
    ),
    Mutation(
        "cull-spot-spread-half",
        CULL_F,
        "spread = angle + xp.arcsin(xp.clip(radius / safe, 0.0, 1.0))",
        "spread = angle + 0.5 * xp.arcsin(xp.clip(radius / safe, 0.0, 1.0))",
        "spot_visible: the sphere's angular radius halved (spheres reaching in dropped)",
        SCENE,
    ),
    Mutation(
        "cull-spot-around-apex",
        CULL_F,
        "inside = dist <= radius",
        "inside = dist <= 0.5 * radius",
        "spot_visible: a sphere holding the apex judged by its angle (dropped behind the cone)",
        SCENE,
    ),
    Mutation(
        "cull-clip-half-radius",
        CULL_F,
        "return xp.all(value >= -radius, axis=-2)",
        "return xp.all(value >= -0.5 * radius, axis=-2)",
        "the clip rule: a sphere kept only when reaching in by half its radius",
        SCENE,
    ),
    Mutation(
        "cull-cube-near-far-end",
        CULL_F,
        "near = casts & (lo <= np.min(hi[casts], initial=np.inf))",
        "near = casts & (hi <= np.min(hi[casts], initial=np.inf))",
        "cube_range_candidates: near candidates by their far end (the nearest caster missed)",
        SCENE,
    ),
    Mutation(
        "cull-cube-far-receivers",
        CULL_F,
        "    either = casts | receives\n",
        "    either = casts\n",
        "cube_range_candidates: receivers left out of the far candidates",
        SCENE,
    ),
    Mutation(
        "cull-interval-box-upper",
        CULL_F,
        "np.minimum(p + radius[:, None], q + half)",
        "np.minimum(p + radius[:, None], q)",
        "light_intervals: the upper end cut at the box's centre (objects judged inside)",
        SCENE,
    ),
    Mutation(
        "cull-interval-signed-rotation",
        CULL_F,
        "half = mid @ R.T + t, 0.5 * (bounds[:, 1] - bounds[:, 0]) @ np.abs(R).T",
        "half = mid @ R.T + t, 0.5 * (bounds[:, 1] - bounds[:, 0]) @ R.T",
        "light_intervals: a box's half-extents rotated with signs (not |R|): too small",
        SCENE,
    ),
    Mutation(
        "summary-sphere-mean",
        SUMMARY_F,
        "radius = float(np.max(np.linalg.norm(points - center, axis=1)))",
        "radius = float(np.mean(np.linalg.norm(points - center, axis=1)))",
        "a summary's sphere of the mean distance (not holding every point)",
        SCENE,
    ),
    Mutation(
        "summary-corners-strict",
        SUMMARY_F,
        "feasible = np.all(x @ DIRECTIONS.T <= h + 4 * eps, axis=1)",
        "feasible = np.all(x @ DIRECTIONS.T <= h - 4 * eps, axis=1)",
        "a summary's corners on its planes refused (the hull loses corners)",
        SCENE,
    ),
    # the spot light's clipping loop (run in Python by its tests without Numba)
    Mutation(
        "spot-loop-edge-end",
        SPOT_LOOP_F,
        "return s, den != 0 and s >= 0 and s <= 1",
        "return s, den != 0 and s >= 0",
        "spot_clip_loop: an edge's crossing past its end counted",
        SPOT_LOOP,
    ),
    Mutation(
        "spot-loop-dropped-two-corners",
        SPOT_LOOP_F,
        "if g0[k] < -2.0 * tau and g1[k] < -2.0 * tau and g2[k] < -2.0 * tau:",
        "if g0[k] < -2.0 * tau and g1[k] < -2.0 * tau:",
        "spot_clip_loop: a triangle dropped with two corners outside a side",
        SPOT_LOOP,
    ),
    Mutation(
        "spot-loop-lateral-sign",
        SPOT_LOOP_F,
        "ok = n0 * det >= 0 and n1 * det >= 0 and n2 * det >= 0 and det != 0",
        "ok = n0 * det >= 0 and n1 * det >= 0 and det != 0",
        "spot_clip_loop: a lateral edge's point outside the triangle kept",
        SPOT_LOOP,
    ),
    # the atlas redraw
    Mutation(
        "redraw-clip-ignored",
        REDRAW_F,
        "keep = had & same_port & same_clip",
        "keep = had & same_port",
        "atlas_redraw: a tile whose matrix changed kept",
        REDRAW,
    ),
    Mutation(
        "redraw-moved-ignored",
        REDRAW_F,
        "if set(drawn.tolist()) != set(was.tolist()) or changed[drawn].any():",
        "if set(drawn.tolist()) != set(was.tolist()):",
        "atlas_redraw: a tile one of whose objects moved kept",
        REDRAW,
    ),
    # pcss_parameters' recorded map size
    Mutation(
        "pcss-recorded-size-unchecked",
        PCSS_MAPS_F,
        "if given != tuple(recorded):",
        "if False:",
        "pcss_parameters: a map_size other than the fit's recorded one taken",
        PCSS,
    ),
    Mutation(
        "pcss-recorded-size-swapped",
        PCSS_MAPS_F,
        "    return recorded[0], recorded[1]\n",
        "    return recorded[1], recorded[0]\n",
        "pcss_parameters: the recorded width and height swapped",
        PCSS,
    ),
    # the placement check and the precision warning
    Mutation(
        "placement-w-unchecked",
        "shadowmath/_math/_fit_formulas.py",
        "maximum(fabs(b[14]), fabs(b[15] - 1.0)))",
        "maximum(fabs(b[14]), fabs(b[14])))",
        "placement_affine: a bottom row (0, 0, 0, w != 1) accepted",
        PLACEMENT,
    ),
    Mutation(
        "placement-absolute-tolerance",
        "shadowmath/_math/_fit_formulas.py",
        "return off <= 4.0 * eps * big",
        "return off <= 4.0 * eps",
        "placement_affine: the tolerance absolute, not relative to the matrix's scale",
        PLACEMENT,
    ),
    Mutation(
        "precision-one-texel",
        DOOR_F,
        "if p is not None and p.step > p.texel / TEXEL_FRACTION:",
        "if p is not None and p.step > p.texel:",
        "float32 warning: only past a whole texel, not a quarter",
        PRECISION,
    ),
    Mutation(
        "precision-light-ignored",
        DOOR_F,
        "big = max(big, abs(lx), abs(ly), abs(lz))",
        "big = max(big, 0.0 * lx)",
        "float32 warning: a light far from the origin not counted in the coordinates' size",
        PRECISION,
    ),
    # the array forms that keep the traced programs small: corners on a last axis, the
    # bounds as one reduction, the edges by strided slices, the rows as matrix products
    Mutation(
        "slice-array-edge",
        "shadowmath/_math/_cascade_steps.py",
        "n8 = tuple(xp.stack([nc[3 * (k & 3) + c] for k in range(8)], axis=-1) for c in range(3))",
        "n8 = tuple(xp.stack([nc[3 * (k & 1) + c] for k in range(8)], axis=-1) for c in range(3))",
        "slice corners (array form): two of the frustum's four edges read twice",
        CASCADES,
    ),
    Mutation(
        "box-array-bits",
        "shadowmath/_math/_cascade_steps.py",
        "x, y, z = (xp.stack([box[3 * ((k >> c) & 1) + c] for k in range(8)], axis=-1)",
        "x, y, z = (xp.stack([box[3 * ((k >> 1) & 1) + c] for k in range(8)], axis=-1)",
        "scene box corners (array form): every coordinate from one bit of k (a diagonal, not"
        " the box; swapping two bits would be equivalent: the same corners and edges)",
        CASCADES,
    ),
    Mutation(
        "edge-ends-along-k",
        "shadowmath/_math/_cascade_bounds.py",
        "xp.concat([v[..., 1::2], along_j[1], v[..., 4:]], axis=-1)",
        "xp.concat([v[..., 1::2], along_j[1], v[..., :4]], axis=-1)",
        "cascade body (array form): the edges along k end where they start",
        CASCADES,
    ),
    Mutation(
        "body-bounds-low-sign",
        "shadowmath/_math/_cascade_bounds.py",
        "low = [-b6[..., 2 * c, :] for c in range(3)]",
        "low = [b6[..., 2 * c, :] for c in range(3)]",
        "cascade bounds (array form): the minimum read without its sign",
        CASCADES,
    ),
    Mutation(
        "rows-array-transposed",
        "shadowmath/_math/_fit_formulas.py",
        "matmul(xp, xp.asarray(np.reshape(c, (4, 4)), dtype=G.dtype), G)",
        "matmul(xp, xp.asarray(np.reshape(c, (4, 4)).T, dtype=G.dtype), G)",
        "fit rows (array form): the API's constant matrix transposed",
        CASCADES,
    ),
    Mutation(
        "row-parts-transposed",
        "shadowmath/_fits/cascades/_driver.py",
        "parts.append(xp.broadcast_to(xp.reshape(m, (*m.shape[:-2], 16)), (*full, 16)))",
        "parts.append(xp.broadcast_to(xp.reshape(xp.swapaxes(m, -1, -2), (*m.shape[:-2], 16)),"
        " (*full, 16)))",
        "cascades' rows (array form): a matrix kept whole written column-major",
        CASCADES,
    ),
)


#: The whole table: the fits' mutations, every other module's, then the newest modules'.
ALL: tuple[Mutation, ...] = MUTATIONS + MODULES + NEWEST


class RunnerError(Exception):
    """The run itself failed (exit status 2): not a verdict on any mutation."""


# A mutated run's pytest outcome, as the table says it.
RESULTS = {"failed": "killed", "passed": "SURVIVED"}


@dataclass(frozen=True)
class Outcome:
    """The result of one pytest run."""

    status: str  # "passed", "failed", or "ERROR ..." (timeout, pytest usage or internal error)
    first_failure: str
    seconds: float


def copy_repo(repo: Path, into: Path) -> None:
    """Copy the package and its tests (no caches) into ``into``."""
    for name in COPIED:
        source = repo / name
        if source.is_dir():
            shutil.copytree(source, into / name, ignore=IGNORED)
        elif source.is_file():
            shutil.copy2(source, into / name)
        else:
            raise RunnerError(f"mutations: {source} is missing")


def mutate(mutation: Mutation, text: str) -> str:
    """``text`` with the mutation applied; its original text must occur exactly once."""
    count = text.count(mutation.original)
    if count != 1:
        raise RunnerError(
            f"mutations: {mutation.id}: the original text occurs {count} times in "
            f"{mutation.file} (expected exactly once):\n{mutation.original}"
        )
    return text.replace(mutation.original, mutation.mutated)


def apply(mutation: Mutation, root: Path) -> None:
    """Apply ``mutation`` to the copy of the repository in ``root``."""
    path = root / mutation.file
    path.write_text(mutate(mutation, path.read_text(encoding="utf-8")), encoding="utf-8")


def environment(root: Path) -> dict[str, str]:
    env = dict(os.environ)
    env["SHADOWMATH_NUMBA"] = "0"
    # The render tests (the pygfx integration's) fail instead of skipping without a GPU
    # API: a skipped test would let every mutation it should kill "survive".
    env.setdefault("SHADOWMATH_REQUIRE_GL", "1")
    env["PYTHONPATH"] = str(root)
    env["PYTHONDONTWRITEBYTECODE"] = "1"
    return env


def check_import(root: Path) -> None:
    """Fail unless ``shadowmath`` is imported from ``root`` (not an installed copy)."""
    out = subprocess.run(
        [sys.executable, "-c", "import shadowmath; print(shadowmath.__file__)"],
        cwd=root,
        env=environment(root),
        capture_output=True,
        text=True,
        check=False,
    )
    where = Path(out.stdout.strip() or "?").resolve()
    if out.returncode != 0 or root.resolve() not in where.parents:
        raise RunnerError(
            f"mutations: shadowmath is imported from {where}, not from the copy in {root}:\n"
            f"{out.stderr}"
        )


def first_failure(output: str) -> str:
    """The first ``FAILED``/``ERROR`` node of pytest's short summary, or ``""``."""
    for line in output.splitlines():
        for tag in ("FAILED ", "ERROR "):
            if line.startswith(tag):
                return line[len(tag) :].split(" - ", 1)[0].strip()
    return ""


def run_tests(root: Path, tests: Sequence[str], seed: int) -> Outcome:
    """``pytest -x`` on ``tests`` in the copy at ``root``."""
    command = [sys.executable, "-m", "pytest", "-x", "-q", "-p", "no:cacheprovider"]
    command += [f"--hypothesis-seed={seed}", *tests]
    start = time.perf_counter()
    try:
        out = subprocess.run(
            command,
            cwd=root,
            env=environment(root),
            capture_output=True,
            text=True,
            timeout=TIMEOUT_S,
            check=False,
        )
    except subprocess.TimeoutExpired:
        return Outcome(f"ERROR timeout {TIMEOUT_S:.0f} s", "", time.perf_counter() - start)
    seconds = time.perf_counter() - start
    output = out.stdout + out.stderr
    failed = first_failure(output)
    if out.returncode == 0:
        return Outcome("passed", "", seconds)
    if out.returncode == 1:
        return Outcome("failed", failed, seconds)
    tail = output.strip().splitlines()[-1:] or [""]
    return Outcome(f"ERROR pytest exit {out.returncode}", failed or tail[0], seconds)


def run_one(repo: Path, mutation: Mutation | None, tests: Sequence[str], seed: int) -> Outcome:
    """Copy ``repo``, apply ``mutation`` (None: the baseline) and run ``tests`` there."""
    with tempfile.TemporaryDirectory(prefix="shadowmath-mutation-") as folder:
        root = Path(folder)
        copy_repo(repo, root)
        if mutation is not None:
            apply(mutation, root)
        check_import(root)
        return run_tests(root, tests, seed)


def table(rows: Iterable[Sequence[str]], header: Sequence[str]) -> str:
    """A plain-text table, columns padded to their widest cell."""
    cells = [list(header), *(list(r) for r in rows)]
    widths = [max(len(r[i]) for r in cells) for i in range(len(header))]
    lines = ["  ".join(c.ljust(w) for c, w in zip(r, widths, strict=True)).rstrip() for r in cells]
    lines.insert(1, "  ".join("-" * w for w in widths))
    return "\n".join(lines)


def select(only: Sequence[str] | None) -> tuple[Mutation, ...]:
    if not only:
        return ALL
    known = {m.id for m in ALL}
    unknown = [i for i in only if i not in known]
    if unknown:
        raise RunnerError(f"mutations: unknown id(s) {unknown}; --list shows them")
    return tuple(m for m in ALL if m.id in only)


def main(argv: Sequence[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--repo", type=Path, default=ROOT, help="checkout to mutate (copied)")
    parser.add_argument("--only", action="append", metavar="ID", help="run this mutation only")
    parser.add_argument("--list", action="store_true", help="list the mutations and exit")
    parser.add_argument(
        "--no-baseline", action="store_true", help="skip the unmutated run of the tests"
    )
    parser.add_argument("--seed", type=int, default=0, help="hypothesis seed (default 0)")
    args = parser.parse_args(argv)
    try:
        return run(args)
    except RunnerError as err:
        print(err, file=sys.stderr)
        return 2


def run(args: argparse.Namespace) -> int:
    """The run that :func:`main` parsed the options of; the exit status."""
    mutations = select(args.only)
    repo = args.repo.resolve()

    if args.list:
        listed = [(m.id, m.file, m.description, " ".join(m.tests)) for m in mutations]
        print(table(listed, ("id", "file", "description", "tests")))
        return 0

    # Every original text must be found before anything runs (fail loudly and early).
    for m in mutations:
        mutate(m, (repo / m.file).read_text(encoding="utf-8"))

    start = time.perf_counter()
    if not args.no_baseline:
        files = list(dict.fromkeys(t for m in mutations for t in m.tests))
        base = run_one(repo, None, files, args.seed)
        print(
            f"baseline (unmutated, {len(files)} test files): {base.status} in {base.seconds:.0f} s"
        )
        if base.status != "passed":  # the unmutated code must pass its own tests
            print(f"mutations: the baseline fails ({base.first_failure}); nothing to measure")
            return 2

    rows: list[tuple[str, ...]] = []
    results = []
    for m in mutations:
        outcome = run_one(repo, m, m.tests, args.seed)
        result = RESULTS.get(outcome.status, outcome.status)
        results.append(result)
        seconds = f"{outcome.seconds:.0f}"
        rows.append((m.id, m.description, result, outcome.first_failure, seconds))
        print(f"{m.id}: {result} in {seconds} s", flush=True)
    print()
    print(table(rows, ("id", "description", "result", "first failing test", "s")))
    survived = results.count("SURVIVED")
    errors = sum(r.startswith("ERROR") for r in results)
    total = time.perf_counter() - start
    print(
        f"\n{results.count('killed')} killed, {survived} survived, {errors} errors in {total:.0f} s"
    )
    if errors:
        return 2
    return 1 if survived else 0


if __name__ == "__main__":
    sys.exit(main())
