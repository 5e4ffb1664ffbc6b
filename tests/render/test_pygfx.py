"""pygfx's own shadows with shadowmath's cameras (shadowmath.integrations.pygfx), against the
ray caster.

pygfx renders the scene offscreen (wgpu on Mesa's Vulkan driver without a GPU) twice, with
the light's shadows on and off; a pixel is in shadow where the shadowed picture keeps less
than half of the unshadowed one's linear light. The ground truth: the pixel's surface point,
found by casting the camera's ray through the pixel centre against the meshes, then
segments from that point to the light against the casters (shadowmath.groundtruth). No
shadow pixel may be lost outside a band of BAND pixels around the edges of the shadow, of
the lit region and of the bodies. pygfx's default cameras fail the same comparison (the test
can fail), and their texels are several times larger on the receivers.
"""

from __future__ import annotations

import itertools
import re
from pathlib import Path
from typing import Any, NamedTuple

import numpy as np
import pytest

import shadowmath as sm
from shadowmath.groundtruth import segment_hits_triangles
from shadowmath.meshes import box, grid, torus

from .conftest import unavailable
from .scenes import edge_band, place, rotation

SIZE = (200, 150)  # the picture, width x height
BAND = 2
LIFT = 1e-4  # the ground truth's segments start this far off the surface
DOCS = Path(__file__).resolve().parents[2] / "docs" / "pygfx.md"


def _unavailable(err: Exception) -> None:
    unavailable(
        f"no pygfx offscreen renderer: {err}; install the 'pygfx' extra and the Debian "
        "package mesa-vulkan-drivers (apt-get install -y mesa-vulkan-drivers)"
    )


@pytest.fixture(scope="session")
def gfx() -> Any:
    """pygfx itself; missing, it fails on CI (SHADOWMATH_REQUIRE_GL=1) and skips elsewhere."""
    try:
        import pygfx
    except ImportError as err:
        _unavailable(err)
    return pygfx


@pytest.fixture(scope="session")
def pygfx_canvas(gfx) -> Any:
    """The offscreen canvas and renderer (wgpu's adapter: Mesa's llvmpipe without a GPU)."""
    try:
        from rendercanvas.offscreen import RenderCanvas

        canvas = RenderCanvas(size=SIZE, pixel_ratio=1)
        renderer = gfx.renderers.WgpuRenderer(
            canvas, pixel_scale=1, pixel_filter="nearest", ppaa="none"
        )
    except Exception as err:  # no rendercanvas, or no wgpu adapter
        _unavailable(err)
    return canvas, renderer


@pytest.fixture(scope="module", autouse=True)
def _gl_current_after_pygfx() -> Any:
    """pygfx's rendering leaves its own context current on this thread: after this module,
    make the reference renderer's shared GL context current again for the tests that use
    it directly (its render functions do so themselves: render.resolve_context)."""
    yield
    try:
        from shadowmath.render import standalone_context

        standalone_context()
    except Exception:  # no GL here: the GL tests report it themselves
        pass


# ---- scenes ------------------------------------------------------------------------------


class Body(NamedTuple):
    vertices: np.ndarray  # (N, 3) world coordinates
    triangles: np.ndarray  # (M, 3)
    cast: bool  # a caster (the fit's blocker); the others only receive


def body(mesh: sm.Mesh, to_world: np.ndarray, *, cast: bool) -> Body:
    v = np.asarray(mesh.vertices, dtype=float) @ to_world[:3, :3].T + to_world[:3, 3]
    return Body(v, np.asarray(mesh.faces), cast)


class Scene(NamedTuple):
    bodies: list[Body]
    kind: str  # "directional", "spot" or "point"
    light: np.ndarray  # toward the light (directional) or its position (spot, point)
    aim: np.ndarray  # the spot's target (and the default directional light's target)
    angle: float  # the spot's half-angle in radians
    eye: tuple[float, float, float]  # the viewing camera
    target: tuple[float, float, float]

    def casters(self) -> np.ndarray:
        return np.concatenate([b.vertices for b in self.bodies if b.cast])

    def receivers(self) -> sm.Triangles:
        return sm.Triangles(np.concatenate([b.vertices[b.triangles] for b in self.bodies]))

    def sm_light(self) -> Any:
        if self.kind == "directional":
            return sm.DirectionalLight(self.light)
        return sm.SpotLight(self.light, self.aim - self.light, np.array(self.angle))


