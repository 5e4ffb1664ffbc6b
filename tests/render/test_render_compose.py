"""Several lights and several blockers (pass 4), and the matrices of both backends."""

from __future__ import annotations

import numpy as np

from shadowmath import fit_shadow
from shadowmath.groundtruth import segment_hits_triangles
from shadowmath.meshes import box, grid, torus
from shadowmath.render import Body, Light, look_at, perspective, render_scene

from .scenes import edge_band, place, rotation, world_mesh

SIZE = (192, 144)
CAMERA = perspective(45.0, SIZE[0] / SIZE[1], 0.1, 60.0) @ look_at(
    (0.5, -7.0, 7.0), (0.0, 0.5, 0.0), (0.0, 0.0, 1.0)
)
FLOOR = Body(*grid((10.0, 10.0), segments=(2, 2)), color=(0.7, 0.8, 0.9), plane=(0, 0, 1, 0))
BLOCKERS = [
    Body(
        *torus(1.0, 0.3, segments=32, sides=12),
        to_world=place(rotation((1, 0, 0), 20), (-0.6, 0.4, 2.0)),
    ),
    Body(*box((1.2, 1.2, 1.2)), to_world=place(rotation((0, 0, 1), 30), (0.3, 0.2, 3.0))),
]
LIGHTS = [Light((-1.0, -0.5, 7.0), (0.6, 0.5, 0.4)), Light((4.0, 1.0, 5.0), (0.3, 0.4, 0.5))]
AMBIENT = 0.1


def _expected(frame):
    """The picture computed in NumPy from the ray caster: albedo (a + sum of unshadowed
    Lambert terms), and each light's per-blocker shadows."""
    on = frame.body == 0
    p = frame.position[on].astype(float)
    n = frame.normal[on].astype(float)
    light_sum = np.full((len(p), 3), AMBIENT)
    hits = []
    for light in LIGHTS:
        to_light = np.asarray(light.position) - p
        lambert = np.maximum(np.sum(n * to_light, axis=1) / np.linalg.norm(to_light, axis=1), 0)
        per_blocker = [segment_hits_triangles(p, light.position, *world_mesh(b)) for b in BLOCKERS]
        shadowed = np.any(per_blocker, axis=0)
        light_sum += np.outer(lambert * ~shadowed, light.color)
        hits.append(per_blocker)
    color = np.zeros((*on.shape, 3))
    color[on] = light_sum * np.asarray(FLOOR.color)
    return on, color, hits


def _image(on, values):
    out = np.zeros(on.shape, dtype=bool)
    out[on] = values
    return out


def test_lights_subtract_and_blockers_combine(gl):
    frame = render_scene(
        [FLOOR], BLOCKERS, LIGHTS, CAMERA, image_size=SIZE, ambient=AMBIENT, ctx=gl
    )
    on, expected, hits = _expected(frame)
    edges = np.zeros(on.shape, dtype=bool)
    for per_blocker in hits:
        for h in per_blocker:
            edges |= edge_band(_image(on, h), 1)
    inner = on & ~edges
    error = np.abs(frame.color - expected).max(axis=-1)
    double = _image(on, hits[0][0] & hits[0][1]) & inner  # both blockers, first light
    both_lights = _image(on, np.any(hits[0], axis=0) & np.any(hits[1], axis=0)) & inner
    print(
        f"compose: {inner.sum()} pixels off the edges, {double.sum()} in both blockers' "
        f"shadow, {both_lights.sum()} in both lights' shadows, max error {error[inner].max():.2e}, "
        f"{(error[inner] > 2e-3).mean():.2%} over 2e-3"
    )
    assert double.sum() > 150, "the blockers' shadows must overlap for this test to mean anything"
    assert both_lights.sum() > 100, "so must the two lights' shadows"
    assert (error[inner] > 2e-3).mean() <= 0.001
    # Double darkening would take the overlap below the single-shadow colour; exactly one
    # light term is missing there.
    single = _image(on, hits[0][0] & ~hits[0][1] & ~np.any(hits[1], axis=0)) & inner
    overlap = double & ~_image(on, np.any(hits[1], axis=0))
    assert single.sum() > 50
    assert overlap.sum() > 50
    np.testing.assert_allclose(frame.color[overlap], expected[overlap], atol=2e-3)
    np.testing.assert_allclose(frame.shadow[..., 0][overlap], 1.0)


def test_numpy_and_jax_matrices_draw_the_same_pictures(gl):
    """fit_shadow on JAX arrays (float64 and float32, under jit) gives the same shadow maps
    and the same picture as on NumPy arrays. One light keeps JAX's compile time small."""
    import jax
    import jax.numpy as jnp

    fit = jax.jit(fit_shadow, static_argnums=2)
    lights = LIGHTS[:1]

    def setups(convert, fitter):
        return [
            [
                fitter(convert(light.position), convert(b.vertices), 256,
                       blocker_to_world=convert(b.to_world))
                for b in BLOCKERS
            ]
            for light in lights
        ]  # fmt: skip

    as_numpy = setups(lambda x: np.asarray(x, dtype=np.float64), fit_shadow)
    kwargs = {"image_size": SIZE, "ambient": AMBIENT, "ctx": gl}
    reference = render_scene([FLOOR], BLOCKERS, lights, CAMERA, setups=as_numpy, **kwargs)
    assert reference.shadow.sum() > 1000
    for dtype in (jnp.float64, jnp.float32):
        s = setups(lambda x, dtype=dtype: jnp.asarray(x, dtype=dtype), fit)
        assert s[0][0].blocker_to_clip.dtype == dtype
        frame = render_scene([FLOOR], BLOCKERS, lights, CAMERA, setups=s, **kwargs)
        differ = float((np.abs(frame.color - reference.color) > 1e-6).any(axis=-1).mean())
        texels = [
            float(np.mean(a != b))
            for ma, mb in zip(frame.shadow_maps, reference.shadow_maps, strict=True)
            for a, b in zip(ma, mb, strict=True)
        ]
        print(f"{np.dtype(dtype).name}: {differ:.4%} pixels, {max(texels):.4%} texels differ")
        # float32 rounding of the matrices may move a silhouette-edge texel, nothing more.
        assert differ <= 0.001
        assert max(texels) <= 0.001
