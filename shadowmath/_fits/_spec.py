"""The shadow map's spec: what a renderer decides once per light, and the fits' cache key.

:class:`ShadowMapSpec` is the public, hashable set of options (size, border or PCF
kernel, graphics API, reversed Z, stable), checked once when it is made, like
Filament's ``ShadowOptions`` or three.js's ``LightShadow``. :class:`FitKey` adds
what the call's arguments make static (the light's kind, which optional arrays
were given) and is the key of every cached jit and compiled loop variant.
"""

from __future__ import annotations

import dataclasses
import functools
import warnings
from typing import Any, NamedTuple

import numpy as np

from shadowmath._boundary._messages import ShadowFitWarning
from shadowmath._geometry._adaptive_frustum import derived_margins, texel_counts
from shadowmath._geometry._api_convention import check_api
from shadowmath._geometry._depth_bias import check_kernel
from shadowmath._math._bias import PcfFilter
from shadowmath._math._conventions import GraphicsApi, clip_from_gl, texture_from_gl_clip
from shadowmath._math._fit_entry import FitOptions
from shadowmath._math._frustum import NEAR_FAR_SLACK
from shadowmath._math._pcf import border_texels


@dataclasses.dataclass(frozen=True)
class ShadowMapSpec:
    """How one shadow map is laid out and used: the options of a fit that are not arrays.

    Hashable and checked when made, so a renderer builds it once per light and
    passes it every frame (``fit_shadow(light, vertices, spec)``); it is also the
    cache key of the compiled and jitted fits.

    Attributes:
        size: ``(width, height)`` in texels (an int ``n`` means ``(n, n)``).
        border_texels: texels left empty on each side; default 1, or
            :func:`pcf_border_texels` of ``pcf_radius`` when a radius is given.
        pcf_radius, pcf_filter: the PCF kernel the map will be filtered with; it
            sets the default border (give ``border_texels`` or ``pcf_radius``, not both).
        margin: force the fraction of the half-extent inside the border (a float or
            ``(margin_x, margin_y)`` in ``(0, 1]``) instead of deriving it from the
            size and border (exclusive with ``border_texels`` and ``pcf_radius``).
        api: ``"opengl"`` (default), ``"vulkan"``, ``"direct3d"``, ``"metal"`` or
            ``"webgpu"``: the clip and texture conventions of the matrices.
        reversed_z: store depth 1 at near and 0 at far.
        stable: snap a directional map to whole texels of a world-anchored grid at
            a fixed scale (no shimmering); for a point light, a frame that cannot
            jump (the fit then needs ``up``).

    Raises:
        ValueError: a non-integer or non-positive size, a map no larger than its
            borders, a negative border, an unknown API or PCF filter, a margin outside
            ``(0, 1]``, conflicting border options, or ``stable=True`` with a map of at
            most one texel inside its border.

    Example:
        >>> spec = ShadowMapSpec(1024, pcf_radius=2, api="vulkan")  # a 5x5 box kernel
        >>> spec.size, spec.margins
        ((1024, 1024), (0.99609375, 0.99609375))
    """

    size: tuple[int, int]
    border_texels: int | None = None
    pcf_radius: int | None = None
    pcf_filter: PcfFilter = "box"
    margin: float | tuple[float, float] | None = None
    api: GraphicsApi = "opengl"
    reversed_z: bool = False
    stable: bool = False

    def __init__(
        self,
        size: int | tuple[int, int],
        *,
        border_texels: int | None = None,
        pcf_radius: int | None = None,
        pcf_filter: PcfFilter = "box",
        margin: float | tuple[float, float] | None = None,
        api: GraphicsApi = "opengl",
        reversed_z: bool = False,
        stable: bool = False,
    ) -> None:
        m: Any = margin
        if isinstance(m, list | np.ndarray):  # hashable, as a spec must be
            m = tuple(float(v) for v in m)
        values = {
            "size": texel_counts("map_size", size),
            "border_texels": border_texels,
            "pcf_radius": pcf_radius,
            "pcf_filter": pcf_filter,
            "margin": m,
            "api": api,
            "reversed_z": reversed_z,
            "stable": stable,
        }
        for name, value in values.items():
            object.__setattr__(self, name, value)
        _check(self)

    @property
    def margins(self) -> tuple[float, float]:
        """``(margin_x, margin_y)``: the fraction of the map's half-extent inside the border."""
        return _spec_margins(self)

    @property
    def border(self) -> int:
        """The border in texels actually used (``border_texels``, the PCF kernel's, or 1)."""
        if self.border_texels is not None:
            return self.border_texels
        if self.pcf_radius is not None:
            return border_texels(*check_kernel(self.pcf_radius, self.pcf_filter, _PCF_NAMES))
        return 1


_PCF_NAMES = ("pcf_radius", "pcf_filter")


