"""1. Single calls: ``fit_shadow``, ``planar_projection``, a cube map's matrices, a receiver's
texture matrix, PCSS's quantities, eager JAX, ``import shadowmath`` and the first fit in a fresh
process (every option of ``fit_shadow`` is in ``options``)."""

from __future__ import annotations

from functools import partial
from typing import Any

import numpy as np

import shadowmath as sm

from ._scenes import MAP_SIZE, SUN, blob, boxes, glm_cube, glm_fit, to_glm
from ._timing import Config, Row, Section, Timing, fmt_time, measure, run_python, synced

NAME = "single"
TITLE = "1. Single call"

_IMPORT = """
import json, time
t0 = time.perf_counter()
import numpy
t1 = time.perf_counter()
import shadowmath
t2 = time.perf_counter()
heavy = sorted(m for m in ("jax", "jaxlib", "numba", "scipy", "torch", "cupy", "tensorflow")
               if m in sys.modules)
shadowmath.fit_shadow  # its modules load on first use
t3 = time.perf_counter()
print(json.dumps({"numpy": t1 - t0, "shadowmath": t2 - t0, "fit_shadow": t3 - t0,
                  "heavy": heavy}))
"""

_IMPORT_NUMPY = """
import json, time
t0 = time.perf_counter()
import numpy
print(json.dumps({"numpy": time.perf_counter() - t0}))
"""

_FIRST_FIT = """
import json, sys, time
t0 = time.perf_counter()
import numpy as np
import shadowmath as sm
backend = {backend!r}
light = np.array({light!r}, np.float32)
box = np.array([[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (4, 6)], np.float32)
options = {options!r}
options = {{k: np.array(v, np.float32) if isinstance(v, list) else v for k, v in options.items()}}
if backend == "jax":
    import jax, jax.numpy as jnp
    light, box = jnp.asarray(light), jnp.asarray(box)
    block = jax.block_until_ready
else:
    block = lambda x: x
t1 = time.perf_counter()
block(sm.fit_shadow(light, box, 256, **options))
t2 = time.perf_counter()
print(json.dumps({{"import": t1 - t0, "first": t2 - t1, "total": t2 - t0,
                  "scipy": "scipy.linalg" in sys.modules}}))
"""

# The first fits timed in fresh processes: (label, backend, light, options).
_FLOOR = [[x, -3.0, z] for x in (-10.0, 10.0) for z in (-5.0, 15.0)]
FIRST_FITS: list[tuple[str, str, list[float], dict[str, Any]]] = [
    ("NumPy float32, point light", "numpy", [0.0, 0.0, 0.0], {}),
    (
        "NumPy float32, directional + 4 receivers, stable",
        "numpy",
        SUN.tolist(),
        {"receivers": _FLOOR, "stable": True},
    ),
    ("eager JAX float32, point light", "jax", [0.0, 0.0, 0.0], {}),
]


def _fresh(code: str, repeats: int) -> list[dict[str, Any]]:
    return [run_python(code) for _ in range(repeats)]


def _median_timing(values: list[float]) -> Timing:
    return Timing(float(np.median(values)), len(values), 1)


def first_fit_rows(cfg: Config) -> list[Row]:
    """Import + first ``fit_shadow`` in fresh processes: the first process, then warm ones.

    The first process may fill Numba's disk cache (or find it warm already); the row is the
    median of the processes after it (at least one), the first one is in the note.
    """
    rows = []
    for label, backend, light, options in FIRST_FITS:
        code = _FIRST_FIT.format(backend=backend, light=light, options=options)
        first, *warm = _fresh(code, 1 + max(cfg.repeats(3), 1))
        total = _median_timing([float(r["total"]) for r in warm])
        call = _median_timing([float(r["first"]) for r in warm])
        scipy = " (Numba's BLAS check imported scipy.linalg)" if warm[-1]["scipy"] else ""
        rows.append(
            Row(
                f"import + first fit_shadow in a fresh process, {label}, 8 vertices",
                total,
                target="≤ 0.5 s",
                limit=0.5,
                limit_on="seconds",
                note=(
                    f"the first call alone: {fmt_time(call.median)}{scipy}; the first process "
                    f"(disk cache as found): {fmt_time(float(first['total']))}"
                ),
            )
        )
    return rows


def cube_rows(cfg: Config, light: np.ndarray) -> list[Row]:
    """A cube map's matrices: ``cube_face_views`` + ``cube_face_projection`` (≤ 20 µs together).

    PyGLM's six ``lookAt`` and one 90° ``perspective`` are shown as the baseline (for
    reference: the target is on the time).
    """
    import glm

    near, far = 0.1, 50.0
    gl_light = glm.vec3(*map(float, light))

    def both() -> tuple[np.ndarray, np.ndarray]:
        return sm.cube_face_views(light), sm.cube_face_projection(near, far, map_size=MAP_SIZE)

    reps, fast = cfg.repeats(7), cfg.min_time
    return [
        Row(
            "cube_face_views(position) + cube_face_projection(near, far), NumPy float64",
            measure(both, repeats=reps, min_time=fast),
            "PyGLM: 6 lookAt + perspective(90°)",
            measure(partial(glm_cube, gl_light, near, far), repeats=reps, min_time=fast),
            target="≤ 20 µs",
            limit=20e-6,
            limit_on="seconds",
        )
    ]