FLOOR = body(grid((12.0, 12.0), segments=(2, 2)), place(), cast=False)
BOX = body(box((1.2, 1.2, 1.2)), place(rotation((0, 0, 1), 30), (0, 0, 0.6)), cast=True)
TORUS = body(
    torus(1.0, 0.35, segments=32, sides=16),
    place(rotation((1.0, 0.5, 0.0), 80.0), (0.0, 0.0, 1.6)),
    cast=True,
)
#: A desk lamp: a 0.2-unit box under a point light 0.45 above the floor, every caster
#: within pygfx's default near plane (0.5) of it.
SMALL_FLOOR = body(grid((4.0, 4.0), segments=(2, 2)), place(), cast=False)
SMALL_BOX = body(box((0.2, 0.2, 0.2)), place(rotation((0, 0, 1), 20), (0, 0, 0.1)), cast=True)
SCENES = {
    "box, sun": Scene(
        [FLOOR, BOX], "directional", np.array([-3.0, -1.5, 3.5]), np.zeros(3), 0.0,
        (3.0, -5.0, 5.0), (0.0, 0.0, 0.5),
    ),
    "torus, sun": Scene(
        [FLOOR, TORUS], "directional", np.array([4.0, 1.0, 3.5]), np.zeros(3), 0.0,
        (2.0, -5.5, 4.5), (0.0, 0.0, 1.0),
    ),
    "box, spot": Scene(
        [FLOOR, BOX], "spot", np.array([-3.0, -1.5, 3.5]), np.array([0.0, 0.0, 0.6]), 0.7,
        (3.0, -5.0, 5.0), (0.0, 0.0, 0.5),
    ),
    "torus, spot": Scene(
        [FLOOR, TORUS], "spot", np.array([4.0, 1.0, 3.5]), np.array([0.0, 0.0, 1.2]), 0.75,
        (2.0, -5.5, 4.5), (0.0, 0.0, 1.0),
    ),
    "torus, point": Scene(
        [FLOOR, TORUS], "point", np.array([2.0, 0.5, 4.0]), np.zeros(3), 0.0,
        (2.0, -5.5, 4.5), (0.0, 0.0, 1.0),
    ),
    "box, lamp": Scene(
        [SMALL_FLOOR, SMALL_BOX], "point", np.array([0.25, 0.1, 0.45]), np.zeros(3), 0.0,
        (0.6, -1.6, 1.3), (-0.2, 0.0, 0.05),
    ),
}  # fmt: skip
#: A box beside a point light along +Y (a wall behind it): the cube face pygfx 0.17 aims
#: wrong by itself.
SCENES["box, point toward +y"] = Scene(
    [body(grid((12.0, 12.0), segments=(2, 2)), place(rotation((1, 0, 0), 90), (0, 3, 0)),
          cast=False),
     body(box((0.6, 0.6, 0.6)), place(rotation((0, 0, 1), 20), (0.2, 1.5, 0.3)), cast=True)],
    "point", np.zeros(3), np.zeros(3), 0.0, (1.0, -2.0, 1.0), (0.0, 3.0, 0.0),
)  # fmt: skip
#: The scenes whose fit is a frustum (directional and spot lights).
FRUSTUM_SCENES = [name for name, scene in SCENES.items() if scene.kind != "point"]


def fit(scene: Scene) -> Any:
    """The light's fit: a ShadowSetup, or a point light's CubeDepthRange."""
    from shadowmath.integrations.pygfx import PYGFX_SHADOW_MAP_SIZE

    if scene.kind == "point":
        return sm.cube_depth_range(scene.light, scene.casters(), receivers=scene.receivers())
    return sm.fit_shadow(
        scene.sm_light(), scene.casters(), PYGFX_SHADOW_MAP_SIZE, pcf_radius=2, api="webgpu"
    )


def flat_mesh(vertices: np.ndarray, triangles: np.ndarray, *, cast: bool) -> Any:
    """A flat-shaded grey pygfx mesh (unshared vertices: one face normal each) that
    receives shadows, and casts them if ``cast``; ``vertices`` in its local coordinates."""
    import pygfx as gfx

    corners = vertices[triangles]
    n = np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0])
    n /= np.linalg.norm(n, axis=1, keepdims=True)
    geometry = gfx.Geometry(
        positions=corners.reshape(-1, 3).astype(np.float32),
        normals=np.repeat(n, 3, axis=0).astype(np.float32),
        indices=np.arange(3 * len(corners), dtype=np.int32).reshape(-1, 3),
    )
    mesh = gfx.Mesh(geometry, gfx.MeshPhongMaterial(color="#808080", specular="#000000"))
    mesh.cast_shadow, mesh.receive_shadow = cast, True
    return mesh


