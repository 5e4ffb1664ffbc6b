"""Compile the `fast` extra's loops into the package's disk cache before the test suite.

``make pytest`` runs this first (``make test`` runs it beside ruff and mypy): on a fresh
clone each of pytest's workers would otherwise compile the same Numba loops (about 80 s of
CPU for the fits' and the cascades' loops in float64 and float32) on its first call;
compiled once here, the workers load them from the cache (``shadowmath/__pycache__``, or
``$NUMBA_CACHE_DIR``, keyed by the package's sources). Without Numba it does nothing.
Public calls only, each with its answer checked for finiteness, so a broken fit fails here
loudly too (the tests say why).

Usage::

    python tools/warm_numba.py
"""

from __future__ import annotations

import importlib.util
import sys
import time

import numpy as np

import shadowmath as sm


def _camera() -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    view = np.eye(4)
    view[:3, 3] = [0.0, -2.0, -30.0]
    n, f = 0.1, 200.0
    proj = np.array([[1.0, 0, 0, 0], [0, 1.0, 0, 0],
                     [0, 0, (f + n) / (n - f), 2 * f * n / (n - f)], [0, 0, -1.0, 0]])  # fmt: skip
    box = np.array([[-100.0, -100.0, -1.0], [100.0, 100.0, 10.0]])
    return view, proj, box


def main() -> int:
    if importlib.util.find_spec("numba") is None:
        print("warm_numba: Numba is not installed; nothing to compile")
        return 0
    start = time.perf_counter()
    rng = np.random.default_rng(0)
    verts = rng.uniform(-1.0, 1.0, (40, 3)) + np.array([0.3, -0.2, 6.0])
    floor = np.array([[-4.0, -4.0, 9.0], [4.0, -4.0, 9.0], [0.0, 4.0, 9.0]])
    tris = verts[:36].reshape(12, 3, 3)
    view, proj, box = _camera()
    answers = []
    for dt in (np.float64, np.float32):
        v = verts.astype(dt)
        point, sun, axis = (
            np.zeros(3, dt),
            np.array([0.3, 1.0, -0.2], dt),
            np.array([0, 0, 1.0], dt),
        )
        spot = sm.SpotLight(point, axis, 0.6)
        fits = [
            sm.fit_shadow(sm.PointLight(point), v, 256),
            sm.fit_shadow(sm.DirectionalLight(sun), v, 256, receivers=floor.astype(dt)),
            sm.fit_shadow(spot, v, 256),
            sm.fit_shadow(spot, sm.Triangles(tris.astype(dt)), 256),
        ]
        answers += [s.blocker_to_clip for s in fits]
        c = sm.fit_cascades(sun, view.astype(dt), proj.astype(dt), box.astype(dt), 1024)
        answers.append(c.world_to_clip)
    if not all(np.all(np.isfinite(a)) for a in answers):
        print("warm_numba: a fit gave a non-finite matrix", file=sys.stderr)
        return 1
    print(f"warm_numba: the compiled loops are in the cache ({time.perf_counter() - start:.0f} s)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
