"""4b. Compile: what a first ``jax.jit(jax.value_and_grad(loss))`` through each fit traces and
how long it takes to compile, in float64.

For ``fit_shadow`` per light kind and main options, ``fit_cascades`` (four cascades by
default, and a few options) and ``pcss_parameters``: the number of equations in the jaxpr
of ``value_and_grad(loss)`` (counted into every sub-jaxpr: nested ``jit``, ``cond``,
``while``, custom derivatives), the fused kernels XLA emits for it, and the time of
``jit(...).lower(...).compile()`` after ``jax.clear_caches()`` (tracing, lowering and
XLA's compile: what the first call pays, less running it), with JAX's persistent
compilation cache off. ``loss`` is the sum of the squares of the fit's matrices. Under
``--tiny`` every program is traced (its equations are counted) and the point light's fit
alone is compiled.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from typing import Any, NamedTuple

import numpy as np

import shadowmath as sm

from ._timing import Config, Row, Section, Timing

NAME = "compile"
TITLE = "4b. Compile: the first jit(value_and_grad) of each fit (float64)"

#: The programs whose compile time has a target (seconds): the first row of each.
TARGETS = {"fit_shadow, point light": 1.0, "fit_cascades, 4 cascades (defaults)": 2.0}


def count_equations(jaxpr: Any) -> int:
    """The equations of ``jaxpr`` and, recursively, of every jaxpr in their parameters."""
    from jax.extend import core

    total = 0
    for eqn in jaxpr.eqns:
        total += 1
        for value in eqn.params.values():
            for sub in value if isinstance(value, tuple | list) else (value,):
                if isinstance(sub, core.ClosedJaxpr):
                    total += count_equations(sub.jaxpr)
                elif isinstance(sub, core.Jaxpr):
                    total += count_equations(sub)
    return total


def _squares(*arrays: Any) -> Any:
    import jax.numpy as jnp

    return sum(jnp.sum(a * a) for a in arrays)


def _blocker() -> Any:
    rng = np.random.default_rng(2026)
    return rng.uniform(-1.0, 1.0, (8, 3)) + np.array([0.5, -0.4, 6.0])


def _camera() -> tuple[Any, Any, Any]:
    view = np.eye(4)
    view[:3, :3] = [[1, 0, 0], [0, 0.8, -0.6], [0, 0.6, 0.8]]
    view[:3, 3] = [0.0, -2.0, -30.0]
    f, n, far = 1.0, 0.1, 200.0
    a, b = (far + n) / (n - far), 2 * far * n / (n - far)
    proj = np.array([[f, 0, 0, 0], [0, f, 0, 0], [0, 0, a, b], [0, 0, -1, 0]])
    box = np.array([[-100.0, -100.0, -1.0], [100.0, 100.0, 10.0]])
    return view, proj, box


def _shadow_programs() -> dict[str, tuple[Callable[..., Any], tuple[Any, ...]]]:
    import jax.numpy as jnp

    verts = jnp.asarray(_blocker())
    floor = jnp.asarray([[-4.0, -4.0, 9.0], [4.0, -4.0, 9.0], [0.0, 4.0, 9.0]])
    axis = jnp.asarray([0.05, -0.02, 1.0])
    sun = jnp.asarray([0.3, 1.0, -0.2])
    place = jnp.eye(4).at[:3, 3].set(jnp.asarray([0.2, -0.1, 0.3]))

    def fit(light: Any, v: Any, **options: Any) -> Any:
        s = sm.fit_shadow(light, v, 256, **options)
        return _squares(s.blocker_to_clip, s.world_to_texture)

    def point(p: Any, v: Any) -> Any:
        return fit(sm.PointLight(p), v)

    def point_receivers(p: Any, v: Any) -> Any:
        return fit(sm.PointLight(p), v, receivers=floor)

    def point_placed(p: Any, v: Any) -> Any:
        return fit(sm.PointLight(p), v, blocker_to_world=place, api="vulkan", reversed_z=True)

    def spot(p: Any, v: Any) -> Any:
        return fit(sm.SpotLight(p, axis, jnp.asarray(0.6)), v)

    def directional(d: Any, v: Any) -> Any:
        return fit(sm.DirectionalLight(d), v)

    def directional_stable(d: Any, v: Any) -> Any:
        return fit(sm.DirectionalLight(d), v, receivers=floor, stable=True)

    origin = jnp.zeros(3)
    return {
        "fit_shadow, point light": (point, (origin, verts)),
        "fit_shadow, point light, receivers": (point_receivers, (origin, verts)),
        "fit_shadow, point light, blocker_to_world, vulkan, reversed_z": (
            point_placed,
            (origin, verts),
        ),
        "fit_shadow, spot light": (spot, (origin, verts)),
        "fit_shadow, directional light": (directional, (sun, verts)),
        "fit_shadow, directional light, receivers, stable": (directional_stable, (sun, verts)),
    }


def _other_programs() -> dict[str, tuple[Callable[..., Any], tuple[Any, ...]]]:
    import jax.numpy as jnp

    view, proj, box = (jnp.asarray(m) for m in _camera())
    sun = jnp.asarray([0.3, 0.1, 0.9])
    verts = jnp.asarray(_blocker())

    def cascades(d: Any, V: Any, **options: Any) -> Any:
        c = sm.fit_cascades(sm.DirectionalLight(d), V, proj, box, 1024, **options)
        return _squares(c.world_to_clip, c.world_to_texture)

    def stable(d: Any, V: Any) -> Any:
        return cascades(d, V, stable=True)

    def lispsm(d: Any, V: Any) -> Any:
        return cascades(d, V, warp="lispsm")

    def pcss(p: Any, v: Any) -> Any:
        q = sm.pcss_parameters(sm.fit_shadow(sm.PointLight(p), v, 256), light_radius=0.1)
        return _squares(q.texels_per_depth, q.near_depth)

    origin = jnp.zeros(3)
    return {
        "fit_cascades, 4 cascades (defaults)": (cascades, (sun, view)),
        "fit_cascades, 4 cascades, stable": (stable, (sun, view)),
        "fit_cascades, 4 cascades, LiSPSM warp": (lispsm, (sun, view)),
        "pcss_parameters of a point light's fit": (pcss, (origin, verts)),
    }


class Measured(NamedTuple):
    """One first compile of ``jit(value_and_grad(fn))``."""

    equations: int  # the jaxpr's, counted into sub-jaxprs
    traced: float  # seconds to trace it
    seconds: float  # lower + compile, wall clock
    cpu: float  # this process's CPU seconds for it (steadier on a shared machine)
    kernels: int  # the fused kernels of the optimized program (XLA's time grows with them)


def measure_program(fn: Callable[..., Any], args: tuple[Any, ...]) -> Measured:
    """:class:`Measured` for ``jit(value_and_grad(fn))``: the jaxpr's equations, the time to
    trace it, lower + compile in a fresh trace, and the fusions of the optimized program's
    entry computation."""
    import jax

    program = jax.value_and_grad(fn)
    jax.clear_caches()
    t0 = time.perf_counter()
    equations = count_equations(jax.make_jaxpr(program)(*args).jaxpr)
    traced = time.perf_counter() - t0
    jax.clear_caches()
    c0, t0 = time.process_time(), time.perf_counter()
    compiled = jax.jit(program).lower(*args).compile()
    seconds, cpu = time.perf_counter() - t0, time.process_time() - c0
    text = compiled.as_text()
    entry = text[text.index("\nENTRY ") :]
    entry = entry[: entry.index("\n}")]
    kernels = sum(" fusion(" in line for line in entry.splitlines())
    return Measured(equations, traced, seconds, cpu, kernels)


def run(cfg: Config) -> Section:
    import jax

    section = Section(NAME, TITLE)
    x64, cache = jax.config.jax_enable_x64, jax.config.jax_enable_compilation_cache
    jax.config.update("jax_enable_x64", True)
    jax.config.update("jax_enable_compilation_cache", False)
    try:
        programs = {**_shadow_programs(), **_other_programs()}
        for i, (name, (fn, args)) in enumerate(programs.items()):
            _row(cfg, section, name, (fn, args), compile_it=not cfg.tiny or i == 0)
    finally:
        jax.config.update("jax_enable_x64", x64)
        jax.config.update("jax_enable_compilation_cache", cache)
    section.notes.append(
        "median: lower + compile of jit(value_and_grad(loss)) after jax.clear_caches() "
        "(what the first call pays, less the run); equations: the jaxpr's, counted into "
        "sub-jaxprs; persistent compilation cache off",
    )
    section.notes.append(
        "fit_atlas has no row: it reads the atlas on the host and is not traced under jit "
        "(with JAX arrays it runs eagerly, its 2D lights by fit_shadow's formulas)"
    )
    return section


def _row(cfg: Config, section: Section, name: str, program: Any, *, compile_it: bool) -> None:
    limit = TARGETS.get(name)
    reps = cfg.repeats(3 if limit is not None else 1)
    samples, cpu = [], []
    equations, traced, kernels = 0, 0.0, 0
    for _ in range(reps if compile_it else 0):
        equations, traced, seconds, cpu_seconds, kernels = measure_program(*program)
        samples.append(seconds)
        cpu.append(cpu_seconds)
    if not compile_it:
        import jax

        fn, args = program
        t0 = time.perf_counter()
        equations = count_equations(jax.make_jaxpr(jax.value_and_grad(fn))(*args).jaxpr)
        traced = time.perf_counter() - t0
    key = name.replace(", ", "_").replace(" ", "_").replace("+", "")
    section.figures[f"equations_{key}"] = float(equations)
    section.figures[f"trace_s_{key}"] = traced
    if not samples:
        return
    section.figures[f"kernels_{key}"] = float(kernels)
    samples.sort()
    cpu.sort()
    section.figures[f"compile_s_{key}"] = samples[len(samples) // 2]
    section.figures[f"compile_cpu_s_{key}"] = cpu[len(cpu) // 2]
    section.rows.append(
        Row(
            f"{name}: {equations:,} equations, {kernels} kernels, traced in {traced:.2f} s, "
            f"compiled in {cpu[len(cpu) // 2]:.2f} s of CPU",
            Timing(samples[len(samples) // 2], len(samples)),
            target=None if limit is None else f"≤ {limit:g} s",
            limit=limit,
            limit_on="seconds",
        )
    )