def pygfx_scene(scene: Scene, *, fitted: bool) -> tuple[Any, Any, Any]:
    """(scene, camera, light): flat-shaded grey meshes, one shadow-casting light."""
    import pygfx as gfx

    from shadowmath.integrations.pygfx import set_shadow_camera

    world = gfx.Scene()
    for b in scene.bodies:
        world.add(flat_mesh(b.vertices, b.triangles, cast=b.cast))
    if scene.kind == "directional":
        light = gfx.DirectionalLight(intensity=8.0, cast_shadow=True)
        light.local.position = scene.aim + 10.0 * scene.light / np.linalg.norm(scene.light)
    elif scene.kind == "spot":
        light = gfx.SpotLight(intensity=8.0, cast_shadow=True, angle=scene.angle)
        light.local.position = scene.light
    else:  # pygfx's default decay 0: no fall-off, lit like the spot
        light = gfx.PointLight(intensity=8.0, cast_shadow=True)
        light.local.position = scene.light
    if scene.kind != "point":
        light.target.local.position = scene.aim
        world.add(light.target)
    world.add(light)
    if fitted:
        set_shadow_camera(light, fit(scene))
    camera = gfx.PerspectiveCamera(45, SIZE[0] / SIZE[1])
    camera.local.position = scene.eye
    camera.world.reference_up = (0, 0, 1)
    camera.look_at(scene.target)
    return world, camera, light


def draw(canvas_renderer: Any, world: Any, camera: Any) -> np.ndarray:
    canvas, renderer = canvas_renderer
    canvas.request_draw(lambda: renderer.render(world, camera))
    srgb = np.asarray(canvas.draw())[..., :3].astype(np.float64) / 255.0
    linear = np.where(srgb <= 0.04045, srgb / 12.92, ((srgb + 0.055) / 1.055) ** 2.4)
    return linear.mean(axis=-1)


class Picture(NamedTuple):
    shadowed: np.ndarray  # (H, W) the shadowed picture keeps under half the light
    reached: np.ndarray  # the unshadowed picture is lit there
    light: Any  # the pygfx light (its shadow camera as rendered)
    camera: Any  # the viewing camera, as rendered
    peak: float  # brightest unshadowed linear value (under 1: nothing clipped)


def render(canvas_renderer: Any, scene: Scene, *, fitted: bool) -> Picture:
    world, camera, light = pygfx_scene(scene, fitted=fitted)
    shaded = draw(canvas_renderer, world, camera)
    light.cast_shadow = False
    bare = draw(canvas_renderer, world, camera)
    light.cast_shadow = True
    reached = bare > 0.01
    shadowed = shaded < 0.5 * bare
    return Picture(shadowed, reached, light, camera, float(bare.max()))


# ---- the ground truth ----------------------------------------------------------------------


def pixel_rays(camera: Any) -> tuple[np.ndarray, np.ndarray]:
    """World origins and directions through the pixel centres (row 0 at the top)."""
    w, h = SIZE
    x = (np.arange(w) + 0.5) / w * 2 - 1
    y = 1 - (np.arange(h) + 0.5) / h * 2
    X, Y = np.meshgrid(x, y)
    inv = np.linalg.inv(np.asarray(camera.camera_matrix, dtype=np.float64))
    ends = []
    for depth in (0.0, 1.0):  # pygfx's clip depth runs 0..1
        ndc = np.stack([X, Y, np.full_like(X, depth), np.ones_like(X)], axis=-1)
        p = ndc.reshape(-1, 4) @ inv.T
        ends.append(p[:, :3] / p[:, 3:])
    d = ends[1] - ends[0]
    return ends[0], d / np.linalg.norm(d, axis=1, keepdims=True)


def _block_boxes(A, B, C, block):
    """The bounds of each run of ``block`` consecutive triangles, widened by far more than
    rounding: a ray that hits a triangle meets its run's box."""
    corners = np.stack([A, B, C], axis=1)  # (T, 3, 3)
    pad = (-len(A)) % block
    corners = np.concatenate([corners, np.repeat(corners[-1:], pad, axis=0)])
    runs = corners.reshape(-1, block * 3, 3)
    lo, hi = runs.min(axis=1), runs.max(axis=1)
    margin = 1e-6 * (1.0 + np.abs(corners).max())
    return lo - margin, hi + margin


def _rays_meet_boxes(o, d, lo, hi):
    """(R, K): ray ``o + t d`` (t >= 0) meets box k (slab test; an axis the ray runs along
    is met where the origin lies between the box's planes)."""
    with np.errstate(divide="ignore", invalid="ignore"):
        inv = 1.0 / d[:, None, :]
        t1, t2 = (lo[None] - o[:, None, :]) * inv, (hi[None] - o[:, None, :]) * inv
    along = d[:, None, :] == 0
    inside = (o[:, None, :] >= lo[None]) & (o[:, None, :] <= hi[None])
    near = np.where(along, np.where(inside, -np.inf, np.inf), np.minimum(t1, t2))
    far = np.where(along, np.where(inside, np.inf, -np.inf), np.maximum(t1, t2))
    enter, leave = near.max(axis=-1), far.min(axis=-1)
    return (enter <= leave) & (leave >= 0)


