r"""pygfx integration: give a pygfx light the shadow camera of a shadowmath fit.

pygfx (the wgpu-based Python renderer) draws every shadow map at
:data:`PYGFX_SHADOW_MAP_SIZE` texels square, through a camera each light's ``shadow``
object owns: a directional light's is a fixed 1000 x 1000 orthographic box centred on
the light's position, a spot light's a perspective frustum whose field of view pygfx
rebuilds from ``light.angle`` every frame. :func:`set_shadow_camera` replaces that camera's
window, depth range and roll with those of a fit (:func:`shadowmath.shadow_camera`), so
pygfx draws and samples exactly the fitted map (its clip matrix is the fit's
``blocker_to_clip`` for ``api="webgpu"``, to float32 rounding):

The light itself is never written: its position, target, angle, distance, intensity
and every other setting stay what the application set, after every frame; only the
shadow object's camera and the matrices pygfx draws and samples with change.

* **directional** and **spot**: the camera gets ``width``, ``height``, ``fov`` (0 for
  the sun's orthographic box) and ``set_view_offset`` for the window (off-centre where
  the fit clipped it to the cone), ``depth_range = (near, far)`` measured from the eye,
  and ``reference_up = up`` (pygfx's look-at keeps the camera's up closest to it; any
  other up rolls the map). pygfx offers no public hook for the camera's place: once a
  frame its shadow object's ``_update_matrix`` puts the camera at the light, aims it at
  the light's target (and, for a spot light, rebuilds the field of view from
  ``light.angle``) and uploads its matrix. That method is replaced, on that one light's
  shadow object, by one that puts the camera at the fit's ``eye`` (the centre of the
  fitted box for a sun, the light for a spot), aims it along ``forward`` and uploads the
  matrix as pygfx does. Refit when the light or the casters move
  (:func:`fit_scene_shadows` does it for a whole scene, once a frame).
* **point**: pygfx samples a point light's cube map through six fixed 90-degree faces
  whose orientation its shader hard-codes (``uv_to_direction``), so only the depth range
  can be fitted: :func:`shadowmath.cube_depth_range` of the light's position and the
  casters (and receivers) instead of pygfx's default ``(0.5, 100000)``, whose near plane
  clips every caster within 0.5 units of the light. pygfx resets the range every frame
  from ``light.distance`` when that is nonzero, so the shadow object's ``_update_matrix``
  is wrapped, on that one light, to run with a cutoff distance of 0 (the light's
  attenuation keeps its ``distance``) and then to aim the +Y face right: pygfx 0.17's
  ``look_at`` of a direction parallel to the camera's up (0, 1, 0) leaves that face
  looking down -Z, which loses every shadow cast toward +Y.

**The cache.** :func:`fit_scene_shadows` keeps, per pygfx scene (a
:class:`weakref.WeakKeyDictionary` keyed by the object it is given: dropped with it), an
:class:`shadowmath.ShadowScene`: one object per visible ``gfx.Mesh`` with
``cast_shadow`` or ``receive_shadow`` (one per instance of a ``gfx.InstancedMesh``,
placed by its world matrix times the instance's), each geometry summarized once (its
own triangles when few, else its 26-DOP's surface). A call reads the meshes, their flags,
instance counts and geometries' versions; if any of these changed (a mesh added, removed,
hidden or shown, a flag or an instance count changed, a geometry's data edited) the
``ShadowScene`` is rebuilt, reusing the summaries of the geometries whose data did not
change. Then the world matrices (and instance matrices) are read and set with
``set_transforms``, and every light is fitted through ``ShadowScene.fit``. A geometry's
version is pygfx's ``rev`` of its ``positions`` and ``indices`` buffers (globally
unique, renewed by ``update_range``, ``update_full`` and ``set_data``, but in pygfx 0.17
only once the buffer has been uploaded to the GPU) with a fingerprint of their values (a
weighted sum, computed each call: about 1 ms per million floats), so an edit made before
the first draw, or made in place without telling pygfx, is seen too. A new ``Buffer``
assigned to ``geometry.positions`` is a new version.

**Draw lists.** Each :class:`LightFit` lists, per map, the meshes (and instances) that
can cast into it: ``ShadowScene``'s culling by bounding spheres (a spot light's cone, a
cube face's pyramid). pygfx 0.17 cannot use them: its shadow pass
(``renderers/wgpu/engine/shadowutil.py``, ``render_shadow_maps``) draws every
shadow-casting object, all its instances, into every map of every shadow-casting light
(one pass per sun or spot, six per point light). A renderer that honoured the lists would
skip the other draws; in the 50-mesh scene of ``benchmarks/bench_pygfx.py`` (1 sun, 6
spots, 4 point lights: 35 maps) they hold about 385 of the 2,015 (object, map) draws,
81 % saved.

The map size is one module-level constant in pygfx's private renderer code, the same
for every light; fit with ``map_size=PYGFX_SHADOW_MAP_SIZE``, ``pcf_radius=2`` and
``pcf_filter="bilinear"`` (pygfx filters with 17 taps up to 2 texels away through a
linear comparison sampler, which reads one texel further: a 3-texel border, as
:func:`shadowmath.pcf_border_texels` says), and ``api="webgpu"`` if you also use the
fit's matrices yourself. The overrides are checked against pygfx's private API at every
call (``_update_matrix``, the shadow's matrix buffer and the light uniform's
``light_view_proj_matrix``: :class:`RuntimeError` if one is gone) and pygfx versions
outside :data:`TESTED_PYGFX` warn.
"""

