"""three.js in headless Chromium draws the package's fitted shadows: the ray caster's picture.

A page served from 127.0.0.1 (``threejs/page.html``) draws a white ground ``z = 0`` seen from
above by an orthographic camera (pixel ``(i, j)`` is the ground point at its centre), lit by
one light whose casters the viewer does not see (layer 1: drawn only into the shadow map),
with three.js's ``BasicShadowMap`` (one hard comparison per pixel) through SwiftShader's
WebGL. ``shadowmath.js`` applies the data of ``shadowmath.integrations.threejs``. The red
channel says lit (> 127) or dark; the ray caster (:mod:`shadowmath.groundtruth`) says, for
each ground point, whether the light reaches it and whether a caster blocks it. Off a band
of ``BAND`` pixels around the true edges (of the shadow, of what the light reaches), every
pixel must agree: 0 shadow pixels lost, 0 lit pixels darkened.

Each scene also holds a caster that three.js's default shadow camera cannot see (behind its
near plane: above a sun placed near the ground, or within 0.5 of a spot or point light);
the same scene without the data loses its shadow, so a module that did not apply the fit
fails these tests.
"""

from __future__ import annotations

from collections.abc import Iterator
from typing import Any, NamedTuple

import numpy as np
import pytest

import shadowmath as sm
from shadowmath.groundtruth import segment_hits_triangles
from shadowmath.integrations import threejs

from .conftest import unavailable
from .scenes import edge_band
from .threejs_browser import ARGS, browser_path, routes, serve

SIZE = 128  # pixels square
VIEW = (-6.0, 6.0, -6.0, 6.0)  # the ground's square, and what the camera sees
BAND = 2
LIFT = 1e-4
MAP = 1024


def box(lo: Any, hi: Any) -> tuple[np.ndarray, np.ndarray]:
    corners = np.array([[x, y, z] for x in (0, 1) for y in (0, 1) for z in (0, 1)], float)
    vertices = np.asarray(lo, float) + corners * (np.asarray(hi, float) - np.asarray(lo, float))
    faces = [[0, 1, 3], [0, 3, 2], [4, 6, 7], [4, 7, 5], [0, 4, 5], [0, 5, 1]]
    faces += [[2, 3, 7], [2, 7, 6], [0, 2, 6], [0, 6, 4], [1, 5, 7], [1, 7, 3]]
    return vertices, np.array(faces)


GROUND = sm.Mesh(
    np.array([[x, y, 0.0] for x in VIEW[:2] for y in VIEW[2:]]), np.array([[0, 2, 3], [0, 3, 1]])
)
SUN = np.array([0.3, -0.2, 1.0]) / np.linalg.norm([0.3, -0.2, 1.0])
SUN_BOXES = [box([-1, -1, 3], [1, 0, 3.6]), box([2, 1, 0.5], [3, 2, 1.2])]
SPOT = (np.array([0.5, 0.3, 4.0]), 0.6)
SPOT_BOXES = [box([0.45, 0.25, 3.65], [0.55, 0.35, 3.72]), box([-1, -0.5, 1], [0, 0.2, 1.5])]
POINT = np.array([0.0, 0.0, 3.0])
POINT_BOXES = [
    box([-0.08, -0.08, 2.62], [0.08, 0.08, 2.7]),
    box([1.5, -0.5, 0.8], [2.5, 0.5, 1.3]),
    box([-1, -2.6, 1], [0.5, -1.8, 1.6]),
]


def mesh(boxes: list[tuple[np.ndarray, np.ndarray]]) -> sm.Mesh:
    return sm.gather_meshes([(sm.Mesh(v, f), np.eye(4)) for v, f in boxes])


def ground_points() -> np.ndarray:
    """Pixel centres on the ground, rows bottom first (``readPixels``' order)."""
    u = VIEW[0] + (np.arange(SIZE) + 0.5) * (VIEW[1] - VIEW[0]) / SIZE
    v = VIEW[2] + (np.arange(SIZE) + 0.5) * (VIEW[3] - VIEW[2]) / SIZE
    x, y = np.meshgrid(u, v)
    return np.stack([x, y, np.zeros_like(x)], axis=-1)


class Truth(NamedTuple):
    reached: np.ndarray  # (SIZE, SIZE) the light reaches the ground point
    shadow: np.ndarray  # reached and blocked
    band: np.ndarray  # within BAND pixels of a true edge


