"""Receiver shadows (passes 2-4) against the NumPy ray caster, which shares no code with the
matrices: for every visible receiver pixel, does the segment to the light cross a blocker?

Mismatches are counted over all receiver pixels and outside a one-pixel band around the
ground truth's shadow edges (where a texel of the shadow map, or a pixel centre on either
side of the true edge, can legitimately disagree)."""

from __future__ import annotations

import numpy as np
import pytest

from shadowmath import fit_shadow
from shadowmath.meshes import box, grid, sphere, torus
from shadowmath.render import Body, Light, look_at, perspective, render_scene

from .scenes import agreement, place, ray_cast_shadow, rotation, world_mesh

SIZE = (192, 144)
BAND = 1  # pixels excluded on each side of a true shadow edge
MAX_OFF_EDGE = 0.001  # at most 0.1 % of the receiver pixels off the edges may disagree
MAX_ALL = 0.01  # at most 1 % of all receiver pixels, edges included


def camera(eye, target, up=(0.0, 0.0, 1.0)):
    return perspective(45.0, SIZE[0] / SIZE[1], 0.1, 60.0) @ look_at(eye, target, up)


def _torus(translation, scale=1.0, tilt=35.0):
    return Body(
        *torus(1.0, 0.35, segments=32, sides=16),
        to_world=place(rotation((1.0, 0.5, 0.0), tilt), translation, scale),
        color=(0.9, 0.4, 0.2),
    )


def _bumpy() -> Body:
    flat = grid((8.0, 8.0), segments=(64, 64))
    v = flat.vertices.copy()
    x, y = v[:, 0], v[:, 1]
    v[:, 2] = 0.3 * np.sin(1.7 * x) * np.cos(1.3 * y) + 0.1 * np.sin(3.1 * y + 0.5)
    return Body(v, flat.faces)


LIGHT = Light((1.0, -0.5, 7.0))
SCENES = {
    "plane": (
        Body(*grid((10.0, 10.0), segments=(4, 4)), plane=(0, 0, 1, 0)),
        _torus((0.3, 0.2, 2.0)),
        camera((3.0, -5.0, 6.0), (-0.3, 0.0, 0.0)),
    ),
    "sphere": (
        Body(*sphere(2.0, segments=64, rings=32), to_world=place(translation=(0, 0, -1.0))),
        _torus((0.3, 0.2, 3.6), scale=0.6),
        camera((3.0, -4.0, 5.0), (0.0, 0.0, 0.5)),
    ),
    "bumpy": (_bumpy(), _torus((0.3, 0.2, 2.0)), camera((3.0, -5.0, 6.0), (-0.3, 0.0, 0.0))),
}


@pytest.mark.parametrize("shape", list(SCENES))
def test_projected_shadow_agrees_with_ray_caster(gl, shape):
    receiver, blocker, cam = SCENES[shape]
    frame = render_scene([receiver], [blocker], [LIGHT], cam, image_size=SIZE, ctx=gl)
    on, truth = ray_cast_shadow(frame, LIGHT.position, [blocker], [0])
    a = agreement(frame.shadow[..., 0] > 0.5, truth, on, BAND)
    print(f"{shape}: {a}")
    assert a.shadowed > 600, "the scene must show a sizeable shadow to test anything"
    assert a.mismatch_off_edge <= MAX_OFF_EDGE, a
    assert a.mismatch_all <= MAX_ALL, a


def test_planar_and_projected_shadows_agree(gl):
    """Blinn's flattened blocker and Nagy's shadow texture on the same floor and wall."""
    floor = Body(*grid((8.0, 8.0)), to_world=place(translation=(0, 0, 0)), plane=(0, 0, 1, 0))
    wall = Body(
        *grid((8.0, 5.0)),
        to_world=place(rotation((1, 0, 0), 90.0), (0, 4.0, 2.5)),
        plane=(0, -1, 0, 4.0),
    )
    blocker = _torus((0.0, 1.0, 1.6), tilt=50.0)
    light = Light((-3.5, -2.5, 3.5))
    cam = camera((2.0, -7.0, 4.0), (0.0, 1.5, 1.0))
    kwargs = {"image_size": SIZE, "ctx": gl}
    texture = render_scene([floor, wall], [blocker], [light], cam, method="texture", **kwargs)
    planar = render_scene([floor, wall], [blocker], [light], cam, method="planar", **kwargs)
    on = np.isin(texture.body, [0, 1])
    a = agreement(planar.shadow[..., 0] > 0.5, texture.shadow[..., 0] > 0.5, on, BAND)
    print(f"planar vs texture: {a}")
    assert (texture.shadow[..., 0][texture.body == 1] > 0.5).sum() > 600, "shadow on the wall"
    assert (texture.shadow[..., 0][texture.body == 0] > 0.5).sum() > 600, "shadow on the floor"
    assert a.mismatch_off_edge <= MAX_OFF_EDGE, a
    assert a.mismatch_all <= MAX_ALL, a
    # and both against the ray caster
    _, truth = ray_cast_shadow(planar, light.position, [blocker], [0, 1])
    b = agreement(planar.shadow[..., 0] > 0.5, truth, on, BAND)
    print(f"planar vs ray caster: {b}")
    assert b.mismatch_off_edge <= MAX_OFF_EDGE, b


