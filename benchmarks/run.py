"""shadowmath's benchmark suite (``make bench``): speed against PyGLM, NumPy and the memory limit.

Sections (``--only NAME``, repeatable or comma-separated):

* ``single``: one ``fit_shadow`` (8, 1,000, 100,000 vertices), ``planar_projection``, a cube
  map's ``cube_face_views`` + ``cube_face_projection``, a receiver's texture matrix, eager JAX,
  ``import shadowmath`` and the first fit in a fresh process (point and directional, the disk
  cache warm; the first process in the note); baselines PyGLM ``lookAt`` + ``perspective`` and
  the one-line NumPy planar matrix.
* ``options``: every light and option of ``fit_shadow`` on one 8-vertex blocker (point ``xyz``,
  ``xyzw``, ``up``; directional, with receivers and ``stable``, ``api="vulkan"``,
  ``reversed_z``), with the ``fast`` extra against PyGLM (``perspective`` or ``ortho``) and
  with NumPy alone (compiled loop disabled) against a hand-written NumPy fit.
* ``batch``: 100,000 point fits of 8-vertex blockers, NumPy and jitted JAX, float32 and
  float64, against a Python loop of PyGLM.
* ``suns``: 1,000 directional fits with receivers and ``stable=True`` in one call, with the
  ``fast`` extra and with NumPy alone, against a Python loop of PyGLM's ``lookAt`` + ``ortho``.
* ``large``: one 4M-vertex float32 blocker against one flat ``sum`` of the array.
* ``derivatives``: the jitted gradient of the fitting objective against its forward pass;
  ``optimize_frustum`` on 1,000 and 500,000 vertices and on a batch of 100 blockers.
* ``compile``: the first ``jax.jit(jax.value_and_grad(loss))`` through ``fit_shadow`` (per light
  kind and main options), ``fit_cascades`` (four cascades; ``stable``, LiSPSM) and
  ``pcss_parameters``, float64: the jaxpr's equations and the time to lower and compile it in a
  fresh trace (targets: 1 s for ``fit_shadow``, 2 s for four cascades).
* ``gpu``: the batch and large-blocker figures on a GPU (skipped without one).
* ``coverage``: ``benchmarks/bench_fit.py``, the optimized fit's coverage (needs OpenGL).
* ``cascades``: ``benchmarks/bench_cascades.py``, ``fit_cascades``: the shadow-map texel's area
  per pixel on the receivers of three scenes against three.js's and bevy's schemes, and the
  time of four cascades for one camera and for a batch of 100.
* ``sweep``: ``benchmarks/bench_sweep.py``, ``fit_cascades`` over 72 camera poses (heights
  1.7-100 m, pitch from the horizon to steeply down, heading from facing the sun to away from
  it, sun 10-70° high, two scenes): the texel area per pixel footprint, median and 90th
  percentile, of the default fit against three.js and bevy, of ``stable=True`` against
  three.js, Godot and Unreal, of the LiSPSM warp against none; the distance to the aliasing
  limit; candidate default split schemes.
* ``atlas``: ``benchmarks/bench_atlas.py``, ``allocate_atlas`` + ``fit_atlas`` for 64 lights per
  frame against a loop of public calls per light, the fraction of the atlas used, and the tiles
  moved over frames of small motion.
* ``cube``: ``benchmarks/bench_cube_depth.py``, ``cube_depth_range`` on 1,000, 5,000 and 50,000
  caster triangles against one flat NumPy read of the same array (and jitted JAX on 5,000).
* ``spot``: ``benchmarks/bench_spot.py``, one spot light's ``fit_shadow`` over 43,212 caster
  triangles of 50 gathered meshes (its cone covering part of them), with the ``fast`` extra
  and with NumPy alone, against a directional light's fit of the same triangles; the former
  selection (19 candidates per triangle) timed alone.
* ``pygfx``: ``benchmarks/bench_pygfx.py``, ``shadowmath.integrations.pygfx.fit_scene_shadows``
  once a frame on an animated scene (14 meshes, a sun, a spot and a point light) against the
  time pygfx takes to draw that frame offscreen (skipped without pygfx or a wgpu adapter).
* ``scene``: ``benchmarks/bench_scene.py``, ``ShadowScene``'s whole per-frame update (matrices
  in, culling, 32 lights' fits, draw lists) for 1,000 objects at 10k and 1M triangles, against
  today's per-light fit over every triangle; the draws the draw lists save.

Each prints a Markdown table: median (with its repeat count), the baseline measured in the
same process, ratio = median / baseline median, the issue's target and an informational
PASS/MISS; the run ends with every target on one line. ``--json PATH`` writes every figure
(and the targets); ``--tiny`` runs each benchmark once at a tiny size (what
``tests/test_benchmarks.py`` does: the figures must exist, nothing is said about time).
"""

from __future__ import annotations

import argparse
import datetime
import json
import os
import platform
import subprocess
import sys
import time
import traceback
from importlib import metadata
from types import ModuleType
from typing import Any

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))