def truth(light: np.ndarray, boxes: list[tuple[np.ndarray, np.ndarray]], cone: Any) -> Truth:
    """The ray caster: ``light`` homogeneous (w = 0: toward the sun); ``cone`` (axis, angle)."""
    p = ground_points().reshape(-1, 3)
    all_mesh = mesh(boxes)
    blocked = segment_hits_triangles(p + [0, 0, LIFT], light, all_mesh.vertices, all_mesh.faces)
    reached = np.full(len(p), light[2] > 0)
    if cone is not None:
        axis, angle = cone
        to_p = p - light[:3]
        cos = to_p @ axis / np.linalg.norm(to_p, axis=1) / np.linalg.norm(axis)
        reached &= cos > np.cos(angle)
    shape = (SIZE, SIZE)
    shadow = (blocked & reached).reshape(shape)
    dark = (blocked | ~reached).reshape(shape)
    return Truth(reached.reshape(shape), shadow, edge_band(shadow, BAND) | edge_band(dark, BAND))


class Count(NamedTuple):
    shadowed: int  # ground-truth shadow pixels off the band
    lost: int  # in shadow, drawn lit, off the band
    acne: int  # reached and not in shadow, drawn dark, off the band


def compare(red: np.ndarray, t: Truth, where: np.ndarray | None = None) -> Count:
    dark = red.reshape(SIZE, SIZE) <= 127
    off = t.reached & ~t.band & (True if where is None else where)
    return Count(
        int((off & t.shadow).sum()),
        int((off & t.shadow & ~dark).sum()),
        int((off & ~t.shadow & dark).sum()),
    )


@pytest.fixture(scope="session")
def chromium() -> Iterator[Any]:
    """One headless Chromium for the session (Debian's, driven by Playwright)."""
    path = browser_path()
    try:
        from playwright.sync_api import sync_playwright
    except ImportError:
        unavailable("the three.js tests need Playwright's Python client: pip install playwright")
    if path is None:
        unavailable(
            "the three.js tests need Chromium: apt-get install -y chromium "
            "(Debian's package; Playwright drives it, no `playwright install`)"
        )
    with sync_playwright() as p:
        browser = p.chromium.launch(executable_path=path, args=ARGS)
        yield browser
        browser.close()


@pytest.fixture(scope="session")
def page(chromium: Any) -> Iterator[Any]:
    """The test page, served from 127.0.0.1."""
    server = serve(routes())
    tab = chromium.new_page()
    tab.goto(f"http://127.0.0.1:{server.server_port}/")
    tab.wait_for_function("window.ready === true", timeout=20_000)
    yield tab
    tab.close()
    server.shutdown()
    server.server_close()


def draw(page: Any, light: dict[str, Any], boxes: list[Any], shadow: Any) -> dict[str, Any]:
    casters = [
        {"positions": v.reshape(-1).tolist(), "indices": f.reshape(-1).tolist()} for v, f in boxes
    ]
    spec = {
        "size": [SIZE, SIZE],
        "ground": list(VIEW),
        "view": list(VIEW),
        "casters": casters,
        "light": light,
        "shadow": shadow,
        "mapSize": MAP,
    }
    result: dict[str, Any] = page.evaluate("spec => render(spec)", spec)
    result["red"] = np.asarray(result["red"], dtype=np.uint8)
    return result


def sun_case() -> tuple[dict[str, Any], Any, Truth]:
    light = {"kind": "directional", "position": (2.5 * SUN).tolist(), "target": [0, 0, 0]}
    fit = sm.fit_shadow(sm.DirectionalLight(SUN), mesh(SUN_BOXES), MAP, receivers=GROUND)
    return light, threejs.shadow_data(fit), truth(np.append(SUN, 0.0), SUN_BOXES, None)


def spot_case() -> tuple[dict[str, Any], Any, Truth]:
    position, angle = SPOT
    light = {"kind": "spot", "position": position.tolist(), "target": [0, 0, 0], "angle": angle}
    spot = sm.SpotLight(position, -position, angle)
    fit = sm.fit_shadow(spot, mesh(SPOT_BOXES), MAP, receivers=GROUND)
    cone = (-position, angle)
    return light, threejs.shadow_data(fit), truth(np.append(position, 1.0), SPOT_BOXES, cone)


