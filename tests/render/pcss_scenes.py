"""PCSS against the true soft shadow: scenes, the area light's visible fraction by ray
casting, and the statistics the tests and docs/pcss.md compare.

Scenes are seen from straight above through an orthographic camera, so the pixels are a
regular grid of floor points. Lights are what PCSS models: a point or spot light of
radius ``R`` is a disk of that radius facing the map's axis (the light frame's ``Z``);
a sun of angular radius ``theta`` is the cone of directions whose tangent-plane disk has
radius ``tan(theta)``. The truth casts one segment (a ray for the sun) from each floor
point to each of ``TRUTH_SAMPLES`` points of a Vogel spiral on that disk
(:func:`shadowmath.groundtruth.segment_hits_triangles`); its error is at most about one
sample's share per pixel, ``1/256``, smaller on average.
"""

from __future__ import annotations

import functools
from typing import NamedTuple

import numpy as np

import shadowmath as sm
from shadowmath.groundtruth import segment_hits_triangles
from shadowmath.meshes import box, grid
from shadowmath.render import Body, Frame, Light, render_scene

from .scenes import place, world_mesh

TRUTH_SAMPLES = 256
MAP = 512


class View(NamedTuple):
    """An orthographic camera straight down onto the floor's square of half-side
    ``half`` about ``(x, y)``, ``pixels`` square: pixel ``(row, col)`` shows the floor
    point ``x - half + (col + 1/2) step``, ``y + half - (row + 1/2) step``."""

    x: float
    y: float
    half: float
    pixels: int

    @property
    def step(self) -> float:
        """Floor units per pixel."""
        return 2 * self.half / self.pixels

    def world_to_clip(self) -> np.ndarray:
        """Depth ``z = 10`` to the near plane, ``z = -1`` to the far one."""
        s = 1.0 / self.half
        return np.array(
            [[s, 0, 0, -s * self.x], [0, s, 0, -s * self.y], [0, 0, -2 / 11, 9 / 11], [0, 0, 0, 1]]
        )

    def floor_points(self) -> np.ndarray:
        """``(pixels, pixels, 3)`` the floor point at each pixel's centre."""
        c = (np.arange(self.pixels) + 0.5) * self.step - self.half
        x, y = np.meshgrid(self.x + c, self.y - c)
        return np.stack([x, y, np.zeros_like(x)], axis=-1)


#: The whole scene (``top``); the box's corner ``(0, 0.2)`` where the shadow's edge
#: leaves its foot (``contact``: a pixel about two thirds of a texel of the suns' 512 maps).
VIEWS = {"top": View(0.0, 0.0, 3.0, 160), "contact": View(0.08, 0.1, 0.1, 96)}

FLOOR = Body(*grid((10.0, 10.0)), plane=(0.0, 0.0, 1.0, 0.0))
#: A unit cube on the floor (contact shadows) and a tall thin pillar (wide penumbrae).
CASTERS = {
    "box": Body(*box((1.0, 1.0, 1.0)), to_world=place(translation=(-0.5, -0.3, 0.5))),
    "pillar": Body(*box((0.4, 0.4, 2.5)), to_world=place(translation=(-1.0, -0.6, 1.25))),
}
#: The box's face ``x = 0`` at the ``contact`` view.
BOX_FACE_X = 0.0
PLATE_CENTRE = np.array([0.3, -0.2, 1.2])
#: A thin horizontal 1 x 1 slab at ``PLATE_CENTRE``: a flat blocker parallel to the
#: ``-Z`` face of a point light's cube map above it (PCSS's exact case there).
CASTERS["slab"] = Body(*box((1.0, 1.0, 0.01)), to_world=place(translation=PLATE_CENTRE))
#: A long thin bar at height 0.7 whose shadow under ``SEAM_LIGHT`` runs along ``x``
#: across the floor line ``x = 1.5`` where the light's cube turns from its ``-Z`` face to
#: its ``+X`` face (tests/render/test_render_pcss_seams.py).
CASTERS["bar"] = Body(*box((2.0, 0.3, 0.02)), to_world=place(translation=(1.5, 0.3, 0.7)))


class LightCase(NamedTuple):
    """A light of a size: ``kind`` is ``"spot"``, ``"point"`` or ``"sun"``; ``where``
    its position (spot, point) or direction toward it (sun); ``size`` its radius or its
    angular radius in radians."""

    kind: str
    where: tuple[float, float, float]
    size: float


