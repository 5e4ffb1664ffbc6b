"""Cascaded shadow maps fitted to a camera: the door of :func:`fit_cascades`.

It converts and checks the arguments once (the options into a ``ShadowMapSpec``, the
warp, the orientation, the splits, the arrays and their shapes, the measured depth
range), makes the static options record, and runs the driver (:mod:`._driver`) in the
form :func:`shadowmath._fits._backend.form` chooses; the driver returns the result
(:mod:`._result`).
"""

from __future__ import annotations

import functools
import math
from typing import Any, Literal

import numpy as np

from shadowmath._boundary._projection import check_projection
from shadowmath._boundary._shapes import ArrayLike, BoolLike, Real
from shadowmath._boundary._validate import (
    Array,
    Checks,
    all_finite,
    batch_shape,
    convert,
    non_finite,
    require_last,
    require_matrix,
)
from shadowmath._fits._backend import form
from shadowmath._fits._spec import ShadowMapSpec, api_rows, map_spec
from shadowmath._geometry._api_convention import check_api as _check_api
from shadowmath._math._bias import PcfFilter
from shadowmath._math._cascade_steps import CascadeOptions, options_record
from shadowmath._math._conventions import GraphicsApi
from shadowmath._math._conventions import clip_from_gl as _clip_from_gl
from shadowmath._math._frustum import NEAR_FAR_SLACK
from shadowmath.lights import DirectionalLight

from ._driver import PYTHON_LOOP_CAMERAS, _arrays, _Call, _compiled
from ._lispsm import check_warp
from ._orientation import check_orientation
from ._result import Cascades, CascadeState, _grid
from ._splits import CascadeScheme, check_count, scheme_lam, stable_bands_inside

__all__ = ["CascadeState", "Cascades", "fit_cascades"]

CascadeLayout = Literal["layers", "atlas"]
DepthRangeName = Literal["camera", "visible"]
_RANGE_CODES = {"camera": 0, "visible": 1}