from __future__ import annotations

import math
import warnings
import weakref
from typing import Any, Final, NamedTuple

import numpy as np

from shadowmath import (
    CubeDepthRange,
    DirectionalLight,
    GeometrySummary,
    LightShadows,
    Mesh,
    PointLight,
    ShadowCamera,
    ShadowMapSpec,
    ShadowScene,
    ShadowSetup,
    SpotLight,
    cube_depth_range,
    fit_shadow,
    gather_meshes,
    shadow_camera,
    summarize_geometry,
)

try:
    import pygfx as gfx
    from pygfx.objects._lights import LightShadow as _LightShadow
    from pygfx.objects._lights import PointLightShadow as _PointLightShadow
    from pygfx.objects._lights import get_pos_from_camera_parent_or_target as _aimed_at
except ImportError as err:  # pragma: no cover - the extra is part of `dev`
    raise ImportError(
        "shadowmath.integrations.pygfx needs pygfx: pip install 'shadowmath[pygfx]'"
    ) from err

__all__ = [
    "PYGFX_SHADOW_MAP_SIZE",
    "TESTED_PYGFX",
    "DrawItem",
    "LightFit",
    "SceneSurfaces",
    "fit_scene_shadows",
    "gather_scene",
    "set_shadow_camera",
]

#: Texels along each side of every pygfx shadow map (``LightRenderState.shadow_map_size``
#: in pygfx 0.17, not configurable): the ``map_size`` to fit with.
PYGFX_SHADOW_MAP_SIZE: Final = 1024

#: The pygfx versions ``[first, last)`` this integration is tested with.
TESTED_PYGFX: Final = ((0, 17), (0, 18))

# pygfx clamps a field of view below 1 degree up to 1 (and 0 means orthographic), and
# one above 179 down to 179.
_MIN_HALF_TAN: Final = math.tan(math.radians(0.5))
_MAX_HALF_TAN: Final = math.tan(math.radians(89.5))


def set_shadow_camera(light: Any, fit: ShadowSetup | ShadowCamera | CubeDepthRange) -> Any:
    r"""Make a pygfx light draw and sample the shadow map of a fit.

    A point light takes the :class:`~shadowmath.CubeDepthRange` of
    :func:`shadowmath.cube_depth_range` fitted at its position: its shadow camera's depth
    range becomes ``(near, far)`` (its six faces are fixed; see the module docstring).
    A directional or spot light takes a fit, and this sets, on ``light.shadow.camera``
    only (the light is not written): its place to the fit's ``eye`` looking along
    ``forward``, kept there every frame by the override of the module docstring, its
    ``reference_up`` to ``up``, its depth range to ``(near, far)`` and its window. A
    perspective window ``[l, r] x [b, t]`` (tangents) is cut out of the symmetric frustum
    of half-extents :math:`X = \max(-l, r)`, :math:`Y = \max(-b, t)`, whose field of view
    pygfx reads as

    .. math:: \mathrm{fov} = 2 \arctan\frac{X + Y}{2}, \qquad \mathrm{aspect} = X / Y,

    by ``set_view_offset(2X, 2Y, l + X, Y - t, r - l, t - b)`` (offsets from the top-left
    corner); an orthographic window the same way in world units. Call it again whenever
    you refit (the casters or the light moved).

    Arguments:
        light: a ``pygfx.DirectionalLight`` (with an orthographic fit: ``sm.fit_shadow``
            of an ``sm.DirectionalLight``), a ``pygfx.SpotLight`` (with a perspective
            fit: an ``sm.SpotLight``, whose frame's ``Z`` is the cone's axis, or an
            ``sm.PointLight``), or a ``pygfx.PointLight``. Fit along the direction pygfx
            lights with (from the light to its target, or along the camera's view for a
            light parented to a camera).
        fit: one light's :class:`ShadowSetup` (from :func:`shadowmath.fit_shadow`, no
            batch) or :class:`ShadowCamera` (from :func:`shadowmath.shadow_camera`); for
            a point light, one :class:`CubeDepthRange` (scalar ``near`` and ``far``).

    Returns:
        ``light.shadow.camera``, the pygfx camera now placed as the fit's: its
        ``camera_matrix`` is the fit's world-to-clip matrix for ``api="webgpu"`` (for a
        point light, the camera pygfx turns to each face, with the fitted depth range).

    Raises:
        ValueError: a light that is not a pygfx directional, spot or point light, a fit
            that is not a ``ShadowSetup`` or ``ShadowCamera`` (a ``CubeDepthRange`` for a
            point light), a batch of fits, an orthographic
            fit for a spot light or a perspective one for a directional light, non-finite
            fields, a field of view wider than pygfx's 179 degrees, a depth range without
            ``0 < near < far``.
        RuntimeError: pygfx lacks the private ``_update_matrix`` methods, matrix buffer
            or uniform field the overrides replace and write.

    Example:
        >>> import numpy as np, pygfx as gfx, shadowmath as sm
        >>> cube = np.array([[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (0, 2)])
        >>> setup = sm.fit_shadow(sm.DirectionalLight([1.0, 0.5, 2.0]), cube,
        ...                       PYGFX_SHADOW_MAP_SIZE, pcf_radius=2, pcf_filter="bilinear",
        ...                       api="webgpu")
        >>> sun = gfx.DirectionalLight(cast_shadow=True)
        >>> camera = set_shadow_camera(sun, setup)
        >>> camera.width < 4 < 1000  # the cube's box, not pygfx's default 1000 x 1000
        True
        >>> world_to_clip = setup.blocker_to_clip  # blocker_to_world is the identity
        >>> bool(np.allclose(camera.camera_matrix, world_to_clip, atol=1e-6))
        True
    """
    _check_pygfx(light)
    kind = _light_kind(light)
    if kind == "point":
        return _set_cube_depth(light, fit)
    cam = _one_camera(fit)
    if cam.orthographic != (kind == "directional"):
        wanted = "an orthographic" if kind == "directional" else "a perspective"
        raise ValueError(
            f"fit: a pygfx {kind} light needs {wanted} fit (fit_shadow of an sm."
            f"{'DirectionalLight' if kind == 'directional' else 'SpotLight or sm.PointLight'})"
        )
    camera = light.shadow.camera
    _set_window(camera, cam)  # first: it refuses a field of view pygfx cannot draw
    camera.world.reference_up = cam.up
    camera.maintain_aspect = False
    camera.zoom = 1.0
    camera.depth_range = (cam.near, cam.far)
    _hold_camera(light.shadow, cam.eye, cam.forward)
    _aim(camera, cam.eye, cam.forward)  # what the override does each frame, now
    return camera


