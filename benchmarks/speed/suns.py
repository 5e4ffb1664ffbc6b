"""2b. 1,000 directional fits with receivers and ``stable=True`` in one call, with the ``fast``
extra and with NumPy alone, against a Python loop of PyGLM's ``lookAt`` + ``ortho``.

Lights ``(n, 4)``, blockers ``(n, 8, 3)`` (box corners), one floor of 64 receivers broadcast
over the batch. The stable fit needs each blocker's minimal enclosing sphere (Welzl's algorithm
compiled with the ``fast`` extra; without it, every entry's support at once in NumPy,
``shadowmath/_math/_ball_support.py``), and the receivers' pass reads ``n x 64`` points. The
baseline loops the PyGLM fit (bounding sphere about the box centre, ``lookAt`` + ``ortho``, no
receivers) over all ``n`` pairs. Target in both modes: ≥ 20× the loop's rate (ratio ≤ 0.05).
"""

from __future__ import annotations

from functools import partial
from typing import Any

import shadowmath as sm

from ._scenes import MAP_SIZE, boxes, floor, glm_ortho_fit, suns, to_glm
from ._timing import Config, Row, Section, fast_extra, measure, numpy_alone
from .batch import batch_row

NAME = "suns"
TITLE = "2b. Batch: 1,000 directional fits with receivers and stable=True"
TARGET = 0.05  # ratio to the PyGLM loop, in both modes
BASELINE = "Python loop of the PyGLM lookAt + ortho fit"


def rows(cfg: Config) -> list[Row]:
    """The fit with the fast extra as installed (when there) and NumPy alone, and the loop."""
    n = cfg.size(1_000, 16)
    _, corners = boxes(n, cfg.seed + 1)
    lights, receivers = suns(n, cfg.seed + 1), floor(8)[:64]
    scene = [to_glm(lights[i, :3], corners[i]) for i in range(n)]

    def loop() -> list[Any]:
        return [glm_ortho_fit(d, verts) for d, verts in scene]

    reps = cfg.repeats(7)
    fit = partial(sm.fit_shadow, lights, corners, MAP_SIZE, receivers=receivers, stable=True)
    label = f"fit_shadow, {n:,} directional fits + {len(receivers)} shared receivers, stable=True"
    out = []
    base = measure(loop, repeats=reps, min_time=cfg.min_time)
    if fast_extra():
        t = measure(fit, repeats=reps, min_time=cfg.min_time)
        out.append(batch_row(f"{label}, fast extra", t, base, n, TARGET, baseline=BASELINE))
    with numpy_alone():
        t = measure(fit, repeats=reps, min_time=cfg.min_time)
    out.append(batch_row(f"{label}, NumPy alone", t, base, n, TARGET, baseline=BASELINE))
    return out


def run(cfg: Config) -> Section:
    section = Section(NAME, TITLE)
    section.rows.extend(rows(cfg))
    if not fast_extra():
        section.notes.append(
            "the fast extra is not available here (Numba missing or SHADOWMATH_NUMBA=0): "
            "NumPy alone only"
        )
    section.notes.append(
        f"All {cfg.size(1_000, 16):,} pairs in one call (float64, one floor of receivers "
        "broadcast over the batch) against a loop of PyGLM's lookAt + ortho over all of them "
        "(glm.vec3 lists made before timing). NumPy alone: the compiled loop disabled (as "
        "without Numba). Target: ≥ 20× the loop's rate in both modes (ratio ≤ 0.05)."
    )
    return section
