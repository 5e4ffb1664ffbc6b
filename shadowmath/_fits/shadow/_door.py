""":func:`fit_shadow`'s door: its arguments converted and checked once, and reopened
cheaply for arrays of a kind already seen.

:func:`open_door` reads the light's kind (its type, or ``w`` of a homogeneous
``(x, y, z, w)``), converts the arrays, checks their shapes and makes the static
:class:`shadowmath._fits._spec.FitKey`. Everything it decides depends only on the operands' types,
dtypes and shapes and on the options, so a :class:`PreparedDoor` keeps it for one
:func:`signature` and :meth:`PreparedDoor.reopen` hands new arrays of that signature
to the fit with a few attribute reads (the values are still checked, by the fit).
:class:`shadowmath.ShadowFitter` holds one; :func:`fit_shadow` keeps a small cache of
them for the calls that recur every frame.
"""

from __future__ import annotations

import functools
import math
import warnings
from typing import Any, Literal, NamedTuple

import numpy as np

from shadowmath._boundary import _messages as msg
from shadowmath._boundary._validate import (
    Array,
    Context,
    batch_shape,
    check_faces,
    convert,
    is_tracer,
    require_last,
    require_matrix,
    require_no_new_batch,
    require_vertices,
    shape_error,
)
from shadowmath._fits._light_kinds import homogeneous, spot_rows
from shadowmath._fits._spec import FitKey, ShadowMapSpec, api_rows
from shadowmath.lights import DirectionalLight, PointLight, SpotLight
from shadowmath.receivers import Mesh, Triangles

from ._arrays import Inputs
from ._spot_select import spot_selection

__all__ = [
    "Door",
    "Operands",
    "PreparedDoor",
    "open_door",
    "precision",
    "refine",
    "select_casters",
    "signature",
    "warn_precision",
]


class Operands(NamedTuple):
    """:func:`fit_shadow`'s arrays as given (before the door)."""

    light: Any
    blocker_vertices: Any
    blocker_to_world: Any = None
    receivers: Any = None
    up: Any = None
    near: Any = None
    far: Any = None


class Door(NamedTuple):
    """What the door of :func:`fit_shadow` read: trusted arrays, batch shape, static key."""

    ctx: Context
    a: Inputs
    shape: tuple[int, ...]
    key: FitKey
    casters: Array  # (*batch, N, 3) points or (*batch, M, 3, 3) triangles
    triangles: bool  # casters are triangles


def open_door(g: Operands, spec: ShadowMapSpec, aim_bbox: bool) -> Door:
    """Convert and check :func:`fit_shadow`'s arrays once: kinds, dtypes and shapes."""
    light = g.light
    spot = isinstance(light, SpotLight)
    if isinstance(light, SpotLight):  # (not `spot`: mypy narrows the type)
        named = {"light.position": light[0], "light.direction": light[1], "light.angle": light[2]}
    else:
        named = {"light": light[0] if isinstance(light, PointLight | DirectionalLight) else light}
    kind, r_name, r_array = _receiver_kind(g.receivers)
    c_kind, c_name, c_array = _receiver_kind(g.blocker_vertices, "blocker_vertices")
    ctx, (*parts, verts, B, n, f, R, U) = convert(
        **named, **{c_name: c_array}, blocker_to_world=g.blocker_to_world, near=g.near,
        far=g.far, **{r_name: r_array}, up=g.up,
    )  # fmt: skip
    if R is not None:
        R = _receiver_rows(ctx, kind, R, g.receivers)
    if spot:
        directional, L = False, _spot_array(ctx, *parts)
    else:
        typed = None  # a raw array: its kind is read from w
        if isinstance(light, PointLight | DirectionalLight):
            typed = isinstance(light, DirectionalLight)
        directional, L = _light_kind(ctx, typed, parts[0])
    casters = verts
    if c_kind != "points":
        casters = caster_triangles(ctx, c_kind, verts, g.blocker_vertices, "blocker_vertices")
        verts = ctx.xp.reshape(casters, (*casters.shape[:-3], -1, 3))
    a = Inputs(L, verts, B, R, U, n, f)
    shape = _check_shapes(a)
    given = (B is not None, R is not None, U is not None, n is not None, f is not None)
    key = _fit_key(directional, spot, aim_bbox, spec, (*given, kind != "points"))
    return Door(ctx, a, shape, key, casters, c_kind != "points")


