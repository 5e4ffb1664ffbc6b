"""Accuracy against 50-digit mpmath references, on random and near-degenerate inputs.

Every error is measured against the exact result for the *same* floating-point inputs
(converted exactly to mpmath), so it is the error of the implementation alone. The
figure per case is the normwise relative error ``max|out - ref| / max|ref|`` in ulps of
the dtype (``eps``); ``planar_projection`` is also measured entrywise. Each function's
bound is ``C * kappa`` ulps, with ``kappa`` the relative condition number of the problem
(1 for the well-conditioned ones; see ``CONDITION`` below and docs/accuracy.md).

Run ``python -m tests.test_accuracy`` for the full table in docs/accuracy.md (more cases,
NumPy and JAX); the test below runs a few cases per family.
"""

from __future__ import annotations

import sys
from collections.abc import Callable, Iterator
from fractions import Fraction
from typing import Any, NamedTuple

import mpmath
import numpy as np
import pytest

import shadowmath as sm

mpmath.mp.dps = 50
MPF = np.vectorize(lambda x: mpmath.mpf(float(x)), otypes=[object])

#: Bounds: error <= BOUND_ULPS * kappa ulps, for every function, family and dtype.
BOUND_ULPS = 16.0

#: How kappa is defined per function (also the text of the docs' table).
CONDITION = {
    "planar_projection": "1 (compensated pi.L and diagonal)",
    "mean_direction_vector": "sum_i |V_i - P| / |sum_i (V_i - P)|",
    "light_frame": "as mean_direction_vector",
    "light_frame_from_direction": "1",
    "world_to_light": "1",
    "light_to_world": "1",
    "adaptive_frustum": "max_i |V_i - P| / z_i  /  min(rx_max, ry_max)",
    "blocker_projection": "1",
    "receiver_projection": "1",
    "fit_shadow": "kappa(MDV) + kappa(frustum)",
    "offcenter_frustum": "max_i |V_i - P| / z_i  /  min(R_x, R_y)",
    "smooth_max": "(max |x_i| + T) / |smax|",
    "rolled_light_frame": "1 / |Z x up|",
    "border_margin": "1",
}


# --- references ------------------------------------------------------------------------------


def mp_array(a: Any) -> np.ndarray:
    return MPF(np.asarray(a, dtype=np.float64))


def mp_sqrt(x: Any) -> Any:
    return mpmath.sqrt(x)


def mp_cross(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    return np.array(
        [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]],
        dtype=object,
    )


def mp_normalize(a: np.ndarray) -> np.ndarray:
    return a / mp_sqrt(np.sum(a * a))


def ref_planar(plane: np.ndarray, light: np.ndarray) -> np.ndarray:
    pi, L = mp_array(plane), mp_array(light)
    pl = np.sum(pi * L)
    s = 1 if pl >= 0 else -1
    eye = np.eye(4, dtype=int).astype(object)
    return s * (pl * eye - np.outer(L, pi))


def ref_frame(light: np.ndarray, direction: np.ndarray, helper: np.ndarray) -> list[np.ndarray]:
    z = mp_normalize(direction)
    x = mp_normalize(mp_cross(z, mp_array(helper)))
    return [mp_array(light), x, mp_cross(x, z), z]


def ref_rigid(R: np.ndarray, t: np.ndarray) -> np.ndarray:
    top = np.concatenate([R, t[:, None]], axis=1)
    return np.concatenate([top, mp_array([[0, 0, 0, 1]])], axis=0)


def ref_frustum(frame: list[np.ndarray], verts: np.ndarray) -> tuple[Any, ...]:
    off = mp_array(verts) - frame[0]
    x, y, z = (off @ frame[k] for k in (1, 2, 3))
    slack = mpmath.mpf(1) / 64
    rx = max(abs(a) / b for a, b in zip(x, z, strict=True))
    ry = max(abs(a) / b for a, b in zip(y, z, strict=True))
    return rx, ry, min(z) * (1 - slack), max(z) * (1 + slack)


