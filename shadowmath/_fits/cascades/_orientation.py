r"""A tight cascade's map turned about the light's axis to enclose its body in the least area.

``fit_cascades(..., orientation="fitted")``: the light frame's ``X`` and ``Y`` (Nagy's helper
axis or ``up``) are turned about ``Z`` per cascade by the angle of the minimum-area rectangle
(:func:`shadowmath._math._enclosing_rectangle.min_area_rectangle`) enclosing the light-space
projection of the cascade's slice intersected with the scene box (the vertices of
:func:`._cascade_bounds.cascade_body`: the clipped ends of its 24 edges). With
``(c, s)`` the turn (``|θ| <= 45°``)

.. math:: X' = c X + s Y, \qquad Y' = -s X + c Y, \qquad Z' = Z,

and the map's box is the rectangle's bounds, its depth range the unturned one's (a turn
about ``Z`` keeps ``z``). The texels keep their shape (a rotation, not a shear) and their
count, and cover at most the axis-aligned map's area. Trusted inputs only: nothing here
raises except :func:`check_orientation`, on the options.
"""

from __future__ import annotations

from typing import Any

from shadowmath._math._enclosing_rectangle import min_area_rectangle

__all__ = ["check_orientation", "fitted_cascade"]


def check_orientation(orientation: object, stable: bool, warp: object) -> bool:
    """Whether ``orientation`` is ``"fitted"``; refuses an unknown name, and ``"fitted"``
    with ``stable=True`` or a warp."""
    if orientation not in ("light", "fitted"):
        raise ValueError(f"orientation: expected 'light' or 'fitted', got {orientation!r}")
    if orientation == "fitted" and stable:
        raise ValueError(
            "orientation: 'fitted' cannot be combined with stable=True: the turn follows "
            "the camera, so the texel grid cannot stay anchored (use orientation='light')"
        )
    if orientation == "fitted" and warp is not None:
        raise ValueError(
            "orientation: 'fitted' cannot be combined with a warp: the warp sets the map's "
            "own axes (use orientation='light' with warp, or warp=None)"
        )
    return orientation == "fitted"


def fitted_cascade(xp: Any, F: Any, steps: tuple[Any, Any, Any, Any], row: list[Any]) -> None:
    """The array mode's cascade fit (in place of ``cascade_fit``) with each map turned to
    its body's minimum-area rectangle. ``steps = (e, sl, j, o)``: the entry, the slices,
    the cascades' indices and the options; ``row``: the cascades' rows (parts at
    ``ROW_AT``)."""
    e, sl, j, o = steps
    a = e.camera.axes
    body = F.cascade_body(
        sl.light_corners, sl.box_values, (e.box_light, e.box_camera), (sl.s0, sl.s1)
    )
    b = F.body_bounds(body)
    ends, ok, corners, _ = body
    seen = xp.any(ok, axis=-1, keepdims=True)  # else the slice's own corners, as body_bounds
    x = xp.concat([ends[0], xp.broadcast_to(corners[0], (*ok.shape[:-1], 8))], axis=-1)
    y = xp.concat([ends[1], xp.broadcast_to(corners[1], (*ok.shape[:-1], 8))], axis=-1)
    use = xp.concat([ok, xp.broadcast_to(~seen, (*ok.shape[:-1], 8))], axis=-1)
    r = min_area_rectangle(xp, x, y, use)
    F.store_turned(a, r, b, (sl, j, o), row)