def select_casters(door: Door) -> tuple[Inputs, Array]:
    """The casters the fit uses (a spot light's, clipped to its cone) and their count."""
    ctx, a, shape = door.ctx, door.a, door.shape
    xp = ctx.xp
    if door.key.spot:
        selection = spot_selection(ctx, a.light, a.U, a.B, door.casters, triangles=door.triangles)
        used = selection.kept
        if tuple(used.shape) != shape:
            used = xp.broadcast_to(used, shape)
        return a._replace(verts=selection.points), used
    # every caster, in every entry (a 0-d array costs a fraction of broadcast_to)
    count = door.casters.shape[-3 if door.triangles else -2]
    return a, np.array(count) if not shape and xp is np else xp.full(shape, count)


@functools.lru_cache(maxsize=256)
def _fit_key(
    directional: bool, spot: bool, aim_bbox: bool, spec: ShadowMapSpec, given: tuple[bool, ...]
) -> FitKey:
    """The static key of a call (cached: the same few recur every frame)."""
    return FitKey(
        directional,
        spot,
        aim_bbox,
        bool(spec.stable),
        spec.margins,
        spec.size,
        api_rows(spec.api, bool(spec.reversed_z)),
        *given,
    )


class Precision(NamedTuple):
    """How finely a fit's coordinates resolve its casters (:func:`precision`)."""

    step: float  # eps max |p|: the rounding step of the largest coordinate
    extent: float  # the casters' extent: the widest side of their box (world units)
    texel: float  # extent / n: a texel's size across the casters (n the map's larger side)
    dtype: str


#: The fit's refusals that a coarse rounding step can cause: renamed by :func:`refine`.
_ROUNDING_REFUSALS = frozenset({msg.ZERO_DIRECTION, msg.ZERO_SILHOUETTE, msg.BEHIND_LIGHT})

#: A rounding step over ``1 / TEXEL_FRACTION`` of a texel warns (:func:`warn_precision`).
TEXEL_FRACTION = 4.0

#: A rounding step of ``1 / ROUNDING_MARGIN`` of the casters' extent makes their whole shape
#: rounding noise: the fit's rounding tolerance (``32 eps`` times the coordinates).
ROUNDING_MARGIN = 32.0


_EPS = {np.dtype(t): float(np.finfo(t).eps) for t in (np.float32, np.float64)}


def precision(door: Door) -> Precision | None:
    """The coarsest entry's rounding step against its casters' extent and texel, from the
    light (a position) and the casters in world coordinates; None for traced arrays or
    casters of no extent (refused by the fit's own checks)."""
    a, key = door.a, door.key
    if door.ctx.lazy and (is_tracer(a.verts) or is_tracer(a.light) or is_tracer(a.B)):
        return None
    V = a.verts if type(a.verts) is np.ndarray else np.asarray(a.verts)
    if V.size == 0:  # no casters, or an empty batch: nothing to resolve
        return None
    eps = _EPS.get(V.dtype) or float(np.finfo(V.dtype).eps)
    if a.B is None and V.ndim == 2 and a.light.ndim == 1:  # one entry: on Python floats
        x0, y0, z0 = V.min(axis=0).tolist()
        x1, y1, z1 = V.max(axis=0).tolist()
        big = max(x1, -x0, y1, -y0, z1, -z0)  # max |p| over the casters' box
        if not key.directional:
            lx, ly, lz = np.asarray(a.light)[:3].tolist()
            big = max(big, abs(lx), abs(ly), abs(lz))
        e = max(x1 - x0, y1 - y0, z1 - z0)
        if not (e > 0 and math.isfinite(big) and math.isfinite(e)):
            return None
        return Precision(eps * big, e, e / max(key.texels), V.dtype.name)
    if a.B is not None:
        B = np.asarray(a.B)
        V = V @ np.swapaxes(B[..., :3, :3], -1, -2) + B[..., None, :3, 3]
    with np.errstate(all="ignore"):
        lo, hi = V.min(axis=-2), V.max(axis=-2)
        coords = np.maximum(np.abs(lo), np.abs(hi)).max(axis=-1)
        if not door.key.directional:  # a position: rounded as the casters are
            coords = np.maximum(coords, np.abs(np.asarray(a.light)[..., :3]).max(axis=-1))
        coords, extent = np.broadcast_arrays(coords, (hi - lo).max(axis=-1))
        ratio = eps * coords / extent  # the rounding step in casters' extents
    ratio = np.where(extent > 0, ratio, 0.0)  # (NaN: non-finite input, refused by the fit)
    i = int(np.argmax(np.nan_to_num(ratio, nan=0.0)))
    if not ratio.flat[i] > 0:
        return None
    e = float(extent.flat[i])
    return Precision(eps * float(coords.flat[i]), e, e / max(key.texels), V.dtype.name)


