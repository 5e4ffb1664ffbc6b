"""Directional and stable fits held to geometry that the other tests leave loose.

Each test here was written to kill a mutation of the fit that survived the rest of
the suite (``tools/mutations.py`` lists them and checks that they die); each asserts a
property of the public :func:`shadowmath.fit_shadow` only, never numbers read off
the implementation:

* the stable map holds the blocker's bounding sphere *after* its centre was
  snapped to the texel grid: every vertex inside the border margin;
* a flat blocker facing the sun still gets a depth range with the blocker in it
  and the frame's origin behind it;
* a directional light's depth range holds the receivers inside the map beyond the
  casters, while receivers on the sun's side of every caster (which nothing can
  shadow) move nothing and get depths before ``near`` (lit).
"""

from __future__ import annotations

from typing import Any

import numpy as np
import pytest

import shadowmath as sm


def _ndc(M: np.ndarray, pts: np.ndarray) -> np.ndarray:
    """``(*batch, N, 3)`` NDC of ``(*batch, N, 3)`` world points through ``(*batch, 4, 4)``."""
    h = np.concatenate([pts, np.ones((*pts.shape[:-1], 1))], axis=-1)
    clip = h @ np.swapaxes(np.asarray(M), -1, -2)
    return clip[..., :3] / clip[..., 3:]


def _unit(rng: np.random.Generator, shape: tuple[int, ...]) -> np.ndarray:
    v = rng.normal(size=(*shape, 3))
    return v / np.linalg.norm(v, axis=-1, keepdims=True)


# ---- stable maps: the bounding sphere stays inside the margin after snapping -------------

# Map sizes along X and Y (square and not, odd and even, small and large), per batch.
STABLE_SIZES = [(8, 8), (13, 40), (64, 64), (100, 37), (255, 256), (512, 129), (1024, 1024)]
BATCH = 48  # fits per map size, one batched call each
# Float64 rounding of an NDC coordinate here: the blocker is at most ~100 radii from
# the world origin, so the matrix's translation cancels ~100 times the result, and a
# few tens of roundings give well below 1e-11. A vertex pushed out by the snapping,
# if the half-texel enlargement were short by even 1 % of a texel, lands 1e-4 texel
# = 2e-4 / size >= 2e-7 NDC outside on maps up to 1024 texels.
NDC_TOL = 1e-9


def _stable_scenes(seed: int, size: tuple[int, int], with_up: bool) -> dict[str, Any]:
    """A batch of directional lights and blockers whose vertices lie on their bounding sphere.

    The vertices come in antipodal pairs ``c +- r v`` about a centre ``c``, so their
    mean is ``c`` and the sphere about the mean has radius ``r``: the stable fit's
    sphere (the ``stable`` docstring: "the blocker's bounding sphere about its
    vertices' mean") is this one, whatever the rounding of ``c``.
    """
    rng = np.random.default_rng(seed)
    r = 10.0 ** rng.uniform(-3, 3, BATCH)  # millimetres to kilometres
    c = rng.uniform(-1, 1, (BATCH, 3)) * r[:, None] * 10.0 ** rng.uniform(-1, 2, (BATCH, 1))
    toward = _unit(rng, (BATCH,)) * 10.0 ** rng.uniform(-2, 2, (BATCH, 1))
    light = np.concatenate([toward, np.zeros((BATCH, 1))], axis=-1)
    up = _unit(rng, (BATCH,)) if with_up else None
    v = _unit(rng, (BATCH, 12))
    cloud = np.concatenate([v, -v], axis=1) * r[:, None, None] + c[:, None, :]
    # The pairs along the map's own axes are the first to leave the margin when the
    # snapped centre moves. The frame of a directional light depends on the light
    # (and up) only, so the axes of a first fit are those of the second.
    frame = sm.fit_shadow(light, cloud, size, stable=True, up=up).frame
    axes = np.stack([frame.x_axis, frame.y_axis], axis=1)  # (BATCH, 2, 3)
    on_axes = np.concatenate([axes, -axes], axis=1) * r[:, None, None] + c[:, None, :]
    return {"light": light, "verts": np.concatenate([cloud, on_axes], axis=1), "up": up}


