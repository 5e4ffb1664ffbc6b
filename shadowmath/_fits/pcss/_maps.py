"""The maps of each fit as :mod:`shadowmath._math._pcss` reads them (for
:func:`~shadowmath.pcss_parameters`): ``world_to_texture``, the texture's size
in texels, perspective or not, and the light's travel of an orthographic map."""

from __future__ import annotations

from typing import Any, NamedTuple

import numpy as np

from shadowmath._boundary._validate import Array, convert, is_tracer
from shadowmath._fits._spec import ShadowMapSpec
from shadowmath._fits.atlas._result import AtlasFit
from shadowmath._fits.cascades._result import Cascades
from shadowmath._fits.cube._result import CubeDepthRange
from shadowmath._fits.shadow._result import ShadowSetup
from shadowmath._geometry._adaptive_frustum import texel_counts
from shadowmath._geometry._cube_faces import face_scale
from shadowmath._math import _cube
from shadowmath._math._frustum import OrthographicBox
from shadowmath._math._specialize import scalar_formulas

PcssFit = ShadowSetup | Cascades | AtlasFit | CubeDepthRange

BAD_CUBE = "fit: a CubeDepthRange needs 0 < near < far"


class Maps(NamedTuple):
    """A fit's maps."""

    M: Array  # (*maps, 4, 4) world_to_texture
    size: tuple[float, float]  # the texture's texels: (s, t) in [0, 1] span them
    perspective: Any  # a Python bool, or an (*maps,) NumPy bool array (an atlas's tiles)
    toward: Array | None  # (*maps, 3) the light's travel (orthographic maps) or None:
    reversed: bool = False  # then an orthographic map's depth direction is this


def switch(reversed_z: object) -> bool | None:
    """``reversed_z`` as given: None, True or False."""
    if reversed_z is None or isinstance(reversed_z, bool | np.bool_):
        return None if reversed_z is None else bool(reversed_z)
    raise ValueError(f"reversed_z: expected True, False or None, got {reversed_z!r}")


def _texels(map_size: object, what: str) -> tuple[int, int]:
    """``(W, H)`` of a ``map_size`` or a spec's, which ``what`` does not record."""
    if map_size is None:
        raise ValueError(f"map_size: {what} does not record its texel counts: give its map_size")
    if type(map_size) is int and map_size > 0:  # the common case, without the checks' cost
        return map_size, map_size
    if isinstance(map_size, ShadowMapSpec):
        return map_size.size
    return texel_counts("map_size", map_size)


def _setup_texels(recorded: Any, map_size: object) -> tuple[int, int]:
    """``(W, H)`` of a :class:`ShadowSetup`: the size it records (:func:`fit_shadow`'s),
    which a given ``map_size`` must equal; a setup made by hand records none."""
    if recorded is None:
        return _texels(map_size, "a ShadowSetup made without fit_shadow")
    if not all(type(n) is int for n in recorded):  # arrays: out of jax.jit or jax.vmap
        if any(is_tracer(n) for n in recorded):
            if map_size is None:
                raise ValueError(
                    "map_size: the fit's recorded map size is traced (a ShadowSetup passed "
                    "into a JAX transformation): give its map_size"
                )
            return _texels(map_size, "")
        sizes = [np.unique(np.asarray(n)) for n in recorded]
        if any(len(v) != 1 for v in sizes):
            raise ValueError(
                "fit: its entries were fitted for maps of different sizes; call "
                "pcss_parameters once per size"
            )
        recorded = (int(sizes[0][0]), int(sizes[1][0]))
    if map_size is not None:
        given = _texels(map_size, "")
        if given != tuple(recorded):
            raise ValueError(
                f"map_size: the fit was made for a {recorded[0]}x{recorded[1]} map, not "
                f"{given[0]}x{given[1]}; leave map_size out (a ShadowSetup from fit_shadow "
                "records its size) or refit for the new size"
            )
    return recorded[0], recorded[1]


def fit_maps(fit: object, map_size: Any, border_texels: Any, rev: bool | None) -> Maps:
    """The maps of ``fit``, its arguments checked."""
    kind = type(fit)  # the four are NamedTuples: their exact types, without isinstance's cost
    if kind is not CubeDepthRange and border_texels != 0:
        raise ValueError(
            "border_texels: only a CubeDepthRange takes it (the other fits' matrices hold "
            "their borders)"
        )
    if kind is ShadowSetup:
        setup: Any = fit
        size = _setup_texels(setup.map_size, map_size)
        if type(setup.frustum) is not OrthographicBox:
            return Maps(setup.world_to_texture, size, True, None)
        return Maps(setup.world_to_texture, size, False, setup.world_to_light[..., 2, :3])
    if kind in (Cascades, AtlasFit) and map_size is not None:
        raise ValueError(f"map_size: a {kind.__name__} records its texture size: leave it out")
    if kind is Cascades:
        c: Any = fit
        return Maps(c.world_to_texture, c.texture_size, False, c.world_to_light[..., 2, :3])
    if kind is AtlasFit:
        return _atlas_maps(fit, rev)  # type: ignore[arg-type]
    if kind is CubeDepthRange:
        return _cube_maps(fit, map_size, border_texels, bool(rev))  # type: ignore[arg-type]
    raise ValueError(
        f"fit: expected a ShadowSetup, Cascades, AtlasFit or CubeDepthRange, got {kind.__name__}"
    )


def _atlas_maps(fit: AtlasFit, rev: bool | None) -> Maps:
    """An atlas's tiles: perspective where ``q`` varies; ``reversed_z`` given or read from
    a perspective tile (its ``d_near``), needed for the directional ones."""
    M = np.asarray(fit.world_to_texture)
    persp = np.any(M[:, 3, :3] != 0, axis=-1)
    fitted = ~((np.asarray(fit.near) == 0) & (np.asarray(fit.far) == 0))
    if rev is None and bool(np.any(~persp & fitted)):
        shown = np.flatnonzero(persp & fitted)
        if not shown.size:
            raise ValueError(
                "reversed_z: an atlas of directional lights only does not show its depth "
                "direction: give fit_atlas's reversed_z"
            )
        row = M[shown[0]].reshape(16).tolist()
        rev = scalar_formulas().pcss_perspective(row, 1.0, 1.0, 1.0)[2] == 1
    return Maps(fit.world_to_texture, fit.texture_size, persp, None, bool(rev))


def _cube_maps(fit: CubeDepthRange, map_size: Any, border_texels: Any, rev: bool) -> Maps:
    """A cube face's ``world_to_texture`` (every face has the same ``K``): a face of a
    light at the origin, looking down its view's ``-z``, depth in ``[0, 1]``."""
    if map_size is None:
        raise ValueError(
            "map_size: a CubeDepthRange does not record its texel counts: give the faces' map_size"
        )
    k = face_scale(map_size, border_texels)
    ctx, (n, f) = convert(near=fit.near, far=fit.far)
    if not ctx.lazy and not bool(ctx.xp.all((n > 0) & (f > n))):
        raise ValueError(BAD_CUBE)
    P = _cube.cube_face_projection(ctx.xp, n, f, k, zero_to_one=True, flip_y=False, reversed_z=rev)
    T = ((0.5, 0.0, 0.0, 0.5), (0.0, 0.5, 0.0, 0.5), (0.0, 0.0, 1.0, 0.0), (0.0, 0.0, 0.0, 1.0))
    N = float(map_size)
    return Maps(ctx.constant(T) @ P, (N, N), True, None)