def warn_precision(door: Door) -> None:
    """Warn (NumPy input) where the coordinates' rounding step exceeds a quarter texel.

    A coordinate of magnitude ``|p|`` is rounded to within ``eps |p|``, and the fit's
    differences (a caster about the light or the frame's origin) carry that step. The
    map resolves its casters' extent ``E`` to a texel, ``E / n``: a step over a quarter
    texel moves shadow edges and stored depths by a visible part of one (the map's own
    rasterization is exact to well under a quarter texel), so the fit is only as good as
    its rounding. :func:`fit_shadow` asks for float32 only: in float64 the step reaches a
    quarter texel at ``max |p| > E / (4 n eps)``, about ``10^15 E / n``, and the check's
    few microseconds would be spent on every call for nothing."""
    p = precision(door)
    if p is not None and p.step > p.texel / TEXEL_FRACTION:
        warnings.warn(
            f"blocker_vertices: {p.dtype} coordinates this far from the origin are rounded in "
            f"steps of {p.step:.2g}, more than a quarter of a texel ({p.texel:.2g}: casters "
            f"{p.extent:.3g} across on {max(door.key.texels)} texels); shadow edges and "
            "depths are off by that much: pass float64 arrays, or recentre the coordinates "
            "(subtract a nearby origin from the light, casters and receivers)",
            msg.ShadowFitWarning,
            stacklevel=3,
        )


def refine(door: Door, err: ValueError) -> ValueError:
    """The fit's refusal ``err``, or, where the coordinates' rounding step reaches the
    casters' extent within the fit's rounding tolerance (the casters' shape is rounding
    noise), the refusal that names the precision instead of its symptom."""
    if str(err) not in _ROUNDING_REFUSALS:
        return err
    p = precision(door)
    if p is None or ROUNDING_MARGIN * p.step < p.extent:
        return err
    return ValueError(
        f"blocker_vertices: {p.dtype} coordinates this far from the origin are rounded in "
        f"steps of {p.step:.2g}, too coarse for casters {p.extent:.3g} across (their shape and the "
        "light's direction are rounding noise): pass float64 arrays, or recentre the "
        "coordinates (subtract a nearby origin from the light, casters and receivers)"
    )


def _spot_array(ctx: Context, position: Array, direction: Array, angle: Array) -> Array:
    """A spot light as one ``(*batch, 8)`` array: position, axis, ``tan(angle)``, angle."""
    xp = ctx.xp
    require_last("light.position", position, 3, hint="a position is (x, y, z)")
    require_last("light.direction", direction, 3, hint="the cone's axis is (x, y, z)")
    names = ("light.position", "light.direction", "light.angle")
    shapes = (position.shape[:-1], direction.shape[:-1], angle.shape)
    shape = batch_shape(*shapes, names=names)
    parts = (xp.broadcast_to(position, (*shape, 3)), xp.broadcast_to(direction, (*shape, 3)))
    return spot_rows(xp, *parts, xp.broadcast_to(angle, shape))