LIGHTS = {
    "spot": LightCase("spot", (1.2, 0.8, 5.0), 0.3),
    "point": LightCase("point", (-1.6, 1.4, 4.5), 0.25),
    **{
        f"sun {deg}°": LightCase("sun", (-0.45, 0.3, 1.0), float(np.radians(deg)))
        for deg in (0.5, 2.0, 5.0)
    },
}


#: A point light 1.5 above the floor's origin, radius 0.25 (the ``bar``'s seam scene).
SEAM_LIGHT = LightCase("point", (0.0, 0.0, 1.5), 0.25)


def light_axis(case: LightCase) -> np.ndarray:
    """The unit axis of the light's map toward the scene: the sun's direction away from
    it, a spot's aim (the origin), a point light's direction to the plate's centre."""
    where = np.asarray(case.where, float)
    axis = {"sun": -where, "spot": -where, "point": PLATE_CENTRE - where}[case.kind]
    return axis / np.linalg.norm(axis)


def caster(scene: str, light: str) -> Body:
    """``CASTERS[scene]``, or for ``"plate"`` a thin 1 x 1 slab centred at
    ``PLATE_CENTRE`` facing the light's axis: a flat blocker parallel to the light's
    plane, where PCSS is exact but for its sampling."""
    if scene != "plate":
        return CASTERS[scene]
    z = light_axis(LIGHTS[light])
    x = np.cross([0.0, 1.0, 0.0], z)
    x /= np.linalg.norm(x)
    frame = np.stack([x, np.cross(z, x), z], axis=1)
    return Body(*box((1.0, 1.0, 0.01)), to_world=place(frame, PLATE_CENTRE))


def spot_light(case: LightCase) -> sm.SpotLight:
    """A spot light at ``case.where`` aimed at the origin, a 35° half-angle."""
    position = np.asarray(case.where, float)
    return sm.SpotLight(position, -position, np.radians(35.0))


def render(
    scene: str,
    light: str,
    *,
    view: str = "top",
    light_size: float | None = None,
    map_size: int = MAP,
    ctx=None,
) -> Frame:
    """The PCSS render of a scene under a light (``light_size`` overrides the light's)."""
    case = LIGHTS[light]
    body = caster(scene, light)
    size = case.size if light_size is None else light_size
    lamp = Light(direction=case.where) if case.kind == "sun" else Light(case.where)
    setups = None
    if case.kind == "spot":  # as a renderer fits a spot: refit with the kernel's border
        v, _ = world_mesh(body)
        corners = sm.Triangles(np.concatenate([w[t] for w, t in map(world_mesh, (FLOOR, body))]))
        fit = sm.fit_shadow(spot_light(case), v, map_size, receivers=corners)
        p = sm.pcss_parameters(fit, light_radius=size, map_size=map_size)
        border = sm.pcss_border_texels(p)
        setups = [
            [sm.fit_shadow(spot_light(case), v, map_size, receivers=corners, border_texels=border)]
        ]
    return render_scene(
        [FLOOR], [body], [lamp], VIEWS[view].world_to_clip(), image_size=VIEWS[view].pixels,
        map_size=map_size,
        method="pcss", light_size=size, setups=setups, ctx=ctx,
    )  # fmt: skip


def disk_samples(count: int) -> np.ndarray:
    """``(count, 2)`` a Vogel spiral on the unit disk (equal areas, stratified)."""
    i = np.arange(count) + 0.5
    r, a = np.sqrt(i / count), i * np.pi * (3 - np.sqrt(5))
    return np.stack([r * np.cos(a), r * np.sin(a)], axis=-1)


