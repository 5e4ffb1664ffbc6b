"""1b. Every light and option of ``fit_shadow`` on the single-call path (8-vertex blocker), with
the ``fast`` extra against PyGLM and with NumPy alone against a hand-written NumPy fit.

Each case of :data:`CASES` gives two rows: ``fit_shadow`` as installed (the compiled loop where
Numba is there and serves the case) against the PyGLM fit of its light kind (target ≤ 1), and
``fit_shadow`` with the compiled loop disabled (``_timing.numpy_alone``, what a plain
``pip install shadowmath`` runs) against the hand-written NumPy fit of the same options
(``_numpy_fits``; target ≤ 0.5). A new light or option is one more ``Case`` line; a new light
kind (a spot light) one more :data:`KINDS` entry with its two baselines.
"""

from __future__ import annotations

import traceback
from collections.abc import Callable
from dataclasses import dataclass
from functools import partial
from typing import Any

import numpy as np

import shadowmath as sm

from . import _numpy_fits
from ._scenes import MAP_SIZE, SUN, boxes, floor, glm_fit, glm_ortho_fit, to_glm
from ._timing import Config, Row, Section, Timing, fast_extra, measure, numpy_alone

NAME = "options"
TITLE = "1b. Single call: every light and option of fit_shadow (8 vertices)"
FAST_TARGET = 1.0  # ratio to PyGLM's fit, with the fast extra
NUMPY_TARGET = 0.5  # ratio to the hand-written NumPy fit, NumPy alone


@dataclass(frozen=True)
class Scene:
    """One blocker and its lights: what every case fits (float64)."""

    position: np.ndarray  # (3,) a point light
    sun: np.ndarray  # (4,) a directional light (x, y, z, 0)
    blocker: np.ndarray  # (8, 3) box corners
    receivers: np.ndarray  # (M, 3) a floor's corners and points


@dataclass(frozen=True)
class Kind:
    """A light kind's two baselines: a PyGLM fit and a hand-written NumPy fit."""

    glm_label: str
    glm_fit: Callable[[Any, list[Any]], Any]
    glm_light: Callable[[Scene], np.ndarray]  # the (3,) vector PyGLM gets
    numpy_label: str
    numpy_fit: Callable[..., tuple[np.ndarray, np.ndarray]]


KINDS: dict[str, Kind] = {
    "point": Kind(
        "PyGLM lookAt + perspective, bounding sphere",
        glm_fit,
        lambda s: s.position,
        "hand-written NumPy point fit",
        _numpy_fits.point_fit,
    ),
    "directional": Kind(
        "PyGLM lookAt + ortho, bounding sphere",
        glm_ortho_fit,
        lambda s: s.sun[:3],
        "hand-written NumPy directional fit",
        _numpy_fits.directional_fit,
    ),
}


def position(s: Scene) -> np.ndarray:
    """The point light ``(x, y, z)``."""
    return s.position


def sun(s: Scene) -> np.ndarray:
    """The directional light ``(x, y, z, 0)``."""
    return s.sun


def no_options(s: Scene) -> dict[str, Any]:
    return {}


def scene_options(s: Scene, **extra: Any) -> dict[str, Any]:
    """Receivers and ``stable=True``, and ``extra``: a directional light's scene options."""
    return {"receivers": s.receivers, "stable": True, **extra}


@dataclass(frozen=True)
class Case:
    """One row pair: a light (what ``fit_shadow`` gets) and options, of a :data:`KINDS` kind.

    ``baseline_light`` is what the hand-written fit gets (default: the same light; a typed
    light object would give its plain array here).
    """

    label: str
    kind: str
    light: Callable[[Scene], Any]
    options: Callable[[Scene], dict[str, Any]] = no_options
    baseline_light: Callable[[Scene], np.ndarray] | None = None


VULKAN = partial(scene_options, api="vulkan")
VULKAN_REVERSED = partial(scene_options, api="vulkan", reversed_z=True)

CASES: list[Case] = [
    Case("point (x, y, z)", "point", position),
    Case("point (x, y, z, 1)", "point", lambda s: np.append(s.position, 1.0)),
    Case("point, up=(0, 1, 0)", "point", position, lambda s: {"up": (0.0, 1.0, 0.0)}),
    Case("directional (x, y, z, 0)", "directional", sun),
    Case("directional, receivers, stable", "directional", sun, scene_options),
    Case("directional, receivers, stable, api='vulkan'", "directional", sun, VULKAN),
    Case("directional, receivers, stable, vulkan, reversed_z", "directional", sun, VULKAN_REVERSED),
    # A typed light is one more line, e.g.
    # Case("PointLight", "point", lambda s: sm.PointLight(s.position), baseline_light=position),
    # and a spot light too, once KINDS has a "spot" entry with its two baselines.
]


