"""3. Large blocker: one ``fit_shadow`` of 4M float32 vertices against one full read of the array
(a flat ``sum``, measured in the same run), NumPy and jitted JAX."""

from __future__ import annotations

from typing import Any

import numpy as np

import shadowmath as sm

from ._scenes import MAP_SIZE, blob
from ._timing import Config, Row, Section, Timing, measure, once, synced

NAME = "large"
TITLE = "3. Large blocker: 4M float32 vertices"
BASELINE = "one flat sum of the array, NumPy"


def time_jax(
    light: np.ndarray, verts: np.ndarray, repeats: int, device: Any = None
) -> dict[str, Timing]:
    """First call and medians of the jitted fit, and of a jitted flat sum, on ``device``."""
    import jax
    import jax.numpy as jnp

    j_light = jax.device_put(light, device)
    j_verts = jax.device_put(verts, device)
    fit = jax.jit(lambda light, verts: sm.fit_shadow(light, verts, MAP_SIZE))
    total = jax.jit(jnp.sum)
    return {
        "first": once(synced(fit, j_light, j_verts)),
        "fit": measure(synced(fit, j_light, j_verts), repeats=repeats, warmup=0),
        "sum": measure(synced(total, j_verts), repeats=repeats, warmup=1),
    }


def run(cfg: Config) -> Section:
    section = Section(NAME, TITLE)
    n = cfg.size(4_000_000, 1_000)
    light, verts = blob(n, cfg.seed, np.float32)
    section.figures["megabytes"] = verts.nbytes / 1e6
    base = measure(verts.sum, repeats=cfg.repeats(9), min_time=cfg.min_time)
    t = measure(lambda: sm.fit_shadow(light, verts, MAP_SIZE), repeats=cfg.repeats(5), warmup=1)
    section.rows.append(
        Row(f"fit_shadow, {n:,} vertices, NumPy float32", t, BASELINE, base, "≤ 3", 3.0)
    )
    jx = time_jax(light, verts, cfg.repeats(5))
    section.rows.append(
        Row(
            f"fit_shadow, {n:,} vertices, jitted JAX float32",
            jx["fit"],
            BASELINE,
            base,
            "≤ 3",
            3.0,
            note=f"first call {jx['first'].median:.2f} s",
        )
    )
    section.rows.append(
        Row("flat sum of the array, jitted JAX (for reference)", jx["sum"], BASELINE, base)
    )
    section.notes.append(
        f"The array is {verts.nbytes / 1e6:.0f} MB ({n:,} × 3 float32), C-contiguous; the "
        "baseline reads it once (`verts.sum()`)."
    )
    return section
