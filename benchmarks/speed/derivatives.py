"""4. Derivatives: the jitted gradient of the fitting objective against its forward pass, and
``optimize_frustum`` on 1,000- and 500,000-vertex blockers and on a batch of 100 blockers."""

from __future__ import annotations

import math
from functools import partial
from typing import Any

import numpy as np

import shadowmath as sm

from ._scenes import MAP_SIZE, blob
from ._timing import Config, Row, Section, Timing, measure, once, synced

NAME = "derivatives"
TITLE = "4. Derivatives and the optimized fit"


def objective(params: Any, light: Any, vertices: Any, temperature: float) -> Any:
    """The fitting objective, from public functions only.

    ``log`` of the :func:`shadowmath.cross_section_area` of the smooth,
    off-centre frustum of the rolled frame ``(direction, roll) = params``
    (what ``optimize_frustum`` minimises, up to the constant MDV area).
    """
    import jax.numpy as jnp

    frame = sm.rolled_light_frame(light, params[:3], params[3])
    frustum = sm.smooth_frustum(frame, vertices, MAP_SIZE, temperature=temperature, symmetric=False)
    return jnp.log(sm.cross_section_area(frustum))


def _gradient_rows(cfg: Config, section: Section) -> None:
    import jax
    import jax.numpy as jnp

    for n in (cfg.size(1_000, 16), cfg.size(100_000, 64)):
        light, verts = blob(n, cfg.seed, np.float32)
        j_light, j_verts = jnp.asarray(light), jnp.asarray(verts)
        params = jnp.asarray([0.1, 0.05, 1.0, 0.3], jnp.float32)
        f = partial(objective, temperature=0.005)
        forward = jax.jit(f)
        gradient = jax.jit(jax.grad(f))
        value = forward(params, j_light, j_verts)
        g = gradient(params, j_light, j_verts)
        section.figures[f"objective_{n}"] = float(value)
        section.figures[f"gradient_norm_{n}"] = float(jnp.linalg.norm(g))
        reps = cfg.repeats(15)
        t_f = measure(
            synced(forward, params, j_light, j_verts), repeats=reps, min_time=cfg.min_time
        )
        t_g = measure(
            synced(gradient, params, j_light, j_verts), repeats=reps, min_time=cfg.min_time
        )
        section.rows.append(
            Row(
                f"jit(grad(objective)), {n:,} vertices, float32",
                t_g,
                "jit(objective), the forward pass",
                t_f,
                "≤ 3",
                3.0,
            )
        )


def _optimize_rows(cfg: Config, section: Section) -> None:
    # Fewer steps under --tiny: the figures only need to exist there.
    kwargs: dict[str, Any] = {"steps": 8, "starts": 2} if cfg.tiny else {}
    single: Timing | None = None
    n_small = cfg.size(1_000, 40)
    for n in (n_small, cfg.size(500_000, 200)):
        light, verts = blob(n, cfg.seed + n)
        run = partial(sm.optimize_frustum, light, verts, MAP_SIZE, **kwargs)
        first = once(run)
        t = measure(run, repeats=cfg.repeats(3 if n > 10_000 else 7), warmup=0)
        base = measure(
            partial(sm.fit_shadow, light, verts, MAP_SIZE),
            repeats=cfg.repeats(5),
            min_time=cfg.min_time,
        )
        fit = run()
        area = math.exp(float(np.min(fit.losses)))
        section.figures[f"optimized_area_vs_mdv_{n}"] = area
        big = n > 10_000
        section.rows.append(
            Row(
                f"optimize_frustum, {n:,} vertices, after compilation",
                t,
                'fit_shadow (method="mdv"), same blocker',
                base,
                target="≤ 1 s" if big else None,
                limit=1.0 if big else None,
                limit_on="seconds",
                note=f"first call {first.median:.2f} s; cross-section {area:.3f} of the MDV one",
            )
        )
        if n == n_small:
            single = t
    assert single is not None

    count = cfg.size(100, 3)
    rng = np.random.default_rng(cfg.seed)
    light, verts = blob(n_small, cfg.seed)
    # 100 blockers: the same ellipsoid turned about the line of sight and shifted a little.
    angles = rng.uniform(0, math.pi, count)
    turns = np.zeros((count, 3, 3))
    turns[:, 0, 0] = turns[:, 1, 1] = np.cos(angles)
    turns[:, 1, 0] = np.sin(angles)
    turns[:, 0, 1] = -turns[:, 1, 0]
    turns[:, 2, 2] = 1.0
    centre = verts.mean(axis=0)
    batch = (verts - centre) @ np.swapaxes(turns, -1, -2) + centre
    batch += rng.uniform(-1, 1, (count, 1, 3))
    lights = np.broadcast_to(light, (count, 3))
    run = partial(sm.optimize_frustum, lights, batch, MAP_SIZE, **kwargs)
    first = once(run)
    t = measure(run, repeats=cfg.repeats(3), warmup=0)
    section.rows.append(
        Row(
            f"optimize_frustum, batch of {count} blockers × {n_small:,} vertices, one call",
            t,
            f"{count} × the one-blocker median above",
            Timing(single.median * count, single.repeats, single.number),
            note=f"first call {first.median:.2f} s",
        )
    )


def run(cfg: Config) -> Section:
    section = Section(NAME, TITLE)
    _gradient_rows(cfg, section)
    _optimize_rows(cfg, section)
    section.notes.append(
        "objective(direction, roll) = log cross_section_area(smooth_frustum(rolled_light_frame("
        "light, direction, roll), vertices, 256, temperature=0.005, symmetric=False)): the "
        "off-centre smooth frustum that optimize_frustum minimises, from public functions."
    )
    section.notes.append(
        "optimize_frustum runs with its defaults (80 Adam steps from 6 starting rolls) on NumPy "
        "float64 input; with jax_enable_x64 off (JAX's default) it computes in float32. "
        "'cross-section' is its exact loss, as a ratio: the fitted off-centre frustum's "
        "cross-section over the MDV frustum's (lower is better)."
    )
    return section