def test_planar_shadow_darkens_once_and_stays_on_the_receiver(gl):
    """A closed torus flattens into many overlapping triangles: each shadowed pixel must lose
    the light's diffuse term exactly once (colour = albedo * ambient, not darker), and the
    shadow must not spill past the floor's edge onto the background."""
    floor = Body(*grid((3.0, 3.0)), color=(0.5, 0.6, 0.7), plane=(0, 0, 1, 0))
    blocker = _torus((0.8, 0.0, 1.2), tilt=20.0)  # its shadow hangs over the floor's edge
    light = Light((-1.0, 0.0, 5.0))
    cam = camera((0.0, -5.0, 5.0), (0.5, 0.0, 0.0))
    ambient, background = 0.2, (0.1, 0.2, 0.3)
    frame = render_scene(
        [floor], [blocker], [light], cam, image_size=SIZE, method="planar",
        ambient=ambient, background=background, ctx=gl,
    )  # fmt: skip
    on, truth = ray_cast_shadow(frame, light.position, [blocker], [0])
    a = agreement(frame.shadow[..., 0] > 0.5, truth, on, BAND)
    assert a.mismatch_off_edge <= MAX_OFF_EDGE, a
    inner = truth & on & ~_band(truth)
    assert inner.sum() > 300
    expected = np.array(floor.color) * ambient
    np.testing.assert_allclose(
        frame.color[inner], np.broadcast_to(expected, (inner.sum(), 3)), atol=2e-3
    )
    assert frame.color[on].min() >= expected.min() - 2e-3, "a pixel was darkened twice"
    empty = frame.body == -1
    np.testing.assert_allclose(
        frame.color[empty], np.broadcast_to(background, (empty.sum(), 3)), atol=1e-6
    )
    assert np.all(frame.shadow[frame.body != 0] == 0)
    # The flattened torus really does reach past the floor: the confinement is being tested.
    v, _ = world_mesh(blocker)
    from shadowmath import planar_projection

    flat = (planar_projection([0, 0, 1, 0], [*light.position, 1.0]) @ np.c_[v, np.ones(len(v))].T).T
    assert (flat[:, 0] / flat[:, 3]).max() > 1.5


def _band(image):
    from .scenes import edge_band

    return edge_band(image, BAND)


def test_receiver_behind_the_light_gets_no_shadow(gl):
    """A wall behind the light (q < 0 there): the projective divide mirrors the map onto it,
    so without the q <= 0 test part of it would sample the silhouette."""
    blocker = Body(*box((1.5, 1.5, 0.5)), to_world=place(translation=(0.3, 0.2, 3.0)))
    behind = Body(*grid((12.0, 12.0)), to_world=place(translation=(0, 0, -3.0)))  # faces +z
    light = Light((0.0, 0.0, 0.0))
    cam = camera((0.5, -0.5, 1.5), (0.0, 0.0, -3.0), up=(0.0, 1.0, 0.0))
    frame = render_scene([behind], [blocker], [light], cam, image_size=SIZE, ctx=gl)
    on, truth = ray_cast_shadow(frame, light.position, [blocker], [0])
    assert on.sum() > 1000
    assert not truth.any()
    assert np.all(frame.shadow[..., 0][on] == 0.0)
    # Without the test: (s, t) = (s q, t q) / q of these points lands inside the silhouette.
    setup = fit_shadow(light.position, blocker.vertices, 256, blocker_to_world=blocker.to_world)
    p = frame.position[on].astype(float)
    stq = (setup.world_to_texture @ np.c_[p, np.ones(len(p))].T).T
    assert np.all(stq[:, 3] < 0)
    st = stq[:, :2] / stq[:, 3:]
    smap = frame.shadow_maps[0][0]
    h, w = smap.shape
    inside = (st >= 0).all(axis=1) & (st < 1).all(axis=1)
    texels = smap[(st[inside, 1] * h).astype(int), (st[inside, 0] * w).astype(int)]
    assert (texels > 0.5).sum() > 200
    # Blinn's planar shadow on the same wall: the blocker lies beyond the light as seen from
    # the plane, its flattened points get w < 0 and the GPU clips them (no anti-shadow).
    for plane in ((0, 0, 1, 3.0), (0, 0, -1, -3.0)):  # either sign of the same plane
        planar = render_scene(
            [behind._replace(plane=plane)], [blocker], [light], cam,
            image_size=SIZE, method="planar", ctx=gl,
        )  # fmt: skip
        assert np.all(planar.shadow[..., 0] == 0.0)


def test_back_faces_get_no_shadow(gl):
    """The camera looks at the dark side of a sphere whose lit side is shadowed by a torus:
    the shadow volume goes through the sphere, and the shadow texture projects onto both
    sides; the article's back-face elimination must keep it off the far side."""
    ball = Body(*sphere(1.5, segments=64, rings=32))
    blocker = _torus((0.0, 0.0, 3.0), scale=0.5, tilt=10.0)
    light = Light((0.0, 0.0, 6.0))
    cam = camera((0.5, -1.0, -6.0), (0.0, 0.0, 0.0), up=(0.0, 1.0, 0.0))
    frame = render_scene([ball], [blocker], [light], cam, image_size=SIZE, ctx=gl)
    on = frame.body == 0
    p = frame.position[on].astype(float)
    n = frame.normal[on].astype(float)
    back = np.sum(n * (np.array(light.position) - p), axis=1) <= 0
    v, t = world_mesh(blocker)
    from shadowmath.groundtruth import segment_hits_triangles

    blocked = segment_hits_triangles(p, light.position, v, t)
    assert (back & blocked).sum() > 300, "the test needs back faces inside the shadow volume"
    assert np.all(frame.shadow[..., 0][on][back] == 0.0)
    # The few front faces visible at the rim still get their shadow where it falls.
    front_shadowed = ~back & blocked
    if front_shadowed.any():
        assert (frame.shadow[..., 0][on][front_shadowed] > 0.5).mean() > 0.5