def ref_projection(rx: Any, ry: Any, n: Any, f: Any, mx: Any, my: Any) -> np.ndarray:
    zero = mpmath.mpf(0)
    return np.array(
        [
            [mx / rx, zero, zero, zero],
            [zero, my / ry, zero, zero],
            [zero, zero, (f + n) / (f - n), -2 * f * n / (f - n)],
            [zero, zero, mpmath.mpf(1), zero],
        ],
        dtype=object,
    )


def ref_texture(P: np.ndarray) -> np.ndarray:
    half = mpmath.mpf(1) / 2
    T = np.array(
        [[half, 0, 0, half], [0, half, 0, half], [0, 0, half, half], [0, 0, 0, 1]], dtype=object
    )
    return T @ P


# --- error measures --------------------------------------------------------------------------


def normwise_ulps(out: Any, ref: np.ndarray, dtype: Any) -> float:
    out_mp = mp_array(np.asarray(out, dtype=np.float64))
    err = max(abs(e) for e in np.ravel(out_mp - ref))
    size = max(abs(e) for e in np.ravel(ref))
    return float(err / size) / float(np.finfo(dtype).eps)


def entrywise_ulps(out: Any, ref: np.ndarray, dtype: Any) -> float:
    out_mp = mp_array(np.asarray(out, dtype=np.float64))
    worst = 0.0
    for o, r in zip(np.ravel(out_mp), np.ravel(ref), strict=True):
        if r == 0:
            if o != 0:
                return float("inf")
            continue
        worst = max(worst, float(abs(o - r) / abs(r)))
    return worst / float(np.finfo(dtype).eps)


# --- input families --------------------------------------------------------------------------


class Scene(NamedTuple):
    plane: np.ndarray
    light4: np.ndarray
    light: np.ndarray
    verts: np.ndarray
    map_size: int
    fits: bool  # the placement admits a frustum (light outside the blocker)


def _unit(rng: np.random.Generator) -> np.ndarray:
    v = rng.normal(size=3)
    return v / np.linalg.norm(v)


def _blocker(rng: np.random.Generator, n: int = 12) -> np.ndarray:
    pts = rng.uniform(-1, 1, size=(n, 3))
    pts -= pts.mean(axis=0)
    return pts / np.linalg.norm(pts, axis=-1).max()


def scene(
    rng: np.random.Generator,
    *,
    scale: float = 1.0,
    offset: float = 0.0,
    plane_gap: float = 1.0,
    distance_ratio: float = 4.0,
    direction: np.ndarray | None = None,
    centroid_gap: float | None = None,
) -> Scene:
    """One scene: a plane with a light ``plane_gap * scale`` off it; a blocker of radius
    ``scale`` whose centroid is ``distance_ratio`` radii from the light (or
    ``centroid_gap`` radii: the MDV nearly zero); everything shifted by ``offset * scale``."""
    shift = rng.uniform(-1, 1, size=3) * offset * scale
    n = _unit(rng) * rng.uniform(0.5, 2)
    anchor = shift + rng.uniform(-1, 1, size=3) * scale
    plane = np.append(n, -n @ anchor)
    lateral = rng.uniform(-1, 1, size=3) * scale
    lateral -= (lateral @ n) / (n @ n) * n
    light_on_plane = anchor + lateral + plane_gap * scale * n / np.linalg.norm(n)
    light4 = np.append(light_on_plane, 1.0)
    if rng.uniform() < 0.3:  # a directional light at angle ~plane_gap to the plane
        d = lateral / max(np.linalg.norm(lateral), 1e-300) + plane_gap * n / np.linalg.norm(n)
        light4 = np.append(d, 0.0)
    verts = _blocker(rng) * scale + shift
    centroid = verts.mean(axis=0)
    u = _unit(rng) if direction is None else direction / np.linalg.norm(direction)
    gap = distance_ratio if centroid_gap is None else centroid_gap
    light = centroid - u * gap * scale
    return Scene(plane, light4, light, verts, int(rng.integers(16, 4097)), centroid_gap is None)


