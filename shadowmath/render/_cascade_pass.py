"""The cascades pass's description, built once and read by both graphics APIs.

:func:`describe_cascades` checks a :func:`render_cascades` call (bodies, sun, camera,
options), fits the cascades in the API's conventions and returns a :class:`CascadePass`:
the fitted :class:`shadowmath.Cascades`, each cascade's draws (:class:`MapDraw`) and the
camera pass's uniform block packed once (:data:`FRAME_DTYPE`), the bytes of ``struct
Frame`` in ``cascades.wgsl`` and of the std140 block ``Frame`` in ``cascades.frag``.
The moderngl pass (``_pass_cascades``) and the WebGPU one (``_pass_cascades_wgpu``) only
upload and draw what it holds.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any, Literal, NamedTuple

import numpy as np
from numpy.typing import NDArray

import shadowmath as sm

from ._context import check_camera_projection, check_matrix
from ._map_draws import DrawLists, MapDraw, map_draws
from ._pass_depth import depth_bias_option, nonnegative_option, pcf_radius_option
from ._pass_pcss import light_size_option
from ._resources import Body, Light, Prepared, PreparedLight, prepare_bodies, prepare_light
from ._scene_fit import SceneFit, body_scene, scene_fit_option
from ._shader_constants import MAX_CASCADES

#: The default scale of the normal offset (:func:`shadowmath.normal_offset`'s derived minimum).
NORMAL_OFFSET = 1.0

#: The resolution ``r_min`` of a 24-bit depth buffer, the unit of ``depth_bias``'s constant
#: in OpenGL (:func:`render_cascades`).
DEPTH_RESOLUTION = 1.0 / (2**24 - 1)

#: The resolution ``r_min`` of a ``depth32float`` buffer near depth 1 (as
#: :func:`shadowmath.slope_scaled_bias` with ``depth_bits=None``): ``depth_bias``'s unit
#: in WebGPU (:func:`render_cascades_wgpu`).
FLOAT_DEPTH_RESOLUTION = 2.0**-24

#: One cascade in the uniform block (std140 and WGSL agree: 112 bytes).
#: ``world_to_texture`` is stored transposed (column-major, as ``mat4`` reads it);
#: ``near``, ``far`` are ``splits[i]``, ``splits[i + 1]``; ``k``, ``d_near`` are PCSS's
#: (:func:`cascade_pcss_parameters`, 0 without).
CASCADE_DTYPE = np.dtype(
    {
        "names": ["world_to_texture", "viewport", "near", "far", "band_end", "k", "d_near"],
        "formats": [("<f4", (4, 4)), ("<i4", (4,)), "<f4", "<f4", "<f4", ("<f4", (2,)), "<f4"],
        "offsets": [0, 64, 80, 84, 88, 96, 104],
        "itemsize": 112,
    }
)

#: The camera pass's uniform block, 1024 bytes: the camera's ``world_to_clip`` in the
#: API's clip conventions (column-major), ``view_depth = -view[2]``, ``light`` the sun
#: ``(x, y, z, 0)``, ``count`` cascades, ``pcf_radius``, ``atlas`` (1: one atlas layer),
#: ``normal_offset``, ``slope_factor``, ``constant_bias`` (depth units), ``pcss`` (1: PCSS),
#: then :data:`MAX_CASCADES` records of :data:`CASCADE_DTYPE` (zero past ``count``).
FRAME_DTYPE = np.dtype(
    {
        "names": ["world_to_clip", "view_depth", "light", "count", "pcf_radius", "atlas",
                  "normal_offset", "slope_factor", "constant_bias", "pcss", "cascades"],
        "formats": [("<f4", (4, 4)), ("<f4", (4,)), ("<f4", (4,)), "<i4", "<i4", "<i4",
                    "<f4", "<f4", "<f4", "<i4", (CASCADE_DTYPE, (MAX_CASCADES,))],
        "offsets": [0, 64, 80, 96, 100, 104, 108, 112, 116, 120, 128],
        "itemsize": 128 + MAX_CASCADES * 112,
    }
)  # fmt: skip


#: The arguments of :func:`render_cascades` and :func:`render_cascades_wgpu` that go to the
#: fit (:func:`shadowmath.fit_cascades`' keywords, ``scene_bounds`` and ``map_size``).
FIT_KEYWORDS = ("scene_bounds", "map_size", "count", "splits", "scheme", "lam", "max_distance",
                "overlap", "stable", "warp", "orientation")  # fmt: skip


def fit_keywords(arguments: Mapping[str, Any]) -> dict[str, Any]:
    """The :data:`FIT_KEYWORDS` of a render call's ``arguments`` (its ``locals()``)."""
    return {name: arguments[name] for name in FIT_KEYWORDS}


