"""fit_cascades' steps, written once for every backend: one camera's cascades.

Each step takes *per-entry values*: Python or Numba floats (the loop mode: :func:`cascade_loop`
runs them once per camera and cascade) or arrays of the batch shape (the array mode: NumPy or
JAX runs them once on whole arrays, the cascades on a last axis). Data-dependent choices
are the ``where`` primitive; a check sets its bit of :data:`._status.CASCADE_CHECKS` with
``st = st | flag(ok, bit)`` (``0 if ok else bit``, or ``where(ok, 0, bit)``), so both modes
return the same status word. Static options (``o.stable``) are Python branches on the
options record ``o`` (:class:`CascadeOptions`; in the loop a 1-element array of
:func:`options_dtype`, read by name). Buffers come from the ``alloc`` primitive (a NumPy
array under Numba, a list elsewhere; a list holds arrays in the array mode).

Only the pass over the 24 clipped edges has two forms: :func:`_bounds_loop` (outcodes
settle most edges without clipping) and :func:`_bounds_array` (every edge at once,
reductions over the last axis); ``specialize`` binds ``cascade_bounds`` to the mode's one
(:data:`FORMS`). Both use the formulas of :mod:`._cascade_formulas`.

Trusted shapes only: nothing here raises.
"""

from __future__ import annotations

import math
from typing import Any, NamedTuple

import numpy as np

from shadowmath._boundary._shapes import (
    Array,
    ArrayLike,
    Float,
    Int,
    Options,
    Real,
    Row,
    Scalar,
    Status,
)
from shadowmath._boundary._status import (
    C_BOUNDS_FINITE,
    C_BOUNDS_ORDER,
    C_FAR_INFINITE,
    C_INFINITE_FAR,
    C_LIGHT_FINITE,
    C_LIGHT_ZERO,
    C_LOG_NEAR,
    C_MAX_DISTANCE,
    C_PROJECTION_FINITE,
    C_PROJECTION_SINGULAR,
    C_SPLITS_INCREASE,
    C_SPLITS_RANGE,
    C_UP_FINITE,
    C_UP_PARALLEL,
    C_VIEW_AFFINE,
    C_VIEW_FINITE,
    C_VIEW_SINGULAR,
)

# Shared formulas and primitives, rebound by specialize().
from ._cascade_bounds import (
    BODY_VERTICES,
    CornerRow,
    LightBounds,
    body_loop,
    corner_axis,
    points_bounds,
)
from ._cascade_formulas import (  # noqa: F401
    EDGES,
    affine,
    alloc,
    array_api,
    box_values,
    camera_values,
    cascade_box,
    clip_plane,
    clip_segment,
    depth_hysteresis,
    edge_point,
    ladder_hold,
    slice_sphere,
    slice_values,
    split_depth,
    take_last,
)
from ._enclosing_rectangle import Rectangle
from ._fit_formulas import fit_axes, fit_rows, placement_ok, safe_box, stable_sides, to_light
from ._formulas import fabs, flag, isfinite, sqrt, where
from ._rectangle_loop import rectangle_loop
from ._rows import _mul16, inverse4, row16, tile_rows
from ._warp_loop import warp_frustum, warp_rows, warp_samples, warp_view, warp_world

#: The bounds pass of the mode, and the passes over the corners of the scene box and of a
#: slice: each bound by specialize() to its loop form or its array form (:data:`FORMS`).
cascade_bounds: Any = None
box_pass: Any = None
slice_corners: Any = None

#: Names bound per mode by specialize(): ``name: (loop form, array form)``.
FORMS = {"box_pass": ("_box_loop", "_box_array"), "slice_corners": ("_slice_loop", "_slice_array")}

# Status bits (module constants: Numba freezes them at compile time).


class RowFields(NamedTuple):
    """The parts of a cascade's output row, by name: each part's width (:data:`ROW_WIDTH`)
    or where it starts (:data:`ROW_AT`); the row is their concatenation, in this order."""

    world_to_light: int  # 16 entries, row-major
    world_to_clip: int  # 16
    world_to_texture: int  # 16
    frustum: int  # 8: OrthographicBox's fields, in its order
    band_end: int  # 1
    texel_size: int  # 2: along the map's X and Y
    half_width: int  # 1: a stable cascade's laddered half-width (NaN otherwise)


#: Each part's number of entries.
ROW_WIDTH = RowFields(16, 16, 16, 8, 1, 2, 1)
#: Where each part starts in the row.
ROW_AT = RowFields._make(sum(ROW_WIDTH[:k]) for k in range(len(ROW_WIDTH)))
#: The entries of one cascade's output row.
ROW = sum(ROW_WIDTH)


def row_part(name: str) -> slice:
    """The entries of part ``name`` (a field of :class:`RowFields`) in a cascade's row."""
    at = getattr(ROW_AT, name)
    return slice(at, at + getattr(ROW_WIDTH, name))