def first_hits(origins, dirs, vertices, triangles, chunk=512, block=16):
    """Möller–Trumbore: the nearest triangle along each ray (-1 where none) and its distance.

    Each chunk of rays is tested against the triangles of the runs of ``block`` triangles
    whose (widened) bounds one of its rays meets, in their order: a triangle left out has
    no hit on those rays, so the nearest hit, its distance and the first of equal distances
    are those of all the triangles."""
    A, B, C = (vertices[triangles[:, i]] for i in range(3))
    lo, hi = _block_boxes(A, B, C, block)
    e1_all, e2_all = B - A, C - A
    best_t = np.full(len(origins), np.inf)
    best = np.full(len(origins), -1)
    for s in range(0, len(origins), chunk):
        meets = _rays_meet_boxes(origins[s : s + chunk], dirs[s : s + chunk], lo, hi)
        runs = np.flatnonzero(meets.any(axis=0))
        keep = (runs[:, None] * block + np.arange(block)).ravel()
        keep = keep[keep < len(A)]
        if len(keep) == 0:
            continue
        a, e1, e2 = A[keep], e1_all[keep], e2_all[keep]
        o, d = origins[s : s + chunk, None], dirs[s : s + chunk, None]
        h = np.cross(d, e2)
        det = np.sum(e1 * h, axis=-1)
        ok = np.abs(det) > 1e-12
        inv = np.where(ok, 1.0 / np.where(ok, det, 1.0), 0.0)
        q = o - a
        u = np.sum(q * h, axis=-1) * inv
        k = np.cross(q, e1)
        v = np.sum(d * k, axis=-1) * inv
        t = np.sum(e2 * k, axis=-1) * inv
        hit = ok & (u >= 0) & (v >= 0) & (u + v <= 1) & (t > 1e-6)
        t = np.where(hit, t, np.inf)
        i = np.argmin(t, axis=1)
        tmin = t[np.arange(len(i)), i]
        best_t[s : s + chunk] = tmin
        best[s : s + chunk] = np.where(np.isfinite(tmin), keep[i], -1)
    return best, best_t


class Truth(NamedTuple):
    on: np.ndarray  # pixels showing a body
    reached: np.ndarray  # facing the light and inside the spot's cone
    shadow: np.ndarray  # reached and blocked
    band: np.ndarray  # within BAND pixels of an edge of the shadow, the lit region or a body
    points: np.ndarray  # (H, W, 3) the surface point of each pixel (NaN off the bodies)


class Surface(NamedTuple):
    on: np.ndarray  # (H W,) the pixel's ray hits a body
    p: np.ndarray  # (K, 3) the surface point of each of those pixels
    n: np.ndarray  # (K, 3) its unit face normal, on the side the camera sees


def visible_surface(bodies: list[Body], camera: Any) -> Surface:
    """The surface each pixel shows: its camera ray's nearest hit (the costly part of the
    ground truth; one per camera, whatever the light)."""
    origins, dirs = pixel_rays(camera)
    vertices = np.concatenate([b.vertices for b in bodies])
    offsets = np.cumsum([0] + [len(b.vertices) for b in bodies[:-1]])
    triangles = np.concatenate([b.triangles + o for b, o in zip(bodies, offsets, strict=True)])
    tri, t = first_hits(origins, dirs, vertices, triangles)
    on = tri >= 0
    p = origins[on] + t[on, None] * dirs[on]
    corners = vertices[triangles[tri[on]]]
    n = np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0])
    n *= -np.sign(np.sum(n * dirs[on], axis=1))[:, None]  # the side the camera sees
    n /= np.linalg.norm(n, axis=1, keepdims=True)
    return Surface(on, p, n)


#: Each (scene, viewing camera matrix)'s truth, cast once per session (the scene is kept
#: with it, so its id stays its own): several tests view the same torus scene.
_TRUTHS: dict[tuple[int, bytes], tuple[Scene, Truth]] = {}


def ground_truth(scene: Scene, camera: Any, surface: Surface | None = None) -> Truth:
    """The ray caster's picture of ``scene``'s light (read-only arrays, shared);
    ``surface``: the scene's :func:`visible_surface` from ``camera``, if already cast."""
    if surface is not None:
        return cast_truth(scene, surface)
    key = (id(scene), np.asarray(camera.camera_matrix, dtype=np.float64).tobytes())
    if key not in _TRUTHS:
        truth = cast_truth(scene, visible_surface(scene.bodies, camera))
        for a in truth:
            a.flags.writeable = False
        _TRUTHS[key] = (scene, truth)
    return _TRUTHS[key][1]