@pytest.mark.parametrize("with_up", [False, True], ids=["helper-axis", "up"])
@pytest.mark.parametrize("seed", [0, 1])
def test_stable_map_holds_the_bounding_sphere_after_snapping(seed: int, with_up: bool) -> None:
    # After snapping, the map's centre is up to half a texel from the sphere's centre,
    # so the map must reach half a texel beyond the sphere on every side ("enlarged
    # by half a texel"): then every vertex still projects inside the border margin.
    for k, size in enumerate(STABLE_SIZES):
        scene = _stable_scenes(1000 * seed + k, size, with_up)
        s = sm.fit_shadow(scene["light"], scene["verts"], size, stable=True, up=scene["up"])
        ndc = _ndc(s.blocker_to_clip, scene["verts"])
        mx, my = sm.border_margin(size)
        worst_x = float(np.abs(ndc[..., 0]).max())
        worst_y = float(np.abs(ndc[..., 1]).max())
        texel_x, texel_y = 2 / size[0], 2 / size[1]
        assert worst_x <= mx + NDC_TOL, (size, (worst_x - mx) / texel_x)
        assert worst_y <= my + NDC_TOL, (size, (worst_y - my) / texel_y)
        # And the map is no looser than that: some vertex within a texel of the margin.
        assert worst_x > mx - texel_x and worst_y > my - texel_y
        assert np.all(np.abs(ndc[..., 2]) < 1)


# ---- flat blockers facing the sun ---------------------------------------------------------

# The square |u|, |v| <= 1 in a coordinate plane, and suns along its normal (exactly:
# the blocker has no depth at all) or nearly (a depth of rounding size, or a little more).
FLAT = [
    ("y=0", np.array([[x, 0.0, z] for x in (-1, 1) for z in (-1, 1)]), (0.0, 1.0, 0.0)),
    ("y=0 below", np.array([[x, 0.0, z] for x in (-1, 1) for z in (-1, 1)]), (0.0, -1.0, 0.0)),
    ("y=0 tilted 1e-12", np.array([[x, 0.0, z] for x in (-1, 1) for z in (-1, 1)]), (1e-12, 1, 0)),
    (
        "y=0 tilted 1e-3",
        np.array([[x, 0.0, z] for x in (-1, 1) for z in (-1, 1)]),
        (1e-3, 1, -2e-3),
    ),
    ("y=5 far", np.array([[x, 5.0, z] for x in (299, 301) for z in (-401, -399)]), (0.0, 2.0, 0.0)),
    ("x=3", np.array([[3.0, y, z] for y in (-1, 1) for z in (-2, 2)]), (0.5, 0.0, 0.0)),
    ("z=-7", np.array([[x, y, -7.0] for x in (-3, 3) for y in (1, 2)]), (0.0, 0.0, -4.0)),
    ("z=-7 tilted", np.array([[x, y, -7.0] for x in (-3, 3) for y in (1, 2)]), (1e-7, 0, -1)),
]