class CascadeInputs(NamedTuple):
    """One entry's inputs, as per-entry values (row-major matrices)."""

    light: Any  # 3: toward the light
    view_matrix: Any  # 16 (not "view": Numba reserves the name)
    projection: Any  # 16
    box: Any  # 6: min then max corner
    up: Any  # 3 (unused without o.has_up)


class CascadeScalars(NamedTuple):
    """One entry's scalars (NaN where not given); the compiled loop's columns, in order."""

    lam: Any
    max_distance: Any
    overlap: Any
    measured_near: Any  # a measured depth range (o.depth_range == 2)
    measured_far: Any
    previous_near: Any  # the range in use last frame (o.has_state)
    previous_far: Any


class CascadeCamera(NamedTuple):
    """The camera's frustum edges and the light frame, for slicing."""

    sign: Any  # view depth = sign * z_view
    near_corners: Any  # 4 x 3, corner i + 2 j
    far_corners: Any  # 4 x 4, homogeneous, w >= 0
    view_to_world: Any  # 16
    axes: Any  # 9: the light frame's X, Y, Z


class CascadeEntry(NamedTuple):
    """One camera's values before its cascades (:func:`cascade_entry`)."""

    camera: CascadeCamera
    lo: Any  # the view depths the splits span
    hi: Any
    lam: Any  # the scheme's blend
    overlap: Any
    sizes: Any  # the previous stable half-widths (a row)
    box_light: Any  # the scene box's corners in light coordinates, 8 x 3
    box_camera: Any  # their camera side values and view depth, 8 x 5
    status: Any  # the checks' bits


class CascadeSlice(NamedTuple):
    """One cascade's slice of the camera frustum (:func:`cascade_slice`)."""

    s0: Any  # its view depths, s0 <= s1 (s1 with the band)
    s1: Any
    view_corners: Any  # 8 x 3
    light_corners: Any  # 8 x 3
    box_values: Any  # the box's half-space values at the corners, 8 x 6


class StableBox(NamedTuple):
    """A stable cascade's box (:func:`stable_box`)."""

    hx: Any  # half-sizes
    hy: Any
    cx: Any  # centre, light X and Y
    cy: Any
    z_lo: Any  # depth range, light Z
    z_hi: Any
    held: Any  # the laddered half-width (the sphere's radius without a state)


class CascadeOptions(NamedTuple):
    """The options of one call, by name (static for the call)."""

    has_up: bool
    stable: bool
    has_splits: bool
    has_dmax: bool
    mx: float  # the margins: the usable fraction of the map along X and Y
    my: float
    width: float  # each map's texels
    height: float
    eps: float
    tol: float  # sqrt(eps): how far given splits may round past the camera's range
    cascades: int  # how many
    slack: float  # NEAR_FAR_SLACK
    cols: int  # the atlas's grid (0: texture layers, no tiles)
    rows: int
    camera_clip: tuple[float, ...]  # OpenGL clip to the camera's (16)
    map_clip: tuple[float, ...]  # OpenGL clip to the maps' API's (16)
    map_texture: tuple[float, ...]  # its texture rows (16)
    depth_range: int  # 0: the camera's, 1: the visible range, 2: measured (CascadeScalars)
    has_state: bool  # the last range and sizes in use (CascadeScalars.previous_*, W): the ladder
    inside: bool = False  # each cascade's band ends at its practical split (stable "auto")
    fitted: bool = False  # orientation="fitted": each map turned to its least-area rectangle
    warp: bool = False  # warp="lispsm": each map warped (:func:`warp_fit`)


_KINDS = {"bool": np.bool_, "float": np.float64, "int": np.int64}


def options_dtype() -> np.dtype[Any]:
    """The structured dtype of :class:`CascadeOptions` (the compiled loop's record)."""
    fields: list[Any] = []
    for name, hint in CascadeOptions.__annotations__.items():
        kind = getattr(hint, "__forward_arg__", hint)  # NamedTuple keeps a string as a ForwardRef
        fields.append((name, _KINDS[kind]) if kind in _KINDS else (name, np.float64, (16,)))
    return np.dtype(fields)


def options_record(o: CascadeOptions) -> np.ndarray[Any, np.dtype[Any]]:
    """``o`` as a read-only 1-element structured array (read as ``opts[0].stable``)."""
    record = np.array([tuple(o)], dtype=options_dtype())
    record.setflags(write=False)
    return record


def lesser(a: Scalar, b: Scalar) -> Scalar:
    """``min(a, b)`` with the ``where`` primitive."""
    return where(a <= b, a, b)


def greater(a: Scalar, b: Scalar) -> Scalar:
    """``max(a, b)`` with the ``where`` primitive."""
    return where(a >= b, a, b)