def cast_truth(scene: Scene, surface: Surface) -> Truth:
    """The ray caster's shadow of ``scene``'s light on the ``surface`` its camera sees."""
    on, p, n = surface
    if scene.kind == "directional":
        to_light, light = np.broadcast_to(scene.light, p.shape), np.append(scene.light, 0.0)
        inside = np.ones(len(p), dtype=bool)
    elif scene.kind == "point":
        to_light, light = scene.light - p, np.append(scene.light, 1.0)
        inside = np.ones(len(p), dtype=bool)
    else:
        to_light, light = scene.light - p, np.append(scene.light, 1.0)
        axis = (scene.aim - scene.light) / np.linalg.norm(scene.aim - scene.light)
        cos = -np.sum(to_light * axis, axis=1) / np.linalg.norm(to_light, axis=1)
        inside = cos > np.cos(scene.angle)
    reached = (np.sum(n * to_light, axis=1) > 0) & inside
    blocked = np.zeros(len(p), dtype=bool)
    for b in scene.bodies:
        if b.cast:
            blocked |= segment_hits_triangles(p + LIFT * n, light, b.vertices, b.triangles)

    def image(values, fill=False):
        out = np.full(on.shape, fill, dtype=values.dtype)
        out[on] = values
        return out.reshape(SIZE[1], SIZE[0])

    on_image = on.reshape(SIZE[1], SIZE[0])
    shadow = image(blocked & reached)
    dark = image(blocked | ~reached)
    band = edge_band(shadow, BAND) | edge_band(dark, BAND) | edge_band(on_image, BAND)
    points = np.full((len(on), 3), np.nan)
    points[on] = p
    return Truth(on_image, image(reached), shadow, band, points.reshape(SIZE[1], SIZE[0], 3))


class Count(NamedTuple):
    shadowed: int  # ground-truth shadow pixels
    lost: int  # in shadow, drawn lit, off the band
    acne: int  # lit, drawn in shadow, off the band
    unreached: int  # reached in truth but unlit in the unshadowed picture, off the band


def compare(picture: Picture, truth: Truth) -> Count:
    off = truth.on & truth.reached & ~truth.band
    return Count(
        shadowed=int(truth.shadow.sum()),
        lost=int((off & truth.shadow & ~picture.shadowed).sum()),
        acne=int((off & ~truth.shadow & picture.shadowed).sum()),
        unreached=int((off & ~picture.reached).sum()),
    )


# ---- the integration: exact matrices, pictures, resolution ----------------------------------


@pytest.mark.parametrize("name", FRUSTUM_SCENES)
def test_pygfx_draws_with_the_fitted_matrix(gfx, name):
    """What pygfx uploads each frame (its private update, run here) is the fit's matrix."""
    scene = SCENES[name]
    setup = fit(scene)
    _, _, light = pygfx_scene(scene, fitted=True)
    light._gfx_update_uniform_buffer()
    light.shadow._gfx_update_uniform_buffer(light)
    uploaded = light.uniform_buffer.data["light_view_proj_matrix"].T.astype(np.float64)
    expected = np.asarray(setup.blocker_to_clip)  # blocker_to_world is the identity
    # float32 entries of size up to ~5: a few float32 ulps
    assert np.max(np.abs(uploaded - expected)) < 1e-6 * max(1.0, np.abs(expected).max())
    # The casters land inside the map's border margins, as the fit promised.
    clip = np.c_[scene.casters(), np.ones(len(scene.casters()))] @ uploaded.T
    ndc = clip[:, :3] / clip[:, 3:]
    margins = np.array([setup.frustum.margin_x, setup.frustum.margin_y])
    assert np.all(np.abs(ndc[:, :2]) <= margins + 1e-6)  # the silhouette touches them
    assert np.all((ndc[:, 2] >= 0) & (ndc[:, 2] <= 1))
    # The spot's cone keeps its own aim: only the shadow camera follows the fit.
    if scene.kind == "spot":
        direction = light.uniform_buffer.data["direction"][:3]
        axis = (scene.aim - scene.light) / np.linalg.norm(scene.aim - scene.light)
        assert np.allclose(direction, axis, atol=1e-6)


@pytest.mark.parametrize("name", list(SCENES))
def test_pygfx_with_the_fit_loses_no_shadow_pixel(pygfx_canvas, name):
    scene = SCENES[name]
    picture = render(pygfx_canvas, scene, fitted=True)
    truth = ground_truth(scene, picture.camera)
    count = compare(picture, truth)
    print(f"{name}: {count}, peak {picture.peak:.2f}")
    assert picture.peak < 0.95, "the unshadowed picture must not clip"
    assert count.shadowed > 300, "the scene must show a sizeable shadow to test anything"
    assert count.unreached <= 0.005 * (truth.reached & truth.on).sum(), count
    assert count.lost == 0, count
    assert count.acne <= 0.005 * count.shadowed, count


