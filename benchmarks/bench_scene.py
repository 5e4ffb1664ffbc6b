"""A scene at engine scale through ``sm.ShadowScene``: the whole per-frame update.

``python benchmarks/bench_scene.py [--tiny]`` runs it alone; ``make bench`` runs it as the
section ``scene`` (``--only scene``).

**Scene.** 1,000 objects placed over a 200 x 200 floor, instances of 10 geometries (UV
spheres, tori and boxes at several resolutions) scaled to 1,000 or 1M triangles in all;
32 lights: 8 point lights (cube maps), 20 spot lights, 3 suns and 1 sun with 4 cascades
for a moving camera. Each frame 10 % of the objects move (a new rotation and position)
and the camera turns.

**Timed.** One frame: ``scene.set_transforms`` (the matrices in, the moved objects'
summaries to the world), ``scene.fit`` of the 31 lights (culling, every fit, draw lists)
and ``scene.fit_cascades`` of the cascaded sun, the median over frames. The baseline, in
the same run, is today's per-light fit over every triangle: ``sm.gather_meshes`` of the
moved scene, then ``fit_shadow`` (sun, spot) or ``cube_depth_range`` (point) of all of
them per light (timed once on the 1M-triangle scene). The figures ``draws_saved`` count
the draws (object x map) the draw lists save against drawing every caster into every map.
"""

from __future__ import annotations

import contextlib
import os
import sys
from collections.abc import Callable

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))

from speed._timing import Config, Row, Section, fast_extra, measure, numpy_alone, run_alone

import shadowmath as sm
from shadowmath import meshes

NAME = "scene"
TITLE = "ShadowScene: 1,000 objects, 32 lights, the whole per-frame update"
BASELINE = "per-light fit over every triangle (gather_meshes + fit_shadow / cube_depth_range)"
OBJECTS, GEOMETRIES = 1_000, 10