def _light_kind(ctx: Context, directional: bool | None, L: Array) -> tuple[bool, Array]:
    """The light's kind and its ``(*batch, 3)`` array: a position or a direction toward it."""
    hint = "a point light is (x, y, z); a homogeneous light (x, y, z, w), w = 0 directional"
    if directional is not None:
        require_last("light", L, 3, hint="a typed light holds (*batch, 3) arrays")
        return directional, L
    if L.ndim < 1 or L.shape[-1] not in (3, 4):
        raise shape_error("light", "(*batch, 3) or (*batch, 4)", tuple(L.shape), hint)
    if L.shape[-1] == 3:
        return False, L
    if L.ndim == 1 and not ctx.is_jax:  # one NumPy light: read w as a Python float
        w1 = float(L[3])
        if w1 == 0:
            return True, L[:3]
        if math.isfinite(w1):
            return False, L[:3] / w1
    if ctx.lazy and is_tracer(L):
        raise ValueError(
            "light: the kind of a homogeneous light (x, y, z, w) is read from the values of "
            "w, which a traced JAX array does not have; pass sm.PointLight(position) or "
            "sm.DirectionalLight(direction) under jit, vmap or grad"
        )
    with np.errstate(all="ignore"):
        sun, xyz = homogeneous(ctx.xp, L)
    kinds = np.asarray(sun)
    if kinds.all() or not kinds.any():
        return bool(kinds.all()), xyz
    raise ValueError(
        "light: a batch mixes point lights (w != 0) and directional lights (w = 0); their "
        "fits differ in kind: call fit_shadow once per kind (split the batch by w == 0), "
        "or pass sm.PointLight / sm.DirectionalLight"
    )


def _check_shapes(a: Inputs) -> tuple[int, ...]:
    """The arrays' shapes, and the broadcast batch shape."""
    require_vertices("blocker_vertices", a.verts)
    named = [("light", a.light.shape[:-1]), ("blocker_vertices", a.verts.shape[:-2])]
    if a.B is not None:
        require_matrix("blocker_to_world", a.B)
        named.append(("blocker_to_world", a.B.shape[:-2]))
    if a.U is not None:
        require_last("up", a.U, 3, hint="an up hint is (x, y, z)")
        named.append(("up", a.U.shape[:-1]))
    named += [(n, v.shape) for n, v in (("near", a.near), ("far", a.far)) if v is not None]
    shape = batch_shape(*(s for _, s in named), names=[n for n, _ in named])
    if a.R is not None:  # rows checked by _receiver_rows
        require_no_new_batch("receivers", a.R.shape[:-2], shape)
    return shape


ReceiverKind = Literal["points", "triangles", "mesh"]


def _receiver_kind(receivers: Any, name: str = "receivers") -> tuple[ReceiverKind, str, Any]:
    """The kind of a set of surfaces or points (from its type: receivers, or a cube map's
    casters), the name to convert it under and the array to convert."""
    if isinstance(receivers, Triangles):
        return "triangles", name, receivers.corners
    if isinstance(receivers, Mesh):
        return "mesh", f"{name}.vertices", receivers.vertices
    return "points", name, receivers


def _receiver_rows(ctx: Context, kind: ReceiverKind, R: Array, receivers: Any) -> Array:
    """Receivers as ``(*batch, M, 3)`` points or ``(*batch, M, 9)`` triangles (shape-checked)."""
    if kind == "points":
        hint = "receivers= takes points (*batch, N, 3), sm.Triangles or sm.Mesh"
        require_last("receivers", R, 3, min_ndim=2, hint=hint)
        if R.shape[-2] == 0:
            raise ValueError(_NO_RECEIVERS.format("points"))
        return R
    if kind == "triangles":
        if R.ndim < 3 or tuple(R.shape[-2:]) != (3, 3):
            raise shape_error(
                "receivers",
                "(*batch, M, 3, 3)",
                tuple(R.shape),
                "sm.Triangles holds M triangles of three corners (x, y, z)",
            )
    else:
        require_last(
            "receivers.vertices", R, 3, min_ndim=2, hint="a mesh's vertices are (*batch, V, 3)"
        )
        R = _mesh_corners(ctx, R, receivers.faces)
    if R.shape[-3] == 0:
        raise ValueError(_NO_RECEIVERS.format("triangles"))
    return R.reshape(*R.shape[:-2], 9)


