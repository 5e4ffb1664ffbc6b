"""A fit prepared once and run every frame: :class:`ShadowFitter`.

A renderer fits the same light against the same kind of scene every frame: the
light's kind, the map's spec, and the operands' shapes and dtype do not change.
:class:`ShadowFitter` reads and checks them once through :func:`fit_shadow`'s door;
each :meth:`ShadowFitter.fit` then checks only that the arrays are the prepared
ones (type, shape, dtype: a few attribute reads) before it runs the one driver of the
fit into buffers that the caller owns. Values are still checked every frame (the
fit's status): a NaN or a light inside the casters raises as :func:`fit_shadow` does.
"""

from __future__ import annotations

from typing import Any, NamedTuple

import numpy as np

from shadowmath._backends import _kernels
from shadowmath._boundary._validate import Array
from shadowmath._fits._spec import ShadowMapSpec, map_spec

from . import _compiled
from ._compiled import Buffers
from ._door import Door, Operands, PreparedDoor, _check_static, open_door, select_casters, signature
from ._driver import _fit

__all__ = ["PreparedFit", "ShadowFitter"]


class PreparedFit(NamedTuple):
    """One frame's fit: views of the fitter's buffers (valid until the next fit into them).

    Attributes:
        world_to_texture: ``(*batch, 4, 4)`` (see :class:`ShadowSetup`).
        blocker_to_clip: ``(*batch, 4, 4)``.
        world_to_light: ``(*batch, 4, 4)``.
        casters_used: ``(*batch)`` casters the fit used (a spot light's are clipped to
            its cone).
        buffers: the buffers written (rows of frame and frustum fields, the matrices,
            the status words); :meth:`ShadowFitter.setup` reads the whole
            :class:`ShadowSetup` from them when asked.
    """

    world_to_texture: Array
    blocker_to_clip: Array
    world_to_light: Array
    casters_used: Array
    buffers: Buffers