def families(dtype: Any) -> dict[str, Callable[[np.random.Generator], Scene]]:
    f64 = np.dtype(dtype) == np.float64
    # Gaps relative to the coordinates' size, down to ~1000 ulps (the validity threshold is 16).
    lo, hi = (-12, -5) if f64 else (-4.5, -3)
    far = (3, 5) if f64 else (2, 3)

    def tie(rng: np.random.Generator) -> np.ndarray:
        ulps = rng.integers(-3, 4, size=3) * (2.0**-52 if f64 else 2.0**-23)
        return rng.choice([-1.0, 1.0], size=3) * (1 + ulps)

    return {
        "random": lambda rng: scene(rng, scale=10.0 ** rng.uniform(-1, 1)),
        "light near the plane": lambda rng: scene(
            rng, offset=1e3, plane_gap=1e3 * 10.0 ** rng.uniform(lo, hi)
        ),
        "blocker far away": lambda rng: scene(rng, distance_ratio=10.0 ** rng.uniform(*far)),
        "tiny and huge coordinates": lambda rng: scene(
            rng, scale=float(rng.choice([1e-6, 1e6])), offset=float(rng.choice([0.0, 1.0, 1e2]))
        ),
        "tied helper-axis components": lambda rng: scene(rng, direction=tie(rng)),
        "MDV nearly zero": lambda rng: scene(rng, centroid_gap=10.0 ** rng.uniform(lo, hi)),
    }


# --- one case --------------------------------------------------------------------------------