_NO_RECEIVERS = "receivers: no receiver {} (M = 0); pass receivers=None when there are none"


def _mesh_corners(ctx: Context, vertices: Array, faces: Any, name: str = "receivers") -> Array:
    """A mesh's triangles' corners ``(*batch, F, 3, 3)``; faces checked (NaN under tracing)."""
    xp = ctx.xp
    F = xp.asarray(faces)
    check_faces(f"{name}.faces", F, vertices.shape[-2], concrete=not (ctx.lazy and is_tracer(F)))
    if ctx.is_jax:  # a traced index out of range fills NaN instead of clamping silently
        return xp.take(vertices, F, axis=-2, mode="fill", fill_value=xp.nan)
    return xp.take(vertices, F, axis=-2)


def caster_triangles(ctx: Context, kind: str, C: Array, casters: Any, name: str) -> Array:
    """Casters given as surfaces (``kind`` "triangles" or "mesh") as their triangles
    ``(*batch, M, 3, 3)``, shape-checked."""
    if kind == "triangles":
        if C.ndim < 3 or tuple(C.shape[-2:]) != (3, 3):
            hint = "sm.Triangles holds M triangles of three corners (x, y, z)"
            raise shape_error(name, "(*batch, M, 3, 3)", tuple(C.shape), hint)
        T = C
    else:
        require_vertices(f"{name}.vertices", C)
        T = _mesh_corners(ctx, C, casters.faces, name=name)
    if T.shape[-3] == 0:
        raise ValueError(f"{name}: no caster triangles (M = 0); a shadow needs casters")
    return T


def _check_static(key: FitKey, method: str, spec: ShadowMapSpec) -> None:
    """The option combinations refused whatever the values."""
    if key.directional and (key.has_near or key.has_far):
        raise ValueError(
            "near/far: a directional light's depth range is placed by the fit (its frame's "
            "origin moves behind every caster); leave near and far None and pass receivers= "
            "(sm.Triangles for surfaces) to hold what the shadows fall on"
        )
    if key.stable and not key.directional and not key.has_up:
        raise ValueError(msg.STABLE_NEEDS_UP)
    options = key.directional or key.spot or key.has_receivers or key.has_up or spec.api != "opengl"
    if method == "optimized" and (options or spec.reversed_z or spec.stable):
        raise ValueError(
            "method: 'optimized' fits point lights without receivers, api, reversed_z, up "
            "or stable; use method='mdv' with them"
        )


_FLOATS = (np.dtype(np.float32), np.dtype(np.float64))


def signature(g: Operands) -> tuple[Any, ...] | None:
    """What :func:`open_door` decides from: the operands' types, one float dtype and
    their shapes (the count axis of casters and receivers left out: the number of
    casters may change from call to call); ``None`` unless every array is a float32 or
    float64 ndarray of one dtype (and neither casters nor receivers a :class:`Mesh`,
    whose faces index per call)."""
    light, casters, B, R, U, n, f = g
    kind = type(light)
    if kind is np.ndarray:
        head: Any = light
    elif kind is PointLight or kind is DirectionalLight or kind is SpotLight:
        head = light[0]
    else:
        return None
    if type(head) is not np.ndarray or (dtype := head.dtype) not in _FLOATS:
        return None
    sig = [kind, dtype, head.shape, _counted(casters, dtype)]
    if kind is SpotLight:
        sig += [_fixed(light[1], dtype), _angle(light[2], dtype)]
    if B is not None or R is not None or U is not None or n is not None or f is not None:
        sig += [_counted(R, dtype), _fixed(B, dtype), _fixed(U, dtype), _fixed(n, dtype),
                _fixed(f, dtype)]  # fmt: skip
    for v in sig:
        if v is _OTHER:
            return None
    return tuple(sig)