class SceneSurfaces(NamedTuple):
    """A pygfx scene's shadow casters and receivers in world coordinates.

    Attributes:
        casters: :class:`~shadowmath.Mesh` of the visible meshes with ``cast_shadow``.
        receivers: :class:`~shadowmath.Mesh` of those with ``receive_shadow``.
    """

    casters: Mesh
    receivers: Mesh


#: One entry of a draw list: ``(mesh, instance)``, a ``gfx.Mesh`` and None, or a
#: ``gfx.InstancedMesh`` and the index of one of its instances.
DrawItem = tuple[Any, int | None]


class LightFit(NamedTuple):
    """What :func:`fit_scene_shadows` did for one shadow-casting light.

    Attributes:
        light: the pygfx light.
        fit: its :class:`~shadowmath.ShadowSetup` (sun, spot) or
            :class:`~shadowmath.CubeDepthRange` (point light), or None where skipped.
        skipped: "" when fitted; else why not (the fit's ``ValueError`` message, or that
            the scene casts no shadow). A skipped light draws with pygfx's own shadow
            camera, as if never fitted.
        draws: one draw list per shadow map (one for a sun or a spot, six cube faces
            ``+X, -X, +Y, -Y, +Z, -Z`` for a point light): the :data:`DrawItem` that can
            cast into that map, in scene order (``sm.ShadowScene``'s culling); the others
            cast nothing a texel of it samples. pygfx 0.17 draws every caster into every
            map, so these are information only (see the module docstring). Empty for a
            skipped light.
    """

    light: Any
    fit: ShadowSetup | CubeDepthRange | None
    skipped: str
    draws: tuple[tuple[DrawItem, ...], ...] = ()


def gather_scene(scene: Any) -> SceneSurfaces:
    r"""The casters and receivers of a pygfx scene, in world coordinates.

    Every visible ``gfx.Mesh`` under ``scene`` (pygfx draws nothing under an invisible
    parent) with ``cast_shadow`` is a caster and with ``receive_shadow`` a receiver:
    its geometry's ``positions`` and ``indices`` placed by its ``world.matrix`` (times
    each instance's matrix for a ``gfx.InstancedMesh``), gathered by
    :func:`shadowmath.gather_meshes`: :math:`w = M_\text{world} (v, 1)`, faces offset.
    pygfx also draws points and lines with ``cast_shadow`` into its shadow maps; they are
    not gathered, so their shadows may fall outside the fitted maps: give them no
    ``cast_shadow``, or add a mesh around them.

    Arguments:
        scene: a pygfx ``WorldObject``, usually the ``gfx.Scene``.

    Returns:
        :class:`SceneSurfaces`: two :class:`~shadowmath.Mesh`, float64 vertices
        ``(V, 3)`` and int64 faces ``(F, 3)``; empty ``(0, 3)`` where no mesh has the flag.

    Raises:
        ValueError: from :func:`shadowmath.gather_meshes`, naming the entry: a mesh
            with non-finite positions, indices outside its positions or a projective
            world matrix.

    Example:
        >>> import pygfx as gfx
        >>> scene = gfx.Scene()
        >>> floor = gfx.Mesh(gfx.plane_geometry(4, 4), gfx.MeshPhongMaterial())
        >>> floor.receive_shadow = True
        >>> cube = gfx.Mesh(gfx.box_geometry(1, 1, 1), gfx.MeshPhongMaterial())
        >>> cube.cast_shadow = True
        >>> cube.local.position = (0, 0, 3)
        >>> _ = scene.add(floor, cube)
        >>> surfaces = gather_scene(scene)
        >>> surfaces.casters.vertices[:, 2].min(), surfaces.receivers.faces.shape
        (np.float64(2.5), (2, 3))
    """
    casters: list[tuple[Any, Any]] = []
    receivers: list[tuple[Any, Any]] = []
    for mesh in scene.iter(lambda o: isinstance(o, gfx.Mesh), skip_invisible=True):
        if not (mesh.cast_shadow or mesh.receive_shadow):
            continue
        part = _geometry_mesh(mesh.geometry)
        for matrix in _placements(mesh):
            if mesh.cast_shadow:
                casters.append((part, matrix))
            if mesh.receive_shadow:
                receivers.append((part, matrix))
    return SceneSurfaces(gather_meshes(casters), gather_meshes(receivers))


