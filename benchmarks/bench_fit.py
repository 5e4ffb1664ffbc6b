"""Benchmark: silhouette coverage of the optimized frustum fit against the article's MDV set-up.

Over a fixed, seeded set of blockers (tori, boxes, ellipsoids and bars with
random aspect ratios and orientations, lights at random distances), both set-ups
are computed with :func:`shadowmath.fit_shadow` (``method="mdv"`` and
``method="optimized"``), each shadow map is rendered with the reference
renderer (:func:`shadowmath.render.render_shadow_map`, OpenGL through EGL), and
the coverage of the usable map is measured on the rendered mask
(:func:`shadowmath.silhouette_coverage`). Prints a table of medians and 10th
percentiles per family and overall, the ratios to the MDV figures of the same
run, and the time per fit.

Run: ``make bench`` or ``.venv/bin/python benchmarks/bench_fit.py [--per-family N]``;
``--figures DIR`` also writes the figures of ``docs/fitting.md`` there.
"""

from __future__ import annotations

import argparse
import time
from collections.abc import Callable
from typing import Any

import jax
import numpy as np

import shadowmath as sm
from shadowmath import meshes
from shadowmath.render import render_shadow_map

jax.config.update("jax_enable_x64", True)


def _rotation(rng: np.random.Generator) -> np.ndarray:
    """A uniformly random rotation (QR of a Gaussian matrix, signs fixed)."""
    q, r = np.linalg.qr(rng.normal(size=(3, 3)))
    q = q * np.sign(np.diag(r))
    return q if np.linalg.det(q) > 0 else -q


def _placement(rng: np.random.Generator, scale: np.ndarray) -> np.ndarray:
    B = np.eye(4)
    B[:3, :3] = _rotation(rng) @ np.diag(scale)
    B[:3, 3] = rng.uniform(-2, 2, size=3)
    return B


def _torus(rng: np.random.Generator) -> tuple[meshes.Mesh, np.ndarray]:
    mesh = meshes.torus(1.0, rng.uniform(0.08, 0.6), segments=48, sides=16)
    return mesh, _placement(rng, np.ones(3))


def _box(rng: np.random.Generator) -> tuple[meshes.Mesh, np.ndarray]:
    size = np.exp(rng.uniform(np.log(0.1), 0.0, size=3)) * 2
    return meshes.box(tuple(size)), _placement(rng, np.ones(3))


def _ellipsoid(rng: np.random.Generator) -> tuple[meshes.Mesh, np.ndarray]:
    axes = np.exp(rng.uniform(np.log(0.15), 0.0, size=3))
    return meshes.sphere(1.0, segments=32, rings=16), _placement(rng, axes)


def _bar(rng: np.random.Generator) -> tuple[meshes.Mesh, np.ndarray]:
    return meshes.bar(3.0, rng.uniform(0.05, 0.4)), _placement(rng, np.ones(3))


FAMILIES: dict[str, Callable[[np.random.Generator], tuple[meshes.Mesh, np.ndarray]]] = {
    "torus": _torus,
    "box": _box,
    "ellipsoid": _ellipsoid,
    "bar": _bar,
}


def _light(rng: np.random.Generator, mesh: meshes.Mesh, B: np.ndarray) -> np.ndarray:
    """A light at a random direction and a log-uniform distance of 1.5 to 20 radii."""
    world = mesh.vertices @ B[:3, :3].T + B[:3, 3]
    centre = 0.5 * (world.max(0) + world.min(0))
    radius = np.linalg.norm(world - centre, axis=1).max()
    d = rng.normal(size=3)
    return centre + d / np.linalg.norm(d) * radius * np.exp(rng.uniform(np.log(1.5), np.log(20)))


Case = tuple[float, float, float, float, int]
EXAMPLES: dict[str, list[np.ndarray]] = {}  # the first case's two masks per family


def _case(rng: np.random.Generator, family: str, map_size: int) -> Case | None:
    mesh, B = FAMILIES[family](rng)
    light = _light(rng, mesh, B)
    try:
        t0 = time.perf_counter()
        mdv = sm.fit_shadow(light, mesh.vertices, map_size, blocker_to_world=B)
        t1 = time.perf_counter()
        opt = sm.fit_shadow(light, mesh.vertices, map_size, blocker_to_world=B, method="optimized")
        t2 = time.perf_counter()
    except ValueError:  # the light sees the blocker over more than a half-space
        return None
    covers = []
    clipped = 0
    for setup in (mdv, opt):
        mask = render_shadow_map(mesh.vertices, mesh.faces, setup.blocker_to_clip, map_size)
        covers.append(float(sm.silhouette_coverage(mask)))
        EXAMPLES.setdefault(family, [])
        if len(EXAMPLES[family]) < 2:
            EXAMPLES[family].append(mask)
        border = np.concatenate([mask[0], mask[-1], mask[:, 0], mask[:, -1]])
        clipped += int(border.max() > 0)
    return covers[0], covers[1], t1 - t0, t2 - t1, clipped