def measure(s: Scene, dtype: Any, xp: Any = np) -> Iterator[tuple[str, float, float]]:
    """``(function, error in ulps, kappa)`` for every function on one scene."""
    eps = float(np.finfo(dtype).eps)

    def cast(a: Any) -> Any:
        return xp.asarray(np.asarray(a, dtype=dtype))

    plane, light4, light, verts = (np.asarray(a, dtype=dtype) for a in s[:4])
    M = sm.planar_projection(cast(plane), cast(light4))
    ref = ref_planar(plane, light4)
    yield "planar_projection", normwise_ulps(M, ref, dtype), 1.0
    yield "planar_projection (entrywise)", entrywise_ulps(M, ref, dtype), 1.0

    off = mp_array(verts) - mp_array(light)
    mdv_ref = np.sum(off, axis=0) / len(verts)
    dist = [mp_sqrt(np.sum(o * o)) for o in off]
    kappa_mdv = float(sum(dist) / len(verts) / mp_sqrt(np.sum(mdv_ref * mdv_ref)))
    yield (
        "mean_direction_vector",
        normwise_ulps(sm.mean_direction_vector(cast(light), cast(verts)), mdv_ref, dtype),
        kappa_mdv,
    )

    frame = sm.light_frame(cast(light), cast(verts))
    mdv_ref_f = np.array([float(v) for v in mdv_ref])
    frame_np = [np.asarray(f, dtype=np.float64) for f in frame]
    helper = np.asarray(sm.helper_axis(frame.z_axis), dtype=np.float64)
    ref_f = ref_frame(light, mdv_ref, helper)
    # The computed helper axis must be a valid choice for the exact Z too (ties may go
    # either way within rounding; either choice gives a valid frame).
    k = int(np.argmax(helper))
    assert abs(ref_f[3][k]) <= min(abs(c) for c in ref_f[3]) + 8 * eps * kappa_mdv
    yield (
        "light_frame",
        max(normwise_ulps(frame_np[i], ref_f[i], dtype) for i in (1, 2, 3)),
        kappa_mdv,
    )

    fd = sm.light_frame_from_direction(cast(light), frame.z_axis * 3)
    helper_d = np.asarray(sm.helper_axis(fd.z_axis), dtype=np.float64)
    ref_d = ref_frame(light, mp_array(np.asarray(frame.z_axis, np.float64)) * 3, helper_d)
    yield (
        "light_frame_from_direction",
        max(normwise_ulps(np.asarray(fd[i]), ref_d[i], dtype) for i in (1, 2, 3)),
        1.0,
    )

    R = np.array([mp_array(frame_np[i]) for i in (1, 2, 3)], dtype=object)
    P = mp_array(frame_np[0])
    W = sm.world_to_light(frame)
    yield "world_to_light", normwise_ulps(W, ref_rigid(R, -(R @ P)), dtype), 1.0
    yield "light_to_world", normwise_ulps(sm.light_to_world(frame), ref_rigid(R.T, P), dtype), 1.0

    margins = sm.border_margin(s.map_size)
    if np.dtype(dtype) == np.float64:  # Python floats, whatever the arrays' dtype
        exact = Fraction(s.map_size - 2, s.map_size)
        yield "border_margin", abs(float((Fraction(margins[0]) - exact) / exact)) / eps, 1.0

    if not s.fits:
        return
    fr = sm.adaptive_frustum(frame, cast(verts), s.map_size)
    frame_mp = [mp_array(f) for f in frame_np]
    rx, ry, n, f = ref_frustum(frame_mp, verts)
    off_l = mp_array(verts) - frame_mp[0]
    spread = max(mp_sqrt(np.sum(o * o)) / (o @ frame_mp[3]) for o in off_l)
    kappa_fr = float(spread / min(rx, ry))
    got = np.array([float(v) for v in fr[:4]])
    yield "adaptive_frustum", normwise_ulps(got, np.array([rx, ry, n, f]), dtype), kappa_fr

    # The fitting issue's functions on the same scene.
    rx_i = [a / b for a, b in zip(off_l @ frame_mp[1], off_l @ frame_mp[3], strict=True)]
    ry_i = [a / b for a, b in zip(off_l @ frame_mp[2], off_l @ frame_mp[3], strict=True)]
    oc = sm.offcenter_frustum(frame, cast(verts), s.map_size)
    oc_ref = [
        (max(rx_i) - min(rx_i)) / 2,
        (max(ry_i) - min(ry_i)) / 2,
        (max(rx_i) + min(rx_i)) / 2,
        (max(ry_i) + min(ry_i)) / 2,
    ]
    oc_got = np.array([float(v) for v in (oc.rx_max, oc.ry_max, oc.x_offset, oc.y_offset)])
    kappa_oc = float(spread / min(oc_ref[0], oc_ref[1]))
    yield "offcenter_frustum", normwise_ulps(oc_got, np.array(oc_ref), dtype), kappa_oc

    T = mpmath.mpf(float(np.asarray(0.01 * rx, dtype=dtype)))
    x_in = np.array([float(v) for v in rx_i], dtype=dtype)
    smax_ref = T * mpmath.log(sum(mpmath.exp(mpmath.mpf(float(v)) / T) for v in x_in))
    smax = sm.smooth_max(cast(x_in), cast(np.asarray(float(T), dtype=dtype)))
    kappa_smax = float((max(abs(mpmath.mpf(float(v))) for v in x_in) + T) / abs(smax_ref))
    yield "smooth_max", normwise_ulps(smax, np.array([smax_ref]), dtype), kappa_smax

    roll = np.asarray(0.7, dtype=dtype)
    mdv_np = np.asarray(mdv_ref_f, dtype)
    rf = sm.rolled_light_frame(cast(light), cast(mdv_np), cast(roll))
    z = mp_normalize(mp_array(mdv_np))
    x0 = mp_normalize(mp_cross(z, mp_array([0.0, 1.0, 0.0])))
    y0 = mp_cross(x0, z)
    c, sn = mpmath.cos(mpmath.mpf(float(roll))), mpmath.sin(mpmath.mpf(float(roll)))
    rolled_ref = [c * x0 + sn * y0, -sn * x0 + c * y0, z]
    sin_up = float(mp_sqrt(np.sum(mp_cross(z, mp_array([0.0, 1.0, 0.0])) ** 2)))
    yield (
        "rolled_light_frame",
        max(normwise_ulps(np.asarray(rf[i + 1]), rolled_ref[i], dtype) for i in range(3)),
        1 / sin_up,
    )

    fields = [mp_array(np.asarray(v, dtype=np.float64)) for v in fr[:6]]
    P_ref = ref_projection(*(v[()] for v in fields))
    yield "blocker_projection", normwise_ulps(sm.blocker_projection(fr), P_ref, dtype), 1.0
    T_ref = ref_texture(P_ref)
    yield "receiver_projection", normwise_ulps(sm.receiver_projection(fr), T_ref, dtype), 1.0

    # End to end: the exact frame of the exact MDV (same helper axis), the exact frustum.
    # fit_shadow may run another path (the compiled loop sums in float64): at a tie its
    # helper axis may differ from light_frame's, so the reference uses its own choice,
    # which must again be valid for the exact Z.
    setup = sm.fit_shadow(cast(light), cast(verts), s.map_size)
    helper_fit = np.asarray(sm.helper_axis(setup.frame.z_axis), dtype=np.float64)
    ref_f = ref_frame(light, mdv_ref, helper_fit)
    k = int(np.argmax(helper_fit))
    assert abs(ref_f[3][k]) <= min(abs(c) for c in ref_f[3]) + 8 * eps * kappa_mdv
    rx, ry, n, f = ref_frustum(ref_f, verts)
    mx, my = (mpmath.mpf(m) for m in margins)
    R = np.array(ref_f[1:], dtype=object)
    W_ref = ref_rigid(R, -(R @ ref_f[0]))
    P_ref = ref_projection(rx, ry, n, f, mx, my)
    spread = max(mp_sqrt(np.sum(o * o)) / (o @ ref_f[3]) for o in off)
    kappa_fit = kappa_mdv + float(spread / min(rx, ry))
    yield (
        "fit_shadow",
        max(
            normwise_ulps(setup.blocker_to_clip, P_ref @ W_ref, dtype),
            normwise_ulps(setup.world_to_texture, ref_texture(P_ref) @ W_ref, dtype),
        ),
        kappa_fit,
    )