def _placements(mesh: Any) -> list[np.ndarray]:
    world = np.asarray(mesh.world.matrix, dtype=np.float64)
    if not isinstance(mesh, gfx.InstancedMesh):
        return [world]
    count = mesh.instance_buffer.nitems
    return [world @ np.asarray(mesh.get_matrix_at(i), dtype=np.float64) for i in range(count)]


def fit_scene_shadows(scene: Any, *, pcf_radius: int = 2) -> list[LightFit]:
    """Fit the shadow camera of every shadow-casting light of a pygfx scene: one call
    per frame, before drawing it.

    The scene's casters and receivers are kept between calls in an
    :class:`shadowmath.ShadowScene` cached for ``scene`` (see "The cache" in the module
    docstring): each visible ``gfx.Mesh`` with ``cast_shadow`` or ``receive_shadow`` is
    one object (a ``gfx.InstancedMesh`` one per instance, placed by its world matrix
    times the instance's), its geometry summarized once. Each call reads the world
    matrices and each visible light with ``cast_shadow`` (sun, spot or point) as pygfx
    lights it this frame, fits it through :meth:`shadowmath.ShadowScene.fit`, and hands
    the fit to :func:`set_shadow_camera`:

    * ``gfx.DirectionalLight``: ``sm.DirectionalLight(position - target)`` (the camera's
      view direction for a light parented to a camera, as pygfx does);
    * ``gfx.SpotLight``: ``sm.SpotLight(position, target - position, angle)``, fitted to
      the casters whose bounding sphere reaches into its cone (clipped exactly:
      :func:`shadowmath.fit_shadow`'s selection); both with the receivers,
      :data:`PYGFX_SHADOW_MAP_SIZE`, ``pcf_radius``, ``pcf_filter="bilinear"`` and
      ``api="webgpu"``;
    * ``gfx.PointLight``: :func:`shadowmath.cube_depth_range` at its position, of the
      casters, with the receivers (no border ring: pygfx's cube faces are exact
      90-degree frustums).

    The fits read each geometry's summary (its own triangles when they are few, else its
    26-DOP's surface, which holds it): every caster lies in its map, which may be a
    little larger than one fitted to every triangle (equal where the summaries are the
    triangles, as for boxes). Each :class:`LightFit` also lists, per map, the meshes and
    instances that can cast into it (``draws``).

    The lights themselves are read, never written: position, target, angle, distance,
    intensity and every other setting stay what the application set (only each light's
    ``shadow.camera`` and the matrices pygfx draws with change). A light whose fit
    raises ``ValueError`` (no casters, a caster within rounding of the light...) is skipped,
    given back to pygfx's own shadow camera, and reported; the others are fitted.

    Arguments:
        scene: a pygfx ``WorldObject``, usually the ``gfx.Scene`` that is drawn.
        pcf_radius: the kernel radius pygfx filters with (taps up to 2 texels away, each
            bilinear: the border is ``pcf_border_texels(pcf_radius, "bilinear")``, 3).

    Returns:
        One :class:`LightFit` per shadow-casting light, in scene order.

    Raises:
        ValueError: a ``pcf_radius`` that is not an integer >= 0; bad geometry (see
            :func:`gather_scene`).
        RuntimeError: pygfx lacks the private API the overrides use.

    Example:
        >>> import pygfx as gfx
        >>> scene = gfx.Scene()
        >>> cube = gfx.Mesh(gfx.box_geometry(1, 1, 1), gfx.MeshPhongMaterial())
        >>> cube.cast_shadow = True
        >>> sun = gfx.DirectionalLight(cast_shadow=True)
        >>> sun.local.position = (3, -1.5, 3.5)
        >>> inside = gfx.SpotLight(cast_shadow=True)  # at the cube's centre, aimed down -z
        >>> _ = scene.add(cube, sun, sun.target, inside, inside.target)
        >>> fits = fit_scene_shadows(scene)
        >>> [(type(r.light).__name__, r.skipped) for r in fits]
        [('DirectionalLight', ''), ('SpotLight', '')]
        >>> int(fits[1].fit.casters_used)  # the cube's triangles that reach into the cone
        10
        >>> fits[1].draws == (((cube, None),),)  # one map, the cube drawn into it
        True
        >>> sun.local.position.tolist()  # the user's light, untouched
        [3.0, -1.5, 3.5]
    """
    _check_pygfx()
    if isinstance(pcf_radius, bool) or not isinstance(pcf_radius, int) or pcf_radius < 0:
        raise ValueError(f"pcf_radius: expected an integer >= 0, got {pcf_radius!r}")
    kinds = (gfx.DirectionalLight, gfx.SpotLight, gfx.PointLight)
    lights = list(scene.iter(lambda o: isinstance(o, kinds) and o.cast_shadow, skip_invisible=True))
    state = _CACHE.get(scene)
    if state is None:
        state = _CACHE[scene] = _SceneState()
    shadow_scene = state.update(scene)
    if shadow_scene is None:
        for light in lights:
            _release(light)
        return [LightFit(light, None, _NO_CASTER) for light in lights]
    spec = ShadowMapSpec(
        PYGFX_SHADOW_MAP_SIZE, pcf_radius=pcf_radius, pcf_filter="bilinear", api="webgpu"
    )
    converted = [_sm_light(light) for light in lights]
    flat = [i for i, c in enumerate(converted) if isinstance(c, SpotLight | DirectionalLight)]
    cube = [i for i, c in enumerate(converted) if type(c) is PointLight]
    fits: dict[int, LightShadows] = {}
    for group, group_spec in ((flat, spec), (cube, _CUBE_SPEC)):
        ready = [converted[i] for i in group]
        done = shadow_scene.fit(ready, group_spec) if ready else []  # type: ignore[arg-type]
        fits.update(zip(group, done, strict=True))
    reports = []
    for i, light in enumerate(lights):
        sm_light = converted[i]
        if isinstance(sm_light, str):
            _release(light)
            reports.append(LightFit(light, None, sm_light))
            continue
        result = fits[i]
        if result.fit is None and isinstance(sm_light, SpotLight) and result.skipped == _NO_REACH:
            result = _empty_spot(shadow_scene, result, spec)
        reports.append(_hand_over(light, result, state.items))
    return reports