def cascade_camera(
    V: Row, P: Row, o: Options, nc: Row, fc: Row
) -> tuple[Scalar, Scalar, Scalar, Status]:
    """The camera's frustum edges: near corners ``nc`` (4 x 3), far corners ``fc`` (4 x 4,
    homogeneous, ``w >= 0``), both ``i + 2 j``. Returns the view depth's sign, the near and
    far depths (``inf``: an infinite far plane) and the status bits."""
    iP, dp = inverse4(P)
    pn = sqrt(P[0] * P[0] + P[1] * P[1] + P[2] * P[2] + P[3] * P[3])
    for r in range(1, 4):
        q = 4 * r
        pn = pn * sqrt(
            P[q] * P[q] + P[q + 1] * P[q + 1] + P[q + 2] * P[q + 2] + P[q + 3] * P[q + 3]
        )
    st = flag(fabs(dp) > 64.0 * o.eps * pn, C_PROJECTION_SINGULAR)
    zero = 0.0 * dp
    nz, fz, fw = zero, zero, zero
    C = o.camera_clip
    for k in range(8):  # OpenGL's NDC corner (x, y, z) in the camera's clip space, unprojected
        x, y, z = 2.0 * (k & 1) - 1.0, 2.0 * ((k >> 1) & 1) - 1.0, 2.0 * (k >> 2) - 1.0
        c = (
            C[0] * x + C[1] * y + C[2] * z + C[3],
            C[4] * x + C[5] * y + C[6] * z + C[7],
            C[8] * x + C[9] * y + C[10] * z + C[11],
            C[12] * x + C[13] * y + C[14] * z + C[15],
        )
        h = (iP[0] * c[0] + iP[1] * c[1] + iP[2] * c[2] + iP[3] * c[3],
             iP[4] * c[0] + iP[5] * c[1] + iP[6] * c[2] + iP[7] * c[3],
             iP[8] * c[0] + iP[9] * c[1] + iP[10] * c[2] + iP[11] * c[3],
             iP[12] * c[0] + iP[13] * c[1] + iP[14] * c[2] + iP[15] * c[3])  # fmt: skip
        e = k & 3
        if k < 4:
            q = where(h[3] != 0, h[3], 1.0)
            nc[3 * e], nc[3 * e + 1], nc[3 * e + 2] = h[0] / q, h[1] / q, h[2] / q
            nz = nz + 0.25 * nc[3 * e + 2]
        else:
            big = greater(greater(fabs(h[0]), fabs(h[1])), greater(fabs(h[2]), fabs(h[3])))
            big = where(h[3] < 0, -big, where(big > 0, big, 1.0))
            for r in range(4):
                fc[4 * e + r] = h[r] / big
            fz = fz + 0.25 * fc[4 * e + 2]
            fw = fw + 0.25 * fc[4 * e + 3]
    finite_far = fw > 32.0 * o.eps
    safe_fw = where(finite_far, fw, zero + 1.0)
    t = where(finite_far, fz / safe_fw - nz, nz)
    sign = where(t < 0, zero - 1.0, zero + 1.0)
    st = st | flag(finite_far | (sign * nz > 0), C_INFINITE_FAR)
    far = where(finite_far, sign * fz / safe_fw, zero + math.inf)
    return sign, sign * nz, far, st


def cascade_checks(inputs: CascadeInputs, o: Options) -> Status:
    """The finiteness, affinity and order checks of one entry's inputs (status bits)."""
    L, V, P, box, U = inputs.light, inputs.view_matrix, inputs.projection, inputs.box, inputs.up
    tv, tp = V[0], P[0]
    for k in range(1, 16):
        tv, tp = tv + V[k], tp + P[k]
    st = flag(isfinite(L[0] + L[1] + L[2]), C_LIGHT_FINITE)
    st = st | flag(isfinite(tv), C_VIEW_FINITE) | flag(isfinite(tp), C_PROJECTION_FINITE)
    total = box[0] + box[1] + box[2] + box[3] + box[4] + box[5]
    st = st | flag(isfinite(total), C_BOUNDS_FINITE)
    if o.has_up:
        st = st | flag(isfinite(U[0] + U[1] + U[2]), C_UP_FINITE)
    affine_ok = (V[12] == 0) & (V[13] == 0) & (V[14] == 0) & (V[15] == 1)
    st = st | flag(affine_ok, C_VIEW_AFFINE)
    st = st | flag(placement_ok(V, o.eps), C_VIEW_SINGULAR)  # free of scale (Hadamard)
    order = (box[3] >= box[0]) & (box[4] >= box[1]) & (box[5] >= box[2])
    return st | flag(order, C_BOUNDS_ORDER)


def cascade_range(
    near: Scalar,
    far: Scalar,
    sc: CascadeScalars,
    G: Row | Float[Array, "*#batch m"] | None,
    o: Options,
) -> tuple[Scalar, Status]:
    """The last split of the scheme (``near + 1`` where invalid) and the checks of the
    splits: given (``G``, ``n + 1`` increasing within the camera's range, to ``o.tol``
    relative) or of the scheme (``sc``: :class:`CascadeScalars`)."""
    n = o.cascades
    if o.has_splits:
        ok = take_last(G, 1) > take_last(G, 0)
        for k in range(2, n + 1):
            ok = ok & (take_last(G, k) > take_last(G, k - 1))
        st = flag(ok, C_SPLITS_INCREASE)
        inside = (take_last(G, 0) >= near - o.tol * fabs(near)) & (
            take_last(G, n) <= far * (1.0 + o.tol)
        )
        return far, st | flag(inside, C_SPLITS_RANGE)
    if o.has_dmax:
        d = sc.max_distance
        st = flag((d > near) & (d <= far), C_MAX_DISTANCE)
        end = where(d > near, lesser(d, far), near + 1.0)
    else:
        st = flag(isfinite(far), C_FAR_INFINITE)
        end = far
    st = st | flag((sc.lam == 0) | (near > 0), C_LOG_NEAR)
    return where(isfinite(end) & (end > near), end, near + 1.0), st