class CascadeOptions(NamedTuple):
    """The checked options of one :func:`render_cascades` call."""

    layout: Literal["layers", "atlas"]
    pcf_radius: int
    bias: tuple[float, float]
    normal_offset: float
    ambient: float
    background: tuple[float, float, float]
    cascade_colors: bool
    light_size: float = 0.0


class CascadePass(NamedTuple):
    """A cascades pass, described once for both APIs (:func:`describe_cascades`).

    Attributes:
        bodies: the checked bodies.
        sun: the checked directional light.
        view: ``(4, 4)`` the camera's view (OpenGL conventions).
        projection: ``(4, 4)`` its projection (OpenGL conventions).
        fit: the :class:`shadowmath.Cascades`, in the API's conventions (widened for PCSS).
        draws: the bodies drawn into each cascade's map (:attr:`CascadeFrame.draws`).
        options: the checked options.
        frame: one record of :data:`FRAME_DTYPE`, the camera pass's uniform block.
        maps: each cascade's :class:`MapDraw` (layer ``i``, or 0 with an atlas).
    """

    bodies: list[Prepared]
    sun: PreparedLight
    view: NDArray[np.float64]
    projection: NDArray[np.float64]
    fit: sm.Cascades
    draws: DrawLists
    options: CascadeOptions
    frame: NDArray[np.void]
    maps: tuple[MapDraw, ...]


def cascade_options(
    *,
    layout: Literal["layers", "atlas"],
    pcf_radius: int,
    depth_bias: tuple[float, float] | None,
    normal_offset: float,
    ambient: float = 0.15,
    background: tuple[float, float, float] = (0.0, 0.0, 0.0),
    cascade_colors: bool = False,
    light_size: float = 0.0,
) -> CascadeOptions:
    """The options of a cascades pass, checked; ``depth_bias`` defaults to ``(2 k + 1, 2)``,
    :func:`shadowmath.slope_scaled_bias`'s derived minimum for a box PCF of radius ``k``."""
    if layout not in ("layers", "atlas"):
        raise ValueError(f"layout: expected 'layers' or 'atlas', got {layout!r}")
    k = pcf_radius_option(pcf_radius)
    offset = nonnegative_option("normal_offset", normal_offset)
    shade = nonnegative_option("ambient", ambient)
    bias = (2 * k + 1.0, 2.0) if depth_bias is None else depth_bias_option(depth_bias, k)
    return CascadeOptions(layout, k, bias, offset, shade, background, cascade_colors,
                          light_size_option(light_size))  # fmt: skip


