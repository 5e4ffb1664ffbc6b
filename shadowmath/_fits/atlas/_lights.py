r"""The lights of :func:`fit_atlas` read into one kind and one row per light.

Typed lights (:class:`PointLight`, :class:`SpotLight`, :class:`DirectionalLight`, each
possibly a batch) or an ``(L, 4)`` / ``(L, 3)`` array become an ``(L,)`` kind and an
``(L, 8)`` row: position or direction, then a spot's axis, ``tan(angle)`` and angle.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import NDArray

from shadowmath._boundary._validate import require_last, shape_error
from shadowmath._fits._light_kinds import KIND_OF, POINT, SPOT, SUN, homogeneous, spot_row
from shadowmath.lights import DirectionalLight, PointLight, SpotLight

__all__ = ["read_lights"]

Ints = NDArray[np.int64]


def read_lights(lights: Any, count: int) -> tuple[Ints, Any]:
    """Each light's kind and its ``(L, 8)`` row: position or direction, then a spot's
    axis, ``tan(angle)`` and angle."""
    if isinstance(lights, _TYPED):
        lights = [lights]
    if isinstance(lights, list | tuple) and (not lights or isinstance(lights[0], _TYPED)):
        kinds: list[int] = []
        rows: list[list[float]] = []
        for i, light in enumerate(lights):
            kind = _KINDS.get(type(light))
            if kind is None:
                raise ValueError(
                    f"lights[{i}]: expected sm.PointLight, sm.SpotLight or sm.DirectionalLight, "
                    f"got {type(light).__name__}"
                )
            first = light[0]
            if type(first) is np.ndarray and first.shape == (3,):  # one light: the common case
                if kind != SPOT:
                    kinds.append(kind)
                    rows.append(first.tolist() + _PAD)
                    continue
                d, a = light[1], light[2]
                if type(d) is np.ndarray and d.shape == (3,) and _scalar(a):
                    kinds.append(SPOT)
                    rows.append(spot_row(first.tolist(), d.tolist(), float(a)))
                    continue
            _typed_rows(light, kinds, rows)
        kind_arr = np.array(kinds, dtype=np.int64)
        data = np.array(rows, dtype=np.float64).reshape(-1, 8)
    else:
        arr = np.asarray(lights) if not hasattr(lights, "shape") else lights
        if arr.ndim != 2 or arr.shape[-1] not in (3, 4):
            raise shape_error(
                "lights", "a sequence of typed lights, (L, 4) or (L, 3)", tuple(arr.shape),
                "a homogeneous light is (x, y, z, w), w = 0 directional",
            )  # fmt: skip
        arr = np.asarray(arr, dtype=np.float64)
        if arr.shape[-1] == 3:  # positions of point lights
            arr = np.concatenate([arr, np.ones((arr.shape[0], 1))], axis=1)
        with np.errstate(all="ignore"):
            sun, xyz = homogeneous(np, arr)
        kind_arr = np.where(sun, SUN, POINT).astype(np.int64)
        data = np.concatenate([xyz, np.zeros((arr.shape[0], 5))], axis=1)
    if kind_arr.shape[0] != count:
        raise ValueError(f"lights: the atlas has {count} lights, got {kind_arr.shape[0]}")
    return kind_arr, data


_TYPED = (PointLight, SpotLight, DirectionalLight)
_KINDS = KIND_OF
_PAD = [0.0] * 5


def _scalar(a: object) -> bool:
    return type(a) is float or (type(a) is np.ndarray and a.shape == ())


def _typed_rows(light: Any, kinds: list[int], rows: list[list[float]]) -> None:
    """Append a typed light's rows (one per batch entry)."""
    spot = isinstance(light, SpotLight)
    first = np.asarray(light[0], dtype=np.float64)
    require_last("light.position" if spot else "light", first, 3)
    if not spot:
        kind = SUN if isinstance(light, DirectionalLight) else POINT
        for v in first.reshape(-1, 3).tolist():
            kinds.append(kind)
            rows.append(v + _PAD)
        return
    d = np.asarray(light.direction, dtype=np.float64)
    require_last("light.direction", d, 3)
    p = first.reshape(-1, 3)
    count = p.shape[0]
    d = np.broadcast_to(d.reshape(-1, 3), (count, 3))
    a = np.broadcast_to(np.asarray(light.angle, dtype=np.float64).reshape(-1), (count,))
    for pi, di, ai in zip(p.tolist(), d.tolist(), a.tolist(), strict=True):
        kinds.append(SPOT)
        rows.append(spot_row(pi, di, ai))