def cascade_split(
    G: Row | Float[Array, "*#batch m"] | None,
    k: Scalar,
    rng: tuple[Scalar, Scalar, Scalar, Scalar],
    o: Options,
) -> Scalar:
    """Split ``k`` (an int, or the cascades' indices in the array mode): given, or the
    scheme's over ``rng = (near, end, lam, overlap)`` with exact ends.

    With ``o.inside`` each cascade ends, band included, at the scheme's split ``p_k``:
    ``s_k + v (s_k - s_{k-1}) = p_k`` (``v`` the overlap), that is, with ``q = v / (1 + v)``,
    ``s_k = q^k n + (1 - q) sum_{j=1}^{k} q^{k-j} p_j``."""
    if o.has_splits:
        return take_last(G, k)
    near, end, lam, ov = rng
    n = o.cascades
    s = split_depth(near, end, lam, k / n)
    if o.inside:
        q = ov / (1.0 + ov)
        s = q**k * near
        for i in range(1, n):
            p = split_depth(near, end, lam, i / n)
            s = s + where(k >= i, (1.0 - q) * q ** greater(k - i, 0) * p, 0.0 * p)
    return where(k == 0, near, where(k == n, end, s))


def _box_loop(VP: tuple[Row, Row], box: Row, a_sign: tuple[Row, Scalar]) -> tuple[Row, Row]:
    """The scene box's corners (``box``: min then max, 6 numbers, corner ``k``'s ``x, y, z``
    from bits 0, 1, 2 of ``k``): light coordinates (``bl``, 8 x 3), camera side values and
    view depth (``bg``, 8 x 5). The loop form of ``box_pass``."""
    V, P = VP
    a, sign = a_sign
    bl, bg = alloc(24), alloc(40)
    PV = _mul16(P, V)
    for k in range(8):
        x, y, z = box[3 * (k & 1)], box[3 * ((k >> 1) & 1) + 1], box[3 * (k >> 2) + 2]
        p = to_light(x, y, z, a)
        bl[3 * k], bl[3 * k + 1], bl[3 * k + 2] = p[0], p[1], p[2]
        sides = camera_values(PV, x, y, z)
        for c in range(4):
            bg[5 * k + c] = sides[c]
        bg[5 * k + 4] = sign * (V[8] * x + V[9] * y + V[10] * z + V[11])
    return bl, bg


def _box_array(VP: tuple[Row, Row], box: Row, a_sign: tuple[Row, Scalar]) -> tuple[Row, Row]:
    """The array form of ``box_pass`` (:func:`_box_loop`): the same formulas once, on the
    eight corners as a last axis (:class:`._cascade_bounds.CornerRow`)."""
    xp = array_api
    V, P = VP
    a, sign = a_sign
    x, y, z = (xp.stack([box[3 * ((k >> c) & 1) + c] for k in range(8)], axis=-1)
               for c in range(3))  # fmt: skip
    Vc = corner_axis(V)
    sides = camera_values(corner_axis(_mul16(P, V)), x, y, z)
    depth = corner_axis((sign,))[0] * (Vc[8] * x + Vc[9] * y + Vc[10] * z + Vc[11])
    bl = CornerRow(to_light(x, y, z, corner_axis(a)))
    return bl, CornerRow((sides[0], sides[1], sides[2], sides[3], depth))


def cascade_entry(
    inputs: CascadeInputs,
    sc: CascadeScalars,
    GW: tuple[Row | Float[Array, "*#batch m"] | None, Row | Float[Array, "*#batch n"] | None],
    o: Options,
) -> CascadeEntry:
    """One camera's steps before its cascades (a :class:`CascadeEntry`): frustum, checks,
    split range, light frame and scene box. ``inputs``: :class:`CascadeInputs`; ``sc``:
    :class:`CascadeScalars`; ``GW``: the given splits and the previous stable half-widths
    (rows)."""
    L, V, P, box, U = inputs.light, inputs.view_matrix, inputs.projection, inputs.box, inputs.up
    G, W = GW
    nc, fc = alloc(12), alloc(16)
    sign, near, far, st = cascade_camera(V, P, o, nc, fc)
    end, st_range = cascade_range(near, far, sc, G, o)
    coords = greater(greater(greater(fabs(box[0]), fabs(box[1])), fabs(box[2])),
                     greater(greater(fabs(box[3]), fabs(box[4])), fabs(box[5])))  # fmt: skip
    a, ok_light, _, ok_up = fit_axes((-L[0], -L[1], -L[2]), U, o.has_up, coords, o.eps)
    st = st | cascade_checks(inputs, o) | st_range
    st = st | flag(ok_light, C_LIGHT_ZERO) | flag(ok_up, C_UP_PARALLEL)
    bl, bg = box_pass((V, P), box, (a, sign))
    cam = CascadeCamera(sign, nc, fc, inverse4(V)[0], a)
    lo, hi = split_range(cam, (box, bg), (near, end), sc, o)
    return CascadeEntry(cam, lo, hi, sc.lam, sc.overlap, W, bl, bg, st)


