"""The cores' signatures carry shapes, as the public ones do (tests/test_shapes.py).

Every function of ``shadowmath._math`` and ``shadowmath._scene`` annotates each parameter
and its result, with no bare ``Any`` (nor ``Any`` as an item of a tuple, list or union):
an array has its jaxtyping shape (``Float[Array, "*batch N 3"]``), a per-entry formula's
component is a :data:`~shadowmath._boundary._shapes.Scalar`, ``Truth`` or ``Row`` (a
number per entry, an array of the batch's shape on whole arrays). Then the suite runs a
representative set of fits with every core checked against its annotations, as the
public functions are after every call: the per-entry formulas through ``specialize``
(their copies on NumPy arrays and on Python floats), the topic cores wherever a module
holds them by name.
"""

from __future__ import annotations

import importlib
import inspect
import pkgutil
import sys
import types
import typing
from collections.abc import Callable, Iterator
from typing import Any

import numpy as np
import pytest
from jaxtyping import TypeCheckError

import shadowmath as sm
from shadowmath._backends import _kernels
from shadowmath._boundary._shapes import _checking
from shadowmath._math import _specialize, _vector

from .cameras import perspective

CORE_PACKAGES = ("shadowmath._math", "shadowmath._scene")

# Cores whose signatures are not yet shaped (being rewritten in parallel); each entry names
# why. Empty when every core is annotated.
PENDING: dict[str, str] = {}

# The fits' own cores (trusted arrays in, arrays out), checked as the cores of _math are.
FIT_CORES: dict[str, tuple[str, ...]] = {
    "shadowmath._fits.cube._driver": (
        "cube_depth_core",
        "nearest_triangle",
        "_candidates",
        "_chebyshev",
        "_safe_divide",
        "triangle_min_chebyshev",
    ),
    "shadowmath._fits.atlas._fit_cubes": ("_face_projections",),
    "shadowmath._fits.cascades._driver": ("_compiled", "_arrays", "_warp", "_result"),
    "shadowmath._fits.shadow._arrays": (
        "driver",
        "fit_arrays",
        "_report",
        "_components",
        "_vertex_source",
    ),
}

# (module, function, parameter): typed Any by design, with the reason.
ALLOWED: dict[tuple[str, str, str], str] = {}


def _core_modules() -> list[str]:
    names = []
    for package in CORE_PACKAGES:
        path = importlib.import_module(package).__path__
        names += [f"{package}.{m.name}" for m in pkgutil.iter_modules(path)]
    return sorted(names)


def _functions(module: types.ModuleType) -> list[tuple[str, types.FunctionType]]:
    """The functions a module defines (imported ones are their own module's)."""
    return [
        (name, value)
        for name, value in vars(module).items()
        if isinstance(value, types.FunctionType) and value.__module__ == module.__name__
    ]


def _has_any(hint: Any) -> bool:
    """``Any`` itself, or as an item of a tuple, a list or a union (a shape left out)."""
    if hint is Any:
        return True
    origin = typing.get_origin(hint)
    if origin in (tuple, list, typing.Union, types.UnionType):
        return any(_has_any(a) for a in typing.get_args(hint) if a is not Ellipsis)
    return False


def test_the_core_packages_are_found():
    modules = _core_modules()
    assert "shadowmath._math._formulas" in modules
    assert "shadowmath._scene._cull" in modules
    assert set(PENDING) <= set(modules)


def _problems(name: str, functions: list[tuple[str, types.FunctionType]]) -> list[str]:
    short = name.rsplit(".", 1)[1]
    problems = []
    for fname, fn in functions:
        hints = typing.get_type_hints(fn)  # every annotation evaluates in its module
        params = [p for p in inspect.signature(fn).parameters if p not in ("self", "cls")]
        for p in [*params, "return"]:
            if (short, fname, p) in ALLOWED:
                continue
            if p not in hints:
                problems.append(f"{fname}: {p} not annotated")
            elif _has_any(hints[p]):
                problems.append(f"{fname}: {p} typed {hints[p]} (annotate the shape)")
    return problems


@pytest.mark.parametrize("name", _core_modules())
def test_every_core_parameter_is_typed_without_any(name):
    if name in PENDING:
        pytest.xfail(PENDING[name])
    problems = _problems(name, _functions(importlib.import_module(name)))
    assert not problems, "\n".join(problems)


