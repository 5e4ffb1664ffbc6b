"""Cascaded shadow maps (render_cascades, fit_cascades) against the ray caster.

A 200 x 200 ground of two triangles with boxes and towers spread over it, under a low
sun; every body casts and receives. The camera view with cascades may differ from the
ray caster only in the band of BAND pixels around the edges of the shadow and of the lit
region (as for method="depth"), and nowhere off it: across a camera near the ground
looking to the horizon, a camera looking down, one looking across from above, and a
tower behind the camera whose shadow reaches into the view; tight, stable and
LiSPSM-warped cascades. The test can fail: with scene bounds that leave out that tower,
its shadow is lost; without bias the faces shadow themselves; with wrong splits shadows
are lost. Each runs on OpenGL (render_cascades, cascades.frag) and on WebGPU
(render_cascades_wgpu, cascades.wgsl), and the two agree pixel for pixel.
"""

from __future__ import annotations

import functools

import numpy as np
import pytest

from shadowmath.meshes import box, grid
from shadowmath.render import Body, Light, look_at, perspective, render_cascades

from .depth_scenes import BAND, DepthScene, compare, ray_cast
from .rasterization import same_bodies_but_on_edges, same_map_elsewhere
from .scenes import place, rotation

SIZE = (320, 200)
MAP = 1024
NEAR, FAR = 0.5, 250.0
MAX_ALL = 0.01  # edges included, at most 1 % of the visible pixels differ

GROUND = Body(*grid((200.0, 200.0), segments=(1, 1)), color=(0.7, 0.75, 0.7))
#: (x, y, width, depth, height, turn in degrees) of the boxes and towers on the ground.
BLOCKS = [
    (-12.0, -70.0, 3.0, 3.0, 4.0, 20.0),
    (6.0, -62.0, 2.0, 5.0, 6.0, -10.0),
    (-4.0, -45.0, 6.0, 2.0, 3.0, 70.0),
    (14.0, -30.0, 4.0, 4.0, 12.0, 0.0),
    (-20.0, -15.0, 3.0, 3.0, 9.0, 15.0),
    (2.0, 5.0, 8.0, 3.0, 5.0, -25.0),
    (-30.0, 30.0, 5.0, 5.0, 12.0, 65.0),
    (25.0, 40.0, 4.0, 6.0, 10.0, 10.0),
    (-5.0, 70.0, 10.0, 4.0, 8.0, 5.0),
    (40.0, 85.0, 6.0, 6.0, 11.0, -30.0),
]
#: The caster behind the horizon camera, off the ground (out of its view), whose shadow
#: reaches into the view.
BEHIND = (90.0, -140.0, 6.0, 6.0, 75.0, 0.0)
SUN = Light(direction=(0.6, -0.6, 0.45))  # low, behind the camera's right: long shadows


def block(x, y, w, d, h, turn, color=(0.85, 0.55, 0.4)) -> Body:
    return Body(*box((w, d, h)), to_world=place(rotation((0, 0, 1), turn), (x, y, h / 2)),
                color=color)  # fmt: skip


BODIES = [GROUND, *(block(*b) for b in BLOCKS), block(*BEHIND, color=(0.5, 0.5, 0.9))]
CAMERAS = {
    # near the ground, looking along +y to the horizon
    "horizon": look_at((0.0, -90.0, 2.5), (0.0, 0.0, 2.0), (0, 0, 1)),
    # high above, looking down at the middle of the ground
    "down": look_at((-10.0, -60.0, 70.0), (0.0, 0.0, 0.0), (0, 0, 1)),
    # 40 above the ground's edge, looking at its middle (every cascade warped with LiSPSM)
    "oblique": look_at((0.0, -90.0, 40.0), (0.0, 0.0, 0.0), (0, 0, 1)),
}
#: A camera 15 m up looking 75 degrees down, heading 45 degrees across the sun (the kind of
#: pose where the warp's view-axis cap alone left it coarser than no warp, issue 27).
STEEP = look_at((0.0, -22.0, 15.0), (4.0, -22.0, 0.0), (0, 0, 1))
PROJECTION = perspective(45.0, SIZE[0] / SIZE[1], NEAR, FAR)


