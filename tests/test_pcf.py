"""Percentage-closer filtering: analytic cases, a brute-force loop, NumPy = JAX, derivatives."""

from __future__ import annotations

import itertools

import jax
import jax.numpy as jnp
import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from shadowmath import pcf, pcf_border_texels

FILTERS = ["box", "bilinear"]


def brute_force(
    depth_map: np.ndarray, s: float, t: float, d: float, radius: int, filt: str, reversed_z=False
) -> float:
    """The definition, one point at a time, texel by texel (outside the map: lit)."""
    H, W = depth_map.shape
    if not (0 <= s <= 1 and 0 <= t <= 1):
        return 1.0

    def lit(row: int, col: int) -> float:
        if not (0 <= row < H and 0 <= col < W):
            return 1.0
        z = depth_map[row, col]
        return float(d >= z if reversed_z else d <= z)

    taps = range(-radius, radius + 1)
    total = 0.0
    if filt == "box":
        col, row = int(np.floor(s * W)), int(np.floor(t * H))
        for i, j in itertools.product(taps, taps):
            total += lit(row + j, col + i)
    else:
        for i, j in itertools.product(taps, taps):
            u, v = s * W - 0.5 + i, t * H - 0.5 + j  # the tap, in texel-centre units
            c0, r0 = int(np.floor(u)), int(np.floor(v))
            fx, fy = u - c0, v - r0
            total += (
                (1 - fx) * (1 - fy) * lit(r0, c0)
                + fx * (1 - fy) * lit(r0, c0 + 1)
                + (1 - fx) * fy * lit(r0 + 1, c0)
                + fx * fy * lit(r0 + 1, c0 + 1)
            )
    return total / len(taps) ** 2


@pytest.mark.parametrize("filt", FILTERS)
@pytest.mark.parametrize("reversed_z", [False, True])
@given(radius=st.integers(0, 3), seed=st.integers(0, 2**32 - 1))
def test_constant_map_is_all_or_nothing(filt: str, reversed_z: bool, radius: int, seed: int):
    rng = np.random.default_rng(seed)
    H, W = rng.integers(2 * radius + 4, 40, 2)
    depth_map = np.full((H, W), 0.5)
    margin = (radius + 1) / np.array([W, H])
    coords = rng.uniform(margin, 1 - margin, (50, 2))
    nearer = np.full(50, 0.25)
    farther = np.full(50, 0.75)
    lit_near = 1.0 if not reversed_z else 0.0
    kw = {"pcf_radius": radius, "pcf_filter": filt, "reversed_z": reversed_z}
    np.testing.assert_array_equal(pcf(depth_map, coords, nearer, **kw), lit_near)
    np.testing.assert_array_equal(pcf(depth_map, coords, farther, **kw), 1 - lit_near)


@given(radius=st.integers(0, 3), edge=st.integers(4, 12), seed=st.integers(0, 2**32 - 1))
def test_half_plane_edge_box(radius: int, edge: int, seed: int) -> None:
    """Caster over columns < edge: lit fraction = (columns of the kernel >= edge) / (2k + 1)."""
    W = H = 16
    depth_map = np.where(np.arange(W)[None, :] < edge, 0.0, 1.0) * np.ones((H, 1))
    rng = np.random.default_rng(seed)
    s = rng.uniform((radius + 1) / W, 1 - (radius + 1) / W, 64)
    t = rng.uniform((radius + 1) / H, 1 - (radius + 1) / H, 64)
    col = np.floor(s * W)
    expected = np.clip(col + radius + 1 - np.maximum(col - radius, edge), 0, 2 * radius + 1)
    lit = pcf(depth_map, np.stack([s, t], -1), np.full(64, 0.5), pcf_radius=radius)
    np.testing.assert_allclose(lit, expected / (2 * radius + 1), rtol=1e-12)