_NO_CASTER: Final = "the scene has no visible mesh with cast_shadow"
_NO_REACH: Final = "no caster in the light's reach"  # ShadowScene.fit's
#: A point light's cube map: the size pygfx draws, no border (its faces are exact).
_CUBE_SPEC: Final = ShadowMapSpec(PYGFX_SHADOW_MAP_SIZE, border_texels=0)


def _sm_light(light: Any) -> PointLight | SpotLight | DirectionalLight | str:
    """The shadowmath light pygfx lights with this frame, or why there is none."""
    position = np.asarray(light.world.position, dtype=np.float64)
    if not np.all(np.isfinite(position)):
        return "the light's world position contains non-finite values (NaN or inf)"
    if isinstance(light, gfx.PointLight):
        return PointLight(position)
    aim = np.asarray(_aimed_at(light), dtype=np.float64) - position
    if not np.all(np.isfinite(aim)):
        return "the light's target contains non-finite values (NaN or inf)"
    if not np.any(aim):  # pygfx's light shines down -z then
        aim = np.array([0.0, 0.0, -1.0])
    if isinstance(light, gfx.DirectionalLight):
        return DirectionalLight(-aim)
    angle = np.float64(light.angle)
    if not np.isfinite(angle):
        return "the spot light's angle is not finite"
    return SpotLight(position, aim, angle)


def _empty_spot(scene: ShadowScene, result: LightShadows, spec: ShadowMapSpec) -> LightShadows:
    """A spot light none of whose casters' spheres reach its cone: the fit of every
    caster's summary, as the per-frame path made it (its selection keeps none: an empty
    map that shadows nothing; or the ``ValueError`` that path reported)."""
    casters = scene._triangles(scene._casts)  # shadowmath's own class
    try:
        fit = fit_shadow(result.light, casters, spec)
    except ValueError as err:
        return LightShadows(result.light, None, result.draws, str(err))
    return LightShadows(result.light, fit, result.draws, "")


def _hand_over(light: Any, result: LightShadows, items: list[DrawItem]) -> LightFit:
    """One light's fit set on it (and its draw lists), or the light released."""
    fit = result.fit
    if fit is None:
        _release(light)
        return LightFit(light, None, result.skipped)
    try:
        set_shadow_camera(light, fit)
    except ValueError as err:
        _release(light)
        return LightFit(light, None, str(err))
    draws = tuple(tuple([items[k] for k in d.tolist()]) for d in result.draws)
    return LightFit(light, fit, "", draws)


#: A geometry's data version: ``positions.rev``, ``indices.rev`` (or -1) and the
#: :func:`_fingerprint` of each.
_Version = tuple[int, int, float, float]

_WEIGHTS = np.zeros(0)


def _fingerprint(data: Any) -> float:
    """A weighted sum of an array's values, with fixed pseudo-random weights: it changes
    when values change (in place too), with probability 1; NaN when one is NaN."""
    global _WEIGHTS
    flat = np.asarray(data).reshape(-1)
    if len(flat) > len(_WEIGHTS):
        _WEIGHTS = np.random.default_rng(2026).uniform(0.5, 1.5, max(len(flat), 2 * len(_WEIGHTS)))
    return float(np.dot(flat, _WEIGHTS[: len(flat)]))