@pytest.mark.parametrize("stable", [False, True], ids=["tight", "stable"])
@pytest.mark.parametrize(("quad", "toward"), [f[1:] for f in FLAT], ids=[f[0] for f in FLAT])
def test_flat_blocker_facing_the_sun_lies_inside_the_depth_range(
    quad: np.ndarray, toward: tuple[float, float, float], stable: bool
) -> None:
    # A sun straight above a flat caster (a roof, a leaf, a sail) is an ordinary scene:
    # the fit must still succeed, put the origin behind the caster (the docstring:
    # "behind every vertex ... so every z > 0") and give it a depth range it lies in.
    s = sm.fit_shadow([*toward, 0.0], quad, 64, stable=stable)
    assert isinstance(s.frustum, sm.OrthographicBox)
    near, far = float(s.frustum.near), float(s.frustum.far)
    assert 0 < near < far
    z = (quad - s.frame.origin) @ s.frame.z_axis
    assert np.all(z > 0)
    assert np.all((near <= z) & (z <= far))
    ndc = _ndc(s.blocker_to_clip, quad)
    assert np.all(np.abs(ndc[:, 2]) < 1)
    # The map is drawn along the sun: the quad fills it up to the margin on both axes.
    mx, my = sm.border_margin(64)
    assert np.abs(ndc[:, 0]).max() <= mx + 1e-12 and np.abs(ndc[:, 1]).max() <= my + 1e-12


# ---- receivers on either side of the blocker ---------------------------------------------


@pytest.mark.parametrize("stable", [False, True], ids=["tight", "stable"])
def test_directional_depth_range_holds_receivers_beyond_and_ignores_those_before(
    stable: bool,
) -> None:
    # The receivers= docstring: the depth range holds every covered receiver that a
    # caster can shadow; one on the sun's side of every caster cannot be shadowed, so
    # it must not widen the range (depth precision) and gets a depth before near.
    rng = np.random.default_rng(11)
    n = 32
    r = 10.0 ** rng.uniform(-2, 2, n)
    c = rng.uniform(-50, 50, (n, 3)) * r[:, None]
    toward = _unit(rng, (n,))  # toward the sun
    blocker = c[:, None, :] + rng.normal(size=(n, 20, 3)) * r[:, None, None]
    # Receivers along the sun's ray through the blocker's mean (inside the map's sides
    # whatever the fit: the mean is inside the blocker's box and sphere), from 20 radii
    # on the sun's side to 20 radii beyond, and a wide grid across the ray.
    t = np.linspace(-20, 20, 41)
    ray = c[:, None, :] + t[None, :, None] * r[:, None, None] * toward[:, None, :]
    across = _unit(rng, (n, 60)) * (r[:, None] * rng.uniform(0, 6, (n, 60)))[..., None]
    receivers = np.concatenate([ray, ray[:, :1] + across, ray[:, -1:] + across], axis=1)
    light = np.concatenate([toward, np.zeros((n, 1))], axis=-1)
    s = sm.fit_shadow(light, blocker, 128, receivers=receivers, stable=stable)
    ndc = _ndc(s.blocker_to_clip, receivers)
    inside = (np.abs(ndc[..., 0]) <= 1) & (np.abs(ndc[..., 1]) <= 1)
    assert np.all(inside[:, : len(t)])  # the ray is in the map
    # Depth along the sun's rays (away from the sun), and the casters' nearest.
    depth = -np.einsum("bmk,bk->bm", receivers, toward)
    first = (-np.einsum("bnk,bk->bn", blocker, toward)).min(axis=1)
    before = depth < first[:, None]
    assert before[inside].sum() > 100 and (~before[inside]).sum() > 100
    assert np.all(np.abs(ndc[..., 2][inside & ~before]) < 1)  # can be shadowed: in range
    assert np.all(ndc[..., 2][inside & before] < 1)  # nothing before the casters is beyond far
    toward_sun = ndc[..., 2][:, len(t) - 10 : len(t)]  # 11 to 20 radii toward the sun
    assert np.all(toward_sun < -1)  # before near: lit
    assert np.all(np.abs(_ndc(s.blocker_to_clip, blocker)[..., 2]) < 1)
    # Those before every caster changed nothing: the fit without them is the same.
    beyond = np.where((inside & before)[..., None], ray[:, :1], receivers)  # t = -20: beyond
    same = sm.fit_shadow(light, blocker, 128, receivers=beyond, stable=stable)
    np.testing.assert_allclose(same.blocker_to_clip, s.blocker_to_clip, rtol=1e-12, atol=0)