@pytest.fixture(params=["opengl", "webgpu"])
def render(request):
    """``render_cascades`` on the shared GL context, or ``render_cascades_wgpu``."""
    if request.param == "opengl":
        return functools.partial(render_cascades, ctx=request.getfixturevalue("gl"))
    request.getfixturevalue("wgpu_device")
    from shadowmath.render.webgpu import render_cascades_wgpu

    return render_cascades_wgpu


def shadows(camera, render=render_cascades, **kwargs):
    """Render the scene from ``camera`` (with ``render_cascades`` or ``render_cascades_wgpu``);
    the frame and its counts against the ray caster."""
    view = {**CAMERAS, "steep": STEEP}[camera]
    kwargs.setdefault("map_size", MAP)
    frame = render(BODIES, SUN, view, PROJECTION, image_size=SIZE, **kwargs)
    scene = DepthScene(BODIES, len(BODIES) - 1, SUN, PROJECTION @ view)
    truth = ray_cast(frame.body, frame.position, frame.normal, scene)
    # An edge just outside the picture leaves no change of value inside it to put a band
    # around: the BAND pixels along the picture's border count as band too.
    border = np.ones(truth.on.shape, dtype=bool)
    border[BAND:-BAND, BAND:-BAND] = False
    truth = truth._replace(band=truth.band | border)
    return frame, truth, compare(frame.shadow > 0.5, truth)


def reach_off_plane(frame, truth, view, pcf_radius: int = 0) -> np.ndarray:
    """Lit pixels whose lookup reaches texels where the map holds another surface than the
    pixel's own plane: there the derived bias guarantees nothing (it is derived for planar
    receivers, docs/depth-maps.md), and these pixels count as band.

    The shader compares the lifted point ``p + o`` (``sm.normal_offset``) with the texels
    up to ``c = k + 1/2`` per axis around it, in the cascade serving ``p`` and, in a blend
    band, the previous one too. The bias ``2c m`` covers the receiver's own plane there; at
    a crease where a lit face stands on the lit ground (a concave corner) the texels beyond
    the foot hold the ground, nearer to the sun than the face's plane extended by up to
    ``c (|dr/dx| + |dr/dy|)`` of the *ground's* slopes, and the lifted point is no higher
    above the ground than ``p`` (the offset is along the face). For each lit pixel the
    points of its own plane at the corners ``(s, t) +- c`` texels of that square are cast
    toward the sun: if one hits a body, the reach leaves the plane (a crease, a shadow's
    edge).
    """
    from shadowmath.groundtruth import segment_hits_triangles

    from .depth_scenes import LIFT
    from .scenes import world_mesh

    fit, light = frame.cascades, np.append(SUN.direction, 0.0)
    lit = truth.on & ~truth.shadow & (np.nan_to_num(frame.normal) @ light[:3] > 0)
    p = frame.position[lit].astype(np.float64)
    n = frame.normal[lit].astype(np.float64)
    depth = -(p @ view[2, :3] + view[2, 3])
    serving = frame.cascade[lit]
    off = np.zeros(len(p), dtype=bool)
    for step in (0, 1):  # the serving cascade, and the previous one in its blend band
        i = serving - step
        sampled = i >= 0
        if step:
            sampled &= depth <= np.asarray(fit.band_end)[np.maximum(i, 0)]
        M = np.asarray(fit.world_to_texture)[i[sampled]]
        for x in _reach_corners(M, p[sampled], n[sampled], fit.texture_size, pcf_radius):
            hit = np.zeros(len(x), dtype=bool)
            for body in BODIES:
                hit |= segment_hits_triangles(x + LIFT * n[sampled], light, *world_mesh(body))
            off[np.flatnonzero(sampled)[hit]] = True
    mask = np.zeros(lit.shape, dtype=bool)
    mask[lit] = off
    return mask