class _SceneState:
    """What :func:`fit_scene_shadows` keeps of one pygfx scene between calls.

    ``summaries`` maps a geometry's data version (:data:`_Version`: pygfx's revision
    numbers, globally unique, and a fingerprint of the positions' and indices' values:
    pygfx 0.17 renews ``rev`` on ``update_range``/``update_full`` only once the buffer has
    been uploaded, so an edit before the first draw, or one without telling pygfx, is
    seen by the fingerprint alone) to its summary (None: no faces); ``key`` is the
    structure the
    :class:`ShadowScene` was built for: per mesh in scene order, ``(version,
    cast_shadow, receive_shadow, instance count)``, and ``refs`` the meshes themselves
    (weakly: the cache must not keep a scene alive).
    """

    def __init__(self) -> None:
        self.summaries: dict[_Version, GeometrySummary | None] = {}
        self.refs: list[weakref.ref[Any]] = []
        self.key: list[tuple[_Version, bool, bool, int]] = []
        self.scene: ShadowScene | None = None
        self.items: list[DrawItem] = []  # per ShadowScene object: its mesh and instance
        self.meshes: list[Any] = []  # those with an object, in scene order
        self.rebuilds = 0

    def update(self, root: Any) -> ShadowScene | None:
        """The scene's :class:`ShadowScene` for this frame (rebuilt if its meshes, their
        flags, instance counts or geometry versions changed; its transforms set), or None
        when nothing casts."""
        meshes, key = [], []
        sums: dict[int, _Version] = {}  # this frame's, per geometry
        for mesh in root.iter(lambda o: isinstance(o, gfx.Mesh), skip_invisible=True):
            cast, receive = bool(mesh.cast_shadow), bool(mesh.receive_shadow)
            if not (cast or receive):
                continue
            geometry = mesh.geometry
            positions, indices = geometry.positions, getattr(geometry, "indices", None)
            version = sums.get(id(geometry))
            if version is None:
                version = sums[id(geometry)] = (
                    positions.rev,
                    -1 if indices is None else indices.rev,
                    _fingerprint(positions.data),
                    0.0 if indices is None else _fingerprint(indices.data),
                )
            count = mesh.instance_buffer.nitems if isinstance(mesh, gfx.InstancedMesh) else 1
            meshes.append(mesh)
            key.append((version, cast, receive, count))
        same = key == self.key and all(r() is m for r, m in zip(self.refs, meshes, strict=True))
        if not same:
            self._rebuild(root, meshes, key)
        scene = self.scene
        if scene is None:
            return None
        try:
            scene.set_transforms(self._transforms())
        except ValueError:
            gather_scene(root)  # raises the per-entry message (a projective matrix...)
            raise
        return scene

    def _transforms(self) -> np.ndarray:
        """``(N, 4, 4)`` every object's world matrix this frame."""
        out = [_world_matrices(mesh) for mesh in self.meshes]
        return np.concatenate(out) if out else np.zeros((0, 4, 4))

    def _rebuild(self, root: Any, meshes: list[Any], key: list[Any]) -> None:
        self.rebuilds += 1
        summaries: dict[_Version, GeometrySummary | None] = {}
        scene, items, placed, index = ShadowScene(), [], [], {}
        casting = False
        for mesh, (version, cast, receive, count) in zip(meshes, key, strict=True):
            if version not in summaries:
                known = version in self.summaries
                summaries[version] = (
                    self.summaries[version] if known else _summarize(root, mesh.geometry)
                )
            summary = summaries[version]
            if summary is None or count == 0:
                continue  # no faces or no instances: nothing drawn, nothing to fit
            if version not in index:
                index[version] = scene.add_geometry(summary)
            try:
                scene.add_objects(index[version], _world_matrices(mesh), casts=cast,
                                  receives=receive)  # fmt: skip
            except ValueError:
                gather_scene(root)  # raises the per-entry message (a projective matrix...)
                raise
            instanced = isinstance(mesh, gfx.InstancedMesh)
            items += [(mesh, k if instanced else None) for k in range(count)]
            placed.append(mesh)
            casting = casting or cast
        self.summaries = summaries  # those of the scene's geometries only
        self.refs = [weakref.ref(m) for m in meshes]
        self.key, self.items, self.meshes = key, items, placed
        self.scene = scene if casting else None


#: The per-scene caches of :func:`fit_scene_shadows`, dropped with their scene.
_CACHE: weakref.WeakKeyDictionary[Any, _SceneState] = weakref.WeakKeyDictionary()


def _geometry_mesh(geometry: Any) -> Mesh:
    """A pygfx geometry's ``positions`` and ``indices`` (or its positions three at a time)
    as an :class:`~shadowmath.Mesh` in its local coordinates."""
    positions = np.asarray(geometry.positions.data)[:, :3]
    indices = getattr(geometry, "indices", None)
    faces = (
        np.arange(len(positions) - len(positions) % 3)
        if indices is None
        else np.asarray(indices.data)
    )
    return Mesh(positions, faces.reshape(-1, 3).astype(np.int64))


def _summarize(root: Any, geometry: Any) -> GeometrySummary | None:
    """A pygfx geometry's summary (None: no faces), or gather_scene's ValueError."""
    mesh = _geometry_mesh(geometry)
    if len(mesh.faces) == 0:
        return None
    try:
        return summarize_geometry(mesh)
    except ValueError:
        gather_scene(root)  # raises the per-entry message (non-finite positions...)
        raise


def _world_matrices(mesh: Any) -> np.ndarray:
    """``(K, 4, 4)`` a mesh's world matrix times each instance's (one for a plain mesh)."""
    world = np.asarray(mesh.world.matrix, dtype=np.float64)
    if not isinstance(mesh, gfx.InstancedMesh):
        return world[None]
    count = mesh.instance_buffer.nitems
    local = np.asarray(mesh.instance_buffer.data["matrix"][:count], dtype=np.float64)
    return world @ local.transpose(0, 2, 1)


def _fit_gathered(scene: Any, pcf_radius: int = 2) -> list[LightFit]:
    """The per-frame path that :func:`fit_scene_shadows` replaced: gather every triangle
    in world space (:func:`gather_scene`) and fit each light over all of them. Kept for the
    benchmark and the tests that compare the two."""
    surfaces = gather_scene(scene)
    kinds = (gfx.DirectionalLight, gfx.SpotLight, gfx.PointLight)
    lights = scene.iter(lambda o: isinstance(o, kinds) and o.cast_shadow, skip_invisible=True)
    return [_fit_light(light, surfaces, pcf_radius) for light in lights]