def true_visibility(
    points: np.ndarray, scene: str, light: str | LightCase, axis: np.ndarray
) -> np.ndarray:
    """``(P,)`` the fraction of the light's disk (a point or spot light's, facing
    ``axis``; a sun's, in the tangent plane of its direction) each floor point sees
    (``light`` a name of ``LIGHTS`` or a light of its own)."""
    case = LIGHTS[light] if isinstance(light, str) else light
    v, t = world_mesh(CASTERS[scene] if isinstance(light, LightCase) else caster(scene, light))
    centre = np.asarray(case.where, float)
    if case.kind == "sun":
        centre = centre / np.linalg.norm(centre)
        axis = centre
    e1 = np.cross(axis, [0.0, 0.0, 1.0] if abs(axis[2]) < 0.9 else [1.0, 0.0, 0.0])
    e1 /= np.linalg.norm(e1)
    e2 = np.cross(axis, e1)
    radius = np.tan(case.size) if case.kind == "sun" else case.size
    hidden = np.zeros(len(points))
    for u, w in disk_samples(TRUTH_SAMPLES) * radius:
        q = centre + u * e1 + w * e2
        light_at = np.append(q, 0.0) if case.kind == "sun" else q
        hidden += segment_hits_triangles(points, light_at, v, t)
    result: np.ndarray = 1.0 - hidden / TRUTH_SAMPLES
    return result


class Comparison(NamedTuple):
    """PCSS against the truth on the floor's pixels."""

    floor: np.ndarray  # (H, W) the floor is the visible surface
    pcss: np.ndarray  # (H, W) PCSS's visible fraction of the light
    truth: np.ndarray  # (H, W) the true visible fraction (1 off the floor)


@functools.cache
def truth_image(scene: str, light: str, view: str, axis: tuple[float, float, float]) -> np.ndarray:
    """The true visibility of the floor point of every pixel (cached: the renders of the
    same scene, light and view share it)."""
    points = VIEWS[view].floor_points()
    flat = true_visibility(points.reshape(-1, 3), scene, light, np.array(axis))
    return flat.reshape(points.shape[:2])


def compare(frame: Frame, scene: str, light: str, view: str = "top") -> Comparison:
    floor = frame.body == 0
    axis = np.asarray(frame.setups[0][0].frame.z_axis, float)
    truth = truth_image(scene, light, view, tuple(float(a) for a in axis))
    pcss = 1.0 - frame.shadow[..., 0].astype(np.float64)
    return Comparison(floor, pcss, np.where(floor, truth, 1.0))


class Errors(NamedTuple):
    """Visibility errors over the shadow's region: the floor pixels where PCSS or the
    truth sees less than the whole light."""

    mean: float
    p90: float
    pixels: int


def errors(c: Comparison) -> Errors:
    region = c.floor & ((c.pcss < 1.0) | (c.truth < 1.0))
    e = np.abs(c.pcss - c.truth)[region]
    return Errors(float(e.mean()), float(np.percentile(e, 90)), int(region.sum()))


def penumbra_area(visibility: np.ndarray, floor: np.ndarray, view: str = "top") -> float:
    """The floor area (units²) where ``0.1 < visibility < 0.9``: the penumbra's width
    times its edges' length."""
    return float((floor & (visibility > 0.1) & (visibility < 0.9)).sum()) * VIEWS[view].step ** 2


def scaled_size(light: str, factor: float) -> float:
    """The light's size whose ``k`` is ``factor`` times the true one's: the radius times
    ``factor``, a sun's ``atan(factor tan(theta))``."""
    case = LIGHTS[light]
    if case.kind == "sun":
        return float(np.arctan(factor * np.tan(case.size)))
    return factor * case.size


def width_ratio(c: Comparison, view: str = "top") -> float:
    """PCSS's penumbra area over the truth's: their mean widths' ratio along the same edges."""
    return penumbra_area(c.pcss, c.floor, view) / penumbra_area(c.truth, c.floor, view)


def figures(ctx=None) -> list[str]:
    """The table of docs/pcss.md: per scene and light, the mean and 90th-percentile
    visibility errors and the penumbra width ratio (``python -m tests.render.pcss_scenes``)."""
    rows = ["| caster | light | size | mean error | p90 error | width PCSS / truth |"]
    rows.append("|---|---|---|---|---|---|")
    for scene in ("plate", "box", "pillar"):
        for light, case in LIGHTS.items():
            c = compare(render(scene, light, ctx=ctx), scene, light)
            e = errors(c)
            size = f"{np.degrees(case.size):.1f}°" if case.kind == "sun" else f"R = {case.size}"
            rows.append(
                f"| {scene} | {case.kind} | {size} | {e.mean:.4f} | {e.p90:.4f} "
                f"| {width_ratio(c):.2f} |"
            )
    return rows


if __name__ == "__main__":
    print("\n".join(figures()))