def split_range(
    cam: CascadeCamera,
    scene: tuple[Row, Row],
    ne: tuple[Scalar, Scalar],
    sc: CascadeScalars,
    o: Options,
) -> tuple[Scalar, Scalar]:
    """The view depths the splits span: the camera's ``ne = (near, end)``, or the visible
    range (:func:`visible_range`) or a measured one (``sc.measured_*``) within it; with the
    previous range (``sc.previous_*``), widened to the ladder with hysteresis
    (:func:`._cascade_formulas.depth_hysteresis`) and clamped to ``ne``."""
    near, end = ne
    if o.depth_range == 0:
        return near, end
    if o.depth_range == 1:
        lo, hi = visible_range(cam, scene, ne)
    else:
        lo = greater(lesser(sc.measured_near, end), near)
        hi = lesser(greater(sc.measured_far, near), end)
    if o.has_state:
        lo, hi = depth_hysteresis(lo, hi, sc.previous_near, sc.previous_far)
        lo, hi = greater(lo, near), lesser(hi, end)
    return lo, hi


def visible_range(
    cam: CascadeCamera, scene: tuple[Row, Row], ne: tuple[Scalar, Scalar]
) -> tuple[Scalar, Scalar]:
    """The nearest and farthest view depth of the camera's slice ``ne = (near, end)``
    intersected with the scene box: the bounds pass (:data:`cascade_bounds`) with each
    vertex's view depth as its first coordinate (depth is affine in the point, so its
    extremes over the convex intersection are at vertices). ``ne`` where they miss."""
    near, end = ne
    box, bg = scene
    _, _, gs = slice_corners(cam, box, near, end)
    zero = 0.0 * near
    sd, bd = alloc(24), alloc(24)
    for k in range(8):
        sd[3 * k], sd[3 * k + 1], sd[3 * k + 2] = near if k < 4 else end, zero, zero
        bd[3 * k], bd[3 * k + 1], bd[3 * k + 2] = bg[5 * k + 4], zero, zero
    b = cascade_bounds(sd, gs, (bd, bg), (near, end))
    return b.lo_x, b.hi_x


def cascade_slice(
    e: CascadeEntry, box: Row, Z: Row | Float[Array, "*#batch m"], j: Scalar, o: Options
) -> CascadeSlice:
    """Cascade ``j``'s :class:`CascadeSlice`: its depths ``s0 <= s1`` (with its band;
    ``Z``: the ``n + 1`` splits) and its slice's corners."""
    s0, s1 = take_last(Z, j), take_last(Z, j + 1)
    s1 = lesser(s1 + e.overlap * (s1 - s0), take_last(Z, o.cascades))
    vc, lc, gs = slice_corners(e.camera, box, s0, s1)
    return CascadeSlice(s0, s1, vc, lc, gs)


def _slice_loop(cam: CascadeCamera, box: Row, s0: Scalar, s1: Scalar) -> tuple[Row, Row, Row]:
    """The corners of the camera's slice between view depths ``s0`` and ``s1``: view
    (``vc``, 8 x 3), light (``lc``) and the box's half-space values at them (``gs``, 8 x 6).
    ``cam``: :class:`CascadeCamera`. The loop form of ``slice_corners``."""
    sign, nc, fc, iV, a = cam.sign, cam.near_corners, cam.far_corners, cam.view_to_world, cam.axes
    vc, lc, gs = alloc(24), alloc(24), alloc(48)
    lo, hi = (box[0], box[1], box[2]), (box[3], box[4], box[5])
    for k in range(8):
        e4 = k & 3
        p = edge_point((nc[3 * e4], nc[3 * e4 + 1], nc[3 * e4 + 2]),
                       (fc[4 * e4], fc[4 * e4 + 1], fc[4 * e4 + 2], fc[4 * e4 + 3]),
                       sign, s0 if k < 4 else s1)  # fmt: skip
        vc[3 * k], vc[3 * k + 1], vc[3 * k + 2] = p[0], p[1], p[2]
        w = affine(iV, p[0], p[1], p[2])
        q = to_light(w[0], w[1], w[2], a)
        lc[3 * k], lc[3 * k + 1], lc[3 * k + 2] = q[0], q[1], q[2]
        g = box_values(w[0], w[1], w[2], lo, hi)
        for c in range(6):
            gs[6 * k + c] = g[c]
    return vc, lc, gs