@pytest.mark.parametrize("name", ["box, sun", "torus, sun"])
def test_pygfx_default_directional_camera_loses_shadow_pixels(pygfx_canvas, name):
    """The comparison can fail: pygfx's 1000 x 1000 box blurs the shadow into a faint smear."""
    scene = SCENES[name]
    picture = render(pygfx_canvas, scene, fitted=False)
    count = compare(picture, ground_truth(scene, picture.camera))
    print(f"{name}, pygfx default: {count}")
    assert count.lost > 0.5 * count.shadowed, count


#: Face i of a cube map: the axis it looks along (+X, -X, +Y, -Y, +Z, -Z).
FACE_AXES = np.array([[1, 0, 0], [-1, 0, 0], [0, 1, 0], [0, -1, 0], [0, 0, 1], [0, 0, -1]])


def face_errors(light: Any, position: np.ndarray, near: float, far: float) -> np.ndarray:
    """Per face, the largest error of the uploaded matrix against a 90-degree frustum along
    the face's axis: the point ``D (axis + a t1 + b t2)`` lands at NDC ``(+-a, +-b)`` or
    ``(+-b, +-a)`` (pygfx's shader reads each face's texels back with its own roll), at
    depth 0 for ``D = near`` and 1 for ``D = far``. The shader picks the face from the
    direction's major axis, so a face looking elsewhere loses that face's shadows."""
    faces = light.uniform_buffer.data["light_view_proj_matrix"].transpose(0, 2, 1)
    ab = np.random.default_rng(0).uniform(-0.9, 0.9, (20, 2))
    errors = []
    for M, axis in zip(faces.astype(np.float64), FACE_AXES, strict=True):
        t1, t2 = np.eye(3)[np.flatnonzero(axis == 0)]
        worst = 0.0
        for (a, b), (D, depth) in itertools.product(ab, ((near, 0.0), (far, 1.0))):
            clip = M @ np.append(position + D * (axis + a * t1 + b * t2), 1.0)
            if not clip[3] > 0:
                worst = np.inf
                continue
            ndc = clip[:3] / clip[3]
            xy = np.sort(np.abs(ndc[:2])) - np.sort(np.abs([a, b]))
            worst = max(worst, float(np.abs(xy).max()), abs(float(ndc[2]) - depth))
        errors.append(worst)
    return np.array(errors)


def test_pygfx_point_light_faces_as_the_shader_reads_them(gfx):
    """Each face's uploaded matrix maps the directions the shader samples to their NDC,
    with the fitted near plane at depth 0 and far at 1, also with a cutoff distance (from
    which pygfx alone resets the range). pygfx alone aims its +Y face wrong."""
    scene = SCENES["box, lamp"]
    depth_range = fit(scene)
    near, far = float(depth_range.near), float(depth_range.far)
    _, _, light = pygfx_scene(scene, fitted=True)
    light.distance = 5.0  # pygfx alone: depth_range (5e-5, 50) every frame
    light.shadow._gfx_update_uniform_buffer(light)
    assert light.shadow.camera.depth_range == (near, far)
    assert np.all(face_errors(light, scene.light, near, far) < 1e-5)
    # Without the integration: pygfx's range from the distance, and its +Y face looks away.
    _, _, plain = pygfx_scene(scene, fitted=False)
    plain.distance = 5.0
    plain.shadow._gfx_update_uniform_buffer(plain)
    assert plain.shadow.camera.depth_range == pytest.approx((5e-5, 50.0))
    errors = face_errors(plain, scene.light, *plain.shadow.camera.depth_range)
    # (float32 depth of a 1e6 depth ratio: 1e-3)
    assert errors[2] > 0.1 and np.all(np.delete(errors, 2) < 1e-3), errors


@pytest.mark.parametrize("name", ["box, lamp", "box, point toward +y"])
def test_pygfx_default_point_light_loses_shadows(pygfx_canvas, name):
    """The comparison can fail: pygfx's default cube depth range (0.5, 100000) clips every
    caster within 0.5 units of the light, so the lamp's box casts no shadow at all; and
    its +Y face looks away, so every shadow cast toward +Y is lost."""
    scene = SCENES[name]
    picture = render(pygfx_canvas, scene, fitted=False)
    truth = ground_truth(scene, picture.camera)
    count = compare(picture, truth)
    off_band = int((truth.on & truth.reached & ~truth.band & truth.shadow).sum())
    print(f"{name}, pygfx default: {count}, {off_band} shadow pixels off the band")
    assert off_band > 200 and count.lost == off_band, count