def geometries(total: int) -> list[sm.Mesh]:
    """10 meshes, about ``total / OBJECTS`` triangles per object on average."""
    per = max(total // OBJECTS, 12)
    # 3 boxes of 12 triangles and 7 curved meshes of about seg^2 (2 seg (seg / 2)) each
    seg = max(round(float(np.sqrt(max(10 * per - 36, 0) / 7))), 4)
    out: list[sm.Mesh] = []
    for k in range(GEOMETRIES):
        kind = k % 3
        if kind == 0:
            out.append(meshes.sphere(0.5 + 0.1 * k, segments=seg, rings=max(seg // 2, 3)))
        elif kind == 1:
            out.append(meshes.torus(0.6, 0.2, segments=seg, sides=max(seg // 2, 3)))
        else:
            out.append(meshes.box((0.5 + 0.1 * k, 0.8, 0.3 + 0.05 * k)))
    return out


def _rotation(rng: np.random.Generator, n: int) -> np.ndarray:
    q = rng.normal(size=(n, 4))
    q /= np.linalg.norm(q, axis=1, keepdims=True)
    w, x, y, z = q.T
    return np.stack([
        np.stack([1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)], -1),
        np.stack([2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)], -1),
        np.stack([2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)], -1),
    ], axis=-2)  # fmt: skip


def placements(rng: np.random.Generator, n: int) -> np.ndarray:
    M = np.tile(np.eye(4), (n, 1, 1))
    M[:, :3, :3] = _rotation(rng, n)
    M[:, :3, 3] = np.c_[rng.uniform(-90, 90, (n, 2)), rng.uniform(1, 6, n)]
    return M


def lights(rng: np.random.Generator) -> list[sm.PointLight | sm.SpotLight | sm.DirectionalLight]:
    out: list[sm.PointLight | sm.SpotLight | sm.DirectionalLight] = []
    for _ in range(8):
        out.append(sm.PointLight(np.r_[rng.uniform(-80, 80, 2), rng.uniform(8, 12)]))
    for _ in range(20):
        p = np.r_[rng.uniform(-80, 80, 2), rng.uniform(10, 20)]
        d = np.r_[rng.uniform(-0.5, 0.5, 2), -1.0]
        out.append(sm.SpotLight(p, d, np.float64(rng.uniform(0.2, 0.6))))
    for _ in range(3):
        out.append(sm.DirectionalLight(np.r_[rng.uniform(-0.5, 0.5, 2), 1.0]))
    return out


def build(total: int, seed: int) -> tuple[sm.ShadowScene, list[sm.Mesh], np.ndarray]:
    """The scene (floor first, static), its geometries and each object's geometry index."""
    rng = np.random.default_rng(seed)
    scene = sm.ShadowScene()
    floor = scene.add_geometry(meshes.grid((200.0, 200.0)))
    scene.add_objects(floor, casts=False, static=True)
    shapes = geometries(total)
    ids = [scene.add_geometry(m) for m in shapes]
    which = rng.integers(0, GEOMETRIES, OBJECTS)
    for g in range(GEOMETRIES):
        scene.add_objects(ids[g], placements(rng, int(np.sum(which == g))))
    order = np.concatenate([np.full(int(np.sum(which == g)), g) for g in range(GEOMETRIES)])
    return scene, shapes, order


def view(t: float) -> tuple[np.ndarray, np.ndarray]:
    """A camera 8 above the floor turning about the vertical, and its projection."""
    eye = np.array([10 * np.cos(t), 10 * np.sin(t), 8.0])
    target = np.array([0.0, 0.0, 2.0])
    f = (target - eye) / np.linalg.norm(target - eye)
    s = np.cross(f, [0.0, 0.0, 1.0])
    s /= np.linalg.norm(s)
    u = np.cross(s, f)
    V = np.eye(4)
    V[0, :3], V[1, :3], V[2, :3] = s, u, -f
    V[:3, 3] = -V[:3, :3] @ eye
    n, far, k = 0.1, 150.0, 1 / np.tan(np.radians(30))
    a, b = -(far + n) / (far - n), -2 * far * n / (far - n)
    P = np.array([[k / 1.6, 0, 0, 0], [0, k, 0, 0], [0, 0, a, b], [0, 0, -1, 0]])
    return V, P


def frame_loop(total: int, seed: int) -> tuple[Callable[[], object], sm.ShadowScene, list]:
    scene, _, _ = build(total, seed)
    rng = np.random.default_rng(seed + 1)
    all_lights = lights(rng)
    cascade_sun = sm.DirectionalLight(np.array([0.3, 0.2, 1.0]))
    spec = sm.ShadowMapSpec(1024, pcf_radius=1)
    state = {"t": 0.0}
    M = scene.transforms
    movers = 1 + np.flatnonzero(rng.random(OBJECTS) < 0.1)

    def frame() -> object:
        state["t"] += 0.01
        M[movers] = placements(rng, len(movers))
        scene.set_transforms(M)
        fits = scene.fit(all_lights, spec)
        V, P = view(state["t"])
        return fits, scene.fit_cascades(cascade_sun, V, P, spec, max_distance=60.0)

    return frame, scene, all_lights


def baseline(scene: sm.ShadowScene, shapes: list[sm.Mesh], order: np.ndarray,
             all_lights: list, spec: sm.ShadowMapSpec) -> Callable[[], object]:  # fmt: skip
    """Today's frame: every triangle gathered and read by every light."""
    M = scene.transforms

    def frame() -> object:
        casters = sm.gather_meshes([(shapes[g], M[1 + i]) for i, g in enumerate(order)])
        tris = sm.Triangles(np.asarray(casters.vertices)[casters.faces])
        out: list[object] = []
        for light in all_lights:
            if isinstance(light, sm.PointLight):
                out.append(sm.cube_depth_range(light.position, tris))
            else:
                out.append(sm.fit_shadow(light, tris, spec))
        return out

    return frame


def run(cfg: Config) -> Section:
    section = Section(NAME, TITLE)
    sizes = (10_000, 1_000_000) if not cfg.tiny else (2_000,)
    spec = sm.ShadowMapSpec(1024, pcf_radius=1)
    for total in sizes:
        frame, _, all_lights = frame_loop(total, cfg.seed)
        base_scene, shapes, order = build(total, cfg.seed)
        triangles = sum(len(shapes[g].faces) for g in order)
        base = measure(baseline(base_scene, shapes, order, all_lights, spec),
                       repeats=cfg.repeats(3 if total <= 10_000 else 1), warmup=0)  # fmt: skip
        modes = [("fast extra", 1e-3, "≤ 1 ms")] if fast_extra() else []
        for mode, target, label in [*modes, ("NumPy alone", 10e-3, "≤ 10 ms")]:
            with numpy_alone() if mode == "NumPy alone" else contextlib.nullcontext():
                timing = measure(frame, repeats=cfg.repeats(21), warmup=2)
            section.rows.append(
                Row(f"one frame, {triangles:,} caster triangles, {mode}", timing,
                    BASELINE + ", fast extra" * bool(modes), base, label, target, "seconds")
            )  # fmt: skip
        section.figures[f"triangles_{total}"] = float(triangles)
    frame, _, all_lights = frame_loop(sizes[0], cfg.seed)
    fits, cascades = frame()
    drawn = sum(len(d) for f in fits for d in f.draws) + sum(len(d) for d in cascades.draws)
    maps = sum(len(f.draws) for f in fits) + len(cascades.draws)
    every = maps * OBJECTS
    section.figures["draws"] = float(drawn)
    section.figures["draws_every_caster"] = float(every)
    section.figures["draws_saved"] = float(1 - drawn / every)
    section.notes.append(
        "float64, NumPy input (the fast extra's compiled fits where installed); 1,000 "
        "objects of 10 geometries, 32 lights (8 cube maps, 20 spots, 3 suns, 1 sun with 4 "
        "cascades), 10 % of the objects and the camera moving every frame. The baseline "
        "gathers every triangle and fits each light over all of them (once on the 1M "
        "scene). draws_saved: the fraction of (object, map) draws the draw lists save."
    )
    return section


def main(argv: list[str] | None = None) -> int:
    return run_alone(run, (__doc__ or "").splitlines()[0], "a small scene", argv)


if __name__ == "__main__":
    sys.exit(main())
