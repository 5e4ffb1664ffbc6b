"""The atlas pass's description, built once and read by both graphics APIs.

:func:`describe_atlas` checks a :func:`render_atlas` call (bodies, lights, camera,
options), allocates the atlas and fits it in the API's conventions and returns an
:class:`AtlasPass`: the :class:`shadowmath.ShadowAtlas` and :class:`shadowmath.AtlasFit`,
each tile's draws (:class:`MapDraw`) and the two tables the camera pass reads, packed once
as float32 arrays: :data:`TILE_ROWS` rows a tile, :data:`LIGHT_ROWS` rows a light, four
floats a row. ``atlas.frag`` reads them as data textures (a row a texel), ``atlas.wgsl`` as
storage buffers of ``struct Tile`` and ``struct Light`` (the same bytes).
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from typing import Any, Literal, NamedTuple

import numpy as np
from numpy.typing import NDArray

import shadowmath as sm

from ._context import check_camera_projection, check_matrix
from ._map_draws import DrawLists, MapDraw, map_draws
from ._pass_depth import depth_bias_option, nonnegative_option, pcf_radius_option
from ._pass_pcss import PCSS_POLYGON_OFFSET, light_size_option
from ._resources import Body, Prepared, prepare_bodies
from ._scene_fit import SceneFit, body_scene, scene_fit_option

#: The default normal-offset bias of :func:`render_atlas`, in texels of each light's map.
NORMAL_OFFSET = 0.5

#: The atlas lights' kinds, as :func:`render_atlas` takes them.
AtlasLight = sm.PointLight | sm.SpotLight | sm.DirectionalLight

#: A tile's rows in :attr:`AtlasPass.tiles`: 0..3 ``world_to_texture``'s columns (the
#: column-major ``mat4`` both shading languages read), 4 ``(x, y, n, 0)`` the tile's texels
#: (x, y from the first row in memory), 5 ``(K_s, K_t, d_near, 1)`` with PCSS
#: (:func:`shadowmath.pcss_parameters` in atlas texels), 0 without.
TILE_ROWS = 6

#: A light's rows in :attr:`AtlasPass.lights`: 0 ``(x, y, z, 1)`` a position or
#: ``(x, y, z, 0)`` toward a sun, 1 ``(r, g, b, 0)`` its colour, 2 ``(spot axis, cos
#: angle)`` (``w = -2``: not a spot), 3 ``(cube, 0, 0, 0)``, 4 the tiles of faces 0..3,
#: 5 ``(tile of face 4, tile of face 5, 0, 0)`` (``-1`` none; face 0 a 2D map's tile).
LIGHT_ROWS = 6


class LightTable(NamedTuple):
    """The lights as the shader reads them: ``(L, 4, 4)`` rows of light, colour, spot
    ``(axis, cos angle)`` (``w = -2`` not a spot), ``(cube, 0, 0, 0)``."""

    rows: NDArray[np.float32]
    cube: NDArray[np.bool_]


class AtlasPass(NamedTuple):
    """An atlas pass, described once for both APIs (:func:`describe_atlas`).

    Attributes:
        bodies: the checked bodies.
        cast: which bodies cast.
        view, projection: ``(4, 4)`` the camera (OpenGL conventions).
        pcf_radius: the PCF kernel's radius ``k``.
        bias: ``(factor, units)`` the maps' polygon offset.
        normal_offset: the normal-offset bias, in texels.
        ambient: the ambient term of the picture.
        atlas: the :class:`shadowmath.ShadowAtlas`.
        fit: the :class:`shadowmath.AtlasFit`, in the API's conventions.
        pcss: each tile's PCSS ``K`` and ``d_near`` (atlas texels), None without ``light_size``.
        draws: the bodies to draw into each tile (:attr:`AtlasFrame.draws`).
        tiles: ``(T, TILE_ROWS, 4)`` float32, the tiles' table (:data:`TILE_ROWS`).
        lights: ``(L, LIGHT_ROWS, 4)`` float32, the lights' table (:data:`LIGHT_ROWS`).
        maps: each tile's :class:`MapDraw` (layer 0, its viewport).
    """

    bodies: list[Prepared]
    cast: list[bool]
    view: NDArray[np.float64]
    projection: NDArray[np.float64]
    pcf_radius: int
    bias: tuple[float, float]
    normal_offset: float
    ambient: float
    atlas: sm.ShadowAtlas
    fit: sm.AtlasFit
    pcss: sm.PcssParameters | None
    draws: DrawLists
    tiles: NDArray[np.float32]
    lights: NDArray[np.float32]
    maps: tuple[MapDraw, ...]


def describe_atlas(
    bodies: Sequence[Body],
    lights: Sequence[AtlasLight],
    view: Any,
    projection: Any,
    *,
    casters: Sequence[bool] | None,
    colors: Any,
    coverage: Any,
    atlas_size: int,
    budget: float,
    previous: sm.ShadowAtlas | None,
    pcf_radius: int,
    depth_bias: tuple[float, float] | None,
    normal_offset: float,
    ambient: float = 0.15,
    api: Literal["opengl", "webgpu"] = "opengl",
    light_size: Any = None,
    scene_fit: SceneFit = None,
) -> AtlasPass:
    """Check the bodies, lights, camera (OpenGL conventions) and options of an atlas pass;
    allocate the atlas and fit it in ``api``'s conventions, from every caster's triangles
    or, with ``scene_fit``, from a :class:`shadowmath.ShadowScene` of the bodies (step 1 of
    :func:`render_atlas`); each tile's draws; the tiles' and lights' tables
    (:func:`atlas_tables`).

    Raises:
        ValueError: as :func:`render_atlas`.

    Example:
        >>> import shadowmath as sm
        >>> from shadowmath.meshes import box, grid
        >>> from shadowmath.render import Body, look_at, perspective
        >>> cube = Body(*box((2.0, 2.0, 2.0)), to_world=np.array(
        ...     [[1, 0, 0, 0], [0, 1, 0, 0], [0, 0, 1, 1], [0, 0, 0, 1.0]]))
        >>> described = describe_atlas(
        ...     [Body(*grid((20.0, 20.0))), cube], [sm.PointLight(np.array([3.0, 0.0, 4.0]))],
        ...     look_at([0, -12, 8], [0, 0, 0], [0, 0, 1]), perspective(50.0, 1.0, 0.5, 50.0),
        ...     casters=[False, True], colors=None, coverage=None, atlas_size=512, budget=1.0,
        ...     previous=None, pcf_radius=1, depth_bias=None, normal_offset=NORMAL_OFFSET)
        >>> described.tiles.shape, described.lights.shape  # a cube light: six tiles
        ((6, 6, 4), (1, 6, 4))
    """
    prepared = prepare_bodies("bodies", bodies)
    if not prepared:
        raise ValueError("bodies: expected at least one body")
    cast = _casters(casters, len(prepared))
    table = _light_table(lights, colors)
    k = pcf_radius_option(pcf_radius)
    sizes = None if light_size is None else _light_sizes(light_size, table)
    bias = depth_bias_option(depth_bias, k)
    if sizes is not None and depth_bias is None:
        bias = PCSS_POLYGON_OFFSET
    offset = nonnegative_option("normal_offset", normal_offset)
    shade = nonnegative_option("ambient", ambient)
    scene_fit = scene_fit_option(scene_fit)
    v, p = check_matrix("view", view), check_camera_projection(projection)
    fit_tiles = _triangle_fit(prepared, cast, lights, k, api)
    if scene_fit is not None:
        fit_tiles = _scene_fit(prepared, cast, lights, (k, api), scene_fit)

    def allocate(border: int) -> sm.ShadowAtlas:
        return sm.allocate_atlas(
            np.ones(len(table.cube)) if coverage is None else coverage, atlas_size=atlas_size,
            cube=table.cube, border_texels=border, previous=previous, budget=budget,
        )  # fmt: skip

    atlas, fit, draws, pcss = _allocate_and_fit(allocate, fit_tiles, k, sizes)
    tiles, rows = atlas_tables(atlas, fit, table, pcss)
    maps = map_draws(fit.world_to_clip, fit.viewports, draws, [b.to_world for b in prepared],
                     layered=False)  # fmt: skip
    return AtlasPass(prepared, cast, v, p, k, bias, offset, shade, atlas, fit, pcss, draws, tiles,
                     rows, maps)  # fmt: skip


def _allocate_and_fit(
    allocate: Callable[[int], sm.ShadowAtlas],
    fit_tiles: _FitTiles,
    k: int,
    sizes: NDArray[np.float64] | None,
) -> tuple[sm.ShadowAtlas, sm.AtlasFit, DrawLists, sm.PcssParameters | None]:
    """The atlas of the PCF kernel's border, its fit and draws; with PCSS (``sizes`` the
    lights' radii) each tile's parameters, the atlas allocated and fitted again with
    :func:`shadowmath.pcss_border_texels` when that border is wider (it then holds the
    widest search: ``K`` only shrinks with it)."""
    border = sm.pcf_border_texels(k)
    atlas = allocate(border)
    fit, draws = fit_tiles(atlas)
    if sizes is None:
        return atlas, fit, draws, None
    pcss = sm.pcss_parameters(fit, light_radius=sizes[np.asarray(atlas.tile_light)])
    if sm.pcss_border_texels(pcss) > border:
        atlas = allocate(sm.pcss_border_texels(pcss))
        fit, draws = fit_tiles(atlas)
        pcss = sm.pcss_parameters(fit, light_radius=sizes[np.asarray(atlas.tile_light)])
    return atlas, fit, draws, pcss


def atlas_tables(
    atlas: sm.ShadowAtlas,
    fit: sm.AtlasFit,
    table: LightTable,
    pcss: sm.PcssParameters | None,
) -> tuple[NDArray[np.float32], NDArray[np.float32]]:
    """The tiles' ``(T, TILE_ROWS, 4)`` and the lights' ``(L, LIGHT_ROWS, 4)`` float32
    tables (:data:`TILE_ROWS`, :data:`LIGHT_ROWS`): ``fit.world_to_texture`` transposed,
    ``atlas.tile_rect``, the PCSS row; ``table.rows``, ``atlas.light_tiles``."""
    count = len(atlas.tile_rect)
    tiles = np.zeros((count, TILE_ROWS, 4))
    tiles[:, :4] = np.swapaxes(np.asarray(fit.world_to_texture, dtype=np.float64), 1, 2)
    tiles[:, 4, :3] = atlas.tile_rect
    if pcss is not None:
        k_near = np.column_stack([pcss.texels_per_depth, pcss.near_depth])
        tiles[:, 5] = np.nan_to_num(np.column_stack([k_near, np.ones(count)]))
    faces = np.zeros((len(table.rows), 8))
    faces[:, :6] = atlas.light_tiles
    lights = np.concatenate([table.rows, faces.reshape(-1, 2, 4)], axis=1)
    return tiles.astype(np.float32), lights.astype(np.float32)


#: An allocated atlas's fit and each tile's bodies to draw.
_FitTiles = Callable[[sm.ShadowAtlas], tuple[sm.AtlasFit, DrawLists]]


def _triangle_fit(
    prepared: Sequence[Prepared],
    cast: Sequence[bool],
    lights: Sequence[AtlasLight],
    k: int,
    api: Literal["opengl", "webgpu"],
) -> _FitTiles:
    """:func:`shadowmath.fit_atlas` of every caster's world triangles; every caster in
    every tile."""
    world = [b.world_vertices()[b.triangles] for b in prepared]  # (T, 3, 3) each
    # The casters as surfaces: a cube light's near counts a triangle passing nearer the
    # light than its corners. Every body's triangles hold what the shadows fall on: a
    # ground's corners may lie outside a light's map while its middle is under the casters.
    casting = sm.Triangles(np.concatenate([t for t, c in zip(world, cast, strict=True) if c]))
    surfaces = sm.Triangles(np.concatenate(world))
    every = np.flatnonzero(cast)

    def fit_tiles(atlas: sm.ShadowAtlas) -> tuple[sm.AtlasFit, DrawLists]:
        fit = sm.fit_atlas(list(lights), casting, atlas, receivers=surfaces, pcf_radius=k, api=api)
        return fit, tuple(every for _ in range(len(atlas.tile_light)))

    return fit_tiles


def _scene_fit(
    prepared: Sequence[Prepared],
    cast: Sequence[bool],
    lights: Sequence[AtlasLight],
    options: tuple[int, Literal["opengl", "webgpu"]],
    scene_fit: Literal["draw_lists", "every_caster"],
) -> _FitTiles:
    """:meth:`shadowmath.ShadowScene.fit_atlas` of :func:`body_scene` with ``options = (k,
    api)`` (the PCF radius, the API); each tile's draw list (``"draw_lists"``) or every
    caster (``"every_caster"``)."""
    k, api = options
    scene = body_scene(prepared, cast)
    every = np.flatnonzero(cast)

    def fit_tiles(atlas: sm.ShadowAtlas) -> tuple[sm.AtlasFit, DrawLists]:
        fitted = scene.fit_atlas(list(lights), atlas, pcf_radius=k, api=api)
        if scene_fit == "every_caster":
            return fitted.fit, tuple(every for _ in fitted.draws)
        return fitted.fit, tuple(np.asarray(d, dtype=np.int64) for d in fitted.draws)

    return fit_tiles


def _light_sizes(light_size: Any, table: LightTable) -> NDArray[np.float64]:
    """``light_size`` checked: one radius ``>= 0`` per light, point and spot lights only."""
    sizes = np.asarray([light_size_option(r) for r in np.atleast_1d(light_size)])
    if sizes.shape != table.cube.shape:
        raise ValueError(f"light_size: expected one radius per light ({len(table.cube)})")
    if np.any(table.rows[:, 0, 3] == 0):
        raise ValueError("light_size: PCSS in the atlas takes point and spot lights only")
    return sizes


def _casters(casters: Sequence[bool] | None, count: int) -> list[bool]:
    if casters is None:
        return [True] * count
    flags = [bool(c) for c in casters]
    if len(flags) != count:
        raise ValueError(f"casters: expected one flag per body ({count}), got {len(flags)}")
    if not any(flags):
        raise ValueError("casters: at least one body must cast")
    return flags


def _light_table(lights: Sequence[AtlasLight], colors: Any) -> LightTable:
    """The shader's per-light rows; point lights are cube maps."""
    count = len(lights)
    if count == 0:
        raise ValueError("lights: expected at least one light")
    rgb = np.full((count, 3), 1.6 / count) if colors is None else np.asarray(colors, float)
    if rgb.shape != (count, 3) or not np.all(np.isfinite(rgb)) or rgb.min() < 0:
        raise ValueError(f"colors: expected ({count}, 3) finite values >= 0, got {rgb.shape}")
    rows = np.zeros((count, 4, 4))
    rows[:, 2, 3] = -2.0
    with np.errstate(all="ignore"):  # a zero direction's NaNs are refused below
        for i, light in enumerate(lights):
            rows[i] = _light_rows(i, light, rows[i])
    rows[:, 1, :3] = rgb
    bad = np.flatnonzero(~np.isfinite(rows).all(axis=(1, 2)))
    if bad.size:
        raise ValueError(
            f"lights[{bad[0]}]: its position, direction and angle must be finite, the "
            "direction nonzero"
        )
    return LightTable(rows.astype(np.float32), rows[:, 3, 0] > 0.5)


