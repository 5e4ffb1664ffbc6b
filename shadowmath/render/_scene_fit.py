"""The renderer as a client of :class:`shadowmath.ShadowScene` (the passes' ``scene_fit``):
the bodies as a scene (:func:`body_scene`)."""

from __future__ import annotations

from collections.abc import Sequence
from typing import Literal

import shadowmath as sm

from ._resources import Prepared

#: Where a pass's fit and each map's draws come from (``scene_fit``): None, the pass's own
#: fit (every caster's triangles, the scene's bounds) and every caster in every map;
#: ``"draw_lists"``, a :class:`shadowmath.ShadowScene` of the bodies and each map's draw
#: list; ``"every_caster"``, that scene's fit with every caster in every map.
SceneFit = Literal["draw_lists", "every_caster"] | None


def body_scene(prepared: Sequence[Prepared], cast: Sequence[bool]) -> sm.ShadowScene:
    """A :class:`shadowmath.ShadowScene` of the bodies, object ``i`` body ``i``: its mesh in
    local coordinates placed by its ``to_world``, casting per ``cast``, every body
    receiving."""
    scene = sm.ShadowScene()
    for body, casts in zip(prepared, cast, strict=True):
        geometry = scene.add_geometry(sm.Mesh(body.vertices, body.triangles))
        scene.add_objects(geometry, body.to_world, casts=bool(casts))
    return scene


def scene_fit_option(scene_fit: object) -> SceneFit:
    """A pass's ``scene_fit`` option, checked: None, ``"draw_lists"`` or ``"every_caster"``."""
    if scene_fit is None or scene_fit == "draw_lists" or scene_fit == "every_caster":
        return scene_fit
    raise ValueError(f"scene_fit: expected None, 'draw_lists' or 'every_caster', got {scene_fit!r}")