#: A signature's entry for an operand the fast door does not take (a list, a Mesh,
#: another dtype): the whole signature is then None.
_OTHER = ("other",)


def _fixed(v: Any, dtype: Any) -> Any:
    """An operand's entry: its shape (None if not given)."""
    if v is None:
        return None
    if type(v) is not np.ndarray or v.dtype != dtype:
        return _OTHER
    return v.shape


def _counted(v: Any, dtype: Any) -> Any:
    """Points' or triangles' entry: the type and the shape with the count axis as -1."""
    kind = type(v)
    if kind is Triangles:
        v = v[0]
    if v is None or type(v) is not np.ndarray or v.dtype != dtype:
        return _OTHER if v is not None else None
    s = v.shape
    drop = 2 if kind is Triangles else 1
    return (kind, *s[: -1 - drop], -1, *s[-drop:]) if len(s) > drop else (kind, *s)


def _angle(angle: Any, dtype: Any) -> Any:
    """A spot light's angle's entry: a Python float, or an array's shape."""
    if type(angle) is float:
        return float
    return _fixed(angle, dtype)


class PreparedDoor(NamedTuple):
    """What a :class:`Door` read that holds for every call of one :func:`signature`
    (no arrays: a cached door keeps none of the caller's alive); reopened for new arrays."""

    ctx: Context
    shape: tuple[int, ...]
    key: FitKey
    triangles: bool
    signature: tuple[Any, ...] | None  # None: arguments the door must always read

    @classmethod
    def of(cls, door: Door, sig: tuple[Any, ...] | None) -> PreparedDoor:
        """The prepared part of ``door``, opened for arguments of signature ``sig``."""
        return cls(door.ctx, door.shape, door.key, door.triangles, sig)

    def reopen(self, g: Operands) -> Door | None:
        """The door of ``g``, whose :func:`signature` is this one's: its arrays in place of
        the prepared ones (a homogeneous light's ``w`` and the counts read again); ``None``
        where the full door must answer (a light of another kind, no casters)."""
        ctx, key, triangles = self.ctx, self.key, self.triangles
        light, casters, B, R, U, n, f = g
        if type(light) is np.ndarray:
            if light.shape[-1] == 4:  # read w again: the kind must be the prepared one
                directional, light = _light_kind(ctx, None, light)
                if directional != key.directional:
                    return None
        elif key.spot:
            angle = np.asarray(light[2], dtype=ctx.dtype)
            light = _spot_array(ctx, light[0], light[1], angle)
        else:
            light = light[0]
        verts = casters = casters[0] if triangles else casters
        if casters.shape[-3 if triangles else -2] == 0:
            return None
        if triangles:
            verts = casters.reshape(*casters.shape[:-3], -1, 3)
        if R is not None:
            kind: ReceiverKind = "triangles" if key.triangles else "points"
            R = _receiver_rows(ctx, kind, R[0] if key.triangles else R, None)
        a = Inputs(light, verts, B, R, U, n, f)
        return Door(ctx, a, self.shape, key, casters, triangles)


#: Prepared doors of recent calls, by options and :func:`signature` (a renderer's few
#: calls recur every frame); cleared when full.
_DOORS: dict[tuple[Any, ...], PreparedDoor] = {}
_DOORS_MAX = 64


def door_for(g: Operands, spec: ShadowMapSpec, aim_bbox: bool, method: str) -> Door:
    """:func:`open_door` and the static checks of ``method``; reopened from a prepared
    door when a call of the same options and :func:`signature` has passed them."""
    sig = signature(g)
    if sig is not None and method == "mdv":
        cache_key = (spec, aim_bbox, sig)
        prepared = _DOORS.get(cache_key)
        if prepared is not None:
            door = prepared.reopen(g)
            if door is not None:
                return door
    door = open_door(g, spec, aim_bbox)
    _check_static(door.key, method, spec)
    if sig is not None and method == "mdv":
        if len(_DOORS) >= _DOORS_MAX:
            _DOORS.clear()
        _DOORS[cache_key] = PreparedDoor.of(door, sig)
    return door