@given(radius=st.integers(0, 3), edge=st.integers(5, 11), seed=st.integers(0, 2**32 - 1))
def test_half_plane_edge_bilinear(radius: int, edge: int, seed: int) -> None:
    """Each tap interpolates the step linearly between texel centres: clip(u - edge + 1, 0, 1)."""
    W = H = 16
    depth_map = np.where(np.arange(W)[None, :] < edge, 0.0, 1.0) * np.ones((H, 1))
    rng = np.random.default_rng(seed)
    s = rng.uniform((radius + 1) / W, 1 - (radius + 1) / W, 64)
    t = rng.uniform((radius + 2) / H, 1 - (radius + 2) / H, 64)
    u = s * W - 0.5
    taps = np.arange(-radius, radius + 1)
    expected = np.clip(u[:, None] + taps - (edge - 1), 0, 1).mean(axis=1)
    lit = pcf(
        depth_map, np.stack([s, t], -1), np.full(64, 0.5), pcf_radius=radius, pcf_filter="bilinear"
    )
    np.testing.assert_allclose(lit, expected, rtol=1e-12, atol=1e-14)


@pytest.mark.parametrize("filt", FILTERS)
@given(radius=st.integers(0, 2), seed=st.integers(0, 2**32 - 1))
def test_weights_sum_to_one(filt: str, radius: int, seed: int) -> None:
    """A pattern and its complement light every interior point exactly once in total."""
    rng = np.random.default_rng(seed)
    H, W = 12, 14
    pattern = rng.integers(0, 2, (H, W)).astype(float)  # 1 = caster at depth 0
    depth_map = 1 - pattern
    margin = (radius + 1.5) / np.array([W, H])
    coords = rng.uniform(margin, 1 - margin, (40, 2))
    d = np.full(40, 0.5)
    kw = {"pcf_radius": radius, "pcf_filter": filt}
    total = pcf(depth_map, coords, d, **kw) + pcf(1 - depth_map, coords, d, **kw)
    np.testing.assert_allclose(total, 1.0, rtol=1e-12)


@pytest.mark.parametrize("filt", FILTERS)
@pytest.mark.parametrize("reversed_z", [False, True])
@given(radius=st.integers(0, 2), seed=st.integers(0, 2**32 - 1))
def test_matches_brute_force(filt: str, reversed_z: bool, radius: int, seed: int) -> None:
    rng = np.random.default_rng(seed)
    H, W = rng.integers(2 * radius + 3, 20, 2)
    depth_map = rng.uniform(0, 1, (H, W))
    coords = rng.uniform(-0.3, 1.3, (30, 2))  # outside the map too: clamp-to-border
    d = rng.uniform(0, 1, 30)
    got = pcf(depth_map, coords, d, pcf_radius=radius, pcf_filter=filt, reversed_z=reversed_z)
    expected = [
        brute_force(depth_map, *c, di, radius, filt, reversed_z)
        for c, di in zip(coords, d, strict=True)
    ]
    np.testing.assert_allclose(got, expected, rtol=1e-12, atol=1e-14)
    assert ((got >= 0) & (got <= 1)).all()


def test_far_outside_the_map_is_lit() -> None:
    depth_map = np.zeros((8, 8))  # everything shadowed inside
    coords = np.array([[-1.0, 0.5], [0.5, 2.0], [1e6, -1e6]])
    np.testing.assert_array_equal(pcf(depth_map, coords, np.full(3, 0.5), pcf_radius=2), 1.0)