def describe_cascades(
    bodies: Sequence[Body],
    light: Light,
    view: Any,
    projection: Any,
    *,
    options: CascadeOptions,
    fit_options: dict[str, Any],
    api: Literal["opengl", "webgpu"] = "opengl",
    scene_fit: SceneFit = None,
) -> CascadePass:
    """Check the bodies, the sun and the camera (OpenGL conventions); fit the cascades with
    :func:`shadowmath.fit_cascades` in ``api``'s conventions, given the projection in
    ``api``'s (``fit_options``: its keywords, ``scene_bounds`` defaulting to the bodies'
    box), or with ``scene_fit`` :meth:`shadowmath.ShadowScene.fit_cascades` of
    :func:`body_scene`; widened by :func:`shadowmath.widen_cascades` for PCSS
    (``options.light_size > 0``, unless ``stable``); each cascade's draws; the uniform
    block (:func:`cascade_frame`).

    Raises:
        ValueError: as :func:`render_cascades`.

    Example:
        >>> from shadowmath.meshes import grid
        >>> from shadowmath.render import Body, Light, look_at, perspective
        >>> options = cascade_options(layout="layers", pcf_radius=1, depth_bias=None,
        ...                           normal_offset=NORMAL_OFFSET)
        >>> keywords = {"scene_bounds": None, "map_size": 256, "count": 3}
        >>> described = describe_cascades(
        ...     [Body(*grid((50.0, 50.0)))], Light(direction=(1, 1, 2)),
        ...     look_at([0, -20, 3], [0, 0, 1], [0, 0, 1]), perspective(50.0, 1.0, 0.5, 60.0),
        ...     options=options, fit_options=keywords, api="webgpu")
        >>> len(described.frame.tobytes()), int(described.frame["count"]), len(described.maps)
        (1024, 3, 3)
    """
    prepared = prepare_bodies("bodies", bodies)
    if not prepared:
        raise ValueError("bodies: expected at least one body")
    sun = prepare_light("light", light)
    if not sun.directional:
        raise ValueError("light: cascades need a directional light, Light(direction=...)")
    v, p = check_matrix("view", view), check_camera_projection(projection)
    fit, draws = _fit(prepared, sun, (v, p), options, fit_options, api=api, scene_fit=scene_fit)
    if fit.splits.shape[-1] - 1 > MAX_CASCADES:
        raise ValueError(f"count: at most {MAX_CASCADES} cascades, got {fit.splits.shape[-1] - 1}")
    camera = sm.api_convention(api=api).gl_clip_to_clip @ p @ v
    frame = cascade_frame(fit, camera, v, sun.homogeneous, options=options, api=api)
    to_world = [b.to_world for b in prepared]
    maps = map_draws(fit.world_to_clip, fit.viewports, draws, to_world,
                     layered=options.layout == "layers")  # fmt: skip
    return CascadePass(prepared, sun, v, p, fit, draws, options, frame, maps)


def _fit(
    prepared: Sequence[Prepared],
    sun: PreparedLight,
    camera: tuple[NDArray[np.float64], NDArray[np.float64]],
    options: CascadeOptions,
    fit_options: dict[str, Any],
    *,
    api: Literal["opengl", "webgpu"],
    scene_fit: SceneFit,
) -> tuple[sm.Cascades, DrawLists]:
    """The cascades and each one's bodies to draw (:func:`describe_cascades`)."""
    v, p = camera
    fit_options = dict(fit_options)
    bounds = fit_options.pop("scene_bounds")
    widen = options.light_size > 0 and not fit_options.get("stable")
    _check_scene_fit(scene_fit, bounds, warp=fit_options.get("warp"), widen=widen)
    map_size = fit_options.pop("map_size")
    # The projection in api's own clip conventions, as that API's renderer holds it.
    projection = sm.api_convention(api=api).gl_clip_to_clip @ p
    keywords = {"api": api, "pcf_radius": options.pcf_radius, "layout": options.layout,
                **fit_options}  # fmt: skip
    every = np.arange(len(prepared))
    if scene_fit is None:
        bounds = _bounds(prepared) if bounds is None else bounds
        fit = sm.fit_cascades(sun.position, v, projection, bounds, map_size, **keywords)
        draws: DrawLists = tuple(every for _ in range(fit.splits.shape[-1] - 1))
    else:
        scene = body_scene(prepared, [True] * len(prepared))
        fitted = scene.fit_cascades(sm.DirectionalLight(sun.position), v, projection, map_size,
                                    **keywords)  # fmt: skip
        fit = fitted.cascades
        draws = tuple(np.asarray(d, np.int64) for d in fitted.draws)
        if scene_fit == "every_caster":
            draws = tuple(every for _ in draws)
    if widen:
        fit = sm.widen_cascades(fit, angular_radius=options.light_size)
    return fit, draws


def _check_scene_fit(scene_fit: SceneFit, bounds: Any, *, warp: Any, widen: bool) -> None:
    """Refuse what ``scene_fit`` does not take (:func:`render_cascades`)."""
    scene_fit_option(scene_fit)
    if scene_fit is not None and bounds is not None:
        raise ValueError("scene_bounds: the scene's fit (scene_fit) is over the scene's bounds")
    if scene_fit == "draw_lists" and warp is not None:
        raise ValueError("scene_fit: the draw lists are culled to the unwarped maps: no warp")
    if scene_fit == "draw_lists" and widen:
        raise ValueError(
            "scene_fit: the draw lists are culled to the unwidened maps: with light_size > 0, "
            "only stable cascades (widen_cascades widens the others)"
        )