def test_pygfx_wrong_roll_loses_shadow_pixels(pygfx_canvas):
    """The up vector matters: the scene's up (0, 0, 1) instead of the fit's rolls the fitted
    box (twice as wide as high here) off the torus."""
    scene = SCENES["torus, sun"]
    world, camera, light = pygfx_scene(scene, fitted=True)
    light.shadow.camera.world.reference_up = (0.0, 0.0, 1.0)
    canvas_renderer = pygfx_canvas
    shaded = draw(canvas_renderer, world, camera)
    light.cast_shadow = False
    bare = draw(canvas_renderer, world, camera)
    picture = Picture(shaded < 0.5 * bare, bare > 0.01, light, camera, float(bare.max()))
    count = compare(picture, ground_truth(scene, camera))
    print(f"rolled: {count}")
    assert count.lost > 0.1 * count.shadowed, count


def world_to_texture(light: Any) -> np.ndarray:
    """pygfx's shadow lookup as shadowmath's world_to_texture: its camera's webgpu clip
    matrix, then the texture mapping pygfx's shader applies (s = (x+1)/2, t = (1-y)/2)."""
    clip = np.asarray(light.shadow.camera.camera_matrix, dtype=np.float64)
    return np.asarray(sm.api_convention(api="webgpu").clip_to_texture) @ clip


def texel_sizes(scene: Scene, canvas_renderer: Any = None) -> tuple[float, float]:
    """Median texel world size on the receivers' shadowed points: (pygfx default, fitted)."""
    from shadowmath.integrations.pygfx import PYGFX_SHADOW_MAP_SIZE

    sizes = []
    for fitted in (False, True):
        _, camera, light = pygfx_scene(scene, fitted=fitted)
        if not fitted:  # pygfx places its default camera in its once-a-frame update
            light._gfx_update_uniform_buffer()
            light.shadow._gfx_update_uniform_buffer(light)
        camera.set_view_size(*SIZE)
        truth = ground_truth(scene, camera)
        points = truth.points[truth.shadow]
        size = sm.texel_world_size(world_to_texture(light), points, map_size=PYGFX_SHADOW_MAP_SIZE)
        sizes.append(float(np.median(size)))
    return sizes[0], sizes[1]


@pytest.mark.parametrize("name", FRUSTUM_SCENES)
def test_pygfx_fit_makes_sharper_texels_than_the_defaults(gfx, name):
    default, fitted = texel_sizes(SCENES[name])
    print(f"{name}: texel {default:.4g} (pygfx default) vs {fitted:.4g} (fit), "
          f"{default / fitted:.1f}x sharper")  # fmt: skip
    if SCENES[name].kind == "directional":
        # 1000 world units over 1024 texels, everywhere
        assert default == pytest.approx(1000 / 1024, rel=1e-6)
        # the fit's box spans the casters' shadow width (a few units) plus its margins
        assert fitted < 6.0 / 1024
    assert default / fitted > 1.5


# ---- the docs page's example runs ------------------------------------------------------------


def test_docs_example_runs(pygfx_canvas, tmp_path, monkeypatch):
    """docs/pygfx.md's examples, executed as written, in order: the animated scene fitted
    by fit_scene_shadows leaves the lights as set and draws with the fits' matrices."""
    blocks = re.findall(r"```python\n(.*?)```", DOCS.read_text(), flags=re.DOTALL)
    assert len(blocks) == 2
    monkeypatch.chdir(tmp_path)
    namespace: dict[str, Any] = {"__name__": "docs_example"}
    exec(compile(blocks[0], str(DOCS), "exec"), namespace)
    assert (tmp_path / "pygfx_shadows.png").stat().st_size > 1000
    sun, spot, lamp = namespace["sun"], namespace["spot"], namespace["lamp"]
    a = 2 * np.pi * 7 / 8  # the last frame, as the example sets it
    assert np.array_equal(sun.local.position, [3 * np.cos(a), -1.5, 3.5])
    assert np.array_equal(namespace["toward_sun"], sun.local.position)  # its target: 0
    assert spot.angle == 0.7 and np.array_equal(spot.local.position, [3, -2, 4])
    reports = {type(r.light).__name__: r for r in namespace["reports"]}
    assert sorted(reports) == ["DirectionalLight", "PointLight", "SpotLight"]
    assert all(r.skipped == "" for r in reports.values()), reports
    for light in (sun, spot):  # what pygfx uploads each frame is the fit's matrix
        light.shadow._gfx_update_uniform_buffer(light)
        uploaded = light.uniform_buffer.data["light_view_proj_matrix"].T.astype(np.float64)
        expected = np.asarray(reports[type(light).__name__].fit.blocker_to_clip)
        assert np.allclose(uploaded, expected, atol=1e-6)
    exec(compile(blocks[1], str(DOCS), "exec"), namespace)
    setup, depth_range = namespace["setup"], namespace["depth_range"]
    sun.shadow._gfx_update_uniform_buffer(sun)
    uploaded = sun.uniform_buffer.data["light_view_proj_matrix"].T.astype(np.float64)
    assert np.allclose(uploaded, setup.blocker_to_clip, atol=1e-6)
    assert lamp.shadow.camera.depth_range == (float(depth_range.near), float(depth_range.far))