@pytest.mark.parametrize("filt", FILTERS)
@pytest.mark.parametrize("radius", [0, 1, 2, 3])
def test_border_rule(filt: str, radius: int) -> None:
    """With b = pcf_border_texels empty texels the map's lookups equal an infinite map's.

    The infinite map is the map padded with many empty texels; points inside, on and
    past the map's edge agree (past the edge: lit). With one texel less of border
    some point past the edge is not lit by the infinite map (its kernel reaches the
    caster): the soft shadow is cut off at the map's edge.
    """
    b = pcf_border_texels(radius, filt)  # type: ignore[arg-type]
    W = H = 16
    s = np.linspace(-4 / W, 1 + 4 / W, 397)
    coords = np.stack([s, np.full_like(s, 0.5)], -1)
    d = np.full_like(s, 0.5)
    pad = 8

    def cut_off(border: int) -> bool:
        depth_map = np.ones((H, W))
        depth_map[:, border : W - border] = 0.0  # the caster fills the inside
        infinite = np.pad(depth_map, pad, constant_values=1.0)
        inf_coords = (coords * [W, H] + pad) / [W + 2 * pad, H + 2 * pad]
        finite = pcf(depth_map, coords, d, pcf_radius=radius, pcf_filter=filt)
        unbounded = pcf(infinite, inf_coords, d, pcf_radius=radius, pcf_filter=filt)
        return not np.allclose(finite, unbounded, atol=1e-12)

    assert not cut_off(b)
    if b > 1 or radius == 0:  # max(1, k): below 1 the clamp-to-edge rule decides
        assert cut_off(b - 1) == (
            b - 1 < np.ceil(radius + (1.0 if filt == "bilinear" else 0.5) - 0.5)
        )
    assert pcf_border_texels(0) == 1
    assert pcf_border_texels(3, "box") == 3
    assert pcf_border_texels(3, "bilinear") == 4


@pytest.mark.parametrize("filt", FILTERS)
def test_batches_broadcast(filt: str) -> None:
    """B maps with N points each: (B, 1, H, W) with (B, N, 2), as a loop over B."""
    rng = np.random.default_rng(0)
    maps = rng.uniform(0, 1, (3, 1, 10, 12))
    coords = rng.uniform(0, 1, (3, 5, 2))
    d = rng.uniform(0, 1, (3, 5))
    got = pcf(maps, coords, d, pcf_filter=filt)
    assert got.shape == (3, 5)
    for b in range(3):
        np.testing.assert_allclose(got[b], pcf(maps[b, 0], coords[b], d[b], pcf_filter=filt))
    # One map, a grid of points; and depths broadcasting against coords.
    one = pcf(maps[0, 0], coords, 0.5, pcf_filter=filt)
    assert one.shape == (3, 5)
    assert pcf(maps[0, 0], coords[0, 0], 0.5, pcf_filter=filt).shape == ()


@pytest.mark.parametrize("filt", FILTERS)
def test_jax_equals_numpy_under_jit_and_vmap(to, dtype, filt: str) -> None:
    rng = np.random.default_rng(1)
    depth_map = rng.uniform(0, 1, (9, 11))
    coords = rng.uniform(-0.1, 1.1, (20, 2))
    d = rng.uniform(0, 1, 20)
    expected = pcf(depth_map, coords, d, pcf_radius=1, pcf_filter=filt)
    got = pcf(to(depth_map), to(coords), to(d), pcf_radius=1, pcf_filter=filt)
    assert got.dtype == np.dtype(dtype)
    assert type(got) is type(to(d))
    np.testing.assert_allclose(np.asarray(got), expected, atol=1e-6)
    f = jax.jit(lambda m, c, z: pcf(m, c, z, pcf_radius=1, pcf_filter=filt))
    np.testing.assert_allclose(
        f(jnp.asarray(depth_map), jnp.asarray(coords), jnp.asarray(d)), expected, atol=1e-12
    )
    g = jax.vmap(lambda c, z: pcf(jnp.asarray(depth_map), c, z, pcf_radius=1, pcf_filter=filt))
    np.testing.assert_allclose(g(jnp.asarray(coords), jnp.asarray(d)), expected, atol=1e-12)


