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

**Many meshes** (the issue's scene, :func:`many_scene`). A 40 x 40 floor, 50 moving
meshes (boxes, UV spheres and torus knots in turn; every tenth a ``gfx.InstancedMesh`` of
4), 1 sun, 6 spot lights and 4 point lights, about 43k caster triangles; with ``--big``
also 500 meshes on a 120 x 120 floor, about 1.16M triangles. Timed without drawing: a
frame of ``fit_scene_shadows`` (its cache built before timing) against the per-frame
path it replaced (``_fit_gathered``: ``gather_scene``, then every light fitted over every
triangle), both including the meshes' motion, which is also timed alone. Targets: 2 ms
(50 meshes) and 10 ms (500 meshes) a frame. The figures ``many*_draws_saved`` are the
fraction of (object, map) draws the draw lists save against drawing every caster into
every map, as pygfx 0.17 does.
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


#: The issue's scene: (meshes, floor side, sphere segments, knot segments) per variant.
MANY = {50: (50, 40.0, (32, 16), (128, 4)), 500: (500, 120.0, (48, 24), (128, 12))}


def many_scene(gfx: Any, count: int, seed: int) -> tuple[Any, list[Any], list[Any]]:
    """(scene, moving meshes, lights): a floor that receives, ``count`` meshes that cast
    and receive (boxes, UV spheres and torus knots in turn; every tenth a
    ``gfx.InstancedMesh`` of 4), a sun, 6 spot lights and 4 point lights."""
    _, side, (s_w, s_h), (k_t, k_r) = MANY[count]
    rng = np.random.default_rng(seed)
    world = gfx.Scene()
    floor = gfx.Mesh(gfx.plane_geometry(side, side), gfx.MeshPhongMaterial())
    floor.receive_shadow = True
    world.add(floor)
    shapes = [
        gfx.box_geometry(0.8, 0.8, 0.8),
        gfx.sphere_geometry(0.4, s_w, s_h),
        gfx.torus_knot_geometry(0.5, 0.15, k_t, k_r),
    ]
    meshes = []
    for i in range(count):
        geometry, material = shapes[i % 3], gfx.MeshPhongMaterial()
        if i % 10 == 9:
            mesh = gfx.InstancedMesh(geometry, material, 4)
            for k in range(4):
                m = np.eye(4)
                m[:3, 3] = (1.2 * (k % 2), 1.2 * (k // 2), 0.0)
                mesh.set_matrix_at(k, m)
        else:
            mesh = gfx.Mesh(geometry, material)
        mesh.cast_shadow = mesh.receive_shadow = True
        mesh.local.position = (*rng.uniform(-0.4 * side, 0.4 * side, 2), rng.uniform(0.5, 2.0))
        meshes.append(mesh)
        world.add(mesh)
    lights: list[Any] = [gfx.DirectionalLight(cast_shadow=True)]
    for k in range(6):
        spot = gfx.SpotLight(cast_shadow=True, angle=0.5)
        a = 2 * np.pi * k / 6
        spot.local.position = (0.3 * side * np.cos(a), 0.3 * side * np.sin(a), 8.0)
        spot.target.local.position = (0.3 * side * np.cos(a), 0.3 * side * np.sin(a), 0.0)
        lights.append(spot)
    for k in range(4):
        lamp = gfx.PointLight(cast_shadow=True)
        lamp.local.position = (0.25 * side * (-1) ** k, 0.25 * side * (-1) ** (k // 2), 4.0)
        lights.append(lamp)
    for light in lights:
        world.add(light)
        if not isinstance(light, gfx.PointLight):
            world.add(light.target)
    world.add(gfx.AmbientLight(intensity=0.2))
    return world, meshes, lights


def move_many(frame: int, meshes: list[Any], sun: Any) -> None:
    """Every mesh turns and bobs; the sun circles."""
    a = 2 * np.pi * (frame % 60) / 60
    for i, mesh in enumerate(meshes):
        mesh.local.euler_z = a + i
        x, y, _ = mesh.local.position
        mesh.local.position = (x, y, 1.25 + 0.5 * np.sin(a + i))
    sun.local.position = (3 * np.cos(a), 3 * np.sin(a), 5.0)


def draws_saved(reports: list[Any]) -> tuple[int, int]:
    """(draws the lists make, draws of every caster into every map): object x map pairs."""
    made = sum(len(d) for r in reports for d in r.draws)
    casters = max((len(r.draws[0]) for r in reports if r.draws and len(r.draws) == 1
                   and type(r.light).__name__ == "DirectionalLight"), default=0)  # fmt: skip
    maps = sum(6 if type(r.light).__name__ == "PointLight" else 1 for r in reports)
    return made, casters * maps


def run_many(cfg: Config, gfx: Any, count: int, section: Section) -> None:
    """The issue's scene of ``count`` meshes: fit_scene_shadows against the old path."""
    from shadowmath.integrations.pygfx import _fit_gathered, fit_scene_shadows, gather_scene

    world, meshes, lights = many_scene(gfx, count, cfg.seed)
    frames = itertools.count()
    fit_scene_shadows(world)  # builds the cache: the geometries' summaries, once

    def fit() -> object:
        move_many(next(frames), meshes, lights[0])
        return fit_scene_shadows(world)

    def old() -> object:
        move_many(next(frames), meshes, lights[0])
        return _fit_gathered(world)

    def moved() -> object:
        move_many(next(frames), meshes, lights[0])
        return world.world.matrix  # pygfx updates world matrices when read

    repeats = cfg.repeats(21)
    new_t = measure(fit, repeats=repeats, min_time=cfg.min_time)
    old_t = measure(old, repeats=cfg.repeats(5 if count <= 50 else 3), warmup=0)
    move_t = measure(moved, repeats=repeats, min_time=cfg.min_time)
    reports = fit_scene_shadows(world)
    surfaces = gather_scene(world)
    made, every = draws_saved(reports)
    target = 0.002 if count <= 50 else 0.010
    section.rows += [
        Row(
            f"fit_scene_shadows, {len(lights)} lights, {count} meshes (a frame, cached)",
            new_t,
            "the old per-frame path: gather_scene + fit each light over every triangle",
            old_t,
            target=f"<= {target * 1e3:.0f} ms",
            limit=target,
            limit_on="seconds",
        ),
        Row(f"moving the {count} meshes alone (in both rows)", move_t),
    ]
    skipped = [r.skipped for r in reports if r.skipped]
    section.figures.update(
        {
            f"many{count}_caster_triangles": float(len(surfaces.casters.faces)),
            f"many{count}_objects": float(sum(len(r.draws[0]) for r in reports[:1])),
            f"many{count}_draws_saved": 1.0 - made / every if every else 0.0,
            f"many{count}_lights_skipped": float(len(skipped)),
        }
    )
    section.notes.append(
        f"{count} meshes ({len(surfaces.casters.faces)} caster triangles, every tenth an "
        f"InstancedMesh of 4), 1 sun, 6 spots, 4 point lights: the draw lists hold {made} of "
        f"{every} (object, map) draws ({100 * (1 - made / every):.0f} % saved; pygfx 0.17 "
        "draws every caster into every map)." + (f" Skipped: {skipped}." if skipped else "")
    )


def run(cfg: Config, big: bool = False) -> Section:
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
    for count in (50, 500) if big else (50,):
        run_many(cfg, gfx, count, section)
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
    parser.add_argument("--big", action="store_true", help="also the 500-mesh scene (minutes)")
    args = parser.parse_args(argv)
    section = run(Config(tiny=args.tiny), big=args.big)
    print(table(section))
    return 0


if __name__ == "__main__":
    sys.exit(main())
