"""5. GPU: the batch and large-blocker figures of the jitted JAX path on a GPU, when one is present.

Without one (``jax.devices("gpu")`` finds none) the section says so and is skipped: it is a
benchmark, not a test.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from . import batch, large
from ._scenes import blob
from ._timing import Config, Row, Section, measure

NAME = "gpu"
TITLE = "5. GPU: jitted JAX on the GPU"


def gpu_devices() -> list[Any]:
    try:
        import jax

        return list(jax.devices("gpu"))
    except (ImportError, RuntimeError):
        return []


def run(cfg: Config) -> Section:
    section = Section(NAME, TITLE)
    devices = gpu_devices()
    if not devices:
        section.skipped = "no GPU present (jax.devices('gpu') found none), GPU section skipped."
        return section
    device = devices[0]
    section.notes.append(f"device: {device.device_kind} ({device.platform}, {device})")

    n = cfg.size(100_000, 16)
    base, subset = batch.glm_loop(cfg, n)
    first, t, dtype = batch.time_jax(n, cfg.seed, cfg.repeats(7), np.float32, device)
    section.rows.append(
        batch.batch_row(
            f"batch: fit_shadow, {n:,} × 8 vertices, jitted JAX float32 on the GPU",
            t,
            base,
            n,
            0.05,
            f"first call {first.median:.2f} s; result {dtype}",
        )
    )
    section.notes.append(f"The PyGLM loop (CPU) was timed over {subset:,} pairs and scaled.")

    m = cfg.size(4_000_000, 1_000)
    light, verts = blob(m, cfg.seed, np.float32)
    cpu_sum = measure(verts.sum, repeats=cfg.repeats(9), min_time=cfg.min_time)
    jx = large.time_jax(light, verts, cfg.repeats(7), device)
    section.rows.append(
        Row(
            f"large: fit_shadow, {m:,} vertices, jitted JAX float32 on the GPU",
            jx["fit"],
            "one flat sum of the array on the GPU (jitted)",
            jx["sum"],
            "≤ 3",
            3.0,
            note=f"first call {jx['first'].median:.2f} s",
        )
    )
    section.rows.append(
        Row(
            "large: flat sum on the GPU (for reference)",
            jx["sum"],
            large.BASELINE + " (CPU)",
            cpu_sum,
        )
    )
    return section