def point_case() -> tuple[dict[str, Any], Any, Truth]:
    light = {"kind": "point", "position": POINT.tolist()}
    depth = sm.cube_depth_range(POINT, mesh(POINT_BOXES), receivers=GROUND)
    data = threejs.point_shadow_data(POINT, depth, map_size=MAP // 2)
    return light, data, truth(np.append(POINT, 1.0), POINT_BOXES, None)


CASES = {"sun": sun_case, "spot": spot_case, "point": point_case}


@pytest.mark.parametrize("name", CASES)
def test_three_js_draws_the_fitted_shadow(page, name):
    """0 pixels off the band: three.js's shadow through the fitted data is the ray
    caster's; the light's own settings are what the page set, after two frames, and
    ``removeShadow`` restores the shadow's."""
    light, data, t = CASES[name]()
    boxes = {"sun": SUN_BOXES, "spot": SPOT_BOXES, "point": POINT_BOXES}[name]
    result = draw(page, light, boxes, data)
    count = compare(result["red"], t)
    print(f"three.js {name}, fitted: {count}")
    assert count.shadowed > 150
    assert (count.lost, count.acne) == (0, 0)
    assert np.allclose(result["state"]["position"], light["position"])
    if name == "spot":
        assert result["state"]["angle"] == pytest.approx(light["angle"], rel=1e-7)
    if name == "point":
        assert result["state"]["cameraFar"] == pytest.approx(data["far"], rel=1e-7)
    # removeShadow gives the light back to three.js: its camera as constructed, the page's
    # map size, no override left.
    default_far = 500
    expected = {"near": 0.5, "far": default_far, "mapSize": MAP, "bias": 0, "ownUpdate": False}
    assert result["state"]["restored"] == expected


@pytest.mark.parametrize("name", CASES)
def test_three_js_default_shadow_camera_loses_shadows(page, name):
    """The same scenes drawn with three.js's default shadow cameras (a sun's camera near
    the ground, near = 0.5 for spot and point lights) lose the shadow of a caster they do
    not see: what the fitted data gains."""
    light, _, t = CASES[name]()
    boxes = {"sun": SUN_BOXES, "spot": SPOT_BOXES, "point": POINT_BOXES}[name]
    count = compare(draw(page, light, boxes, None)["red"], t)
    print(f"three.js {name}, default camera: {count}")
    assert count.lost > 100


def test_three_js_draws_each_fitted_cascade(page):
    """Each cascade of ``fit_cascades`` (a camera at (0, -8, 4) looking at the origin, three
    slices at view depths 0.5, 6.5, 10, 16, one box's shadow in each),
    applied to one three.js directional light, draws the ray caster's shadow on the ground
    points whose view depth falls in its slice ``[splits[i], splits[i + 1])`` and that the
    camera sees: 0 pixels off the band in every slice, each holding shadow."""
    eye = np.array([0.0, -8.0, 4.0])
    forward = -eye / np.linalg.norm(eye)
    right = np.cross(forward, [0, 0, 1.0])
    right /= np.linalg.norm(right)
    up = np.cross(right, forward)
    view = np.eye(4)
    view[:3, :3] = np.stack([right, up, -forward])
    view[:3, 3] = -view[:3, :3] @ eye
    f, near, far = 1 / np.tan(np.radians(30)), 0.5, 16.0
    projection = np.array(
        [
            [f, 0, 0, 0],
            [0, f, 0, 0],
            [0, 0, -(far + near) / (far - near), -2 * far * near / (far - near)],
            [0, 0, -1, 0],
        ]
    )
    boxes = [
        box([x - 0.4, y - 0.4, 0.6], [x + 0.4, y + 0.4, 1.2])
        for x, y in ((0.5, -4), (-1, 0), (1, 3.5))
    ]
    bounds = np.array([[-6.0, -6.0, -0.1], [6.0, 6.0, 1.5]])
    cascades = sm.fit_cascades(SUN, view, projection, bounds, 512, splits=[0.5, 6.5, 10, 16])
    data = threejs.cascade_shadow_data(cascades)
    p = np.concatenate([ground_points(), np.ones((SIZE, SIZE, 1))], axis=-1)
    p_view = p @ view.T
    clip = p_view @ projection.T
    seen = np.all(np.abs(clip[..., :2]) <= clip[..., 3:], axis=-1)
    depth = -p_view[..., 2]
    t = truth(np.append(SUN, 0.0), boxes, None)
    light = {"kind": "directional", "position": (2.5 * SUN).tolist(), "target": [0, 0, 0]}
    for i, cascade in enumerate(data["cascades"]):
        red = draw(page, light, boxes, cascade)["red"]
        slice_ = seen & (depth >= data["splits"][i]) & (depth < data["splits"][i + 1])
        count = compare(red, t, slice_)
        print(f"three.js cascade {i}: {count}")
        assert count.shadowed > 20
        assert (count.lost, count.acne) == (0, 0)


def test_the_widget_draws_the_fitted_shadow_camera(chromium, tmp_path):
    """The widget's standalone page (``ShadowWidget.to_html``: its ESM and state inline, as a
    static HTML export shows it) imports three.js and ``shadowmath.js`` from that state (no
    network: the page is all the server has), draws the scene, and its
    light's shadow camera is the fitted one (window and depth range of the data), not
    three.js's default ``(-5, 5, 5, -5, 0.5, 500)``. Saves a screenshot (to
    ``$SHADOWMATH_WIDGET_SCREENSHOT`` when set: the README's picture)."""
    import os
    import shutil

    pytest.importorskip("anywidget", reason="the widget extra: pip install 'shadowmath[widget]'")
    from shadowmath.integrations.threejs.widget import ShadowWidget

    floor = box([-4, -4, -0.05], [4, 4, 0])
    sun = {"kind": "directional", "position": [3.0, -2.0, 6.0], "target": [0.0, 0.0, 0.0]}
    w = ShadowWidget(
        [sm.Mesh(*floor), sm.Mesh(*SUN_BOXES[1]), sm.Mesh(*box([-1.5, -1, 0.6], [-0.5, 0, 1.4]))],
        light=sun,
        camera={"position": [7.0, -9.0, 7.0], "target": [0.0, 0.0, 0.5]},
        map_size=1024,
        height=360,
        show_map=True,
    )
    server = serve({"/": (w.to_html().encode(), "text/html")})
    try:
        tab = chromium.new_page(viewport={"width": 640, "height": 400})
        tab.goto(f"http://127.0.0.1:{server.server_port}/")
        tab.wait_for_function("window.ready === true", timeout=30_000)
        tab.wait_for_timeout(500)
        camera = tab.evaluate(
            "(() => { const c = window.__shadowmathWidget.light.shadow.camera;"
            " return [c.left, c.right, c.top, c.bottom, c.near, c.far]; })()"
        )
        shot = tmp_path / "widget.png"
        tab.screenshot(path=str(shot))
        tab.close()
    finally:
        server.shutdown()
        server.server_close()
    data = w.shadow
    expected = [data[k] for k in ("left", "right", "top", "bottom", "near", "far")]
    assert camera == pytest.approx(expected, rel=1e-12)
    assert expected[1] < 5  # the fitted box, not three.js's default half-width 5
    from PIL import Image

    pixels = np.asarray(Image.open(shot).convert("L"), dtype=float)
    assert pixels.std() > 10  # a drawn scene, not a blank canvas
    if os.environ.get("SHADOWMATH_WIDGET_SCREENSHOT"):
        shutil.copy(shot, os.environ["SHADOWMATH_WIDGET_SCREENSHOT"])


@pytest.mark.parametrize("system", ["webgl", "webgpu"])
@pytest.mark.parametrize("name", ["sun", "spot"])
def test_three_js_own_matrices_are_the_fits(page, name, system):
    """three.js's own code (``LightShadow.updateMatrices`` as the module replaces it, and
    ``_updateMatrix``), in the page, turns the data into the fit's matrices: world-to-clip is
    the fit's OpenGL ``blocker_to_clip`` (WebGL) or the same with depth ``(z + w) / 2``
    (WebGPU), and ``shadow.matrix`` the fit's ``world_to_texture`` in both (JavaScript's
    numbers are float64, as the data: 1e-9 relative). A module that left three.js's own
    ``updateMatrices`` in place, or built the projection in WebGL's depth range for the
    WebGPU renderer, fails."""
    light, data, _ = CASES[name]()
    fit = {
        "sun": lambda: sm.fit_shadow(
            sm.DirectionalLight(SUN), mesh(SUN_BOXES), MAP, receivers=GROUND
        ),
        "spot": lambda: sm.fit_shadow(
            sm.SpotLight(SPOT[0], -SPOT[0], SPOT[1]), mesh(SPOT_BOXES), MAP, receivers=GROUND
        ),
    }[name]()
    got = page.evaluate(
        "spec => matrices(spec)", {"light": light, "shadow": data, "system": system}
    )
    clip = np.asarray(got["clip"]).reshape(4, 4).T
    shadow = np.asarray(got["shadow"]).reshape(4, 4).T
    expected = np.asarray(fit.blocker_to_clip)
    if system == "webgpu":
        expected = np.array([[1, 0, 0, 0], [0, 1, 0, 0], [0, 0, 0.5, 0.5], [0, 0, 0, 1]]) @ expected
    scale = np.abs(expected).max()
    assert np.abs(clip - expected).max() <= 1e-9 * scale
    texture = np.asarray(fit.world_to_texture)
    assert np.abs(shadow - texture).max() <= 1e-9 * np.abs(texture).max()


CASCADE_CAMERA = {
    "position": [0.0, -8.0, 4.0],
    "target": [0.0, 0.0, 0.0],
    "fov": 60.0,
    "aspect": 1.0,
    "near": 4.0,
    "far": 16.0,
}
CASCADE_BOXES = [
    box([x - 0.4, y - 0.4, 0.6], [x + 0.4, y + 0.4, 1.2]) for x, y in ((0.5, -4), (-1, 0), (1, 3.5))
]


def widget_case(name: str) -> tuple[Any, Truth]:
    """The widget (ground first, then the case's boxes) and the ray caster's truth."""
    from shadowmath.integrations.threejs.widget import ShadowWidget

    sun = {"kind": "directional", "position": (2.5 * SUN).tolist(), "target": [0, 0, 0]}
    position, angle = SPOT
    spot = {"kind": "spot", "position": position.tolist(), "target": [0, 0, 0], "angle": angle}
    light, boxes, truth_light, cone = {
        "sun": (sun, SUN_BOXES, np.append(SUN, 0.0), None),
        "spot": (spot, SPOT_BOXES, np.append(position, 1.0), (-position, angle)),
        "point": ({"kind": "point", "position": POINT.tolist()}, POINT_BOXES, None, None),
        "cascades": (sun, CASCADE_BOXES, np.append(SUN, 0.0), None),
    }[name]
    if truth_light is None:
        truth_light = np.append(POINT, 1.0)
    w = ShadowWidget(
        [GROUND] + [sm.Mesh(v, f) for v, f in boxes],
        light=light,
        camera=CASCADE_CAMERA if name == "cascades" else None,
        map_size=MAP // 2 if name == "point" else MAP,
        cascades=3 if name == "cascades" else 0,
        show_frustum=True,
        show_map=True,
    )
    assert w.fit_error == ""
    return w, truth(truth_light, boxes, cone)


def cascade_slices(w: Any) -> list[np.ndarray]:
    """The ground pixels the widget's camera sees in each cascade's view-depth slice."""
    from shadowmath.integrations.threejs.widget import view_camera

    view, projection = view_camera(w.camera)
    p = np.concatenate([ground_points(), np.ones((SIZE, SIZE, 1))], axis=-1) @ view.T
    clip = p @ projection.T
    seen = np.all(np.abs(clip[..., :2]) <= clip[..., 3:], axis=-1)
    depth, splits = -p[..., 2], w.shadow["splits"]
    return [seen & (depth >= splits[i]) & (depth < splits[i + 1]) for i in range(len(splits) - 1)]


@pytest.mark.parametrize("name", ["sun", "spot", "point", "cascades"])
def test_the_widget_draws_the_fitted_shadow(chromium, name):
    """The widget's standalone page (``ShadowWidget.to_html``) draws, through its own lights,
    materials and the data its Python side fitted to the whole scene, the ray caster's shadow
    on the ground: 0 pixels off the band lost or darkened. Its test hook ``readback`` only
    looks from above (casters drawn into the shadow maps only; no helpers, gizmo or map
    picture). Cascades: the sun split in 3 (``fit_cascades`` from the widget's camera), each
    cascade's light alone, compared on the ground the camera sees in its slice, each holding
    shadow."""
    pytest.importorskip("anywidget", reason="the widget extra: pip install 'shadowmath[widget]'")
    w, t = widget_case(name)
    server = serve({"/": (w.to_html().encode(), "text/html")})
    try:
        tab = chromium.new_page(viewport={"width": 320, "height": 240})
        tab.goto(f"http://127.0.0.1:{server.server_port}/")
        tab.wait_for_function("window.ready === true", timeout=30_000)
        spec: dict[str, Any] = {"size": [SIZE, SIZE], "view": list(VIEW), "receivers": [0]}
        solos = list(range(len(w.shadow["cascades"]))) if name == "cascades" else [None]
        reds = []
        for solo in solos:
            if solo is not None:
                spec["solo"] = solo
            red = tab.evaluate("spec => window.__shadowmathWidget.readback(spec)", spec)
            reds.append(np.asarray(red, dtype=np.uint8))
        tab.close()
    finally:
        server.shutdown()
        server.server_close()
    slices = cascade_slices(w) if name == "cascades" else [None]
    for i, (red, where) in enumerate(zip(reds, slices, strict=True)):
        count = compare(red, t, where)
        print(f"widget {name} {i}: {count}")
        assert count.shadowed > (20 if name == "cascades" else 150)
        assert (count.lost, count.acne) == (0, 0)
