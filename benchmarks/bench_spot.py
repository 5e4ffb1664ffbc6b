"""One spot light's fit over a scene of 43,212 caster triangles: ``sm.fit_shadow(spot, ...)``.

``python benchmarks/bench_spot.py [--tiny]`` runs it alone; ``make bench`` runs it as the
section ``spot`` (``--only spot``).

**Scene.** 50 meshes gathered with ``sm.gather_meshes``: 20 spheres (960 triangles each),
10 tori (2,304), 19 boxes and a 24 x 24 floor grid (744), placed at random over the
floor (float64); the spot light hangs 9 above it, its cone (0.55 rad) covering about a
quarter of the scene, so that most triangles lie outside it and a few hundred straddle
its sides.

**Timed.** The public ``sm.fit_shadow(spot, sm.Triangles(triangles), 1024)`` with the
``fast`` extra (the compiled clipping loop, :mod:`shadowmath._math._spot_loop`) and with
NumPy alone (the compiled loops disabled: only the straddling triangles are clipped),
against a directional light's fit of the same triangles in the same mode (which reads
every corner and selects nothing), all medians in the same process. The former NumPy
selection, every triangle's 19 candidates (``_spot_casters.clip_triangles``, the form JAX
still runs), is timed alone for comparison. Figures: the triangles kept, the straddling
ones and the points the fit reads after the selection.
"""

from __future__ import annotations

import functools
import os
import sys
from typing import Any

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))

from speed._timing import Config, Row, Section, fast_extra, measure, numpy_alone, run_alone

import shadowmath as sm
from shadowmath import meshes

NAME = "spot"
TITLE = "fit_shadow: one spot light over 43,212 caster triangles (clipped to its cone)"
BASELINE = "a directional light's fit of the same triangles, same mode"
TARGET = 2e-3  # seconds with the fast extra


def scene(seed: int, tiny: bool = False) -> tuple[sm.SpotLight, np.ndarray]:
    """(spot light, triangles (M, 3, 3)): 50 meshes over a floor, the spot above them."""
    rng = np.random.default_rng(seed)
    kinds = ["sphere"] * 20 + ["torus"] * 10 + ["box"] * 19 if not tiny else ["sphere", "box"]
    parts: list[tuple[Any, Any]] = []
    for kind in kinds:
        M = np.eye(4)
        c, s = np.cos(rng.uniform(0, 2 * np.pi)), np.sin(rng.uniform(0, 2 * np.pi))
        M[:3, :3] = np.array([[c, -s, 0], [s, c, 0], [0, 0, 1]]) * rng.uniform(0.4, 1.0)
        M[:3, 3] = [rng.uniform(-10, 10), rng.uniform(-10, 10), rng.uniform(0.5, 2.0)]
        mesh = {"sphere": meshes.sphere, "torus": meshes.torus, "box": meshes.box}[kind]()
        parts.append((mesh, M))
    parts.append((meshes.grid((24.0, 24.0), segments=(12, 31)), None))
    gathered = sm.gather_meshes(parts)
    spot = sm.SpotLight(np.array([2.0, 1.0, 9.0]), np.array([0.1, 0.05, -1.0]), np.array(0.55))
    return spot, gathered.vertices[gathered.faces]


def figures(spot: sm.SpotLight, triangles: np.ndarray) -> dict[str, float]:
    """Triangles kept and straddling, and the points the fit reads after the selection."""
    from shadowmath._boundary._validate import convert
    from shadowmath._fits._light_kinds import spot_rows
    from shadowmath._fits.shadow._spot_select import _frame, spot_selection
    from shadowmath._math import _spot_casters as sc

    ctx, (position, direction, angle) = convert(p=spot[0], d=spot[1], a=spot[2])
    light = spot_rows(np, position, direction, angle)
    selection = spot_selection(ctx, light, None, None, triangles, triangles=True)
    p, axes, t = _frame(ctx, light, None)
    planes = sc.pyramid_planes(np, p, axes, t)
    _, straddle = sc.classify(sc.corner_values(planes, triangles), ctx.eps)
    return {
        "triangles": float(len(triangles)),
        "kept": float(selection.kept),
        "straddling": float(straddle.sum()),
        "points_read": float(len(selection.points)),
    }


def _former_selection(spot: sm.SpotLight, triangles: np.ndarray) -> Any:
    """The selection before the loop: every triangle's 19 candidates (``clip_triangles``)."""
    from shadowmath._boundary._validate import convert
    from shadowmath._fits._light_kinds import spot_rows
    from shadowmath._fits.shadow._spot_select import _frame
    from shadowmath._math import _spot_casters as sc

    ctx, (position, direction, angle) = convert(p=spot[0], d=spot[1], a=spot[2])
    light = spot_rows(np, position, direction, angle)
    p, axes, t = _frame(ctx, light, None)
    planes = sc.pyramid_planes(np, p, axes, t)
    square = np.zeros((4, 3))

    def call() -> Any:
        with np.errstate(all="ignore"):
            return sc.clip_triangles(np, planes, triangles, square, ctx.eps)

    return call


def run(cfg: Config) -> Section:
    section = Section(NAME, TITLE)
    repeats, min_time = cfg.repeats(21), cfg.min_time
    spot, triangles = scene(cfg.seed, cfg.tiny)
    casters = sm.Triangles(triangles)
    sun = sm.DirectionalLight(np.array([0.3, 0.2, 1.0]))
    count = f"{len(triangles):,} triangles"
    spot_fit = functools.partial(sm.fit_shadow, spot, casters, 1024)
    sun_fit = functools.partial(sm.fit_shadow, sun, casters, 1024)
    if fast_extra():
        fast = measure(spot_fit, repeats=repeats, min_time=min_time)
        base = measure(sun_fit, repeats=repeats, min_time=min_time)
        row = Row(f"spot fit, {count}, fast extra", fast, BASELINE, base, "≤ 2 ms", TARGET,
                  "seconds")  # fmt: skip
        section.rows.append(row)
    else:
        section.notes.append("Numba is not installed: no row for the fast extra.")
    with numpy_alone():
        alone = measure(spot_fit, repeats=repeats, min_time=min_time)
        base = measure(sun_fit, repeats=repeats, min_time=min_time)
    section.rows.append(Row(f"spot fit, {count}, NumPy alone", alone, BASELINE, base))
    former = measure(_former_selection(spot, triangles), repeats=cfg.repeats(7), min_time=0.0)
    section.rows.append(
        Row(f"former selection alone (19 candidates per triangle), {count}, NumPy", former,
            "the spot fit with NumPy alone", alone)
    )  # fmt: skip
    section.figures.update(figures(spot, triangles))
    section.notes.append(
        "float64. The spot's cone covers part of the scene; the fit reads only the kept "
        "triangles' corners and their straddlers' clipped points (figures kept, straddling, "
        "points_read). The directional baseline reads every corner."
    )
    return section


def main(argv: list[str] | None = None) -> int:
    return run_alone(run, (__doc__ or "").splitlines()[0], "a tiny scene", argv)


if __name__ == "__main__":
    sys.exit(main())