# ---- arguments -------------------------------------------------------------------------------


def test_pygfx_bad_arguments(gfx):
    from shadowmath.integrations.pygfx import set_shadow_camera

    directional = fit(SCENES["box, sun"])
    spot = fit(SCENES["box, spot"])
    with pytest.raises(ValueError, match="PointLight's six cube faces are fixed"):
        set_shadow_camera(gfx.PointLight(), spot)
    with pytest.raises(ValueError, match="DirectionalLight, SpotLight or PointLight"):
        set_shadow_camera(gfx.AmbientLight(), spot)
    cube = fit(SCENES["box, lamp"])
    with pytest.raises(ValueError, match="CubeDepthRange is a point light's"):
        set_shadow_camera(gfx.SpotLight(), cube)
    with pytest.raises(ValueError, match=r"one light's depth range .* \(2,\)"):
        set_shadow_camera(gfx.PointLight(), sm.CubeDepthRange(np.ones(2), np.full(2, 3.0)))
    with pytest.raises(ValueError, match=r"finite 0 < near < far, got near 2\.0, far 1\.0"):
        set_shadow_camera(gfx.PointLight(), sm.CubeDepthRange(np.float64(2), np.float64(1)))
    with pytest.raises(ValueError, match="orthographic fit"):
        set_shadow_camera(gfx.DirectionalLight(), spot)
    with pytest.raises(ValueError, match="perspective fit"):
        set_shadow_camera(gfx.SpotLight(), directional)
    with pytest.raises(ValueError, match="ShadowSetup or ShadowCamera"):
        set_shadow_camera(gfx.SpotLight(), np.eye(4))
    batch = sm.fit_shadow(
        sm.PointLight(np.array([[0.0, 0.0, 5.0], [1.0, 0.0, 5.0]])), BOX.vertices, 1024
    )
    with pytest.raises(ValueError, match=r"one light's fit .* \(2, 3\)"):
        set_shadow_camera(gfx.SpotLight(), batch)
    nan = sm.shadow_camera(spot)._replace(near=np.float64(np.nan))
    with pytest.raises(ValueError, match="non-finite"):
        set_shadow_camera(gfx.SpotLight(), nan)
    wide = sm.shadow_camera(spot)._replace(left=np.float64(-300.0))
    with pytest.raises(ValueError, match="wider than pygfx's 179"):
        set_shadow_camera(gfx.SpotLight(), wide)


def test_pygfx_narrow_fit_widens_the_frustum_and_cuts_the_window(gfx):
    """A field of view under pygfx's 1-degree floor: the view offset keeps the exact window."""
    from shadowmath.integrations.pygfx import set_shadow_camera

    far_light = sm.PointLight(np.array([0.0, -200.0, 150.0]))
    setup = sm.fit_shadow(far_light, BOX.vertices, 1024, pcf_radius=2, api="webgpu")
    cam = sm.shadow_camera(setup)
    assert np.degrees(2 * np.arctan(0.5 * (cam.width + cam.height) / 2)) < 1.0
    camera = set_shadow_camera(gfx.SpotLight(), setup)
    assert camera.fov == pytest.approx(1.0, abs=1e-9)
    assert np.allclose(camera.camera_matrix, setup.blocker_to_clip, rtol=1e-6, atol=1e-5)


#: A fresh process: the GL context first, then pygfx's first renderer, whose wgpu instance
#: (probing every backend, EGL included) leaves its own context current; then a render.
AFTER_PYGFX = """
import numpy as np, pygfx as gfx, shadowmath as sm
from rendercanvas.offscreen import RenderCanvas
from shadowmath.render import render_shadow_map, standalone_context
gl = standalone_context()
gfx.renderers.WgpuRenderer(RenderCanvas(size=(8, 8), pixel_ratio=1))
box = np.array([[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (4, 6)], float)
setup = sm.fit_shadow([0.0, 0.0, 0.0], box, 16)
mask = render_shadow_map(box, [[0, 4, 6], [0, 6, 2]], setup.blocker_to_clip, 16, ctx=gl)
assert mask[0].max() == 0 and mask[1:-1, 1:-1].min() == 1  # the border, the face
print("drawn")
"""


def test_the_reference_renderer_draws_after_pygfx(pygfx_canvas, gl):
    """pygfx's first renderer leaves another context current on the thread; the reference
    renderer's functions make theirs current again (render.resolve_context) instead of
    failing every GL call ("cannot create buffer")."""
    import subprocess
    import sys

    run = subprocess.run([sys.executable, "-c", AFTER_PYGFX], capture_output=True, text=True,
                         timeout=300, check=False)  # fmt: skip
    assert run.returncode == 0 and "drawn" in run.stdout, run.stderr[-2000:]
