"""A point light's cube-map depth range over caster triangles: ``sm.cube_depth_range``.

``python benchmarks/bench_cube_depth.py [--tiny]`` runs it alone; ``make bench`` runs it as
the section ``cube`` (``--only cube``).

**Scene.** A 12 x 12 floor (2 triangles) and 14 meshes of small triangles (about 0.2
across, on spheres of radius 0.5 at random places over the floor, as in the ``pygfx``
section's scene), 1,000, 5,000 and 50,000 caster triangles in all, float64; the point
light hangs 3 above the floor's middle.

**Timed.** One public ``sm.cube_depth_range(light, sm.Triangles(triangles))`` (the exact
nearest Chebyshev distance over the triangles' surfaces, the farthest corner) against one
flat NumPy read of the same array (``triangles.min()``), both medians in the same process;
also jitted JAX on the 5,000 triangles (which weighs every triangle: no pruning under
tracing; float32 unless ``jax_enable_x64`` is on). The section's figure ``searched_<n>``
is how many triangles could come nearer than the nearest corner (the others are skipped
by their bounding boxes).
"""

from __future__ import annotations

import functools
import os
import sys

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))

from speed._timing import Config, Row, Section, measure, run_alone, synced

import shadowmath as sm
from shadowmath._fits.cube._driver import _candidates

NAME = "cube"
TITLE = "cube_depth_range: a point light's cube-map near/far over caster triangles"
BASELINE = "one flat min of the same array, NumPy"
SIZES = (1_000, 5_000, 50_000)
TARGET = 1e-3  # seconds for 5,000 triangles: one point light of a frame's fit


def scene(count: int, seed: int) -> tuple[np.ndarray, np.ndarray]:
    """(light (3,), triangles (count, 3, 3)): a floor and 14 balls of small triangles."""
    rng = np.random.default_rng(seed)
    floor = np.array([[[-6, -6, 0], [6, -6, 0], [6, 6, 0]], [[-6, -6, 0], [6, 6, 0], [-6, 6, 0]]])
    centers = np.c_[rng.uniform(-4, 4, (14, 2)), rng.uniform(0.5, 2, 14)]
    n = count - 2
    direction = rng.normal(size=(n, 3))
    on_ball = 0.5 * direction / np.linalg.norm(direction, axis=1, keepdims=True)
    balls = centers[rng.integers(0, 14, n), None] + on_ball[:, None]
    triangles = balls + rng.uniform(-0.1, 0.1, (n, 3, 3))
    return np.array([0.0, 0.0, 3.0]), np.concatenate([floor, triangles])


def searched(light: np.ndarray, triangles: np.ndarray) -> int:
    """How many triangles' bounding boxes come nearer than the nearest corner."""
    R = np.ascontiguousarray(np.moveaxis(triangles - light, (-2, -1), (0, 1)))[:, :, None]
    return len(_candidates(R, float(np.finfo(np.float64).eps))[1])


def run(cfg: Config) -> Section:
    section = Section(NAME, TITLE)
    repeats, min_time = cfg.repeats(21), cfg.min_time
    for count in SIZES if not cfg.tiny else (100,):
        light, triangles = scene(count, cfg.seed)
        call = functools.partial(sm.cube_depth_range, light, sm.Triangles(triangles))
        fit = measure(call, repeats=repeats, min_time=min_time)
        base = measure(triangles.min, repeats=repeats, min_time=min_time)
        target = ("≤ 1 ms", TARGET, "seconds") if count == 5_000 else (None, None, "ratio")
        section.rows.append(
            Row(f"cube_depth_range, {count:,} triangles, NumPy", fit, BASELINE, base, *target)
        )
        section.figures[f"searched_{count}"] = float(searched(light, triangles))
    section.rows.append(jitted(cfg, 5_000 if not cfg.tiny else 100))
    section.notes.append(
        "float64; the light 3 above a 12 x 12 floor among 14 balls of small triangles. "
        "NumPy searches only the triangles whose bounding box comes nearer than the nearest "
        "corner (figures searched_<n>); jitted JAX weighs every triangle."
    )
    return section


def jitted(cfg: Config, count: int) -> Row:
    import jax

    light, triangles = scene(count, cfg.seed)
    fn = jax.jit(lambda L, t: tuple(sm.cube_depth_range(L, sm.Triangles(t))))
    fit = measure(synced(fn, jax.numpy.asarray(light), jax.numpy.asarray(triangles)),
                  repeats=cfg.repeats(21), min_time=cfg.min_time)  # fmt: skip
    base = measure(triangles.min, repeats=cfg.repeats(21), min_time=cfg.min_time)
    return Row(f"cube_depth_range, {count:,} triangles, jitted JAX", fit, BASELINE, base)


def main(argv: list[str] | None = None) -> int:
    return run_alone(run, (__doc__ or "").splitlines()[0], "100 triangles", argv)


if __name__ == "__main__":
    sys.exit(main())
