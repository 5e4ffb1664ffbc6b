"""Stable cascades with a state along a camera path: sizes change only at ladder crossings.

With the ladder ``2^(k/4)``, a value in use ``p`` is kept while the target ``t`` satisfies
``t <= p <= q s^M`` (``q`` the ladder value just above ``t``, ``docs/cascades.md``). If ``q`` is
the same as in the frame before, ``p`` is kept: ``p`` was ``q`` or was kept with ``p >= t``,
and a ladder value at least ``t`` is at least ``q``. So a value in use changes only in a frame
where its target's ladder value changed: a *ladder crossing*. The targets are the depth
range's ends (the visible range, from Qhull's frustum-and-box intersection, or the measured
one given) and each slice's visible part's half-width (half the larger side of its light-space
bounds, Qhull's vertices); a stable square's size is the lesser of its ladder half-width and
its slice's sphere (which depends on the splits only), plus half a texel. Hence the counts
below are bounded by the crossings, derived from the oracle, not from the fit.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
import pytest

import shadowmath as sm

from .cameras import perspective
from .test_cascade_range import BOX, SUN, is_ladder, pose, visible
from .test_cascades import body

FRAMES = 30
PROJ = perspective(1.0, 1.6, 0.1, 400.0)


def frames() -> Any:
    """A camera that climbs from 1.7 to 60, pitches down, turns and moves sideways."""
    t = np.linspace(0.0, 1.0, FRAMES)
    for k in range(FRAMES):
        h = 1.7 * (60.0 / 1.7) ** t[k]
        yield pose(h, 0.05 + 0.85 * t[k], yaw=0.4 + 1.2 * t[k], x=10.0 + 3.0 * k)


def half_width_targets(view: np.ndarray, c: Any) -> list[float]:
    """Half the larger side of each slice's visible part's light-space bounds (Qhull); of the
    whole slice where it misses the scene (a measured range may reach past it)."""
    out = []
    for i in range(len(c.band_end)):
        try:
            v = body(view, PROJ, BOX, c.splits[i], c.band_end[i])
        except AssertionError:  # the slice misses the box
            v = body(view, PROJ, BOX * 1e4, c.splits[i], c.band_end[i])
        xy = v @ c.world_to_light[i, :2, :3].T
        out.append(0.5 * float(np.max(xy.max(axis=0) - xy.min(axis=0))))
    return out


@pytest.mark.parametrize("measured", [False, True])
def test_stable_sizes_change_only_at_ladder_crossings(measured: bool) -> None:
    state, prev, last_range, last_targets = sm.CascadeState.initial(), None, None, None
    sizes = splits = range_crossings = crossings = 0
    for view in frames():
        lo, hi = visible(view, PROJ, BOX)
        if measured:  # last frame's visible depths, as a depth buffer's min/max would give
            rng: Any = np.array(last_range if last_range is not None else (lo, hi))
            lo, hi = rng
        else:
            rng = "visible"
        c = sm.fit_cascades(SUN, view, PROJ, BOX, 512, depth_range=rng, stable=True, state=state)
        assert np.all(is_ladder(c.state.half_width))  # sizes from the ladder
        ends = (math.floor(4 * math.log2(lo)), math.ceil(4 * math.log2(hi)))
        widths = tuple(math.ceil(4 * math.log2(t)) for t in half_width_targets(view, c))
        if prev is not None:
            size_changed = bool(np.any(c.frustum.half_width != prev.frustum.half_width))
            split_changed = bool(np.any(c.splits != prev.splits))
            assert not split_changed or ends != last_targets[0]
            assert not size_changed or (ends, widths) != last_targets
            same = c.frustum.half_width == prev.frustum.half_width
            for k, centre in enumerate(("center_x", "center_y")):
                move = (getattr(c.frustum, centre) - getattr(prev.frustum, centre))[same]
                move = move / c.texel_size[same, k]
                np.testing.assert_allclose(move, np.round(move), rtol=0, atol=1e-9)
            sizes, splits = sizes + size_changed, splits + split_changed
            range_crossings += ends != last_targets[0]
            crossings += (ends, widths) != last_targets
        prev, state, last_targets = c, c.state, (ends, widths)
        last_range = visible(view, PROJ, BOX)
    print(f"sizes {sizes}, splits {splits}, crossings {range_crossings} / {crossings}")
    assert 0 < splits <= range_crossings and 0 < sizes <= crossings < FRAMES - 1