def _slice_array(cam: CascadeCamera, box: Row, s0: Scalar, s1: Scalar) -> tuple[Row, Row, Row]:
    """The array form of ``slice_corners`` (:func:`_slice_loop`): the same formulas once, on
    the eight corners as a last axis (:class:`._cascade_bounds.CornerRow`): ``s0``, ``s1``
    ``(*b, n)``, the rows ``(*b, n)`` per entry, their columns ``(*b, n, 8)``."""
    xp = array_api
    nc, fc = cam.near_corners, cam.far_corners
    n8 = tuple(xp.stack([nc[3 * (k & 3) + c] for k in range(8)], axis=-1) for c in range(3))
    f8 = tuple(xp.stack([fc[4 * (k & 3) + c] for k in range(8)], axis=-1) for c in range(4))
    shape = (*xp.broadcast_shapes(xp.shape(s0), xp.shape(s1)), 4)
    d8 = xp.concat([xp.broadcast_to(s0[..., None], shape), xp.broadcast_to(s1[..., None], shape)],
                   axis=-1)  # fmt: skip
    p = edge_point(n8, f8, corner_axis((cam.sign,))[0], d8)
    w = affine(corner_axis(cam.view_to_world), p[0], p[1], p[2])
    q = to_light(w[0], w[1], w[2], corner_axis(cam.axes))
    b = corner_axis(box)
    g = box_values(w[0], w[1], w[2], (b[0], b[1], b[2]), (b[3], b[4], b[5]))
    return CornerRow(p), CornerRow(q), CornerRow(g)


def cascade_fit(e: CascadeEntry, sl: CascadeSlice, j: Scalar, o: Options, row: Row) -> None:
    """Cascade ``j``'s map into ``row`` (:data:`ROW` entries, parts at :data:`ROW_AT`) from
    its :class:`CascadeSlice` ``sl`` and the camera's :class:`CascadeEntry` ``e``."""
    b = cascade_bounds(sl.light_corners, sl.box_values, (e.box_light, e.box_camera), (sl.s0, sl.s1))
    bounds_fit(e, sl, b, (j, o), row)


def bounds_fit(
    e: CascadeEntry, sl: CascadeSlice, b: LightBounds, jo: tuple[Scalar, Options], row: Row
) -> None:
    """:func:`cascade_fit` from the slice's :class:`LightBounds` ``b`` (``jo = (j, o)``)."""
    j, o = jo
    a = e.camera.axes
    if o.stable:
        sb = stable_box((sl.view_corners, e.camera.view_to_world, a), b, e.sizes, j, o)
        depth = sb.z_hi - sb.z_lo
        pad = depth + greater(sb.hx, sb.hy)
        box6, z_lo = (sb.hx, sb.hy, sb.cx, sb.cy, pad, pad + depth), sb.z_lo
        row[ROW_AT.half_width] = sb.held
    else:
        box6, z_lo = cascade_box((b.lo_x, b.hi_x, b.lo_y, b.hi_y, b.z_lo, b.z_hi)), b.z_lo
        row[ROW_AT.half_width] = math.nan
    store_cascade(a, box6, z_lo, (j, o), row)
    row[ROW_AT.band_end] = sl.s1


def fitted_fit(e: CascadeEntry, sl: CascadeSlice, j: Scalar, o: Options, row: Row) -> None:
    """The loop form of ``orientation="fitted"`` (in place of :func:`cascade_fit`; the
    array form is :func:`shadowmath._fits._orientation.fitted_cascade`): cascade ``j``'s
    map turned about the light's ``Z`` to the least-area rectangle enclosing its body's
    vertices (:func:`._cascade_bounds.body_loop`, :func:`._rectangle_loop.rectangle_loop`)."""
    pts = alloc(3 * BODY_VERTICES)
    m, _ = body_loop(sl.light_corners, sl.box_values, (e.box_light, e.box_camera),
                     (sl.s0, sl.s1), pts)  # fmt: skip
    b = points_bounds(pts, m, e.box_light)
    store_turned(e.camera.axes, rectangle_loop(pts, m), b, (sl, j, o), row)


def store_turned(
    a: Row,
    r: Rectangle,
    b: LightBounds,
    slo: tuple[CascadeSlice, Scalar, Options],
    row: Row,
) -> None:
    """A fitted cascade's row from the light frame ``a``, the least-area rectangle ``r``
    (:class:`._enclosing_rectangle.Rectangle`: the turn ``(c, s)`` and its bounds) and the
    :class:`LightBounds` ``b`` (its depths); ``slo = (slice, j, o)``. With ``(c, s)`` the
    turn, ``X' = c X + s Y``, ``Y' = -s X + c Y``, ``Z' = Z``."""
    sl, j, o = slo
    c, s = r.c, r.s
    turned = (c * a[0] + s * a[3], c * a[1] + s * a[4], c * a[2] + s * a[5],
              c * a[3] - s * a[0], c * a[4] - s * a[1], c * a[5] - s * a[2],
              a[6], a[7], a[8])  # fmt: skip
    box = cascade_box((r.lo_u, r.hi_u, r.lo_v, r.hi_v, b.z_lo, b.z_hi))
    store_cascade(turned, box, b.z_lo, (j, o), row)
    row[ROW_AT.band_end], row[ROW_AT.half_width] = sl.s1, math.nan