class Row(NamedTuple):
    worst_random: float
    worst_degenerate: float
    worst_over_kappa: float
    kappa_max: float
    family: str


def table(dtype: Any, cases: int, xp: Any = np, seed: int = 2024) -> dict[str, Row]:
    rows: dict[str, Row] = {}
    for fam, make in families(dtype).items():
        rng = np.random.default_rng([seed, len(fam)])
        for _ in range(cases):
            for name, err, kappa in measure(make(rng), dtype, xp):
                r = rows.get(name, Row(0.0, 0.0, 0.0, 1.0, ""))
                rand = max(r.worst_random, err) if fam == "random" else r.worst_random
                degen = max(r.worst_degenerate, err) if fam != "random" else r.worst_degenerate
                ratio = err / kappa
                worst_family = fam if ratio > r.worst_over_kappa else r.family
                rows[name] = Row(
                    rand,
                    degen,
                    max(r.worst_over_kappa, ratio),
                    max(r.kappa_max, kappa),
                    worst_family,
                )
    return rows


# --- tests -----------------------------------------------------------------------------------


@pytest.mark.parametrize("dtype", [np.float64, np.float32], ids=["f64", "f32"])
def test_every_function_within_a_few_ulps_times_the_condition(dtype: Any) -> None:
    rows = table(dtype, cases=3)
    assert len(rows) == (15 if np.dtype(dtype) == np.float64 else 14)
    for name, row in rows.items():
        assert row.worst_over_kappa <= BOUND_ULPS, (name, row)
    # Compensation makes the planar matrix accurate entry by entry, not just normwise.
    assert rows["planar_projection (entrywise)"].worst_degenerate <= 4
    if "border_margin" in rows:
        assert rows["border_margin"].worst_random <= 0.5  # correctly rounded


def test_jit_keeps_the_compensated_dot_product() -> None:
    """XLA must not simplify the error-free transformations away (float64 and float32)."""
    import jax
    import jax.numpy as jnp

    planar = jax.jit(sm.planar_projection)
    for dtype, lo in [(np.float64, -12), (np.float32, -4.5)]:
        rng = np.random.default_rng(7)
        for _ in range(5):
            s = scene(rng, offset=1e3, plane_gap=1e3 * 10.0 ** rng.uniform(lo, lo + 1.5))
            plane, light4 = (np.asarray(a, dtype=dtype) for a in s[:2])
            M = planar(jnp.asarray(plane), jnp.asarray(light4))
            assert entrywise_ulps(M, ref_planar(plane, light4), dtype) <= 4