def test_grad_coords_bilinear_matches_finite_differences() -> None:
    rng = np.random.default_rng(2)
    H = W = 16
    depth_map = rng.uniform(0, 1, (H, W))
    # Away from texel-centre lines, where the tent weights have their kinks.
    cells = rng.integers(3, 12, (10, 2))
    frac = rng.uniform(0.15, 0.85, (10, 2))
    coords = (cells + 0.5 + frac) / [W, H]
    d = rng.uniform(0.2, 0.8, 10)

    def f(c):
        return jnp.sum(
            pcf(jnp.asarray(depth_map), c, jnp.asarray(d), pcf_radius=1, pcf_filter="bilinear")
        )

    grad = np.asarray(jax.grad(f)(jnp.asarray(coords)))
    assert np.isfinite(grad).all()
    h = 1e-6
    for i in range(10):
        for a in range(2):
            e = np.zeros_like(coords)
            e[i, a] = h
            fd = (float(f(jnp.asarray(coords + e))) - float(f(jnp.asarray(coords - e)))) / (2 * h)
            np.testing.assert_allclose(grad[i, a], fd, rtol=1e-6, atol=1e-6)
    assert np.abs(grad).max() > 0


@pytest.mark.parametrize("filt", FILTERS)
def test_grad_depths_through_the_smooth_step(filt: str) -> None:
    rng = np.random.default_rng(3)
    depth_map = rng.uniform(0.4, 0.6, (12, 12))
    coords = rng.uniform(0.3, 0.7, (8, 2))
    d = rng.uniform(0.45, 0.55, 8)

    def f(z):
        return jnp.sum(
            pcf(jnp.asarray(depth_map), jnp.asarray(coords), z, pcf_filter=filt, softness=0.2)
        )

    grad = np.asarray(jax.grad(f)(jnp.asarray(d)))
    assert np.isfinite(grad).all()
    assert (grad < 0).all()  # deeper = less lit
    h = 1e-6
    for i in range(8):
        e = np.zeros(8)
        e[i] = h
        fd = (float(f(jnp.asarray(d + e))) - float(f(jnp.asarray(d - e)))) / (2 * h)
        np.testing.assert_allclose(grad[i], fd, rtol=1e-6, atol=1e-7)
    # Without softness the step's derivative is zero almost everywhere.
    hard = jax.grad(lambda z: jnp.sum(pcf(jnp.asarray(depth_map), jnp.asarray(coords), z)))
    np.testing.assert_array_equal(np.asarray(hard(jnp.asarray(d))), 0.0)


def test_softness_is_exact_away_from_the_stored_depth() -> None:
    depth_map = np.full((8, 8), 0.5)
    c = np.array([[0.5, 0.5]] * 3)
    d = np.array([0.39, 0.5, 0.61])
    np.testing.assert_allclose(pcf(depth_map, c, d, softness=0.2), [1.0, 0.5, 0.0])


# --- errors ---------------------------------------------------------------------------


@pytest.mark.parametrize(
    ("depth_map", "match"),
    [
        (np.ones(8), r"depth_map: expected shape \(\*batch, H, W\)"),
        (np.ones((8, 0)), r"depth_map: expected shape"),
        (np.ones((8, 8), dtype=np.uint16), "depth_map: expected a floating dtype"),
        (np.ones((8, 8), dtype=bool), "depth_map: expected a floating dtype"),
        (np.ones((8, 8), dtype=complex), "depth_map: expected a floating dtype"),
    ],
)
def test_bad_depth_maps(depth_map, match: str) -> None:
    with pytest.raises(ValueError, match=match):
        pcf(depth_map, [0.5, 0.5], 0.5)