def fit_cascades(
    light: Real[ArrayLike, "*#batch 3"] | Real[ArrayLike, "*#batch 4"] | DirectionalLight,
    view: Real[ArrayLike, "*#batch 4 4"],
    projection: Real[ArrayLike, "*#batch 4 4"],
    scene_bounds: Real[ArrayLike, "*#batch 2 3"],
    map_size: int | tuple[int, int] | ShadowMapSpec,
    *,
    count: int = 4,
    splits: Real[ArrayLike, "*#batch _"] | None = None,
    scheme: CascadeScheme = "auto",
    lam: Real[ArrayLike, "*#batch"] | None = None,
    max_distance: Real[ArrayLike, "*#batch"] | None = None,
    overlap: Real[ArrayLike, "*#batch"] = 0.1,
    up: Real[ArrayLike, "*#batch 3"] | None = None,
    stable: BoolLike = False,
    border_texels: int | None = None,
    pcf_radius: int | None = None,
    pcf_filter: PcfFilter = "box",
    api: GraphicsApi = "opengl",
    reversed_z: BoolLike = False,
    camera_api: GraphicsApi | None = None,
    camera_reversed_z: BoolLike = False,
    layout: CascadeLayout = "layers",
    warp: Literal[None, "lispsm"] = None,
    depth_range: DepthRangeName | Real[ArrayLike, "*#batch 2"] = "camera",
    state: CascadeState | None = None,
    orientation: Literal["light", "fitted"] = "light",
) -> Cascades:
    r"""Fit a directional light's cascaded shadow maps to what a camera sees.

    The camera's view depth range ``[near, far]`` (or ``[near, max_distance]``) is
    cut at :func:`cascade_splits`; cascade ``i`` covers the frustum slice between
    ``splits[i]`` and ``band_end[i]`` (its split plus ``overlap`` of its length,
    for blending). Each cascade's orthographic map is fitted in one light frame
    (``Z`` along the light's travel, the helper axis or ``up`` for ``Y``):

    * **lateral box**: the light-space bounds of the slice intersected exactly
      with ``scene_bounds`` (the convex polyhedron's vertices are the clipped
      ends of both solids' edges), so no texel covers empty space beside the
      scene; with ``stable=True`` instead a square of fixed size, the slice's
      bounding sphere (which depends on the projection and the splits only) plus
      half a texel, its centre snapped to whole texels of a grid anchored at the
      world origin: as the camera moves and turns, every cascade keeps its size
      and its texel grid moves by whole texels (with ``state``, the square of the
      visible part's bounds instead: half-width the lesser of the sphere's and a
      ladder value with hysteresis, centred on the part);
    * **depth**: from the scene box's corner nearest the light (every caster that
      can shadow the slice lies behind it, seen or not) to the slice's deepest
      point in the scene, widened by ``NEAR_FAR_SLACK``;
    * **border**: each map leaves ``border_texels`` (or the PCF kernel's border)
      on every side, so a PCF kernel never reads past its cascade (nor, in an
      atlas, into a neighbour's tile).

    Arguments:
        light: :class:`DirectionalLight`, or ``(*batch, 3)`` a direction toward the
            light, or ``(*batch, 4)`` with ``w = 0``.
        view: ``(*batch, 4, 4)`` the camera's world-to-view matrix (rigid, affine).
        projection: ``(*batch, 4, 4)`` its projection, in ``camera_api``'s clip
            conventions (perspective or orthographic; an infinite far plane needs
            ``max_distance``), a column-vector matrix (``clip = projection @ p_view``)
            with its last row as every API writes it: ``(0, 0, -1, 0)`` or
            ``(0, 0, 1, 0)`` (perspective, looking down ``-z`` or ``+z``) or
            ``(0, 0, 0, 1)`` (orthographic), to rounding; any depth row (reversed Z,
            ``[0, 1]`` or ``[-1, 1]`` depth, an infinite far plane).
        scene_bounds: ``(*batch, 2, 3)`` the scene's box, ``[min_corner, max_corner]``:
            every caster and receiver inside it.
        map_size: each cascade's map, ``size``, ``(width, height)`` or a
            :class:`ShadowMapSpec` holding it with the map's options (then give none of
            ``border_texels``, ``pcf_radius``, ``pcf_filter``, ``api``, ``reversed_z``
            and ``stable`` as keywords: as in :func:`fit_shadow`, an option given in
            both is refused; its ``margin`` is not used).
        count: the number of cascades (ignored when ``splits`` is given).
        splits: ``(*batch, n + 1)`` custom increasing view depths within the
            camera's range, instead of a scheme.
        scheme, lam: :func:`cascade_splits`'s scheme (``"uniform"``, ``"log"``,
            ``"practical"``) and blend (``None``: 0.75), or ``"auto"`` (the default): the
            practical scheme with ``lam`` if given, else a rule from the pose sweep
            (``docs/cascades.md``): ``lam = 0.75`` over the camera's range
            (``depth_range="camera"``), the log scheme (``lam = 1``) over a visible or
            measured range, whose near end is where the scene starts; with
            ``stable=True`` over the camera's range, three.js's ``lam = 0.5`` with each
            cascade ending, band included, at its practical split (``band_end[i]`` is
            that split, ``splits[i + 1]`` lies ``overlap`` of the cascade before it), so
            that no stable cascade is larger than three.js's.
        max_distance: ``(*batch,)`` the shadow distance: the last split (at most
            the camera's far plane).
        overlap: the blend band, a fraction of each cascade's length in ``[0, 1)``.
        up: ``(*batch, 3)`` optional up hint of the light frame.
        stable: fixed sizes and texel-snapped centres (see above).
        border_texels, pcf_radius, pcf_filter: the map's border, as in
            :class:`ShadowMapSpec`.
        api, reversed_z: the shadow maps' graphics API conventions.
        camera_api, camera_reversed_z: the conventions of ``projection``
            (default: ``api`` and not reversed).
        layout: ``"layers"`` (one texture layer per cascade) or ``"atlas"`` (tiles
            in a grid of ``ceil(sqrt(n))`` columns, each ``map_size``); the texture
            to allocate is ``texture_size`` (with ``texture_layers``) of the result.
        warp: ``"lispsm"``: light-space perspective warping of each cascade (Wimmer
            et al. 2004, ``docs/lispsm.md``): more texels near the eye; the matrices
            then have ``q = w != 1`` (divide by it) and ``texel_size`` is the largest
            texel, along the map's axes; ``frustum`` stays the unwarped box. Its
            strength fades as the view turns toward the light and is capped so that
            the warped texels are no coarser than the orthographic ones over the
            nearer part of each cascade; falls back to the orthographic cascade
            where the strength vanishes (the view within ~1.15 degrees of the light,
            ``sin < 0.02``, or no warp beats the orthographic map) or the camera is
            orthographic. Not with ``stable=True`` (``ValueError``).
        depth_range: the view depths the scheme's splits span. ``"camera"``: the
            camera's ``[near, far]`` (or ``[near, max_distance]``); ``"visible"``: the
            nearest and farthest view depth at which that range of the camera sees
            ``scene_bounds``, exactly (the extremes of the affine view depth over the
            vertices of the frustum intersected with the box; the camera's range where
            they miss), so no cascade covers empty depths; or ``(*batch, 2)`` a range
            the renderer measured (``[min, max]`` of last frame's view depths), clipped
            to the camera's. Not with custom ``splits``.
        state: the range in use in the last frame (its result's
            ``state``; :meth:`CascadeState.initial` before the first), with
            ``depth_range`` ``"visible"`` or measured: the range's ends are then rounded
            outward to a ladder of depths ``2^(k/4)``, grow at once and shrink only when
            the target's ladder value is more than a step inside, so the splits change
            only at ladder steps; with ``stable=True`` each square's half-width likewise
            follows its slice's visible part (``docs/cascades.md``).
        orientation: ``"light"``: every map's ``X`` and ``Y`` are the light frame's
            (the helper axis or ``up``); ``"fitted"``: each cascade's map turned about
            the light's axis (by at most 45 degrees) to the minimum-area rectangle
            enclosing the light-space projection of its slice intersected with
            ``scene_bounds`` (Freeman and Shapira 1975): the same texel count over at
            most the axis-aligned map's area (finer texels), the texels' shape kept;
            ``world_to_light`` then turns per cascade and ``frustum`` is the turned
            box. The turn follows the camera (the map shimmers as it moves): tight
            cascades only, not with ``stable=True`` nor a ``warp`` (``ValueError``).

    Returns:
        :class:`Cascades`.

    Raises:
        ValueError: wrong shapes, non-finite values, a non-invertible view or
            projection, a projective view, a ``projection`` whose last row is
            neither perspective nor orthographic (a transposed or scaled matrix), a
            zero light direction, ``up`` parallel to the light, an inverted
            ``scene_bounds``, splits outside the camera's range or not increasing, bad
            scheme options, a measured ``depth_range`` not finite or with near beyond
            far, a ``state`` likewise (these are NaN under JAX transformations);
            and whatever the values: map options given both in a :class:`ShadowMapSpec`
            and as keywords, a ``depth_range`` that is neither a name nor ``(*batch,
            2)``, with custom ``splits``, or a ``state`` without one.

    Example:
        >>> import numpy as np, shadowmath as sm
        >>> view = np.eye(4); view[2, 3] = -1.0                 # camera at z = 1, looking down -z
        >>> f, n, far = 1.0, 0.1, 50.0                          # 90 degree OpenGL perspective
        >>> proj = np.array([[f, 0, 0, 0], [0, f, 0, 0],
        ...                  [0, 0, (far + n) / (n - far), 2 * far * n / (n - far)], [0, 0, -1, 0]])
        >>> box = np.array([[-20.0, -20.0, -60.0], [20.0, 20.0, 2.0]])
        >>> c = sm.fit_cascades(np.array([0.3, 0.2, 1.0]), view, proj, box, 1024)
        >>> c.world_to_clip.shape, c.splits.shape
        ((4, 4, 4), (5,))
    """
    spec = map_spec(map_size, border_texels=border_texels, pcf_radius=pcf_radius,
                    pcf_filter=pcf_filter, api=api, reversed_z=reversed_z,
                    stable=stable)  # fmt: skip
    check_warp(warp, spec.stable)
    fitted = check_orientation(orientation, spec.stable, warp)
    cam_api = spec.api if camera_api is None else camera_api
    _check_api(cam_api, camera_reversed_z)
    if layout not in ("layers", "atlas"):
        raise ValueError(f"layout: expected 'layers' or 'atlas', got {layout!r}")
    range_code, measured = _range_option(depth_range, splits is not None, state)
    direction = light.direction if isinstance(light, DirectionalLight) else light
    lam_v = scheme_lam(scheme, lam, fitted_range=range_code != 0, stable=spec.stable)
    inside = splits is None and stable_bands_inside(
        scheme, lam, fitted_range=range_code != 0, stable=spec.stable
    )
    n_given = None if splits is not None else check_count(count)
    # Python numbers stay Python numbers (the common case): no array conversion per frame.
    plain = all(type(v) in (float, int) for v in (lam_v, overlap)) and (
        max_distance is None or type(max_distance) in (float, int)
    )
    prev = (None,) * 3 if state is None else tuple(state)
    ctx, (L, V, P, box, S, U, dmax, lm, ov, M, Qn, Qf, W) = convert(
        light=direction, view=view, projection=projection, scene_bounds=scene_bounds,
        splits=splits, up=up, max_distance=None if plain else max_distance,
        lam=None if plain else lam_v, overlap=None if plain else overlap,
        depth_range=measured,
        **{"state.near": prev[0], "state.far": prev[1], "state.half_width": prev[2]},
    )  # fmt: skip
    if plain:
        lm, ov = float(lam_v), float(overlap)
        dmax = None if max_distance is None else float(max_distance)
    checks = Checks(ctx)
    L = _light_vector(checks, L)
    shape = _batch(checks, (L, V, P, box, U, S, dmax, M, Qn, Qf))
    n = S.shape[-1] - 1 if S is not None else n_given
    assert n is not None
    _scalar_checks(checks, (lm, ov, dmax, S))
    W = _range_checks(checks, M, (Qn, Qf, W), (shape, n))
    C = _clip_from_gl(cam_api, camera_reversed_z)
    given = (U is not None, S is not None, dmax is not None, range_code, Qn is not None,
             (fitted, warp is not None))  # fmt: skip
    o, record = _options(
        spec, layout, n, given, eps=ctx.eps, C=tuple(v for row in C for v in row), inside=inside
    )
    call = _Call(ctx, spec, layout, shape, o)
    extra = None if M is None and Qn is None else _range_scalars(ctx.xp, M, (Qn, Qf))
    arrays = (L, V, P, box, U, S, dmax, lm, ov, extra, W)
    small = math.prod(shape) <= PYTHON_LOOP_CAMERAS and warp is None  # the warp's Python
    # loop is slower than its array form
    chosen = form(ctx.xp is np, small=small)
    if chosen != "arrays":
        try:
            return _compiled(call, arrays, None if chosen == "python" else record)
        except (ZeroDivisionError, OverflowError):
            pass  # Python floats raise where Numba's give inf: invalid input, which the
            # array mode below reports with its message
    return _arrays(call, checks, arrays, warp)