def _reach_corners(M, p, n, size, pcf_radius):
    """``(4, N, 3)``: the points of each plane ``(p, n)`` whose texture coordinates are the
    lifted point's ``(s, t) +- c`` texels (``c = k + 1/2``), ``M`` ``(N, 4, 4)``."""
    import shadowmath as sm

    lifted = p + np.asarray(sm.normal_offset(M, p, n, map_size=size, pcf_radius=pcf_radius))
    h = np.einsum("nij,nj->ni", M, np.append(lifted, np.ones((len(p), 1)), axis=1))
    st = h[:, :2] / h[:, 3:]
    plane = np.append(n, -np.sum(n * p, axis=1)[:, None], axis=1)
    corners = []
    for corner in ((-1, -1), (-1, 1), (1, -1), (1, 1)):
        s, t = (st + (pcf_radius + 0.5) * np.asarray(corner) / np.asarray(size)).T
        # (row_s - s row_q) . (x, 1) = 0, the same for t, and the plane: three equations.
        rows = np.stack([M[:, 0] - s[:, None] * M[:, 3], M[:, 1] - t[:, None] * M[:, 3], plane],
                        axis=1)  # fmt: skip
        corners.append(np.linalg.solve(rows[:, :, :3], -rows[:, :, 3:])[..., 0])
    return corners


def behind_shadow(frame, truth) -> np.ndarray:
    """Ground pixels in the tower-behind-the-camera's shadow (it is the last body)."""
    from shadowmath.groundtruth import segment_hits_triangles

    from .scenes import world_mesh

    on_ground = truth.shadow & (frame.body == 0)
    p = frame.position[on_ground].astype(np.float64)
    hit = segment_hits_triangles(p + 1e-4 * np.array([0, 0, 1.0]), (*SUN.direction, 0.0),
                                 *world_mesh(BODIES[-1]))  # fmt: skip
    mask = np.zeros_like(on_ground)
    mask[on_ground] = hit
    return mask


def test_no_face_grazes_the_sun():
    """The scene's premise: every face meets the sun at least 10 degrees off grazing (acne
    on grazing faces is the bias's business, measured by test_render_depth)."""
    from .scenes import world_mesh

    sun = np.asarray(SUN.direction) / np.linalg.norm(SUN.direction)
    for body in BODIES:
        v, t = world_mesh(body)
        n = np.cross(v[t[:, 1]] - v[t[:, 0]], v[t[:, 2]] - v[t[:, 0]])
        cos = n @ sun / np.linalg.norm(n, axis=1)
        assert np.all(np.abs(cos) > np.sin(np.radians(10))), body


VARIANTS = {
    "layers": {},
    "atlas": {"layout": "atlas"},
    "stable": {"stable": True},
    "stable atlas pcf": {"stable": True, "layout": "atlas", "pcf_radius": 1},
    "lispsm": {"warp": "lispsm"},
    "lispsm atlas pcf": {"warp": "lispsm", "layout": "atlas", "pcf_radius": 1},
}


@pytest.mark.parametrize("variant", list(VARIANTS))
@pytest.mark.parametrize("camera", list(CAMERAS))
def test_cascades_agree_with_the_ray_caster(render, camera, variant):
    frame, truth, count = shadows(camera, render, **VARIANTS[variant])
    print(f"{camera} {variant}: {count}, cascades used {np.unique(frame.cascade)}")
    assert count.shadowed > 1500, "the view must show sizeable shadows to test anything"
    used = np.unique(frame.cascade[frame.body >= 0])
    assert len(used) >= 3, f"the view must span several cascades, got {used}"
    assert count.differ_off_band == 0, count
    assert count.differ <= MAX_ALL * truth.on.sum(), count


@pytest.mark.parametrize("camera", ["down", "oblique"])
def test_the_warp_variant_warps_the_views_from_above(render, camera):
    """LiSPSM's matrices divide by ``q`` (their last row is not ``(0, 0, 0, 1)``): the
    ``lispsm`` variants above test the shaders' division and the bias that follows the
    warped depth, from the cameras above; near the ground the warp's cap leaves the
    orthographic maps (``docs/lispsm.md``)."""
    frame, _, _ = shadows(camera, render, warp="lispsm")
    rows = np.asarray(frame.cascades.world_to_clip)[..., 3, :3]
    assert np.all(np.any(np.abs(rows) > 0, axis=-1))