import bench_atlas
import bench_cascades
import bench_cube_depth
import bench_pygfx
import bench_scene
import bench_spot
import bench_sweep
from speed import SECTIONS as SPEED_SECTIONS
from speed._timing import Config, Section, table, target_line, targets

SECTIONS: dict[str, ModuleType] = {
    **SPEED_SECTIONS,
    bench_cascades.NAME: bench_cascades,
    bench_sweep.NAME: bench_sweep,
    bench_atlas.NAME: bench_atlas,
    bench_cube_depth.NAME: bench_cube_depth,
    bench_spot.NAME: bench_spot,
    bench_pygfx.NAME: bench_pygfx,
    bench_scene.NAME: bench_scene,
}


def _version(dist: str) -> str:
    try:
        return metadata.version(dist)
    except metadata.PackageNotFoundError:
        return "not installed"


def _cpu() -> str:
    try:
        with open("/proc/cpuinfo") as f:
            for line in f:
                if line.startswith("model name"):
                    return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return platform.processor() or platform.machine()


def _commit() -> str:
    """The repository's commit, and whether shadowmath/ differs from it in the working tree."""
    root = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
    try:
        head = subprocess.run(
            ["git", "-C", root, "rev-parse", "--short", "HEAD"],
            capture_output=True,
            text=True,
            check=True,
        ).stdout.strip()
        dirty = subprocess.run(
            ["git", "-C", root, "status", "--porcelain", "--", "shadowmath"],
            capture_output=True,
            text=True,
            check=True,
        ).stdout.strip()
    except (OSError, subprocess.CalledProcessError):
        return "unknown"
    return head + (" (shadowmath/ modified in the working tree)" if dirty else "")


def environment(cfg: Config) -> dict[str, Any]:
    import jax
    import numpy as np

    import shadowmath

    return {
        "date": datetime.datetime.now().astimezone().isoformat(timespec="seconds"),
        "machine": f"{os.cpu_count()} cores, {_cpu()}, {platform.system()} {platform.machine()}",
        "python": platform.python_version(),
        "numpy": np.__version__,
        "jax": _version("jax"),
        "jaxlib": _version("jaxlib"),
        "jax_devices": [str(d) for d in jax.devices()],
        "jax_enable_x64": bool(jax.config.read("jax_enable_x64")),
        "pyglm": _version("pyglm"),
        "shadowmath": shadowmath.__file__,
        "commit": _commit(),
        "tiny": cfg.tiny,
    }


def _names(only: list[str] | None) -> list[str]:
    if not only:
        return list(SECTIONS)
    names = [n.strip() for item in only for n in item.split(",") if n.strip()]
    unknown = [n for n in names if n not in SECTIONS]
    if unknown:
        raise SystemExit(f"unknown benchmark(s) {unknown}; choose from {list(SECTIONS)}")
    return names


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(
        description=(__doc__ or "").splitlines()[0],
        epilog=(__doc__ or "").split("\n", 1)[-1].strip(),
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    parser.add_argument(
        "--only",
        action="append",
        metavar="NAME",
        help="run these only (repeatable or comma-separated: " + ", ".join(SECTIONS) + ")",
    )
    parser.add_argument("--tiny", action="store_true", help="each once, at a tiny size")
    parser.add_argument("--json", metavar="PATH", help="write every figure to PATH")
    parser.add_argument("--seed", type=int, default=2026)
    args = parser.parse_args(argv)
    cfg = Config(tiny=args.tiny, seed=args.seed)
    names = _names(args.only)

    env = environment(cfg)
    tiny = " (--tiny: sizes and repeats are not real)" if cfg.tiny else ""
    print(f"# shadowmath speed benchmarks{tiny}\n")
    for key in ("date", "machine", "python", "numpy", "jax", "pyglm", "jax_enable_x64"):
        print(f"* {key}: {env[key]}")
    print(f"* shadowmath: {env['shadowmath']} (repository at {env['commit']})")
    print()
    sections: dict[str, Section] = {}
    failed = False
    for name in names:
        module = SECTIONS[name]
        t0 = time.perf_counter()
        try:
            section = module.run(cfg)
        except Exception:
            failed = True
            section = Section(name, module.TITLE, error=traceback.format_exc())
        sections[name] = section
        print(table(section))
        print(f"\n({name}: {time.perf_counter() - t0:.1f} s)\n", flush=True)
    goals = targets(sections)
    print("## Targets\n")
    print("\n".join(target_line(name, row) for name, row in goals) or "(none measured)")
    print(f"\n{sum(r.status == 'PASS' for _, r in goals)} of {len(goals)} targets met{tiny}\n")
    if args.json:
        out = {
            "environment": env,
            "benchmarks": {n: s.to_json() for n, s in sections.items()},
            "targets": [{"benchmark": n, **r.to_json()} for n, r in goals],
        }
        with open(args.json, "w") as f:
            json.dump(out, f, indent=2)
            f.write("\n")
        print(f"wrote {args.json}")
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