def _row(name: str, mdv: np.ndarray, opt: np.ndarray) -> str:
    ratio = opt / mdv
    med_m, med_o = np.median(mdv), np.median(opt)
    p10_m, p10_o = np.percentile(mdv, 10), np.percentile(opt, 10)
    return (
        f"| {name} | {len(mdv)} | {med_m:.3f} | {med_o:.3f} | **{med_o / med_m:.2f}** "
        f"| {p10_m:.3f} | {p10_o:.3f} | **{p10_o / p10_m:.2f}** "
        f"| {np.median(ratio):.2f} | {np.percentile(ratio, 10):.2f} | {ratio.min():.2f} |"
    )


def main(argv: list[str] | None = None) -> dict[str, Any]:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--per-family", type=int, default=25)
    parser.add_argument("--map-size", type=int, default=256)
    parser.add_argument("--seed", type=int, default=2026)
    parser.add_argument("--figures", default=None, help="folder for the docs' figures")
    args = parser.parse_args(argv)
    rng = np.random.default_rng(args.seed)

    # Warm-up: compile the optimiser for every vertex-count bucket used below.
    for family in FAMILIES:
        mesh, _ = FAMILIES[family](np.random.default_rng(0))
        sm.fit_shadow([9.0, 9.0, 9.0], mesh.vertices, args.map_size, method="optimized")

    results: dict[str, list[Case]] = {f: [] for f in FAMILIES}
    skipped = 0
    for family in FAMILIES:
        while len(results[family]) < args.per_family:
            r = _case(rng, family, args.map_size)
            if r is None:
                skipped += 1
            else:
                results[family].append(r)

    header = (
        "| blockers | n | median MDV | median optimized | median ratio | p10 MDV "
        "| p10 optimized | p10 ratio | median per-case ratio | p10 per-case ratio "
        "| worst per-case ratio |\n|---|---|---|---|---|---|---|---|---|---|---|"
    )
    print(f"Silhouette coverage of the usable {args.map_size}x{args.map_size} map, rendered")
    print(header)
    all_m, all_o = [], []
    for family, rows in results.items():
        arr = np.array(rows)
        all_m.append(arr[:, 0])
        all_o.append(arr[:, 1])
        print(_row(family, arr[:, 0], arr[:, 1]))
    mdv, opt = np.concatenate(all_m), np.concatenate(all_o)
    print(_row("all", mdv, opt))
    every = np.concatenate([np.array(r) for r in results.values()])
    t_mdv, t_opt = np.median(every[:, 2]), np.median(every[:, 3])
    print(
        f"\ntime per fit (median, after compilation): MDV {1e3 * t_mdv:.2f} ms, "
        f"optimized {1e3 * t_opt:.1f} ms ({t_opt / t_mdv:.0f}x); "
        f"maps touching their border: {int(every[:, 4].sum())}; "
        f"lights rejected (blocker not in front of the light): {skipped}"
    )
    med_ratio = np.median(opt) / np.median(mdv)
    p10_ratio = np.percentile(opt, 10) / np.percentile(mdv, 10)
    print(f"targets: median ratio {med_ratio:.2f} (>= 1.2), p10 ratio {p10_ratio:.2f} (>= 1.5)")
    if args.figures:
        _figures(args.figures, results)
    return {"median_ratio": med_ratio, "p10_ratio": p10_ratio}


def _figures(folder: str, results: dict[str, list[Case]]) -> None:
    import os

    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    os.makedirs(folder, exist_ok=True)
    fig, ax = plt.subplots(figsize=(4.6, 4.2))
    for family, rows in results.items():
        arr = np.array(rows)
        ax.scatter(arr[:, 0], arr[:, 1], s=14, label=family)
    ax.plot([0, 1], [0, 1], color="gray", lw=0.8, ls="--")
    ax.set_xlim(0, 1)
    ax.set_ylim(0, 1)
    ax.set_xlabel("coverage, article's MDV set-up")
    ax.set_ylabel('coverage, method="optimized"')
    ax.legend(loc="lower right")
    fig.tight_layout()
    fig.savefig(os.path.join(folder, "fitting_scatter.png"), dpi=90)
    plt.close(fig)

    fig, axes = plt.subplots(2, len(EXAMPLES), figsize=(2.2 * len(EXAMPLES), 4.6))
    for col, (family, masks) in enumerate(EXAMPLES.items()):
        for row, (title, mask) in enumerate(zip(("MDV", "optimized"), masks, strict=True)):
            ax = axes[row, col]
            ax.imshow(mask[::-1], cmap="gray_r", vmin=0, vmax=1, interpolation="nearest")
            ax.set_title(
                f"{family}, {title}: {float(sm.silhouette_coverage(mask)):.2f}", fontsize=8
            )
            ax.set_xticks([])
            ax.set_yticks([])
    fig.tight_layout()
    fig.savefig(os.path.join(folder, "fitting_examples.png"), dpi=90)
    plt.close(fig)


if __name__ == "__main__":
    main()