def _range_option(
    depth_range: Any, has_splits: bool, state: CascadeState | None
) -> tuple[int, Any]:
    """``depth_range``'s code (0 camera, 1 visible, 2 measured) and the measured range."""
    if isinstance(depth_range, str):
        if depth_range not in _RANGE_CODES:
            raise ValueError(
                f"depth_range: expected 'camera', 'visible' or a measured (*batch, 2) "
                f"[near, far], got {depth_range!r}"
            )
        code, measured = _RANGE_CODES[depth_range], None
    else:
        code, measured = 2, depth_range
    if code and has_splits:
        raise ValueError("depth_range: custom splits set their own range; give one or the other")
    if state is not None and not isinstance(state, CascadeState):
        raise ValueError(
            f"state: expected a CascadeState (a result's .state), got {type(state).__name__}"
        )
    if state is not None and code == 0:
        raise ValueError("state: needs depth_range='visible' or a measured range")
    return code, measured


def _range_checks(checks: Checks, M: Any, state: tuple[Any, ...], sn: Any) -> Any:
    """A measured range and a previous state: finite (or NaN: none), ``near <= far``,
    half-widths positive; the half-widths with a last axis of ``n``. One camera's NumPy
    values are checked as Python floats first (the per-frame case)."""
    xp = checks.ctx.xp
    if M is not None and not (xp is np and M.ndim == 1 and _plain_range(*M.tolist())):
        checks.require(all_finite(xp, M, 1), non_finite("depth_range"))
        checks.require(M[..., 0] <= M[..., 1], "depth_range: the measured near exceeds its far")
    if state[0] is None:
        return None
    near, far, W = state
    shape, n = sn
    if W.ndim and (W.shape[-1] not in (1, n) or not _broadcasts(W.shape[:-1], shape)):
        raise ValueError(
            f"state: half_width must be (*batch, n) = {(*shape, n)} or one number, "
            f"got {tuple(W.shape)}"
        )
    if not (xp is np and near.ndim == far.ndim == 0 and W.ndim <= 1 and _plain_state(state)):
        none = xp.isnan(near) & xp.isnan(far)  # CascadeState.initial()
        ok = none | (all_finite(xp, near, 0) & all_finite(xp, far, 0))
        checks.require(ok, non_finite("state") + " (or NaN: initial())")
        checks.require(none | (near <= far), "state: its near exceeds its far")
        w_ok = ~(W <= 0) & ~xp.isinf(W)  # per cascade: the entry's check is all of them
        checks.require(xp.all(w_ok, axis=-1) if W.ndim else w_ok, _HALF_WIDTH)
    return W if W.ndim and W.shape[-1] == n else xp.broadcast_to(W, (*W.shape[:-1], n))


