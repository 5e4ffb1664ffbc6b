"""fit_scene_shadows' rules, each on a small scene measured without shadowmath's fit: the
receivers' depth is held, a light whose target is its own position aims where pygfx
lights, and the map's border is the bilinear kernel's.

One box (casts, receives) above a floor (receives only): every floor point the map
covers must have a stored depth in ``[0, 1]`` (else the floor is clipped and no shadow
falls on it), the shadow camera must look the way pygfx lights (its ``direction``
uniform), and every caster's texel must lie at least ``pcf_border_texels(2,
"bilinear")`` texels inside the map (pygfx's PCF reads 5 x 5 bilinear taps, 3 texels
from the centre).
"""

from __future__ import annotations

from typing import Any

import numpy as np
import pytest

import shadowmath as sm
from shadowmath.meshes import box, grid

from .test_pygfx import flat_mesh, gfx  # noqa: F401  (the fixture, used by name)


def _scene(gfx: Any, light: Any) -> tuple[Any, np.ndarray, np.ndarray]:  # noqa: F811
    """A scene of a unit box (its base at z = 1) over a 12 x 12 floor at z = 0 lit by
    ``light``; the box's and the floor's world points (a dense grid for the floor)."""
    scene = gfx.Scene()
    cube = box((1.0, 1.0, 1.0))
    caster = flat_mesh(cube.vertices, cube.faces, cast=True)
    caster.local.position = (0.3, -0.2, 1.5)
    floor = grid((12.0, 12.0), segments=(2, 2))
    scene.add(caster, flat_mesh(floor.vertices, floor.faces, cast=False), light)
    if hasattr(light, "target"):
        scene.add(light.target)
    corners = cube.vertices + np.array([0.3, -0.2, 1.5])
    u = np.linspace(-6.0, 6.0, 121)
    ground = np.stack(np.meshgrid(u, u, [0.0], indexing="ij"), axis=-1).reshape(-1, 3)
    return scene, corners, ground


def _texture(setup: sm.ShadowSetup, points: np.ndarray) -> np.ndarray:
    """``(s, t, r)`` of world points (``world_to_texture``, divided by ``q``)."""
    h = np.c_[points, np.ones(len(points))] @ np.asarray(setup.world_to_texture).T
    return h[:, :3] / h[:, 3:]


def _fitted(gfx: Any, light: Any) -> tuple[Any, np.ndarray, np.ndarray]:  # noqa: F811
    from shadowmath.integrations.pygfx import fit_scene_shadows

    scene, corners, ground = _scene(gfx, light)
    (report,) = fit_scene_shadows(scene)
    assert report.skipped == "" and report.fit is not None
    return report.fit, corners, ground


@pytest.mark.parametrize("kind", ["directional", "spot"])
def test_the_floor_the_map_covers_lies_in_its_depth_range(gfx: Any, kind: str) -> None:  # noqa: F811
    # The floor only receives: dropped from the fit, the depth range would end just past
    # the box, and the floor under the box (farther from the light) would be clipped.
    light = gfx.DirectionalLight(cast_shadow=True) if kind == "directional" else (
        gfx.SpotLight(angle=0.9, cast_shadow=True)
    )  # fmt: skip
    light.local.position = (1.0, 0.5, 6.0)
    fit, _, ground = _fitted(gfx, light)
    str_ = _texture(fit, ground)
    covered = np.all((str_[:, :2] >= 0) & (str_[:, :2] <= 1), axis=1)
    if kind == "spot":  # in front of the light only (the perspective divide)
        covered &= (np.c_[ground, np.ones(len(ground))] @ np.asarray(fit.world_to_texture)[3]) > 0
    assert covered.sum() > 100  # the shadow's part of the floor, at least
    depth = str_[covered, 2]
    assert np.all((depth >= 0) & (depth <= 1)), (depth.min(), depth.max())


@pytest.mark.parametrize("kind", ["directional", "spot"])
def test_a_light_aimed_at_its_own_position_is_fitted_the_way_pygfx_lights(
    gfx: Any,  # noqa: F811
    kind: str,
) -> None:
    # pygfx lights down -z when the target is the light's position: the shadow camera
    # looks that way too (the light's direction uniform), and the box below is in its map.
    light = gfx.DirectionalLight(cast_shadow=True) if kind == "directional" else (
        gfx.SpotLight(angle=0.9, cast_shadow=True)
    )  # fmt: skip
    light.local.position = (0.3, -0.2, 6.0)
    light.target.local.position = (0.3, -0.2, 6.0)
    fit, corners, _ = _fitted(gfx, light)
    light._gfx_update_uniform_buffer()
    lit_along = np.asarray(light.uniform_buffer.data["direction"][:3], dtype=np.float64)
    np.testing.assert_allclose(lit_along, [0.0, 0.0, -1.0], atol=1e-6)  # pygfx's rule
    np.testing.assert_allclose(np.asarray(fit.frame.z_axis), lit_along, atol=1e-6)
    st = _texture(fit, corners)
    assert np.all((st >= 0) & (st <= 1))


@pytest.mark.parametrize("kind", ["directional", "spot"])
def test_every_caster_lies_the_bilinear_kernels_reach_inside_the_map(
    gfx: Any,  # noqa: F811
    kind: str,
) -> None:
    # pygfx filters with 5 x 5 bilinear taps: a caster's texel centre 2 texels from a tap's
    # centre, the tap reads one texel farther: 3 texels (pcf_border_texels(2, "bilinear")),
    # where the box filter's border would be 2.
    from shadowmath.integrations.pygfx import PYGFX_SHADOW_MAP_SIZE

    light = gfx.DirectionalLight(cast_shadow=True) if kind == "directional" else (
        gfx.SpotLight(angle=0.9, cast_shadow=True)
    )  # fmt: skip
    light.local.position = (2.0, 1.0, 6.0)
    fit, corners, _ = _fitted(gfx, light)
    n = PYGFX_SHADOW_MAP_SIZE
    border = sm.pcf_border_texels(2, "bilinear")
    assert border == 3
    texels = _texture(fit, corners)[:, :2] * n
    gap = np.minimum(texels, n - texels).min()
    assert gap == pytest.approx(border, abs=1e-6 * n)  # held, and the fit is tight