def _bounds(bodies: Sequence[Prepared]) -> NDArray[np.float64]:
    """``(2, 3)`` the bodies' world bounding box."""
    points = np.concatenate([b.world_vertices() for b in bodies])
    return np.stack([points.min(axis=0), points.max(axis=0)])


def cascade_frame(
    fit: sm.Cascades,
    camera: NDArray[np.float64],
    view: NDArray[np.float64],
    light: NDArray[np.float64],
    *,
    options: CascadeOptions,
    api: Literal["opengl", "webgpu"],
) -> NDArray[np.void]:
    """The camera pass's uniform block (:data:`FRAME_DTYPE`): ``camera`` the ``(4, 4)``
    world-to-clip in ``api``'s conventions, ``view`` the OpenGL view, ``light`` the sun's
    ``(x, y, z, 0)``; the constant bias ``options.bias[1] r_min`` with ``r_min``
    :data:`DEPTH_RESOLUTION` (OpenGL) or :data:`FLOAT_DEPTH_RESOLUTION` (WebGPU); with
    PCSS each cascade's ``K`` and near depth (:func:`cascade_pcss_parameters`)."""
    n = int(np.asarray(fit.splits).shape[-1]) - 1
    frame = np.zeros((), dtype=FRAME_DTYPE)
    frame["world_to_clip"] = np.asarray(camera, dtype=np.float64).T
    frame["view_depth"] = -view[2]
    frame["light"] = light
    frame["count"], frame["pcf_radius"] = n, options.pcf_radius
    frame["atlas"] = options.layout == "atlas"
    frame["normal_offset"], frame["slope_factor"] = options.normal_offset, options.bias[0]
    unit = DEPTH_RESOLUTION if api == "opengl" else FLOAT_DEPTH_RESOLUTION
    frame["constant_bias"] = options.bias[1] * unit
    frame["pcss"] = options.light_size > 0
    cascades = frame["cascades"][:n]
    cascades["world_to_texture"] = np.swapaxes(np.asarray(fit.world_to_texture, np.float64), 1, 2)
    cascades["viewport"] = np.asarray(fit.viewports, dtype=np.int64)
    splits = np.asarray(fit.splits, dtype=np.float32)
    cascades["near"], cascades["far"] = splits[:-1], splits[1:]
    cascades["band_end"] = np.asarray(fit.band_end, dtype=np.float32)
    if options.light_size > 0:
        p = cascade_pcss_parameters(fit, options.light_size)
        cascades["k"] = np.asarray(p.texels_per_depth, dtype=np.float64)
        cascades["d_near"] = np.asarray(p.near_depth, dtype=np.float64)
    return frame


def cascade_pcss_parameters(fit: sm.Cascades, light_size: float) -> sm.PcssParameters:
    """The cascades' :func:`shadowmath.pcss_parameters` for a sun of angular radius
    ``light_size``: ``(n, 2)`` texels per unit of stored depth and ``(n,)`` near depths."""
    return sm.pcss_parameters(fit, angular_radius=light_size)


def cascade_index(
    position: NDArray[np.float32], view: NDArray[np.float64], splits: NDArray[np.float64]
) -> NDArray[np.int32]:
    """``(H, W)`` the cascade ``i`` with ``splits[i] <= d < splits[i + 1]`` for each pixel's
    view depth ``d = -(view @ p)_z`` (``position`` ``(H, W, 3)``, NaN on the background;
    ``splits`` ``(n + 1,)``); ``-1`` on the background and outside ``[splits[0], splits[n]]``."""
    depth = -(position.astype(np.float64) @ view[2, :3] + view[2, 3])
    valid = np.isfinite(depth) & (depth >= splits[0]) & (depth <= splits[-1])
    index = np.clip(np.searchsorted(splits, np.where(valid, depth, 0.0), side="right") - 1,
                    0, len(splits) - 2)  # fmt: skip
    return np.where(valid, index, -1).astype(np.int32)