def _plain_range(lo: float, hi: float) -> bool:
    """A measured range that passes its checks (Python floats)."""
    return math.isfinite(lo) and math.isfinite(hi) and lo <= hi


def _plain_state(state: tuple[Any, ...]) -> bool:
    """One camera's state that passes its checks (as Python floats)."""
    near, far, W = float(state[0]), float(state[1]), state[2].tolist()
    none = near != near and far != far
    ws = W if isinstance(W, list) else [W]
    return (none or _plain_range(near, far)) and all(
        not (w <= 0) and w not in (math.inf, -math.inf) for w in ws
    )


def _broadcasts(a: tuple[int, ...], shape: tuple[int, ...]) -> bool:
    """Whether a batch shape ``a`` broadcasts to ``shape``."""
    return len(a) <= len(shape) and all(
        x in (1, y) for x, y in zip(a[::-1], shape[::-1], strict=False)
    )


def _range_scalars(xp: Any, M: Any, state: tuple[Any, ...]) -> tuple[Any, ...]:
    """The measured range's ends and the previous range's, NaN where not given."""
    nan = math.nan
    lo, hi = (nan, nan) if M is None else (M[..., 0], M[..., 1])
    return (lo, hi, *((nan, nan) if state[0] is None else state))


def _batch(checks: Checks, arrays: tuple[Any, ...]) -> tuple[int, ...]:
    """The shape checks of the arrays and their batch shape."""
    L, V, P, box, U, S, dmax, M, Qn, Qf = arrays[:10]
    require_matrix("view", V)
    check_projection(checks, P)
    require_last("scene_bounds", box, 3, min_ndim=2, hint="[min_corner, max_corner]")
    if box.shape[-2] != 2:
        raise ValueError(
            f"scene_bounds: expected shape (*batch, 2, 3) ([min_corner, max_corner]), "
            f"got {tuple(box.shape)}"
        )
    if U is not None:
        require_last("up", U, 3)
    if S is not None:
        require_last("splits", S, S.shape[-1] if S.ndim else 2)
        if S.shape[-1] < 2:
            raise ValueError(
                f"splits: expected (*batch, n + 1) depths, n >= 1, got {tuple(S.shape)}"
            )
    shapes = [L.shape[:-1], V.shape[:-2], P.shape[:-2], box.shape[:-2]]
    names = ["light", "view", "projection", "scene_bounds"]
    if M is not None:
        require_last("depth_range", M, 2, hint="a measured [near, far]")
    if (Qn is None) != (Qf is None) or (Qn is not None and Qn.shape != Qf.shape):
        raise ValueError("state: near and far must have one shape")
    named = (("up", U, 1), ("splits", S, 1), ("max_distance", dmax, 0),
             ("depth_range", M, 1), ("state", Qn, 0))  # fmt: skip
    for name, v, drop in named:
        if v is not None and not isinstance(v, float):
            shapes.append(v.shape[: v.ndim - drop])
            names.append(name)
    return batch_shape(*shapes, names=names)


