r"""The 2D lights of a shadow atlas fitted, one group of (kind, tile size, border) at a time.

Each group runs :func:`fit_shadow`'s compiled loop once, writing into one output block
(NumPy with Numba), or its array driver (JAX, or NumPy alone; small NumPy groups one light
at a time on Python floats).
"""

from __future__ import annotations

import functools
from typing import Any

import numpy as np
from numpy.typing import NDArray

from shadowmath._backends import _kernels
from shadowmath._boundary._validate import Array, Checks, Context
from shadowmath._fits._backend import failure_messages, failures, first_failure, form
from shadowmath._fits._light_kinds import SPOT, SUN
from shadowmath._fits._spec import FitKey
from shadowmath._fits.shadow import _compiled
from shadowmath._fits.shadow._arrays import Inputs, driver, fit_arrays
from shadowmath._fits.shadow._spot_select import spot_selection
from shadowmath._geometry._adaptive_frustum import border_margin
from shadowmath._math._frame import stack_matrix
from shadowmath._math._loops import FIT_MATRIX, FIT_ROW_AT

from ._allocate import ShadowAtlas
from ._report import AtlasInputs, Report, pick

__all__ = ["fit_2d"]

Ints = NDArray[np.int64]


def fit_2d(
    ctx: Context, atlas: ShadowAtlas, kinds: Ints, inputs: AtlasInputs, report: Report
) -> list[tuple[Ints, Array, Array, Array, Array]]:
    """One fit per group of 2D lights of one (kind, size, border).

    The lights are sorted by group, so each group is a slice; the compiled loop of each
    group writes straight into its slice of one output block. A spot group's casters are
    selected per light first (:func:`spot_selection`: triangles clipped to each cone's
    square pyramid). A light whose fit fails is reported and gets ``report``'s matrices.
    """
    lights = np.flatnonzero((~atlas.light_cube) & (atlas.light_size > 0))
    if lights.size == 0:
        return []
    data, verts, tris, R, n, f = inputs
    code = (kinds[lights] << 40) | (atlas.light_size[lights] << 16) | atlas.light_border[lights]
    order = np.argsort(code, kind="stable")
    lights, code = lights[order], code[order]
    starts = [0, *(np.flatnonzero(code[1:] != code[:-1]) + 1).tolist()]
    ends = [*starts[1:], lights.size]
    rows = report.api
    light_rows = data[lights]
    positions = light_rows[:, :3] if ctx.is_jax else np.ascontiguousarray(light_rows[:, :3])
    per_light = verts[lights] if verts.ndim == 3 else None
    near_all = None if n is None else pick(ctx, n, lights)
    far_all = None if f is None else pick(ctx, f, lights)
    compiled = form(not ctx.is_jax) == "compiled"
    block = _Block(ctx, lights.size) if compiled else None
    out = []
    for start, end, c in zip(starts, ends, code[starts].tolist(), strict=True):
        kind, size, border = c >> 40, (c >> 16) & 0xFFFFFF, c & 0xFFFF
        sun = kind == SUN
        given = (not sun and n is not None, not sun and f is not None)
        key = _group_key((kind, size, border), rows, _receiver_flags(R), given)
        part = slice(start, end)
        group = verts if per_light is None else per_light[part]
        if kind == SPOT:
            casters = group if tris is None else tris if tris.ndim == 3 else tris[lights[part]]
            selected = spot_selection(
                ctx, light_rows[part], None, None, casters, triangles=tris is not None
            )
            group = selected.points
        a = Inputs(
            light_rows[part] if kind == SPOT else positions[part], group, None, R, None,
            None if near_all is None or sun else near_all[part],
            None if far_all is None or sun else far_all[part],
        )  # fmt: skip
        if block is not None:
            block.run(key, a, part, lights, report)
        else:
            values = _run_arrays(ctx, key, a, lights[part], report)
            out.append((atlas.light_tiles[lights[part], 0], *values))
    if block is not None:
        mats, frusta = block.mats, block.out
        m, near = FIT_MATRIX, FIT_ROW_AT.frustum + 2  # the frustum's near, then far
        clip, tex = mats[:, m.blocker_to_clip], mats[:, m.world_to_texture]
        return [(atlas.light_tiles[lights, 0], clip, tex, frusta[:, near], frusta[:, near + 1])]
    return out