def warp_fit(
    e: CascadeEntry,
    sl: CascadeSlice,
    VP: tuple[Row, Row],
    jo: tuple[Scalar, Options],
    row: Row,
) -> None:
    """The loop form of ``warp="lispsm"`` (the array form is
    :func:`shadowmath._fits.cascades._lispsm.warp_cascades`): cascade ``j``'s orthographic
    row (:func:`cascade_fit`) with its clip and texture rows and texel size replaced by the
    warped ones (:mod:`._warp_loop`) where the warp applies; ``VP``: the camera's view and
    projection (16 each), ``jo = (j, o)``."""
    j, o = jo
    pts, buf = alloc(3 * BODY_VERTICES), alloc(5 * 256)
    m, seen = body_loop(sl.light_corners, sl.box_values, (e.box_light, e.box_camera),
                        (sl.s0, sl.s1), pts)  # fmt: skip
    bounds_fit(e, sl, points_bounds(pts, m, e.box_light), jo, row)
    a, at = e.camera.axes, ROW_AT.texel_size
    vw = warp_view(e.camera.view_to_world, e.camera.sign, VP, a)
    if not vw.ok:
        return
    k = warp_samples(sl.light_corners, e.box_light, a, buf)
    texels = o.mx * o.my * o.width * o.height
    wp = warp_frustum(vw, (pts, m if seen else 0, e.box_light), (buf, k),
                      (row[at] * row[at + 1] * texels, texels))  # fmt: skip
    if not wp.ok:
        return
    rows, h, ok = warp_rows(vw, wp, (pts, m), (o.mx, o.my, o.slack))
    if not ok:
        return
    gl = warp_world(rows, a)
    clip = _mul16(row16(o.map_clip, 0), gl)
    tex = cascade_tile(_mul16(row16(o.map_texture, 0), gl), j, o)
    for q in range(16):
        row[ROW_AT.world_to_clip + q] = clip[q]
        row[ROW_AT.world_to_texture + q] = tex[q]
    row[at] = 2.0 * wp.f * h / (o.mx * o.width)
    row[at + 1] = wp.f * (wp.f - wp.n) / (o.my * o.height * wp.n)


def stable_box(
    cam: tuple[Row, Row, Row],
    b: LightBounds,
    W: Row | Float[Array, "*#batch n"] | None,
    j: Scalar,
    o: Options,
) -> StableBox:
    """The :class:`StableBox` of one cascade: a square of half-width ``r`` plus half a
    texel, its centre snapped to whole texels (:func:`._fit_formulas.stable_sides`), its
    depth range (``b``: the :class:`LightBounds`, with the box's own ``z``) and ``r``.

    ``r`` is the radius of the slice's sphere, centred there; with a previous state
    (``W``: the laddered half-widths in use) the half-width of the visible part's
    light-space bounds ``b`` on the ladder with hysteresis
    (:func:`._cascade_formulas.ladder_hold`), returned as ``held``, but at most
    ``r``, centred on those bounds, with their depths. ``cam = (view corners, view to
    world, light axes)``."""
    vc, iV, a = cam
    corners = (
        vc[0], vc[1], vc[2], vc[3], vc[4], vc[5], vc[6], vc[7], vc[8], vc[9], vc[10], vc[11],
        vc[12], vc[13], vc[14], vc[15], vc[16], vc[17], vc[18], vc[19], vc[20], vc[21],
        vc[22], vc[23],
    )  # fmt: skip
    vx, vy, vz, r2 = slice_sphere(corners)
    c = affine(iV, vx, vy, vz)
    r = sqrt(r2)
    held = r
    if o.has_state:
        held = ladder_hold(0.5 * greater(b.hi_x - b.lo_x, b.hi_y - b.lo_y), take_last(W, j))
        r = lesser(held, r)
        mx, my = 0.5 * (b.lo_x + b.hi_x), 0.5 * (b.lo_y + b.hi_y)
        c = (mx * a[0] + my * a[3], mx * a[1] + my * a[4], mx * a[2] + my * a[5])
    hx, hy, ox, oy, _ = stable_sides((c, r * r), a, (o.mx, o.my, o.width, o.height), r, o.eps)
    cx = c[0] * a[0] + c[1] * a[1] + c[2] * a[2] + ox
    cy = c[0] * a[3] + c[1] * a[4] + c[2] * a[5] + oy
    if o.has_state:  # the visible part's own depths
        return StableBox(hx, hy, cx, cy, b.z_lo, b.z_hi, held)
    cz = c[0] * a[6] + c[1] * a[7] + c[2] * a[8]
    z_hi = lesser(cz + r, b.box_z_hi)
    return StableBox(hx, hy, cx, cy, lesser(b.box_z_lo, z_hi - r), z_hi, held)