def pcss_rows(cfg: Config, setup: sm.ShadowSetup) -> list[Row]:
    """PCSS's quantities per frame (issue 28, ≤ 10 µs): ``pcss_parameters`` of one 2D map and
    of a sun's four cascades, NumPy float64 (the cascades fitted once, outside the timing)."""
    view = np.eye(4)
    view[:3, 3] = [0.0, -2.0, -5.0]  # a camera 2 above the ground, looking down -z
    f = 1 / np.tan(0.5)
    proj = np.array([[f, 0, 0, 0], [0, f, 0, 0], [0, 0, -1.002, -0.2002], [0, 0, -1, 0]])
    box = np.array([[-60.0, -0.5, -120.0], [60.0, 15.0, 10.0]])
    cascades = sm.fit_cascades(SUN[:3], view, proj, box, 2048, count=4)
    reps, fast = cfg.repeats(7), cfg.min_time
    cases = (
        ("a point light's 2D map (fit_shadow)",
         partial(sm.pcss_parameters, setup, light_radius=0.2, map_size=MAP_SIZE)),
        ("a sun's 4 cascades (fit_cascades)",
         partial(sm.pcss_parameters, cascades, angular_radius=0.0047)),
    )  # fmt: skip
    return [
        Row(
            f"pcss_parameters of {label}, NumPy float64",
            measure(call, repeats=reps, min_time=fast),
            target="≤ 10 µs",
            limit=10e-6,
            limit_on="seconds",
        )
        for label, call in cases
    ]


def _full_door_row(cfg: Config, light: np.ndarray, verts: np.ndarray, base: Timing) -> Row:
    """A call whose arguments are of a kind not seen before: the whole door (conversion,
    kinds, shapes, static key) runs, as on the first call of each kind."""
    from shadowmath._fits.shadow import _door

    def fresh() -> object:
        _door._DOORS.clear()
        return sm.fit_shadow(light, verts, MAP_SIZE)

    t = measure(fresh, repeats=cfg.repeats(7), min_time=cfg.min_time)
    return Row(
        "fit_shadow, 8 vertices, NumPy float64, the whole door (a new kind of arguments)",
        t,
        "PyGLM lookAt + perspective, bounding sphere",
        base,
    )


def _prepared_row(cfg: Config, light: np.ndarray, verts: np.ndarray, base: Timing) -> Row:
    """The per-frame path: a :class:`ShadowFitter` fitting into buffers it was given."""
    typed = sm.PointLight(light)
    fitter = sm.ShadowFitter(typed, verts, MAP_SIZE)
    out = fitter.buffers()
    t = measure(
        partial(fitter.fit, typed, verts, out=out), repeats=cfg.repeats(7), min_time=cfg.min_time
    )
    return Row(
        "ShadowFitter.fit (prepared), 8 vertices, NumPy float64, into the caller's buffers",
        t,
        "PyGLM lookAt + perspective, bounding sphere",
        base,
        target="≤ 1",
        limit=1.0,
    )


