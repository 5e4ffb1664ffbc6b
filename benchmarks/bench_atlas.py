"""Shadow atlas for many lights: per-frame cost, atlas use and tile stability.

``python benchmarks/bench_atlas.py [--tiny]`` runs it alone; ``make bench`` runs it as the
section ``atlas`` (``--only atlas``).

**Scene.** 64 lights over a yard of 16 boxes (128 shared caster vertices): 16 point lights
with cube maps (6 face tiles each), 32 spot lights (cone half-angle 0.8 rad, aimed at the
yard) and 16 directional lights; each light's screen coverage is drawn once
(``uniform(0, 0.6)²``, seeded), the atlas is 8192² with a PCF border of 2 texels and the
default budget (the whole atlas).

**Speed.** One frame = ``allocate_atlas`` (with the previous frame's atlas) plus
``fit_atlas`` of the 64 lights, as installed (the ``fast`` extra's compiled loops) and with
NumPy alone; also the first frame (no previous atlas). The baseline, timed in the same
process, is the obvious loop: one public ``sm.fit_shadow`` per 2D light and
``sm.cube_face_views`` + ``sm.cube_face_projection`` per cube light, on the same tiles.

**Stability and use.** 120 frames in which every light moves a little (positions by up to
1 cm, coverage by up to 3 %): tiles moved in total (the issue: zero when no size class
changes); then one cube light's coverage grows four times (its six tiles, and no other,
move); the fraction of the atlas used. Nothing is asserted about time.
"""

from __future__ import annotations

import os
import sys
from typing import Any

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))

from speed._timing import Config, Row, Section, measure, numpy_alone, run_alone

import shadowmath as sm

# Until shadowmath exports them (sm.allocate_atlas, ...), from their module.
from shadowmath._fits.atlas._allocate import ShadowAtlas, allocate_atlas
from shadowmath._fits.atlas._door import fit_atlas
from shadowmath._fits.atlas._viewports import atlas_tile_transforms

NAME = "atlas"
TITLE = "Shadow atlas: 64 lights allocated and fitted per frame, atlas use, tiles moved"

LIGHTS = 64
ATLAS = 8192
BORDER = 2
TARGET = 1e-3  # seconds per frame, allocate + fit, with the fast extra
FRAMES = 120


def yard(seed: int) -> tuple[np.ndarray, list[Any], np.ndarray, np.ndarray]:
    """Casters (16 boxes), 64 lights, their cube flags and coverages."""
    rng = np.random.default_rng(seed)
    corners = np.array([[x, y, z] for x in (-0.5, 0.5) for y in (0.0, 1.5) for z in (-0.5, 0.5)])
    centres = rng.uniform(-8, 8, (16, 3)) * [1, 0, 1] + [0, 0.1, 0]
    verts = (centres[:, None, :] + corners).reshape(-1, 3)
    lights: list[Any] = []
    cube = np.zeros(LIGHTS, dtype=bool)
    for i in range(LIGHTS):
        if i % 4 == 0:
            lights.append(sm.PointLight(rng.uniform(-8, 8, 3) * [1, 0, 1] + [0, 4.0, 0]))
            cube[i] = True
        elif i % 4 == 3:
            lights.append(sm.DirectionalLight(np.array([rng.uniform(-0.5, 0.5), 1.0, 0.3])))
        else:
            p = rng.uniform(-10, 10, 3) * [1, 0, 1] + [0, 12.0, 0]
            lights.append(sm.SpotLight(p, -p, np.array(0.8)))
    coverage = rng.uniform(0, 0.6, LIGHTS) ** 2
    return verts, lights, cube, coverage


def moved_a_little(lights: list[Any], rng: np.random.Generator) -> list[Any]:
    out: list[Any] = []
    for light in lights:
        nudge = rng.uniform(-0.01, 0.01, 3)
        if isinstance(light, sm.SpotLight):
            out.append(sm.SpotLight(light.position + nudge, light.direction, light.angle))
        elif isinstance(light, sm.PointLight):
            out.append(sm.PointLight(light.position + nudge))
        else:
            out.append(light)
    return out


def baseline_loop(lights: list[Any], verts: np.ndarray, atlas: ShadowAtlas) -> list[np.ndarray]:
    """The obvious per-light loop of public calls on the same tiles."""
    T = atlas_tile_transforms(atlas)
    out = []
    for i, light in enumerate(lights):
        n = int(atlas.light_size[i])
        if n == 0:
            continue
        b = int(atlas.light_border[i])
        if atlas.light_cube[i]:
            L = light.position
            D = np.abs(verts - L).max(axis=1)
            k = (n - 2 * b) / n
            P = sm.cube_face_projection(k * D.min() * (63 / 64), D.max() * (65 / 64),
                                        map_size=n, border_texels=b)  # fmt: skip
            V = sm.cube_face_views(L)
            for face in range(6):
                out.append(T[atlas.light_tiles[i, face]] @ P @ V[face])
        else:
            s = sm.fit_shadow(light, verts, n, border_texels=b)
            out.append(T[atlas.light_tiles[i, 0]] @ s.world_to_texture)
    return out