def _light_rows(i: int, light: Any, rows: NDArray[np.float64]) -> NDArray[np.float64]:
    """Light ``i``'s shader rows (``rows`` as initialised: the spot row's ``w = -2``)."""
    if isinstance(light, AtlasLight) and np.shape(light[0]) != (3,):
        raise ValueError(
            f"lights[{i}]: expected one light (a (3,) vector), got a batch of shape "
            f"{np.shape(light[0])}; list its lights one by one"
        )
    if isinstance(light, sm.DirectionalLight):
        d = np.asarray(light.direction, dtype=np.float64)
        rows[0] = [*(d / np.linalg.norm(d)), 0.0]
    elif isinstance(light, sm.PointLight | sm.SpotLight):
        rows[0] = [*np.asarray(light.position, dtype=np.float64), 1.0]
    else:
        raise ValueError(
            f"lights[{i}]: expected an sm.PointLight, sm.SpotLight or sm.DirectionalLight, "
            f"got {type(light).__name__}"
        )
    if isinstance(light, sm.SpotLight):
        axis = np.asarray(light.direction, dtype=np.float64)
        rows[2] = [*(axis / np.linalg.norm(axis)), np.cos(float(light.angle))]
    rows[3, 0] = float(isinstance(light, sm.PointLight))
    return rows