def run(cfg: Config) -> Section:
    section = Section(NAME, TITLE)
    rows = section.rows
    reps, fast = cfg.repeats(7), cfg.min_time

    # fit_shadow, NumPy float64, against the PyGLM bounding-sphere fit of the same blocker.
    light8, box8 = boxes(1, cfg.seed)
    sizes = [(8, light8[0], box8[0])]
    for n in (cfg.size(1_000, 20), cfg.size(100_000, 50)):
        light, verts = blob(n, cfg.seed)
        sizes.append((n, light, verts))
    glm8 = None
    for n, light, verts in sizes:
        gl_light, gl_verts = to_glm(light, verts)
        base = measure(partial(glm_fit, gl_light, gl_verts), repeats=reps, min_time=fast)
        glm8 = glm8 or base
        t = measure(partial(sm.fit_shadow, light, verts, MAP_SIZE), repeats=reps, min_time=fast)
        is8 = n == 8
        rows.append(
            Row(
                f"fit_shadow, {n:,} vertices, NumPy float64",
                t,
                "PyGLM lookAt + perspective, bounding sphere",
                base,
                target="≤ 2" if is8 else None,
                limit=2.0 if is8 else None,
            )
        )
        if is8:
            rows.append(_full_door_row(cfg, light, verts, base))
            rows.append(_prepared_row(cfg, light, verts, base))
    assert glm8 is not None

    # planar_projection against the one-line NumPy formula.
    plane = np.array([0.0, 1.0, 0.0, 0.0])
    lamp = np.array([1.0, 10.0, 2.0, 1.0])

    def one_line() -> np.ndarray:
        return np.dot(plane, lamp) * np.eye(4) - np.outer(lamp, plane)

    base = measure(one_line, repeats=reps, min_time=fast)
    t = measure(lambda: sm.planar_projection(plane, lamp), repeats=reps, min_time=fast)
    rows.append(
        Row(
            "planar_projection, NumPy float64",
            t,
            "np.dot(plane, L) * np.eye(4) - np.outer(L, plane)",
            base,
            target="≤ 1",
            limit=1.0,
        )
    )

    rows.extend(cube_rows(cfg, light8[0]))

    # A receiver's texture matrix from a fitted setup, against the plain product.
    setup = sm.fit_shadow(light8[0], box8[0], MAP_SIZE)
    rows.extend(pcss_rows(cfg, setup))
    placement = np.eye(4)
    placement[:3, 3] = [0.0, -1.0, 0.0]
    base = measure(lambda: setup.world_to_texture @ placement, repeats=reps, min_time=fast)
    t = measure(lambda: sm.receiver_texture_matrix(setup, placement), repeats=reps, min_time=fast)
    rows.append(
        Row(
            "receiver_texture_matrix(setup, receiver_to_world) of a fitted setup",
            t,
            "setup.world_to_texture @ receiver_to_world",
            base,
        )
    )

    # The depth-map system's functions (issue 10): a directional fit with receivers, and PCF.
    floor = np.stack(np.meshgrid(np.linspace(-5, 5, 8), [-2.0], np.linspace(0, 10, 8)), -1)
    floor = floor.reshape(-1, 3)
    sun = SUN
    t = measure(
        lambda: sm.fit_shadow(sun, box8[0], MAP_SIZE, receivers=floor),
        repeats=reps,
        min_time=fast,
    )
    rows.append(
        Row(
            "fit_shadow, directional light, 8 casters + 64 receiver points, NumPy float64",
            t,
            "PyGLM lookAt + perspective, bounding sphere",
            glm8,
        )
    )
    rng = np.random.default_rng(cfg.seed)
    depth_map = rng.uniform(0.2, 1.0, (MAP_SIZE, MAP_SIZE))
    count = cfg.size(10_000, 16)
    coords, depths = rng.uniform(0, 1, (count, 2)), rng.uniform(0.2, 1.0, count)
    cols = np.minimum((coords[:, 0] * MAP_SIZE).astype(int), MAP_SIZE - 1)
    rows_ = np.minimum((coords[:, 1] * MAP_SIZE).astype(int), MAP_SIZE - 1)
    base = measure(lambda: depths <= depth_map[rows_, cols], repeats=reps, min_time=fast)
    t = measure(
        lambda: sm.pcf(depth_map, coords, depths, pcf_radius=1), repeats=reps, min_time=fast
    )
    rows.append(
        Row(
            f"pcf, {count:,} lookups, 3x3 box, {MAP_SIZE}² map, NumPy float64",
            t,
            "the same lookups unfiltered (one texel each, NumPy indexing)",
            base,
        )
    )

    # Eager JAX on concrete arrays (no jit by the caller).
    import jax.numpy as jnp

    j_light, j_box = jnp.asarray(light8[0], jnp.float32), jnp.asarray(box8[0], jnp.float32)
    t = measure(synced(sm.fit_shadow, j_light, j_box, MAP_SIZE), repeats=cfg.repeats(5))
    rows.append(
        Row(
            "fit_shadow, 8 vertices, eager JAX float32 (concrete arrays)",
            t,
            "PyGLM lookAt + perspective, bounding sphere",
            glm8,
            target="≤ 1 ms",
            limit=1e-3,
            limit_on="seconds",
        )
    )

    # import shadowmath, and the first fit, in fresh processes.
    imports = _fresh(_IMPORT, cfg.repeats(5))
    numpy_alone = _median_timing([float(r["numpy"]) for r in _fresh(_IMPORT_NUMPY, cfg.repeats(5))])
    heavy = sorted({m for r in imports for m in r["heavy"]})
    for label, field in (
        ("import shadowmath", "shadowmath"),
        ("import shadowmath; shadowmath.fit_shadow", "fit_shadow"),
    ):
        rows.append(
            Row(
                f"{label} (fresh process, NumPy's import included)",
                _median_timing([float(r[field]) for r in imports]),
                "python -c 'import numpy' (fresh process)",
                numpy_alone,
                target="≤ 0.15 s",
                limit=0.15,
                limit_on="seconds",
            )
        )
    section.notes.append(
        "after `import shadowmath` these heavy modules were in sys.modules: "
        + (", ".join(heavy) if heavy else "none (of jax, jaxlib, numba, scipy, torch, cupy, tf)")
    )
    section.figures["import_heavy_modules"] = float(len(heavy))
    rows.extend(first_fit_rows(cfg))
    section.notes.append(
        "PyGLM's input is a list of glm.vec3 made before timing, shadowmath's a NumPy array; "
        "ratio = median / baseline median (below 1: faster than the baseline)."
    )
    return section