def _fit_light(light: Any, surfaces: SceneSurfaces, pcf_radius: int) -> LightFit:
    """One light's fit set on it, or the reason it was skipped (and the light released)."""
    if len(surfaces.casters.faces) == 0:
        _release(light)
        return LightFit(light, None, "the scene has no visible mesh with cast_shadow")
    receivers = surfaces.receivers if len(surfaces.receivers.faces) else None
    position = np.asarray(light.world.position, dtype=np.float64)
    fit: ShadowSetup | CubeDepthRange
    try:
        if isinstance(light, gfx.PointLight):
            fit = cube_depth_range(position, surfaces.casters, receivers=receivers)
        else:
            aim = np.asarray(_aimed_at(light), dtype=np.float64) - position
            if not np.any(aim):  # pygfx's light shines down -z then
                aim = np.array([0.0, 0.0, -1.0])
            sm_light: Any = (
                DirectionalLight(-aim)
                if isinstance(light, gfx.DirectionalLight)
                else SpotLight(position, aim, np.float64(light.angle))
            )
            fit = fit_shadow(
                sm_light, surfaces.casters, PYGFX_SHADOW_MAP_SIZE,
                pcf_radius=pcf_radius, pcf_filter="bilinear", api="webgpu",
                receivers=receivers,
            )  # fmt: skip
        set_shadow_camera(light, fit)
    except ValueError as err:
        _release(light)
        return LightFit(light, None, str(err))
    return LightFit(light, fit, "")


class _Camera:
    """One light's camera as floats and float64 vectors (trusted by the helpers)."""

    def __init__(self, cam: ShadowCamera) -> None:
        self.eye, self.forward, self.up = (
            np.asarray(v, dtype=np.float64) for v in (cam.eye, cam.forward, cam.up)
        )
        self.left, self.right, self.bottom, self.top, self.near, self.far = (
            float(v) for v in (cam.left, cam.right, cam.bottom, cam.top, cam.near, cam.far)
        )
        self.orthographic = bool(np.asarray(cam.orthographic))


def _check_pygfx(light: Any = None) -> None:
    """pygfx's private API that the overrides replace and call (RuntimeError without)."""
    missing = [
        f"{owner.__name__}._update_matrix"
        for owner in (_LightShadow, _PointLightShadow)
        if not callable(getattr(owner, "_update_matrix", None))
    ]
    if light is not None and isinstance(getattr(light, "shadow", None), _LightShadow):
        if not hasattr(light.shadow, "_gfx_matrix_buffer"):
            missing.append("LightShadow._gfx_matrix_buffer")
        names = getattr(getattr(light, "uniform_buffer", None), "data", np.zeros(0)).dtype.names
        if "light_view_proj_matrix" not in (names or ()):
            missing.append("the light uniform's light_view_proj_matrix")
    if missing:
        raise RuntimeError(
            f"pygfx {gfx.__version__} has no {', '.join(missing)}, which "
            "shadowmath.integrations.pygfx overrides and calls; tested with "
            f"pygfx {_versions()}"
        )
    version = tuple(gfx.version_info[:2])
    if not TESTED_PYGFX[0] <= version < TESTED_PYGFX[1]:
        warnings.warn(
            f"shadowmath.integrations.pygfx is tested with pygfx {_versions()}, "
            f"not {gfx.__version__}: check that its shadows render as the fit says",
            UserWarning,
            stacklevel=3,
        )


def _versions() -> str:
    (a, b), (c, d) = TESTED_PYGFX
    return f">={a}.{b},<{c}.{d}"


def _light_kind(light: Any) -> str:
    if isinstance(light, gfx.DirectionalLight):
        kind = "directional"
    elif isinstance(light, gfx.SpotLight):
        kind = "spot"
    elif isinstance(light, gfx.PointLight):
        kind = "point"
    else:
        raise ValueError(
            "light: expected a pygfx DirectionalLight, SpotLight or PointLight, got "
            f"{type(light).__name__}"
        )
    return kind


def _one_camera(fit: ShadowSetup | ShadowCamera | CubeDepthRange) -> _Camera:
    if isinstance(fit, CubeDepthRange):
        raise ValueError(
            "fit: a CubeDepthRange is a point light's; a pygfx directional or spot light "
            "needs a ShadowSetup (sm.fit_shadow) or ShadowCamera"
        )
    if isinstance(fit, ShadowSetup):
        fit = shadow_camera(fit)
    elif not isinstance(fit, ShadowCamera):
        raise ValueError(f"fit: expected a ShadowSetup or ShadowCamera, got {type(fit).__name__}")
    shape = np.shape(fit.eye)
    if shape != (3,):
        raise ValueError(f"fit: expected one light's fit (eye of shape (3,)), got {shape}")
    fields = [np.asarray(getattr(fit, n), dtype=np.float64) for n in ShadowCamera._fields[:-1]]
    if not all(np.all(np.isfinite(f)) for f in fields):
        raise ValueError("fit: contains non-finite values (NaN or inf); pass a valid fit")
    return _Camera(fit)


def _set_window(camera: Any, cam: _Camera) -> None:
    """The window ``[l, r] x [b, t]`` as pygfx's symmetric camera and its view offset."""
    lo, r, b, t = cam.left, cam.right, cam.bottom, cam.top
    X, Y = max(-lo, r), max(-b, t)
    if cam.orthographic:
        camera.fov = 0.0
    else:
        half_tan = 0.5 * (X + Y)
        if half_tan > _MAX_HALF_TAN:
            raise ValueError(
                f"fit: its field of view, {math.degrees(2 * math.atan(half_tan)):.1f} "
                "degrees, is wider than pygfx's 179; fit fewer casters per light"
            )
        if half_tan < _MIN_HALF_TAN:  # widen the full frustum; the offset cuts the window
            X, Y = X * (_MIN_HALF_TAN / half_tan), Y * (_MIN_HALF_TAN / half_tan)
            half_tan = _MIN_HALF_TAN
        camera.fov = math.degrees(2.0 * math.atan(half_tan))
    camera.width, camera.height = 2.0 * X, 2.0 * Y
    if (lo, b) == (-X, -Y) and (r, t) == (X, Y):
        camera.clear_view_offset()
    else:
        camera.set_view_offset(2.0 * X, 2.0 * Y, lo + X, Y - t, r - lo, t - b)