@pytest.mark.parametrize("variant", ["lispsm", "lispsm atlas pcf"])
def test_the_warp_agrees_with_the_ray_caster_looking_steeply_down_across_the_sun(render, variant):
    """The warp capped at the receiver samples' quantiles (``docs/lispsm.md``) is drawn and
    compared like the other variants: the first cascade warped, the bias following the
    warped depth, 0 pixels off the edge band."""
    frame, truth, count = shadows("steep", render, **VARIANTS[variant])
    print(f"steep {variant}: {count}, cascades used {np.unique(frame.cascade)}")
    assert count.shadowed > 1500, "the view must show sizeable shadows to test anything"
    rows = np.asarray(frame.cascades.world_to_clip)[..., 3, :3]
    assert np.any(np.abs(rows[0]) > 0), "the first cascade must be warped"
    assert count.differ_off_band == 0, count
    assert count.differ <= MAX_ALL * truth.on.sum(), count


def test_every_cascade_has_a_band_where_both_agree(render):
    """In the blend bands both cascades must hold the shadow: the bands' pixels (view depths
    in ``[splits[i + 1], band_end[i]]``) are compared like the others and must be there."""
    frame, truth, _ = shadows("horizon", render)
    c = frame.cascades
    view = CAMERAS["horizon"]
    p = frame.position.astype(np.float64)
    depth = -(p @ view[2, :3] + view[2, 3])
    splits, band = np.asarray(c.splits), np.asarray(c.band_end)
    in_band = np.zeros(frame.body.shape, dtype=bool)
    for i in range(len(band) - 1):
        assert band[i] > splits[i + 1], "an overlap of 0.1 gives every inner split a band"
        in_band |= (depth >= splits[i + 1]) & (depth <= band[i])
    assert (in_band & truth.shadow & ~truth.band).sum() > 20, "the bands must hold shadow"
    wrong = ((frame.shadow > 0.5) != truth.shadow) & in_band & ~truth.band
    assert wrong.sum() == 0


def test_a_caster_behind_the_camera_keeps_its_shadow(gl):
    frame, truth, count = shadows("horizon", ctx=gl)
    behind = behind_shadow(frame, truth)
    print(f"behind the camera: {int(behind.sum())} pixels of its shadow in view, {count}")
    assert behind.sum() > 300, "the tower behind the camera must shadow the view"
    assert (behind & (frame.shadow <= 0.5) & ~truth.band).sum() == 0


def test_scene_bounds_without_the_caster_lose_its_shadow(gl):
    """The test can fail: bounds of the ground and the blocks on it leave out the tower behind
    the camera; the maps reach toward the sun only to the box's nearest corner, short of the
    tower's top, and the far part of its shadow, in view, is drawn lit."""
    tallest = max(b[4] for b in BLOCKS)
    ground_and_blocks = np.array([[-100.0, -100.0, 0.0], [100.0, 100.0, tallest]])
    frame, truth, count = shadows("horizon", ctx=gl, scene_bounds=ground_and_blocks)
    behind = behind_shadow(frame, truth)
    lost = behind & (frame.shadow <= 0.5)
    print(f"bounds without the tower: {int(lost.sum())} of {int(behind.sum())} lost, {count}")
    # lost, but for the pixels that another block shadows too
    assert lost.sum() > 0.8 * behind.sum()
    assert count.differ_off_band > 200, count


def test_without_bias_the_surfaces_shadow_themselves(render):
    """The test can fail: with neither the normal offset nor the slope-scaled bias the lit
    faces are covered in acne (shadow pixels off the band, where the ray caster sees light)."""
    _, _, count = shadows("horizon", render, depth_bias=(0.0, 0.0), normal_offset=0.0)
    print(f"no bias: {count}")
    assert count.acne > 1000, count


def test_wrong_splits_lose_shadows(render, monkeypatch):
    """The test can fail: the shader picks the cascade by view depth against ``splits``; with
    the inner splits moved three times further out (capped before the last), points are looked
    up in cascades fitted to nearer slices, outside their maps, and drawn lit."""
    import shadowmath as sm

    fit = sm.fit_cascades

    def wrong_splits(*args, **kwargs):
        c = fit(*args, **kwargs)
        s = np.asarray(c.splits)
        return c._replace(splits=np.r_[s[0], np.minimum(3 * s[1:-1], 0.99 * s[-1]), s[-1]])

    monkeypatch.setattr(sm, "fit_cascades", wrong_splits)
    frame, truth, count = shadows("down", render)
    lost = truth.shadow & (frame.shadow <= 0.5) & ~truth.band
    print(f"wrong splits: {count}, {int(lost.sum())} shadow pixels lost")
    assert lost.sum() > 300, count