def test_no_room_inside_the_map() -> None:
    with pytest.raises(ValueError, match=r"radius: a box kernel of radius 2 needs 2 .* 4 x 8 map"):
        pcf(np.ones((8, 4)), [0.5, 0.5], 0.5, pcf_radius=2)
    with pytest.raises(ValueError, match=r"radius: a bilinear kernel of radius 1 needs 2"):
        pcf(np.ones((4, 8)), [0.5, 0.5], 0.5, pcf_filter="bilinear")
    pcf(np.ones((5, 5)), [0.5, 0.5], 0.5, pcf_filter="bilinear")


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"pcf_radius": -1}, "radius"),
        ({"pcf_radius": 1.5}, "radius"),
        ({"pcf_filter": "gauss"}, "filter"),
        ({"softness": -0.1}, "softness"),
        ({"reversed_z": 1}, "reversed_z"),
    ],
)
def test_bad_options(kwargs, match: str) -> None:
    with pytest.raises(ValueError, match=match):
        pcf(np.ones((8, 8)), [0.5, 0.5], 0.5, **kwargs)


def test_bad_shapes_and_values() -> None:
    with pytest.raises(ValueError, match=r"coords: expected shape \(\*batch, 2\)"):
        pcf(np.ones((8, 8)), [0.5, 0.5, 0.5], 0.5)
    with pytest.raises(ValueError, match="do not broadcast"):
        pcf(np.ones((2, 8, 8)), np.full((3, 2), 0.5), 0.5)
    bad = np.ones((2, 8, 8))
    bad[1, 3, 3] = np.nan
    with pytest.raises(ValueError, match=r"depth_map: contains non-finite.*batch index \(1,\)"):
        pcf(bad, [0.5, 0.5], 0.5)
    with pytest.raises(ValueError, match="coords: contains non-finite"):
        pcf(np.ones((8, 8)), [np.inf, 0.5], 0.5)
    with pytest.raises(ValueError, match="depths: contains non-finite"):
        pcf(np.ones((8, 8)), [[0.5, 0.5]], [np.nan])
    out = jax.jit(lambda z: pcf(jnp.ones((8, 8)), jnp.full((3, 2), 0.5), z))(
        jnp.asarray([0.5, np.nan, 0.5])
    )
    assert np.isnan(out[1])
    assert np.isfinite(np.asarray(out)[[0, 2]]).all()


# ------------------------------------------------------------------ renamed keywords


def test_the_old_keyword_names_still_work_and_warn() -> None:
    """``radius=`` and ``filter=`` are ``pcf_radius=`` and ``pcf_filter=`` (one name per idea)."""
    import shadowmath as sm

    depth_map = np.where(np.arange(8)[None, :] < 4, 0.2, 1.0) * np.ones((8, 1))
    coords, d = np.array([[0.4, 0.5], [0.6, 0.5]]), np.array([0.5, 0.5])
    M = np.array([[0.1, 0, 0, 0.5], [0, 0.1, 0, 0.5], [0, 0, -0.1, 0], [0, 0, 0, 1]])
    p, n = [0.0, 0.0, -3.0], [1.0, 0.0, 1.0]
    calls = [
        (pcf, (depth_map, coords, d), "radius", 2, "filter", "bilinear"),
        (pcf_border_texels, (), "radius", 2, "filter", "bilinear"),
        (sm.slope_scaled_bias, (M, p, n), "radius", 1, "filter", "bilinear"),
        (sm.normal_offset, (M, p, n), "radius", 1, "filter", "bilinear"),
    ]
    for fn, args, r, k, f, filt in calls:
        extra = {"map_size": 100} if fn in (sm.slope_scaled_bias, sm.normal_offset) else {}
        new = fn(*args, pcf_radius=k, pcf_filter=filt, **extra)
        with pytest.warns(
            DeprecationWarning, match=r"\(radius=\.\.\.\) is deprecated.*pcf_radius="
        ):
            old = fn(*args, **{r: k}, pcf_filter=filt, **extra)
        np.testing.assert_array_equal(old, new)
        with pytest.warns(
            DeprecationWarning, match=r"\(filter=\.\.\.\) is deprecated.*pcf_filter="
        ):
            old = fn(*args, pcf_radius=k, **{f: filt}, **extra)
        np.testing.assert_array_equal(old, new)
        with pytest.raises(TypeError, match="got radius= and pcf_radius="):
            fn(*args, radius=k, pcf_radius=k, **extra)