def _hold_camera(shadow: Any, eye: np.ndarray, forward: np.ndarray) -> None:
    """Override ``shadow._update_matrix`` (pygfx's once-a-frame hook) for one light.

    pygfx's own (``LightShadow._update_matrix``, and ``SpotLightShadow``'s, which first
    rebuilds the field of view from ``light.angle``) places the camera at the light,
    aims it at the light's target and uploads its matrix. The override places the
    camera at the fit's ``eye``, aims it along ``forward`` and uploads the same way:
    the light itself is only read by pygfx, never written.
    """

    def update_matrix(light: Any) -> None:
        _aim(shadow.camera, eye, forward)
        _upload(light, shadow._gfx_matrix_buffer, shadow.camera.camera_matrix.T)

    shadow._update_matrix = update_matrix


def _aim(camera: Any, eye: np.ndarray, forward: np.ndarray) -> None:
    camera.world.position = eye
    camera.look_at(eye + forward)


def _upload(light: Any, buffer: Any, matrix: Any, face: int | None = None) -> None:
    """A shadow camera's transposed matrix where pygfx's update puts it: the light's
    uniform (read by the shader; ``face`` of a point light's six) and the buffer the
    shadow pass draws with."""
    if face is None:
        light.uniform_buffer.data["light_view_proj_matrix"] = matrix
    else:
        light.uniform_buffer.data["light_view_proj_matrix"][face] = matrix
    buffer.data["light_view_proj_matrix"] = matrix
    buffer.update_full()


def _release(light: Any) -> None:
    """Give a light back to pygfx's own shadow camera: the override removed, the
    camera's window, range and up those of a new shadow object of the same kind."""
    shadow = light.shadow
    shadow.__dict__.pop("_update_matrix", None)
    default, camera = type(shadow)().camera, shadow.camera
    for name in ("fov", "width", "height", "zoom", "maintain_aspect", "depth_range"):
        setattr(camera, name, getattr(default, name))
    camera.world.reference_up = default.world.reference_up
    camera.clear_view_offset()


def _set_cube_depth(light: Any, fit: Any) -> Any:
    """A point light's fitted depth range, kept by a wrapped ``_update_matrix``."""
    if not isinstance(fit, CubeDepthRange):
        raise ValueError(
            "fit: a pygfx PointLight's six cube faces are fixed; pass its depth range, "
            f"sm.cube_depth_range(light position, casters), got {type(fit).__name__}"
        )
    if np.shape(fit.near) != () or np.shape(fit.far) != ():
        raise ValueError(
            f"fit: expected one light's depth range (scalar near and far), got shapes "
            f"{np.shape(fit.near)} and {np.shape(fit.far)}"
        )
    near, far = float(fit.near), float(fit.far)
    if not (math.isfinite(near) and math.isfinite(far) and 0 < near < far):
        raise ValueError(f"fit: expected finite 0 < near < far, got near {near}, far {far}")
    shadow = light.shadow
    shadow.camera.depth_range = (near, far)

    def update_matrix(light: Any) -> None:
        _PointLightShadow._update_matrix(shadow, _WithoutCutoff(light))
        _turn_up_face(shadow, light)

    shadow._update_matrix = update_matrix
    return shadow.camera


def _turn_up_face(shadow: Any, light: Any) -> None:
    """Face 2 (+Y) as the shader samples it: face 3 (-Y) turned half a turn about X.

    pygfx 0.17 aims each face with ``look_at``; for +Y that direction is parallel to the
    camera's ``reference_up`` (0, 1, 0), and the degenerate case leaves the face looking
    elsewhere (down -Z from a new light), so every shadow cast toward +Y is lost. The
    shader reads face 2 as the direction ``(x_ndc, 1, -y_ndc)`` and face 3 as
    ``(x_ndc, -1, y_ndc)``: the half turn ``(x, y, z) -> (x, -y, -z)`` about the light
    maps one onto the other and keeps the triangles' winding (pygfx culls front faces).
    """
    p = np.asarray(light.world.position, dtype=np.float64)
    to_light, back = np.eye(4), np.eye(4)
    to_light[:3, 3], back[:3, 3] = -p, p
    half_turn = back @ np.diag([1.0, -1.0, -1.0, 1.0]) @ to_light
    stored = light.uniform_buffer.data["light_view_proj_matrix"]  # each face's matrix.T
    up = (np.asarray(stored[3], dtype=np.float64).T @ half_turn).T
    _upload(light, shadow._gfx_matrix_buffer[2], up, face=2)


class _WithoutCutoff:
    """The light as ``PointLightShadow._update_matrix`` reads it, with ``distance = 0``:
    pygfx then keeps the camera's depth range instead of ``(distance / 1e5, 10 distance)``."""

    distance = 0.0

    def __init__(self, light: Any) -> None:
        self._light = light

    def __getattr__(self, name: str) -> Any:
        return getattr(self._light, name)