def _check(spec: ShadowMapSpec) -> None:
    check_api(spec.api, spec.reversed_z)
    if not isinstance(spec.stable, bool | np.bool_):
        raise ValueError(f"stable: expected True or False, got {spec.stable!r}")
    check_kernel(0 if spec.pcf_radius is None else spec.pcf_radius, spec.pcf_filter, _PCF_NAMES)
    given = [n for n in ("border_texels", "pcf_radius", "margin") if getattr(spec, n) is not None]
    if len(given) > 1:
        raise ValueError(
            f"{' and '.join(given)}: give one of border_texels, pcf_radius and margin (each "
            "sets the map's border)"
        )
    # Before the cached margins: a spec with border_texels=True equals (and hashes as) one
    # with border_texels=1, so the cache would answer for it.
    if isinstance(spec.border_texels, bool | np.bool_):
        raise ValueError(
            f"border_texels: expected an int, not a boolean, got {spec.border_texels!r}"
        )
    mx, my = spec.margins
    if min(mx, my) < 0.5:
        inner = min(round(mx * spec.size[0]), round(my * spec.size[1]))
        warnings.warn(
            f"map_size: a border of {spec.border} texel(s) on each side leaves {inner} texels "
            f"of {spec.size[0]}x{spec.size[1]} (less than half per axis) for the blocker's "
            "silhouette; use a larger map or a smaller PCF kernel",
            ShadowFitWarning,
            stacklevel=3,
        )
    if spec.stable:
        for axis, m, size in (("x", mx, spec.size[0]), ("y", my, spec.size[1])):
            if m * size <= 1:
                raise ValueError(
                    f"map_size: stable=True needs more than one texel inside the border "
                    f"along {axis} (got {m * size:g})"
                )


@functools.lru_cache(maxsize=256)
def _spec_margins(spec: ShadowMapSpec) -> tuple[float, float]:
    return derived_margins(spec.size, spec.border, spec.margin)


def map_spec(map_size: Any, **options: Any) -> ShadowMapSpec:
    """The spec of a call taking ``map_size`` (a size or a :class:`ShadowMapSpec`) and
    some of :class:`ShadowMapSpec`'s options as keywords (``options``: those it takes).

    A spec with any of ``options`` set away from its default is refused, whatever the
    spec holds (``ValueError`` naming them): an option has one place. A size makes the
    spec from the options (cached when they are hashable: the same few recur every frame).
    """
    if isinstance(map_size, ShadowMapSpec):
        changed = [k for k, v in options.items() if v != _DEFAULTS[k] or type(v) is not
                   type(_DEFAULTS[k])]  # fmt: skip
        if changed:
            raise ValueError(
                f"{', '.join(changed)}: given both in the ShadowMapSpec and as keywords; "
                "set them in the spec"
            )
        return map_size
    try:
        return _spec_from_options(map_size, **options)
    except TypeError:  # unhashable (a list): made without the cache
        return ShadowMapSpec(map_size, **options)


_DEFAULTS: dict[str, Any] = {
    "border_texels": None,
    "pcf_radius": None,
    "pcf_filter": "box",
    "margin": None,
    "api": "opengl",
    "reversed_z": False,
    "stable": False,
}


@functools.lru_cache(maxsize=256, typed=True)  # typed: True and 1 are different options
def _spec_from_options(size: Any, **options: Any) -> ShadowMapSpec:
    return ShadowMapSpec(size, **options)


class FitKey(NamedTuple):
    """Everything static about one fit call: the key of its cached jit and compiled loop."""

    directional: bool
    spot: bool
    aim_bbox: bool
    stable: bool
    margins: tuple[float, float]
    texels: tuple[int, int]
    api: tuple[tuple[float, ...], tuple[float, ...]]  # OpenGL clip -> API clip, -> texture
    has_placement: bool
    has_receivers: bool
    has_up: bool
    has_near: bool
    has_far: bool
    triangles: bool = False  # receivers given as triangles (rows of 9), not points


@functools.lru_cache(maxsize=256)
def fit_options(key: FitKey, eps: float, single: bool = False) -> FitOptions:
    """The options record of :func:`shadowmath._math._fit_entry.fit_entry` for ``key``: its
    fields by name.

    ``eps``: the input dtype's; ``single``: float32 input computed in float64 (per entry).
    """
    return FitOptions(
        directional=key.directional,
        spot=key.spot,
        aim_bbox=key.aim_bbox,
        stable=key.stable,
        has_placement=key.has_placement,
        has_receivers=key.has_receivers,
        has_up=key.has_up,
        has_near=key.has_near,
        has_far=key.has_far,
        triangles=key.triangles,
        single=single,
        margin_x=key.margins[0],
        margin_y=key.margins[1],
        texels_x=float(key.texels[0]),
        texels_y=float(key.texels[1]),
        eps=eps,
        slack=NEAR_FAR_SLACK,
    )


@functools.lru_cache(maxsize=256)
def api_rows(api: str, reversed_z: bool) -> tuple[tuple[float, ...], tuple[float, ...]]:
    """``C`` and ``T C`` of :func:`api_convention` as 16 row-major floats each."""
    C = tuple(v for row in clip_from_gl(api, reversed_z) for v in row)
    TC = tuple(v for row in texture_from_gl_clip(api, reversed_z) for v in row)
    return C, TC
