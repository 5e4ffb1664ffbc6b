"""fit_shadow's prepared doors: a call that recurs is read from the cache of its kind of
arguments, and must give what the whole door gives, results and refusals alike."""

from __future__ import annotations

import gc
import weakref
from typing import Any

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import shadowmath as sm
from shadowmath._fits.shadow import _door

FIELDS = ("world_to_light", "blocker_to_clip", "world_to_texture", "blocker_to_world")


def _outcome(call: Any) -> Any:
    """A call's result arrays, or its error's type and message."""
    try:
        s = call()
    except (ValueError, TypeError) as e:
        return (type(e), str(e))
    fr = s.frustum
    return [np.asarray(getattr(s, f)) for f in FIELDS] + [
        np.asarray(v) for v in (*s.frame, *fr[:8], s.casters_used)
    ]


def _assert_same(cached: Any, fresh: Any) -> None:
    if isinstance(fresh, tuple):
        assert cached == fresh
        return
    assert not isinstance(cached, tuple), cached
    for a, b in zip(cached, fresh, strict=True):
        np.testing.assert_array_equal(a, b)
        assert a.dtype == b.dtype


def _light(kind: str, rng: np.random.Generator, dtype: Any) -> Any:
    p = (rng.normal(size=3) * 0.2).astype(dtype)
    d = np.array([0.2, 0.3, -1.0], dtype=dtype)
    return {
        "xyz": p,
        "xyzw point": np.array([*p, 1.0], dtype=dtype),
        "xyzw w=2": np.array([*(2 * p), 2.0], dtype=dtype),
        "xyzw sun": np.array([*d, 0.0], dtype=dtype),
        "PointLight": sm.PointLight(p),
        "DirectionalLight": sm.DirectionalLight(d),
        "SpotLight": sm.SpotLight(p, np.array([0.0, 0.0, 1.0], dtype=dtype), 0.5),
    }[kind]


LIGHTS = ("xyz", "xyzw point", "xyzw w=2", "xyzw sun", "PointLight", "DirectionalLight",
          "SpotLight")  # fmt: skip


@settings(max_examples=60, deadline=None)
@given(
    kinds=st.lists(st.sampled_from(LIGHTS), min_size=2, max_size=4),
    counts=st.lists(st.integers(0, 12), min_size=4, max_size=4),
    triangles=st.booleans(),
    receivers=st.sampled_from([None, 0, 5]),
    up=st.booleans(),
    single=st.booleans(),
    seed=st.integers(0, 2**16),
)
def test_a_cached_door_answers_as_the_whole_door(
    kinds: list[str], counts: list[int], triangles: bool, receivers: int | None, up: bool,
    single: bool, seed: int,
) -> None:  # fmt: skip
    """Calls of changing light kinds, caster counts (0 included), receivers and options:
    each answers, bit for bit, what a call with no cached door answers (or raises the
    same error)."""
    rng = np.random.default_rng(seed)
    dtype = np.float32 if single else np.float64
    for i, kind in enumerate(kinds):
        n = counts[i % len(counts)]
        pts = (rng.normal(size=(3 * n, 3)) + [0.0, 0.0, 6.0]).astype(dtype)
        casters: Any = sm.Triangles(pts.reshape(n, 3, 3)) if triangles else pts
        options: dict[str, Any] = {}
        if receivers is not None:
            r = (rng.normal(size=(receivers, 3)) * 3 + [0.0, -2.0, 7.0]).astype(dtype)
            options["receivers"] = r
        if up:
            options["up"] = np.array([0.0, 1.0, 0.0], dtype=dtype)
        light = _light(kind, rng, dtype)

        def call(light: Any = light, casters: Any = casters, options: Any = options) -> Any:
            return sm.fit_shadow(light, casters, 64, **options)

        cached = _outcome(call)  # from the door of an earlier call of this kind, if any
        _door._DOORS.clear()
        fresh = _outcome(call)
        _assert_same(cached, fresh)
        _outcome(call)  # this call's door stays cached for the next one


def test_a_recurring_call_is_read_from_one_cached_door() -> None:
    """The cache holds one door per kind of arguments: new values, counts and light
    positions reuse it; another dtype, batch shape or option opens another."""
    _door._DOORS.clear()
    rng = np.random.default_rng(3)
    for n in (8, 9, 30):
        sm.fit_shadow(rng.normal(size=3) * 0.1, rng.normal(size=(n, 3)) + [0, 0, 6], 64)
    assert len(_door._DOORS) == 1
    box = rng.normal(size=(8, 3)) + [0, 0, 6]
    sm.fit_shadow(np.zeros(3, np.float32), box.astype(np.float32), 64)
    sm.fit_shadow(np.zeros((2, 3)), box, 64)
    sm.fit_shadow(np.zeros(3), box, 64, api="vulkan")
    sm.fit_shadow(np.zeros(3), box, 128)
    assert len(_door._DOORS) == 5


def test_the_cache_keeps_no_caller_array_alive() -> None:
    """A cached door holds kinds and shapes, not the arrays of the call that opened it."""
    _door._DOORS.clear()
    box = np.random.default_rng(1).normal(size=(5000, 3)) + [0, 0, 6]
    light = np.zeros(3)
    refs = [weakref.ref(box), weakref.ref(light)]
    sm.fit_shadow(light, box, 64)
    assert len(_door._DOORS) == 1
    del box, light
    gc.collect()
    assert all(r() is None for r in refs)


@pytest.mark.parametrize("method", ["mdv", "optimized"])
def test_static_refusals_hold_on_a_cached_door(method: str) -> None:
    """An option combination refused whatever the values is refused on every call, cached
    door or not (a directional light with near=)."""
    _door._DOORS.clear()
    box = np.random.default_rng(2).normal(size=(8, 3)) + [0, 0, 6]
    sun = np.array([0.0, 1.0, 0.0, 0.0])
    sm.fit_shadow(sun, box, 64)  # a door of this kind is cached
    for _ in range(2):
        with pytest.raises(ValueError, match=r"near/far|method"):
            sm.fit_shadow(sun, box, 64, near=np.array(1.0), method=method)
