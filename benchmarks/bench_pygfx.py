"""pygfx: the per-frame cost of fitting a whole scene's shadows against drawing the frame.

``python benchmarks/bench_pygfx.py [--tiny]`` runs it alone; ``make bench`` runs it as the
section ``pygfx`` (``--only pygfx``).

**Scene.** A 12 x 12 floor, 8 boxes, 4 spheres and a torus knot (pygfx's own
geometries), each with its own world matrix (the knot under a group); a sun, a spot light
and a point light casting shadows. Every frame the meshes and lights move (as an
application animates them).

**Timed.** One frame's ``fit_scene_shadows(scene)`` (gather the casters and receivers
from the scene graph, fit the three lights, hand pygfx the shadow cameras; the scene's
motion, a few property sets, included) against pygfx drawing that frame offscreen
(``WgpuRenderer`` on a 640 x 480 ``rendercanvas.offscreen`` canvas, three shadow maps
and the picture, read back), both medians in the same process; also ``gather_scene``
alone. Without pygfx or a wgpu adapter the section is skipped.
"""

from __future__ import annotations

import argparse
import itertools
import os
import sys
from typing import Any

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))

from speed._timing import Config, Row, Section, measure, table

NAME = "pygfx"
TITLE = "pygfx: fit_scene_shadows per frame against pygfx drawing the frame"

SIZE = (640, 480)


def scene(gfx: Any, seed: int) -> tuple[Any, list[Any], list[Any], Any]:
    """(scene, moving meshes, lights, the knot's group)."""
    rng = np.random.default_rng(seed)
    world = gfx.Scene()
    floor = gfx.Mesh(gfx.plane_geometry(12, 12), gfx.MeshPhongMaterial())
    floor.receive_shadow = True
    world.add(floor)
    meshes = []
    shapes = [gfx.box_geometry(0.8, 0.8, 0.8)] * 8 + [gfx.sphere_geometry(0.4)] * 4
    for geometry in shapes:
        mesh = gfx.Mesh(geometry, gfx.MeshPhongMaterial())
        mesh.cast_shadow = mesh.receive_shadow = True
        mesh.local.position = (*rng.uniform(-4, 4, 2), 0.5)
        meshes.append(mesh)
        world.add(mesh)
    group = gfx.Group()
    knot = gfx.Mesh(gfx.torus_knot_geometry(0.6, 0.2), gfx.MeshPhongMaterial())
    knot.cast_shadow = knot.receive_shadow = True
    knot.local.position = (0, 0, 1.5)
    group.add(knot)
    world.add(group)
    sun = gfx.DirectionalLight(cast_shadow=True)
    spot = gfx.SpotLight(cast_shadow=True, angle=0.8)
    lamp = gfx.PointLight(cast_shadow=True)
    world.add(sun, sun.target, spot, spot.target, lamp, gfx.AmbientLight(intensity=0.2))
    return world, meshes, [sun, spot, lamp], group


def animate(frame: int, meshes: list[Any], lights: list[Any], group: Any) -> None:
    a = 2 * np.pi * (frame % 60) / 60
    for i, mesh in enumerate(meshes):
        mesh.local.euler_z = a + i
    group.local.euler_z = a
    sun, spot, lamp = lights
    sun.local.position = (3 * np.cos(a), 3 * np.sin(a), 5.0)
    spot.local.position = (-4.0, -4.0 + np.sin(a), 6.0)
    lamp.local.position = (np.cos(a), 1.0, 3.0)


def run(cfg: Config) -> Section:
    section = Section(NAME, TITLE)
    try:
        import pygfx as gfx
        from rendercanvas.offscreen import RenderCanvas

        canvas = RenderCanvas(size=SIZE, pixel_ratio=1)
        renderer = gfx.renderers.WgpuRenderer(canvas, pixel_scale=1)
    except Exception as err:  # no pygfx, no rendercanvas, or no wgpu adapter
        section.skipped = f"no pygfx offscreen renderer: {err}"
        return section
    from shadowmath.integrations.pygfx import fit_scene_shadows, gather_scene

    world, meshes, lights, group = scene(gfx, cfg.seed)
    camera = gfx.PerspectiveCamera(45, SIZE[0] / SIZE[1])
    camera.local.position = (6, -9, 8)
    camera.world.reference_up = (0, 0, 1)
    camera.look_at((0, 0, 0.5))
    frames = itertools.count()

    def fit() -> object:
        animate(next(frames), meshes, lights, group)
        return fit_scene_shadows(world)

    def draw() -> object:
        canvas.request_draw(lambda: renderer.render(world, camera))
        return canvas.draw()

    repeats = cfg.repeats(21)
    fit()  # the first frame's scene, fitted, before pygfx draws it
    drawn = measure(draw, repeats=repeats, warmup=2)
    fitted = measure(fit, repeats=repeats, min_time=cfg.min_time)
    gathered = measure(lambda: gather_scene(world), repeats=repeats, min_time=cfg.min_time)
    reports = fit_scene_shadows(world)
    skipped = [r.skipped for r in reports if r.skipped]
    base = f"pygfx draws the frame offscreen ({SIZE[0]}x{SIZE[1]}, 3 shadow maps)"
    section.rows += [
        Row("fit_scene_shadows, 3 lights, 14 meshes (a frame)", fitted, base, drawn),
        Row("gather_scene alone", gathered, base, drawn),
    ]
    surfaces = gather_scene(world)
    section.figures.update(
        {
            "caster_vertices": float(len(surfaces.casters.vertices)),
            "caster_triangles": float(len(surfaces.casters.faces)),
            "receiver_triangles": float(len(surfaces.receivers.faces)),
            "lights_skipped": float(len(skipped)),
        }
    )
    section.notes.append(
        f"{len(meshes) + 2} meshes ({len(surfaces.casters.faces)} caster triangles, "
        f"{len(surfaces.receivers.faces)} receiver triangles), a sun, a spot and a point light; "
        "the fit row includes moving the scene (a few property sets). The ratio is the fit's "
        "share of a frame drawn by pygfx on this machine's wgpu adapter (on llvmpipe, "
        "Mesa's CPU Vulkan driver, drawing is slow; on a GPU the draw is far cheaper)."
        + (f" Skipped lights: {skipped}." if skipped else "")
    )
    return section


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=(__doc__ or "").splitlines()[0])
    parser.add_argument("--tiny", action="store_true", help="each timing once")
    args = parser.parse_args(argv)
    section = run(Config(tiny=args.tiny))
    print(table(section))
    return 0


if __name__ == "__main__":
    sys.exit(main())