def cascade_tile(tex: tuple[Scalar, ...], j: Scalar, o: Options) -> tuple[Scalar, ...]:
    """Texture rows of cascade ``j`` moved into its atlas tile (:func:`._rows.tile_rows`;
    with texture layers, ``o.cols == 0``, unchanged)."""
    if o.cols > 0:
        return tile_rows(tex, (j % o.cols, j // o.cols, 1.0, 1.0), (o.cols, o.rows))
    return tex


def store_cascade(
    a: Row,
    box6: tuple[Scalar, Scalar, Scalar, Scalar, Scalar, Scalar],
    z_lo: Scalar,
    jo: tuple[Scalar, Options],
    row: Row,
) -> None:
    """The cascade's matrices, frustum and texel size into ``row`` (parts at :data:`ROW_AT`)."""
    j, o = jo
    hx, hy, cx, cy, near, far = box6
    shift = z_lo - near  # the origin, on Z through the world origin: x, y stay anchored
    origin = (shift * a[6], shift * a[7], shift * a[8])
    near, far = near * (1.0 - o.slack), far * (1.0 + o.slack)
    api = (row16(o.map_clip, 0), row16(o.map_texture, 0))
    box = safe_box((hx, hy, cx, cy, near, far))
    w, clip, tex = fit_rows((origin, a), box, (o.mx, o.my), True, api)
    tex = cascade_tile(tex, j, o)
    at_w, at_c, at_t = ROW_AT.world_to_light, ROW_AT.world_to_clip, ROW_AT.world_to_texture
    row[at_w : at_w + 12] = w
    row[at_w + 12], row[at_w + 13], row[at_w + 14], row[at_w + 15] = 0.0, 0.0, 0.0, 1.0
    row[at_c : at_c + 16] = clip  # whole: the array form keeps a product's matrix whole
    row[at_t : at_t + 16] = tex
    f = ROW_AT.frustum  # OrthographicBox's order
    row[f], row[f + 1], row[f + 2], row[f + 3] = hx, hy, near, far
    row[f + 4], row[f + 5], row[f + 6], row[f + 7] = o.mx, o.my, cx, cy
    row[ROW_AT.texel_size] = 2.0 * hx / (o.mx * o.width)
    row[ROW_AT.texel_size + 1] = 2.0 * hy / (o.my * o.height)


def cascade_loop(
    inputs: tuple[Real[ArrayLike, "_ _"], ...],
    opts: tuple[Options] | np.ndarray[Any, np.dtype[Any]],
    out: Float[ArrayLike, "m n r"],
    splits: Float[ArrayLike, "m _"],
    status: Int[ArrayLike, " m"],
) -> None:
    """The loop mode's driver: every camera's cascades, one camera at a time.

    ``inputs``: light ``(m, 3)``, views and projections ``(m, 16)``, boxes ``(m, 6)``
    (min then max), ups ``(m, 3)``, scalars ``(m, 7)`` (:class:`CascadeScalars`' fields in
    order), given splits ``(m, n + 1)`` and the previous stable half-widths ``(m, n)``, each
    ``m = count or 1`` read at ``i % m``; ``opts``: the options record (``opts[0]``).
    ``out``: ``(count, n, ROW)``; ``splits``: ``(count, n + 1)``; ``status``: ``(count,)``.
    """
    light, views, projs, boxes, ups, scalars, given, sizes = inputs
    o = opts[0]
    for i in range(len(out)):
        L, U, bx = light[i % len(light)], ups[i % len(ups)], boxes[i % len(boxes)]
        box = (bx[0], bx[1], bx[2], bx[3], bx[4], bx[5])
        G, s = given[i % len(given)], scalars[i % len(scalars)]
        e = cascade_entry(
            CascadeInputs((L[0], L[1], L[2]), row16(views[i % len(views)], 0),
                          row16(projs[i % len(projs)], 0), box, (U[0], U[1], U[2])),
            CascadeScalars(s[0], s[1], s[2], s[3], s[4], s[5], s[6]),
            (G, sizes[i % len(sizes)]), o,
        )  # fmt: skip
        status[i] = e.status
        rng = (e.lo, e.hi, e.lam, e.overlap)
        for k in range(o.cascades + 1):
            splits[i][k] = cascade_split(G, k, rng, o)
        for j in range(o.cascades):
            sl = cascade_slice(e, box, splits[i], j, o)
            if o.fitted:
                fitted_fit(e, sl, j, o, out[i][j])
            elif o.warp:
                VP = (row16(views[i % len(views)], 0), row16(projs[i % len(projs)], 0))
                warp_fit(e, sl, VP, (j, o), out[i][j])
            else:
                cascade_fit(e, sl, j, o, out[i][j])


FUNCTIONS = (
    "lesser",
    "greater",
    "cascade_camera",
    "cascade_checks",
    "cascade_range",
    "cascade_split",
    "_box_loop",
    "_box_array",
    "cascade_entry",
    "split_range",
    "visible_range",
    "cascade_slice",
    "_slice_loop",
    "_slice_array",
    "cascade_fit",
    "bounds_fit",
    "fitted_fit",
    "store_turned",
    "warp_fit",
    "stable_box",
    "cascade_tile",
    "store_cascade",
    "cascade_loop",
)