def stability(section: Section, seed: int, frames: int) -> None:
    verts, lights, cube, coverage = yard(seed)
    rng = np.random.default_rng(seed + 1)
    atlas = allocate_atlas(coverage, atlas_size=ATLAS, cube=cube, border_texels=BORDER)
    moved = 0
    for _ in range(frames):
        lights = moved_a_little(lights, rng)
        cov = coverage * rng.uniform(0.97, 1.03, LIGHTS)
        atlas = allocate_atlas(cov, atlas_size=ATLAS, cube=cube, border_texels=BORDER,
                               previous=atlas)  # fmt: skip
        fit_atlas(lights, verts, atlas)
        moved += int(atlas.moved.sum())
    # The smallest cube light grows fourfold: its class changes; under the budget others'
    # may too (they move, as they must); a light whose size stays must not move.
    cubes = np.flatnonzero(cube & (atlas.light_size > 0))
    light = int(cubes[np.argmin(atlas.light_size[cubes])])
    grown = coverage.copy()
    grown[light] *= 4.0
    after = allocate_atlas(grown, atlas_size=ATLAS, cube=cube, border_texels=BORDER,
                           previous=atlas)  # fmt: skip
    same = after.light_size == atlas.light_size
    steady = same[after.tile_light]
    changed = int((~same).sum())
    section.figures.update(
        {
            "tiles": float(atlas.tile_light.size),
            "lights_with_tile": float((atlas.light_size > 0).sum()),
            "used": atlas.used,
            "moved_small_motion_total": float(moved),
            "frames": float(frames),
            "class_change_lights_resized": float(changed),
            "class_change_tiles_moved": float(after.moved.sum()),
            "class_change_unresized_tiles_moved": float(after.moved[steady].sum()),
        }
    )
    section.notes.append(
        f"Atlas: {atlas.tile_light.size} tiles ({int((atlas.light_size > 0).sum())} of "
        f"{LIGHTS} lights with a tile), {atlas.used:.1%} of the {ATLAS}² atlas used. Small "
        f"motion over {frames} frames: {moved} tiles moved. Cube light {light} from "
        f"{int(atlas.light_size[light])} to {int(after.light_size[light])} texels: {changed} "
        f"light(s) resized (the budget), {int(after.moved.sum())} tiles moved, "
        f"{int(after.moved[steady].sum())} of them of a light whose size did not change."
    )


def speed(cfg: Config, section: Section) -> None:
    verts, lights, cube, coverage = yard(cfg.seed)
    first = allocate_atlas(coverage, atlas_size=ATLAS, cube=cube, border_texels=BORDER)
    nudged = coverage * np.random.default_rng(cfg.seed).uniform(0.98, 1.02, LIGHTS)
    repeats, min_time = cfg.repeats(15), cfg.min_time

    def frame() -> object:
        atlas = allocate_atlas(nudged, atlas_size=ATLAS, cube=cube, border_texels=BORDER,
                               previous=first)  # fmt: skip
        return fit_atlas(lights, verts, atlas)

    def first_frame() -> object:
        atlas = allocate_atlas(coverage, atlas_size=ATLAS, cube=cube, border_texels=BORDER)
        return fit_atlas(lights, verts, atlas)

    def allocate_only() -> object:
        return allocate_atlas(nudged, atlas_size=ATLAS, cube=cube, border_texels=BORDER,
                              previous=first)  # fmt: skip

    base_label = "loop of public fit_shadow / cube_face_* per light"
    base = measure(lambda: baseline_loop(lights, verts, first), repeats=repeats, min_time=min_time)
    installed = measure(frame, repeats=repeats, min_time=min_time)
    fresh = measure(first_frame, repeats=repeats, min_time=min_time)
    alloc = measure(allocate_only, repeats=repeats, min_time=min_time)
    with numpy_alone():
        alone = measure(frame, repeats=repeats, min_time=min_time)
        base_alone = measure(lambda: baseline_loop(lights, verts, first), repeats=repeats,
                             min_time=min_time)  # fmt: skip
    target = f"≤ {TARGET * 1e3:g} ms"
    section.rows += [
        Row(f"allocate + fit {LIGHTS} lights, a frame (as installed)", installed, base_label,
            base, target, TARGET, "seconds"),
        Row(f"allocate + fit {LIGHTS} lights, first frame (as installed)", fresh, base_label,
            base),
        Row(f"allocate_atlas alone, {LIGHTS} lights, a frame", alloc, base_label, base),
        Row(f"allocate + fit {LIGHTS} lights, a frame (NumPy alone)", alone,
            base_label + " (NumPy alone)", base_alone),
    ]  # fmt: skip
    section.notes.append(
        f"{LIGHTS} lights: 16 cube (96 face tiles), 32 spot, 16 directional; 128 shared "
        f"caster vertices; atlas {ATLAS}², border {BORDER}. 'A frame' passes the previous "
        "atlas (coverage within 2 %, no class change); 'first frame' lays the atlas out "
        "afresh. The baseline fits the same tiles one light at a time through the public "
        "functions. 'NumPy alone' disables the compiled loops (as without the `fast` extra)."
    )


def run(cfg: Config) -> Section:
    section = Section(NAME, TITLE)
    speed(cfg, section)
    stability(section, cfg.seed, cfg.size(FRAMES, 3))
    return section


def main(argv: list[str] | None = None) -> int:
    return run_alone(run, (__doc__ or "").splitlines()[0], "3 frames", argv)


if __name__ == "__main__":
    sys.exit(main())