@pytest.mark.parametrize("name", sorted(FIT_CORES))
def test_the_fits_cores_are_typed_without_any(name):
    module = importlib.import_module(name)
    problems = _problems(name, [(f, getattr(module, f)) for f in FIT_CORES[name]])
    assert not problems, "\n".join(problems)


def test_any_is_found_where_it_hides():
    assert _has_any(Any)
    assert _has_any(tuple[Any, ...])
    assert _has_any(tuple[int, tuple[float, Any]])
    assert _has_any(int | Any)
    assert not _has_any(tuple[float, ...])
    assert not _has_any(dict[str, Any])  # a table of values of every kind: not a shape


# ---------------------------------------------------------------- the cores checked at run time


def _checked_specialize(plain: Callable[..., Any]) -> Callable[..., Any]:
    """``specialize`` whose per-entry copies check their annotations on every call (the
    Python and array forms only: a compiled loop, ``wrap`` given, is left alone)."""
    originals = {
        name: getattr(module, name)
        for module, functions in _specialize._MODULES
        for name in functions
    }

    def checked(copy: types.FunctionType) -> Callable[..., Any]:
        copy.__annotations__ = originals[copy.__name__].__annotations__
        return _checking(copy)

    def specialize(primitives: Any, wrap: Any = None, *, loop: bool = True) -> Any:
        return plain(primitives, checked if wrap is None else wrap, loop=loop)

    return specialize


@pytest.fixture
def checked_cores(monkeypatch: pytest.MonkeyPatch) -> Iterator[None]:
    """Every core a module of the package holds by name is checked after each call, and the
    formulas are specialized anew with checked copies (their caches cleared before and
    after, so no other test sees them)."""
    formula_names = {n for _, functions in _specialize._MODULES for n in functions}
    checked: dict[int, Callable[..., Any]] = {}
    for name in _core_modules():
        for fname, fn in _functions(importlib.import_module(name)):
            if fname not in formula_names:  # those are checked through their copies
                checked[id(fn)] = _checking(fn)
    for name, fnames in FIT_CORES.items():
        module = importlib.import_module(name)
        checked.update({id(getattr(module, f)): _checking(getattr(module, f)) for f in fnames})
    checked[id(_specialize.specialize)] = _checked_specialize(_specialize.specialize)
    for mod_name, module in list(sys.modules.items()):
        if mod_name.split(".")[0] != "shadowmath" or module is None:
            continue
        for attr, value in list(vars(module).items()):
            if isinstance(value, types.FunctionType) and id(value) in checked:
                if mod_name in _FORMULA_MODULES:
                    continue  # specialize (and Numba) read these modules' own functions
                monkeypatch.setattr(module, attr, checked[id(value)])
    caches = _caches()
    for cache in caches:
        cache.cache_clear()
    yield
    for cache in caches:
        cache.cache_clear()


_FORMULA_MODULES = {module.__name__ for module, _ in _specialize._MODULES}


def _caches() -> list[Any]:
    """The caches that hold specialized formulas."""
    from shadowmath._fits.shadow import _arrays, _driver

    return [
        _specialize.formulas,
        _specialize.scalar_formulas,
        _arrays._namespace,
        _driver._jitted_fit,
    ]