def test_webgpu_agrees_with_opengl(gl, wgpu_device):
    """The same pixels show the same points and shadows in both APIs; each WebGPU map is
    OpenGL's upside down (t = 0 is the first row in memory in both: the top of the light's
    view in WebGPU, its bottom in OpenGL), but for texels whose centre lies on an edge (the
    rasterizers' tie rules)."""
    from shadowmath.render.webgpu import render_cascades_wgpu

    web, truth, _ = shadows("horizon", render_cascades_wgpu)
    ogl, _, _ = shadows("horizon", ctx=gl)
    same = same_bodies_but_on_edges(web.body, ogl.body)
    np.testing.assert_allclose(web.position[same], ogl.position[same], atol=1e-3)
    assert (((web.shadow > 0.5) != (ogl.shadow > 0.5)) & ~truth.band).sum() == 0
    error = np.abs(web.shadow_maps[:, ::-1] - ogl.shadow_maps)
    print(f"{web.adapter}: {int((error > 1e-4).sum())} of {error.size} depth texels differ")
    assert (error > 1e-4).sum() <= 0.001 * error.size
    assert float(np.abs(web.shadow_maps - ogl.shadow_maps).max()) > 0.1  # a real flip


def test_the_debug_view_colours_each_cascade(gl):
    frame, _, _ = shadows("horizon", ctx=gl, cascade_colors=True)
    assert frame.cascade_color is not None
    tint = frame.cascade_color / np.maximum(frame.color, 1e-3)
    for i in np.unique(frame.cascade[frame.body >= 0]):
        # off the bands, pixels lit enough to show a colour take their cascade's tint
        depth_ok = frame.cascade == i
        bright = depth_ok & (frame.color.min(axis=-1) > 0.2)
        ratio = np.median(tint[bright], axis=0)
        from shadowmath.render import CASCADE_COLORS

        assert np.allclose(ratio, CASCADE_COLORS[i], atol=0.05), (i, ratio)


def test_the_maps_are_layers_or_an_atlas(gl):
    layers, _, _ = shadows("horizon", ctx=gl, map_size=(256, 128))
    atlas, _, _ = shadows("horizon", ctx=gl, map_size=(256, 128), layout="atlas")
    assert layers.shadow_maps.shape == (4, 128, 256)
    assert atlas.shadow_maps.shape == (1, 256, 512)
    ports = np.asarray(atlas.cascades.viewports)
    bits = gl.info["GL_SUBPIXEL_BITS"]
    for i, (x, y, w, h) in enumerate(ports):
        tile = atlas.shadow_maps[0, y : y + h, x : x + w]
        # each tile holds its cascade's map as its own layer: drawn, and nothing spilled
        # across from a neighbour's viewport, to what the rasterization rules allow for a
        # draw at another place in the window (tests/render/rasterization.py; NVIDIA's
        # depths differ from the layer's in the last bits, llvmpipe's too)
        assert tile.min() < 1.0, i
        same_map_elsewhere(tile, layers.shadow_maps[i], subpixel_bits=bits)
        # and the bound still tells a tile read one texel off, on either axis
        dx, dy = (1 if x == 0 else -1), (1 if y == 0 else -1)
        for off in (np.s_[y : y + h, x + dx : x + w + dx], np.s_[y + dy : y + h + dy, x : x + w]):
            with pytest.raises(AssertionError, match="rasterization bound"):
                same_map_elsewhere(atlas.shadow_maps[0][off], layers.shadow_maps[i],
                                   subpixel_bits=bits)  # fmt: skip


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"pcf_radius": -1}, "pcf_radius"),
        ({"layout": "grid"}, "layout"),
        ({"count": 9}, "count"),
        ({"depth_bias": (1.0, float("inf"))}, "depth_bias"),
    ],
)
def test_bad_options(gl, kwargs, match):
    with pytest.raises(ValueError, match=match):
        render_cascades(BODIES, SUN, CAMERAS["down"], PROJECTION, image_size=16, map_size=16,
                        ctx=gl, **kwargs)  # fmt: skip


def test_a_point_light_is_refused(gl):
    with pytest.raises(ValueError, match="directional"):
        render_cascades(BODIES, Light((0.0, 0.0, 50.0)), CAMERAS["down"], PROJECTION, ctx=gl)