def _light_vector(checks: Checks, L: Array) -> Array:
    """A direction toward the light: ``(*batch, 3)``, or the ``xyz`` of a ``w = 0`` 4-vector."""
    if L.ndim == 0 or L.shape[-1] not in (3, 4):
        raise ValueError(
            f"light: expected a direction (*batch, 3) or (x, y, z, 0), got {tuple(L.shape)}"
        )
    if L.shape[-1] == 4:
        checks.require(
            L[..., 3] == 0, "light: cascades need a directional light (w = 0 in (x, y, z, w))"
        )
        L = L[..., :3]
    return L


def _scalar_checks(checks: Checks, values: tuple[Any, ...]) -> None:
    """lam, overlap, max_distance and splits: finite, and lam and overlap in range (the
    steps trust them). Python floats are checked as they are."""
    lm, ov, dmax, S = values
    xp = checks.ctx.xp
    if type(lm) is float and type(ov) is float:
        if not 0 <= lm <= 1:  # NaN fails both
            raise ValueError(non_finite("lam") if lm != lm else _LAM_RANGE)
        if not 0 <= ov < 1:
            raise ValueError(non_finite("overlap") if ov != ov else _OVERLAP_RANGE)
    else:
        checks.require(all_finite(xp, lm, 0), non_finite("lam"))
        checks.require((lm >= 0) & (lm <= 1), _LAM_RANGE)
        checks.require(all_finite(xp, ov, 0), non_finite("overlap"))
        checks.require((ov >= 0) & (ov < 1), _OVERLAP_RANGE)
    if dmax is not None and not isinstance(dmax, float):
        checks.require(all_finite(xp, dmax, 0), non_finite("max_distance"))
    elif dmax is not None and not math.isfinite(dmax):
        raise ValueError(non_finite("max_distance"))
    if S is not None:
        checks.require(all_finite(xp, S, 1), non_finite("splits"))