def test_plain_dot_product_would_fail_the_entrywise_bound() -> None:
    """The bound above is not vacuous: the uncompensated formula breaks it near the plane."""
    rng = np.random.default_rng(3)
    worst = 0.0
    for _ in range(10):
        s = scene(rng, offset=1e3, plane_gap=1e-5)
        pi, L = s.plane, s.light4
        pl = float(np.sum(pi * L))
        naive = np.sign(pl) * (pl * np.eye(4) - np.outer(L, pi))
        worst = max(worst, entrywise_ulps(naive, ref_planar(pi, L), np.float64))
    assert worst > 1e3


def _float32_units() -> Iterator[np.ndarray]:
    rng = np.random.default_rng(0)
    yield from rng.normal(size=(2000, 3))
    for signs in np.ndindex(2, 2, 2):
        for ulps in np.ndindex(5, 5, 5):
            yield (np.array(signs) * 2 - 1) * (1 + (np.array(ulps) - 2) * 2.0**-23)
    for axis in np.eye(3):
        yield axis + 1e-30


def test_helper_axis_bound_holds_for_every_unit_z_in_float32() -> None:
    """|Z x V| >= sqrt(2/3) |Z| exactly for the float32 Z the frame produces, |Z| = 1 +- 2 eps.

    The helper axis is chosen by exact comparisons, so in exact arithmetic on the float32
    components 3 (z_i^2 + z_j^2) >= 2 |z|^2, with no rounding slack at all."""
    eps = Fraction(float(np.finfo(np.float32).eps))
    for v in _float32_units():
        frame = sm.light_frame_from_direction(np.zeros(3, np.float32), v.astype(np.float32))
        z = [Fraction(float(c)) for c in frame.z_axis]
        k = int(np.argmax(sm.helper_axis(frame.z_axis)))
        norm2 = sum(c * c for c in z)
        cross2 = norm2 - z[k] * z[k]
        assert 3 * cross2 >= 2 * norm2, v
        assert abs(norm2 - 1) <= 4 * eps, v


def main() -> None:
    """Print docs/accuracy.md's table: ``python -m tests.test_accuracy [cases]``."""
    import jax
    import jax.numpy as jnp

    jax.config.update("jax_enable_x64", True)
    cases = int(sys.argv[1]) if len(sys.argv) > 1 else 40
    results = {
        (dt.__name__, name): table(dt, cases, xp)
        for dt in (np.float64, np.float32)
        for name, xp in (("NumPy", np), ("JAX", jnp))
    }
    print(f"{cases} cases per family, 6 families (5 near-degenerate), per dtype and backend\n")
    header = (
        "| function | dtype | random (NumPy / JAX) | near-degenerate (NumPy / JAX) "
        "| worst error / kappa | max kappa | worst family | bound |"
    )
    print(header)
    print("|" + "---|" * 8)
    names = list(results[("float64", "NumPy")])
    for name in names:
        for dt in ("float64", "float32"):
            if name not in results[(dt, "NumPy")]:
                continue
            a, b = results[(dt, "NumPy")][name], results[(dt, "JAX")][name]
            ratio = max(a.worst_over_kappa, b.worst_over_kappa)
            fam = (a.family if a.worst_over_kappa >= b.worst_over_kappa else b.family) or "-"
            print(
                f"| `{name}` | {dt} | {a.worst_random:.2g} / {b.worst_random:.2g} "
                f"| {a.worst_degenerate:.3g} / {b.worst_degenerate:.3g} | {ratio:.2g} "
                f"| {max(a.kappa_max, b.kappa_max):.2g} | {fam} | {BOUND_ULPS:g} kappa |"
            )


if __name__ == "__main__":
    main()