class ShadowFitter:
    """:func:`fit_shadow` prepared once for one light kind, map and set of operand shapes.

    ``ShadowFitter(light, blocker_vertices, map_size, **options)`` takes the arguments
    of :func:`fit_shadow` (NumPy arrays; ``method="mdv"``), checks them once, and keeps
    what does not change from frame to frame: the light's type, the static key of the
    fit (the spec, the options, which operands are given), the arrays' shapes and dtype.
    ``fitter.fit(light, blocker_vertices, ...)`` then fits new values of the same
    shapes into buffers the caller may own (``out=fitter.buffers()``), and returns the
    matrices a renderer uploads as views of them.

    A call whose arrays differ from the prepared ones (another type, shape or dtype,
    a list, an operand given or left out) goes through :func:`fit_shadow`'s full door
    instead, and must still be the prepared fit: otherwise ``ValueError`` says what
    changed. Without Numba (the ``fast`` extra) the same fit runs on arrays and is
    copied into the buffers. JAX input is refused: use ``jax.jit`` around
    :func:`fit_shadow`, which is prepared per static key already.

    Raises:
        ValueError, TypeError: what :func:`fit_shadow` raises for the example; a later
            call whose arrays are not of the prepared kind.

    Example:
        >>> import numpy as np
        >>> box = np.array([[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (4, 6)], float)
        >>> fitter = ShadowFitter(PointLight(np.zeros(3)), box, 256)
        >>> out = fitter.buffers()
        >>> frame = fitter.fit(PointLight(np.array([0.0, 0.5, 0.0])), box, out=out)
        >>> expected = fit_shadow(PointLight(np.array([0.0, 0.5, 0.0])), box, 256)
        >>> bool(np.allclose(frame.world_to_texture, expected.world_to_texture))
        True
    """

    def __init__(
        self,
        light: Any,
        blocker_vertices: Any,
        map_size: int | tuple[int, int] | ShadowMapSpec,
        *,
        blocker_to_world: Any = None,
        receivers: Any = None,
        up: Any = None,
        near: Any = None,
        far: Any = None,
        aim: str = "mean",
        **options: Any,
    ) -> None:
        self._spec = map_spec(map_size, **options)
        self._aim_bbox = aim == "bbox"
        g = Operands(light, blocker_vertices, blocker_to_world, receivers, up, near, far)
        door = open_door(g, self._spec, self._aim_bbox)
        _check_static(door.key, "mdv", self._spec)
        if door.ctx.is_jax:
            raise TypeError(
                "ShadowFitter prepares NumPy fits; under JAX, jax.jit(fit_shadow) is "
                "prepared per static key already"
            )
        self._door = PreparedDoor.of(door, signature(g))  # no arrays kept
        self._views: tuple[Any, ...] = ()
        self._record = _compiled.options(door.key, door.ctx.dtype)[0]
        self._count = int(np.prod(door.shape, dtype=np.int64))

    def buffers(self) -> Buffers:
        """Empty output buffers for one fit (allocate once, fit into them every frame)."""
        return _compiled.buffers(self._count, self._door.ctx.dtype)

    def fit(
        self,
        light: Any,
        blocker_vertices: Any,
        *,
        blocker_to_world: Any = None,
        receivers: Any = None,
        up: Any = None,
        near: Any = None,
        far: Any = None,
        out: Buffers | None = None,
    ) -> PreparedFit:
        """This frame's fit of the prepared kind (see the class): views of ``out``."""
        g = Operands(light, blocker_vertices, blocker_to_world, receivers, up, near, far)
        prepared, door = self._door, None
        if prepared.signature is not None and signature(g) == prepared.signature:
            door = prepared.reopen(g)
        if door is None:
            door = self._checked_door(g)
        a, used = select_casters(door)
        out = self.buffers() if out is None else out
        if _kernels.available():
            _compiled.run(door.ctx, door.key, door.shape, a, out, record=self._record)
        else:
            _copy(_fit(door.ctx, a, door.shape, door.key, "mdv", used=used), out, self._count)
        views = self._views
        if not views or views[0] is not out:  # the matrices' views of these buffers, once
            M, shape = out.mats, (*self._door.shape, 4, 4)
            views = (out, *(M[:, k].reshape(shape) for k in (2, 1, 0)))
            self._views = views
        return PreparedFit(views[1], views[2], views[3], used, out)

    def setup(self, frame: PreparedFit) -> Any:
        """The whole :class:`ShadowSetup` of a :meth:`fit` (frame, frustum, every matrix)."""
        key, shape = self._door.key, self._door.shape
        return _compiled.views(key, shape, frame.buffers, frame.casters_used)

    def _checked_door(self, g: Operands) -> Door:
        door = open_door(g, self._spec, self._aim_bbox)
        if door.key != self._door.key or door.shape != self._door.shape or (
            door.ctx.dtype != self._door.ctx.dtype
        ):  # fmt: skip
            raise ValueError(
                "ShadowFitter.fit: the arguments are not the prepared fit's (another light "
                "kind, operand given or left out, batch shape or dtype): prepare a new "
                "ShadowFitter for them"
            )
        return door


def _copy(setup: Any, out: Buffers, count: int) -> None:
    """A fit on arrays copied into the buffers (without Numba)."""
    out.mats[:, 0] = np.reshape(setup.world_to_light, (count, 4, 4))
    out.mats[:, 1] = np.reshape(setup.blocker_to_clip, (count, 4, 4))
    out.mats[:, 2] = np.reshape(setup.world_to_texture, (count, 4, 4))
    out.mats[:, 3] = np.reshape(setup.blocker_to_world, (count, 4, 4))
    f, fr = setup.frame, setup.frustum
    rows = [f.origin, f.x_axis, f.y_axis, f.z_axis]
    rows += [np.asarray(v)[..., None] for v in fr]  # a Frustum's or a box's 8 fields
    out.rows[:] = np.concatenate([np.reshape(r, (count, -1)) for r in rows], axis=-1)
    out.status[:] = 0