def scene(seed: int) -> Scene:
    """The blocker and point light of the single-call rows (``boxes``), the sun, a floor of 64."""
    lights, corners = boxes(1, seed)
    return Scene(lights[0], SUN.copy(), corners[0], floor(8)[:64])


def check_api_constants(cases: list[Case], s: Scene) -> None:
    """The hand-written fit's API constants are the library's (asserted once, not timed)."""
    for case in cases:
        opts = case.options(s)
        api, rz = opts.get("api", "opengl"), bool(opts.get("reversed_z", False))
        conv = sm.api_convention(api=api, reversed_z=rz)
        clip, texture = _numpy_fits.api_matrices(api, rz)
        assert np.array_equal(clip, conv.gl_clip_to_clip), (api, rz)
        assert np.array_equal(texture, conv.gl_clip_to_texture), (api, rz)


def _rows(case: Case, s: Scene, cfg: Config, glm_times: dict[str, Timing], fast: bool) -> list[Row]:
    kind = KINDS[case.kind]
    light, opts = case.light(s), case.options(s)
    base_light = (case.baseline_light or case.light)(s)
    reps, min_time = cfg.repeats(7), cfg.min_time
    hand = partial(kind.numpy_fit, base_light, s.blocker, MAP_SIZE, **opts)
    _numpy_fits.check(hand(), s.blocker, **opts)
    fit = partial(sm.fit_shadow, light, s.blocker, MAP_SIZE, **opts)
    rows = []
    if fast:
        if case.kind not in glm_times:
            gl_light, gl_verts = to_glm(kind.glm_light(s), s.blocker)
            ndc = _numpy_fits.project(np.array(kind.glm_fit(gl_light, gl_verts)), s.blocker)
            assert np.all(np.abs(ndc) <= 1 + 1e-5), f"PyGLM {case.kind} fit: {ndc}"
            glm_times[case.kind] = measure(
                partial(kind.glm_fit, gl_light, gl_verts), repeats=reps, min_time=min_time
            )
        rows.append(
            Row(
                f"fit_shadow, {case.label}, fast extra",
                measure(fit, repeats=reps, min_time=min_time),
                kind.glm_label,
                glm_times[case.kind],
                target=f"≤ {FAST_TARGET:g}",
                limit=FAST_TARGET,
            )
        )
    with numpy_alone():
        t = measure(fit, repeats=reps, min_time=min_time)
    rows.append(
        Row(
            f"fit_shadow, {case.label}, NumPy alone",
            t,
            kind.numpy_label,
            measure(hand, repeats=reps, min_time=min_time),
            target=f"≤ {NUMPY_TARGET:g}",
            limit=NUMPY_TARGET,
        )
    )
    return rows


def run(cfg: Config) -> Section:
    section = Section(NAME, TITLE)
    s = scene(cfg.seed)
    check_api_constants(CASES, s)
    fast = fast_extra()
    glm_times: dict[str, Timing] = {}
    failed = []
    for case in CASES:
        try:
            section.rows.extend(_rows(case, s, cfg, glm_times, fast))
        except Exception:
            failed.append(f"{case.label}:\n{traceback.format_exc()}")
    if failed:
        section.error = "\n".join(failed)
    if not fast:
        section.notes.append(
            "the fast extra is not available here (Numba missing or SHADOWMATH_NUMBA=0): "
            "the PyGLM rows are left out"
        )
    section.notes.append(
        f"One blocker of 8 box corners (NumPy float64), a {MAP_SIZE}² map; the point light of "
        f"the single-call rows, the sun {tuple(SUN.tolist())}; {len(s.receivers)} receivers "
        "(a floor's 4 corners and 60 points on it)."
    )
    section.notes.append(
        "fast extra: fit_shadow as installed, against PyGLM (a list of glm.vec3 made before "
        "timing, Python loops over the vertices). NumPy alone: the compiled loop disabled "
        "(shadowmath._backends._kernels.disabled(), as without Numba), against a hand-written "
        "NumPy fit "
        "of the same options (benchmarks/speed/_numpy_fits.py; its matrices are checked once, "
        "not timed)."
    )
    return section
