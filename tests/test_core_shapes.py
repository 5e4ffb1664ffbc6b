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

import shadowmath as sm
from shadowmath._backends import _kernels
from shadowmath._boundary._shapes import _checking
from shadowmath._math import _specialize

CORE_PACKAGES = ("shadowmath._math", "shadowmath._scene")

# Cores whose signatures are not yet shaped (being rewritten in parallel); each entry names
# why. Empty when every core is annotated.
_REWRITTEN = "its bodies are being rewritten (records for slots, one form per step)"
PENDING: dict[str, str] = {
    f"shadowmath._math.{m}": _REWRITTEN
    for m in (
        "_ball_support",
        "_cascade_steps",
        "_fit_entry",
        "_loops",
        "_passes",
        "_rows",
        "_vertex_passes",
    )
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


@pytest.mark.parametrize("name", _core_modules())
def test_every_core_parameter_is_typed_without_any(name):
    if name in PENDING:
        pytest.xfail(PENDING[name])
    module = importlib.import_module(name)
    short = name.rsplit(".", 1)[1]
    problems = []
    for fname, fn in _functions(module):
        hints = typing.get_type_hints(fn)  # every annotation evaluates in its module
        params = [p for p in inspect.signature(fn).parameters if p not in ("self", "cls")]
        for p in [*params, "return"]:
            if (short, fname, p) in ALLOWED:
                continue
            if p not in hints:
                problems.append(f"{fname}: {p} not annotated")
            elif _has_any(hints[p]):
                problems.append(f"{fname}: {p} typed {hints[p]} (annotate the shape)")
    assert not problems, "\n".join(problems)


def test_any_is_found_where_it_hides():
    assert _has_any(Any)
    assert _has_any(tuple[Any, ...])
    assert _has_any(tuple[int, tuple[float, Any]])
    assert _has_any(int | Any)
    assert not _has_any(tuple[float, ...])
    assert not _has_any(dict[str, Any])  # a table of values of every kind: not a shape