@functools.lru_cache(maxsize=256)
def _options(
    spec: ShadowMapSpec,
    layout: str,
    n: int,
    given: tuple[bool, bool, bool, int, bool, tuple[bool, bool]],
    *,
    eps: float,
    C: tuple[float, ...],
    inside: bool = False,
) -> tuple[CascadeOptions, Any]:
    """The call's options by name, and as the compiled loop's record (cached: the same
    few recur every frame)."""
    cols, rows = _grid(n, layout)
    C_api, TC_api = api_rows(spec.api, spec.reversed_z)
    has_up, has_splits, has_dmax, range_code, has_state, (fitted, warp) = given
    o = CascadeOptions(
        has_up=has_up, stable=spec.stable, has_splits=has_splits, has_dmax=has_dmax,
        depth_range=range_code, has_state=has_state, inside=inside, fitted=fitted, warp=warp,
        mx=float(spec.margins[0]), my=float(spec.margins[1]), width=float(spec.size[0]),
        height=float(spec.size[1]), eps=eps, tol=math.sqrt(eps), cascades=n,
        slack=NEAR_FAR_SLACK, cols=cols, rows=rows, camera_clip=C, map_clip=tuple(C_api),
        map_texture=tuple(TC_api),
    )  # fmt: skip
    return o, options_record(o)


_HALF_WIDTH = "state: half_width must be positive or NaN"
_LAM_RANGE = "lam: the practical scheme's blend must lie in [0, 1]"
_OVERLAP_RANGE = "overlap: the blend band must be a fraction in [0, 1)"