BOX = np.array([[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (4, 6)], np.float64)
GROUND = np.array([[-8.0, -8.0, 9.0], [8.0, -8.0, 9.0], [0.0, 8.0, 9.0]])


def _fits() -> None:
    """A representative set of fits: every light kind, receivers, a stable map, cascades."""
    rng = np.random.default_rng(5)
    lights = rng.normal(size=(2, 3)) * 0.1
    for light in (lights[0], lights, sm.PointLight(lights[0])):
        sm.fit_shadow(light, BOX, 64, receivers=sm.Triangles(GROUND[None]))
    sm.fit_shadow(sm.DirectionalLight([0.1, 0.2, 1.0]), BOX, (64, 32), stable=True)
    sm.fit_shadow(sm.SpotLight([0.0, 0.0, 0.0], [0.0, 0.0, 1.0], 0.6), BOX, 64)
    sm.fit_shadow([0.0, 0.0, 0.0], BOX.astype(np.float32), 64, near=1.0, far=20.0)
    view = np.eye(4)
    proj = perspective(1.0, 1.5, 0.5, 50.0)
    sun = sm.DirectionalLight([0.3, -1.0, 0.2])
    scene = np.array([[-20.0, -5.0, -40.0], [20.0, 5.0, 0.0]])
    sm.fit_cascades(sun, view, proj, scene, 256, count=3)
    sm.fit_cascades(sun, view, proj, scene, 256, count=2, stable=True)
    # The loop form's fitted orientation, the visible range with a state, given splits, up.
    sm.fit_cascades(sun, view, proj, scene, 256, count=2, orientation="fitted")
    seen = sm.fit_cascades(sun, view, proj, scene, 256, count=2, depth_range="visible", stable=True)
    sm.fit_cascades(
        sun, view, proj, scene, 256, count=2, depth_range="visible", stable=True, state=seen.state
    )
    sm.fit_cascades(sun, view, proj, scene, 256, splits=[0.5, 5.0, 50.0], up=[0.0, 1.0, 0.0])
    sm.cube_face_views([[0.0, 1.0, 2.0]])
    sm.cube_depth_range([0.0, 0.0, 0.0], BOX)
    frame = sm.light_frame([0.0, 0.0, 0.0], BOX)
    sm.adaptive_frustum(frame, BOX, 64)
    sm.smooth_frustum(frame, BOX, 64, temperature=0.01)
    fit = sm.fit_shadow(lights, BOX, 64)
    sm.pcss_parameters(fit, light_radius=0.1)
    points, normals = GROUND[:2], np.array([[0.0, 0.0, -1.0]])
    M = np.asarray(fit.world_to_texture)[:, None]
    sm.slope_scaled_bias(M, points, normals, map_size=64)
    sm.normal_offset(M, points, normals, map_size=64, pcf_radius=1, pcf_filter="bilinear")
    sm.pcf(np.full((8, 8), 0.5), np.full((3, 2), 0.5), np.full(3, 0.25), pcf_radius=1)
    sm.area_light_samples(np.zeros(3), np.eye(3)[0], np.eye(3)[1], 4, seed=0)


def test_the_cores_keep_their_signatures_on_the_python_loop(checked_cores):
    with _kernels.disabled():
        _fits()


def test_the_cores_keep_their_signatures_on_whole_arrays(checked_cores):
    with _kernels.array_path():
        _fits()


def test_the_cores_keep_their_signatures_around_the_compiled_loop(checked_cores):
    """With Numba the loops run compiled (unchecked); the doors' cores are still checked."""
    _fits()


def test_the_cores_keep_their_signatures_under_jax(checked_cores):
    """Traced: the components are tracers, the status a record of checks."""
    import jax.numpy as jnp

    lights = jnp.asarray([[0.0, 0.0, 0.0], [0.1, 0.0, -0.1]])
    sm.fit_shadow(lights, jnp.asarray(BOX), 64, receivers=sm.Triangles(jnp.asarray(GROUND[None])))
    sm.fit_shadow(sm.DirectionalLight(jnp.asarray([0.1, 0.2, 1.0])), jnp.asarray(BOX), 64)


def test_the_checked_cores_refuse_what_their_signatures_refuse(checked_cores):
    """The checking is on: a formula's copy and a topic core each refuse a wrong argument."""
    F, S = _specialize.formulas(np), _specialize.scalar_formulas()
    one = np.ones(2)
    assert np.allclose(F.normalize3(one, one, one)[3], np.sqrt(3))
    assert S.two_sum(1.0, 2.0**-60) == (1.0, 2.0**-60)
    with pytest.raises(TypeCheckError, match="two_sum: argument a"):
        S.two_sum(1j, 2.0)  # a complex number is no real component
    with pytest.raises(TypeCheckError, match="_numpy_where: argument a"):
        F.normalize3(np.ones(2, bool), one, one)  # a mask where a component is meant
    with pytest.raises(TypeCheckError, match="dot: argument a"):
        _vector.dot(np, np.ones((2, 3), int), np.ones((2, 3)))  # integers: not Float
