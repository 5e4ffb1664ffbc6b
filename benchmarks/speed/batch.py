"""2. Batch: ``fit_shadow`` over 100,000 light/blocker pairs of 8 box corners (``aim="bbox"``,
the article's Optimization Tip #2), NumPy and jitted JAX, float32 and float64, against a Python
loop of the PyGLM fit (1,000 directional fits with receivers and ``stable=True``: :mod:`.suns`)."""

from __future__ import annotations

from functools import partial
from typing import Any

import numpy as np

import shadowmath as sm

from ._scenes import MAP_SIZE, boxes, glm_fit, to_glm
from ._timing import (
    Config,
    Row,
    Section,
    Timing,
    measure,
    once,
    run_python,
    synced,
)

NAME = "batch"
TITLE = "2. Batch: 100,000 point fits of 8-vertex blockers"

_X64_CHILD = """
import json
import jax
from speed import batch
print(json.dumps(batch.jax_child({n}, {seed}, {repeats})))
"""


def numpy_fit(lights: np.ndarray, corners: np.ndarray) -> Any:
    return sm.fit_shadow(lights, corners, MAP_SIZE, aim="bbox")


def jitted_fit() -> Any:
    """``jax.jit`` of the batched (broadcasting) ``fit_shadow``."""
    import jax

    return jax.jit(lambda lights, corners: sm.fit_shadow(lights, corners, MAP_SIZE, aim="bbox"))


def time_jax(
    n: int, seed: int, repeats: int, dtype: Any, device: Any = None
) -> tuple[Timing, Timing, str]:
    """(first call, median after compilation, result dtype) of the jitted batch fit."""
    import jax

    lights, corners = boxes(n, seed, dtype)
    j_lights = jax.device_put(lights, device)
    j_corners = jax.device_put(corners, device)
    fit = jitted_fit()
    first = once(synced(fit, j_lights, j_corners))
    t = measure(synced(fit, j_lights, j_corners), repeats=repeats, warmup=0)
    return first, t, str(fit(j_lights, j_corners).blocker_to_clip.dtype)


def jax_child(n: int, seed: int, repeats: int) -> dict[str, Any]:
    """Run in a child process with ``JAX_ENABLE_X64=1``: the float64 jitted batch."""
    first, t, dtype = time_jax(n, seed, repeats, np.float64)
    return {"first": first.median, "median": t.median, "repeats": t.repeats, "dtype": dtype}


def glm_loop(cfg: Config, n: int) -> tuple[Timing, int]:
    """The PyGLM loop's time for ``n`` fits, timed on a subset and scaled; and the subset size."""
    subset = min(n, cfg.size(10_000, 20))
    lights, corners = boxes(subset, cfg.seed)
    scene = [to_glm(lights[i], corners[i]) for i in range(subset)]

    def loop() -> list[Any]:
        return [glm_fit(light, verts) for light, verts in scene]

    t = measure(loop, repeats=cfg.repeats(5), warmup=0 if cfg.tiny else 1)
    return Timing(t.median * n / subset, t.repeats, t.number), subset


def batch_row(
    label: str,
    t: Timing,
    base: Timing,
    n: int,
    target: float | None,
    note: str = "",
    baseline: str = "Python loop of the PyGLM fit",
) -> Row:
    rate = f"{n / t.median / 1e6:.3g} M fits/s"
    return Row(
        label,
        t,
        baseline,
        base,
        target=None if target is None else f"≤ {target:g} (≥ {1 / target:.0f}× faster)",
        limit=target,
        note=rate + (f"; {note}" if note else ""),
    )


def run(cfg: Config) -> Section:
    import jax

    section = Section(NAME, TITLE)
    n = cfg.size(100_000, 16)
    reps = cfg.repeats(5)
    base, subset = glm_loop(cfg, n)
    section.figures["pyglm_fits_per_s"] = n / base.median
    for dtype, name in ((np.float32, "float32"), (np.float64, "float64")):
        lights, corners = boxes(n, cfg.seed, dtype)
        t = measure(partial(numpy_fit, lights, corners), repeats=reps, warmup=1)
        section.rows.append(batch_row(f"fit_shadow, NumPy {name}", t, base, n, 0.1))

    first, t, dtype = time_jax(n, cfg.seed, reps, np.float32)
    section.rows.append(
        batch_row(
            "fit_shadow, jitted JAX float32",
            t,
            base,
            n,
            0.05,
            f"first call {first.median:.2f} s; result {dtype}",
        )
    )
    child = run_python(
        _X64_CHILD.format(n=n, seed=cfg.seed, repeats=reps), env={"JAX_ENABLE_X64": "1"}
    )
    section.rows.append(
        batch_row(
            "fit_shadow, jitted JAX float64 (child process, JAX_ENABLE_X64=1)",
            Timing(float(child["median"]), int(child["repeats"])),
            base,
            n,
            0.05,
            f"first call {float(child['first']):.2f} s; result {child['dtype']}",
        )
    )
    section.notes.append(
        f"Each point-light row fits all {n:,} pairs in one call (leading batch dimension). The "
        f"PyGLM loop was timed over {subset:,} pairs (glm.vec3 lists made before timing) and "
        f"scaled ×{n / subset:g} to {n:,}."
    )
    section.notes.append(
        "Targets: ≥ 20× the loop's rate in the faster backend (≤ 0.05 on the JAX rows), ≥ 10× "
        "in NumPy (≤ 0.1). This process runs JAX with jax_enable_x64="
        f"{bool(jax.config.read('jax_enable_x64'))} (JAX's default; float32 arrays stay "
        "float32); the float64 JAX row runs in a child process with JAX_ENABLE_X64=1."
    )
    return section