class _Block:
    """The compiled loop's output for every 2D light, filled group by group."""

    def __init__(self, ctx: Context, count: int) -> None:
        self.ctx = ctx
        self.out = np.empty((count, _compiled.ROW), dtype=ctx.dtype)
        self.mats = np.empty((count, 4, 4, 4), dtype=ctx.dtype)
        self.status = np.empty(count, dtype=np.int32)

    def run(self, key: FitKey, a: Inputs, part: slice, lights: Ints, report: Report) -> None:
        count = part.stop - part.start
        status = self.status[part]
        operands = _compiled.operands((count,), a)
        options, _ = _compiled.options(key, self.ctx.dtype)
        _kernels.loops().fit_loop(operands, options, (self.out[part], self.mats[part], status))
        errors = failures(status)
        if errors.any():
            messages = failure_messages(a.verts)
            for i in np.flatnonzero(errors).tolist():
                report.fail(int(lights[part][i]), first_failure(int(errors[i]), messages))
            failed = errors != 0
            mats, out, m = self.mats[part], self.out[part], FIT_MATRIX
            mats[failed, m.blocker_to_clip], mats[failed, m.world_to_texture] = (
                report.clip,
                report.tex,
            )
            near = FIT_ROW_AT.frustum + 2  # the frustum's near, then far
            out[failed, near : near + 2] = 0.0


def _receiver_flags(R: Array | None) -> tuple[bool, bool]:
    """Whether there are receivers, and whether they are triangles (rows of 9)."""
    return R is not None, R is not None and R.shape[-1] == 9


@functools.lru_cache(maxsize=256)
def _group_key(
    group: tuple[int, int, int], rows: Any, receivers: tuple[bool, bool], given: tuple[bool, bool]
) -> FitKey:
    """The fit's key of a group ``(kind, size, border)`` of lights."""
    kind, size, border = group
    margins = border_margin(size, border_texels=border)
    return FitKey(kind == SUN, kind == SPOT, False, False, margins, (size, size), rows,
                  False, receivers[0], False, *given, triangles=receivers[1])  # fmt: skip


def _run_arrays(
    ctx: Context, key: FitKey, a: Inputs, idx: Ints, report: Report
) -> tuple[Array, ...]:
    """``world_to_clip``, the tile's ``world_to_texture``, near and far of one group, on
    whole arrays (JAX, or NumPy without the compiled loops)."""
    count = idx.size
    if ctx.xp is np and count <= _SCALAR_GROUP:
        return _run_scalars(ctx, key, a, idx, report)
    checks = Checks(ctx, mode="record")
    with np.errstate(all="ignore"):
        e = fit_arrays(ctx, checks, key, a, driver(ctx, scalar=False))
    xp = ctx.xp
    clip, tex = (stack_matrix(xp, tuple(xp.broadcast_to(v, (count,)) for v in m))
                 for m in (e.clip, e.tex))  # fmt: skip
    lo, hi = (xp.broadcast_to(v, (count,)) for v in (e.box[2], e.box[3]))
    failed = np.zeros(count, dtype=bool)
    for message, bad in checks.recorded:  # in report order: the first failure is kept
        bad_np = np.broadcast_to(np.asarray(bad), (count,))
        for i in np.flatnonzero(bad_np).tolist():
            report.fail(int(idx[i]), message)
        failed |= bad_np
    return report.replace(ctx, failed, (clip, tex, lo, hi))


#: NumPy without the compiled loops fits groups of at most this many lights one light at a
#: time on Python floats (as fit_shadow does one light): the array driver's hundreds of
#: NumPy calls cost more than that below it.
_SCALAR_GROUP = 8


def _run_scalars(
    ctx: Context, key: FitKey, a: Inputs, idx: Ints, report: Report
) -> tuple[Array, ...]:
    """:func:`_run_arrays` one light at a time with the per-entry steps on Python floats."""
    d = driver(ctx, scalar=True)
    mats, depth = [], []
    for i, light in enumerate(idx.tolist()):
        one = Inputs(
            a.light[i], a.verts if a.verts.ndim == 2 else a.verts[i], None, a.R, None,
            None if a.near is None else a.near[i], None if a.far is None else a.far[i],
        )  # fmt: skip
        try:
            with np.errstate(all="ignore"):
                e = fit_arrays(ctx, Checks(ctx), key, one, d)
        except ValueError as err:
            report.fail(light, str(err))
            mats.append((*report.clip.reshape(16).tolist(), *report.tex.reshape(16).tolist()))
            depth.append((0.0, 0.0))
            continue
        mats.append((*e.clip, *e.tex))
        depth.append((e.box[2], e.box[3]))
    m = np.array(mats, dtype=ctx.dtype).reshape(-1, 2, 4, 4)
    z = np.array(depth, dtype=ctx.dtype)
    return m[:, 0], m[:, 1], z[:, 0], z[:, 1]
