r"""pygfx integration: give a pygfx light the shadow camera of a shadowmath fit.

pygfx (the wgpu-based Python renderer) draws every shadow map at
:data:`PYGFX_SHADOW_MAP_SIZE` texels square, through a camera each light's ``shadow``
object owns: a directional light's is a fixed 1000 x 1000 orthographic box centred on
the light's position, a spot light's a perspective frustum whose field of view pygfx
rebuilds from ``light.angle`` every frame. :func:`set_shadow_camera` replaces that camera's
window, depth range and roll with those of a fit (:func:`shadowmath.shadow_camera`), so
pygfx draws and samples exactly the fitted map (its clip matrix is the fit's
``blocker_to_clip`` for ``api="webgpu"``, to float32 rounding):

* **directional**: public attributes only. The light moves to the camera's eye (the
  centre of the fitted box; a directional light's position does not light anything)
  and aims along ``forward``; the orthographic camera gets ``width``, ``height``,
  ``depth_range = (near, far)`` measured from the eye, and ``reference_up = up``
  (pygfx's look-at keeps the camera's up closest to it; any other up rolls the map).
* **spot**: the same public attributes (``fov``, ``width``, ``height`` and
  ``set_view_offset`` for the window, off-centre where the fit clipped it to the cone),
  plus one override, because pygfx offers no public hook: the shadow object's
  ``_update_matrix`` (called once a frame) is replaced, on that one light's shadow
  object, by pygfx's base ``LightShadow._update_matrix`` aimed along the fitted
  ``forward``. That skips only ``SpotLightShadow``'s rebuild of the field of view from
  ``light.angle``; the camera still follows the light's position every frame.
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

The map size is one module-level constant in pygfx's private renderer code, the same
for every light; fit with ``map_size=PYGFX_SHADOW_MAP_SIZE`` and ``pcf_radius=2``
(pygfx filters with a 5 x 5-texel kernel), and ``api="webgpu"`` if you also use the
fit's matrices yourself. The override is checked against pygfx's private API at every
call (:class:`RuntimeError` if it is gone) and pygfx versions outside
:data:`TESTED_PYGFX` warn.
"""

from __future__ import annotations

import math
import warnings
from typing import Any, Final

import numpy as np

from shadowmath import CubeDepthRange, ShadowCamera, ShadowSetup, shadow_camera

try:
    import pygfx as gfx
    from pygfx.objects._lights import LightShadow as _LightShadow
    from pygfx.objects._lights import PointLightShadow as _PointLightShadow
except ImportError as err:  # pragma: no cover - the extra is part of `dev`
    raise ImportError(
        "shadowmath.integrations.pygfx needs pygfx: pip install 'shadowmath[pygfx]'"
    ) from err

__all__ = ["PYGFX_SHADOW_MAP_SIZE", "TESTED_PYGFX", "set_shadow_camera"]

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
    A directional or spot light takes a fit, and this sets, on ``light`` and its
    ``light.shadow.camera``: the light's position to the camera's eye (and a directional
    light's target to ``eye + forward``), the camera's ``reference_up`` to ``up``, its
    depth range to ``(near, far)`` and its window. A
    perspective window ``[l, r] x [b, t]`` (tangents) is cut out of the symmetric frustum
    of half-extents :math:`X = \max(-l, r)`, :math:`Y = \max(-b, t)`, whose field of view
    pygfx reads as

    .. math:: \mathrm{fov} = 2 \arctan\frac{X + Y}{2}, \qquad \mathrm{aspect} = X / Y,

    by ``set_view_offset(2X, 2Y, l + X, Y - t, r - l, t - b)`` (offsets from the top-left
    corner); an orthographic window the same way in world units. A spot light's shadow
    object gets the documented override of the module docstring. Call it again whenever
    you refit (the casters or the light moved).

    Arguments:
        light: a ``pygfx.DirectionalLight`` (with an orthographic fit: ``sm.fit_shadow``
            of an ``sm.DirectionalLight``), a ``pygfx.SpotLight`` (with a perspective
            fit: an ``sm.SpotLight``, whose frame's ``Z`` is the cone's axis, or an
            ``sm.PointLight``), not parented to a camera (pygfx then aims it along the
            camera, ignoring the fit), or a ``pygfx.PointLight``.
        fit: one light's :class:`ShadowSetup` (from :func:`shadowmath.fit_shadow`, no
            batch) or :class:`ShadowCamera` (from :func:`shadowmath.shadow_camera`); for
            a point light, one :class:`CubeDepthRange` (scalar ``near`` and ``far``).

    Returns:
        ``light.shadow.camera``, the pygfx camera now placed as the fit's: its
        ``camera_matrix`` is the fit's world-to-clip matrix for ``api="webgpu"`` (for a
        point light, the camera pygfx turns to each face, with the fitted depth range).

    Raises:
        ValueError: a light that is not a pygfx directional, spot or point light, a light
            parented to a camera, a fit that is not a ``ShadowSetup`` or ``ShadowCamera``
            (a ``CubeDepthRange`` for a point light), a batch of fits, an orthographic
            fit for a spot light or a perspective one for a directional light, non-finite
            fields, a field of view wider than pygfx's 179 degrees, a depth range without
            ``0 < near < far``.
        RuntimeError: pygfx lacks the private ``_update_matrix`` methods the spot and
            point lights' overrides call.

    Example:
        >>> import numpy as np, pygfx as gfx, shadowmath as sm
        >>> cube = np.array([[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (0, 2)])
        >>> setup = sm.fit_shadow(sm.DirectionalLight([1.0, 0.5, 2.0]), cube,
        ...                       PYGFX_SHADOW_MAP_SIZE, pcf_radius=2, api="webgpu")
        >>> sun = gfx.DirectionalLight(cast_shadow=True)
        >>> camera = set_shadow_camera(sun, setup)
        >>> camera.width < 4 < 1000  # the cube's box, not pygfx's default 1000 x 1000
        True
        >>> world_to_clip = setup.blocker_to_clip  # blocker_to_world is the identity
        >>> bool(np.allclose(camera.camera_matrix, world_to_clip, atol=1e-6))
        True
    """
    _check_pygfx()
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
    eye, forward, up = cam.eye, cam.forward, cam.up
    light.world.position = eye
    if kind == "directional":
        light.target.world.position = eye + forward
    else:
        _aim_spot_shadow(light.shadow, forward)
    camera.world.reference_up = up
    # The same look-at pygfx does each frame, done now so that camera_matrix is right.
    camera.world.position = eye
    camera.look_at(eye + forward)
    camera.maintain_aspect = False
    camera.zoom = 1.0
    camera.depth_range = (float(cam.near), float(cam.far))
    _set_window(camera, cam)
    return camera


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


def _check_pygfx() -> None:
    for owner in (_LightShadow, _PointLightShadow):
        if not callable(getattr(owner, "_update_matrix", None)):
            raise RuntimeError(
                f"pygfx {gfx.__version__} has no {owner.__name__}._update_matrix, which "
                "shadowmath.integrations.pygfx calls for spot and point lights; tested with "
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
    if isinstance(light.parent, gfx.Camera):
        raise ValueError(
            "light: it is parented to a camera, so pygfx aims it along that camera and "
            "ignores its target; add it to the scene instead"
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


def _aim_spot_shadow(shadow: Any, forward: np.ndarray) -> None:
    """Override ``shadow._update_matrix`` (pygfx's once-a-frame hook) for one spot light.

    ``SpotLightShadow._update_matrix`` resets the camera's field of view to
    ``2 light.angle`` and its depth range from ``light.distance``, then calls the base
    ``LightShadow._update_matrix``, which places the camera at the light, looks at the
    light's target and uploads the matrix. The override calls that base directly, with
    the light's target swapped (for the call only) for a point along the fitted
    ``forward``, so the cone keeps its own aim.
    """
    aim = gfx.WorldObject()

    def update_matrix(light: Any) -> None:
        aim.world.position = light.world.position + forward
        cone_target = light.target
        light.target = aim
        try:
            _LightShadow._update_matrix(shadow, light)
        finally:
            light.target = cone_target

    shadow._update_matrix = update_matrix


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
    stored[2] = up
    shadow._gfx_matrix_buffer[2].data["light_view_proj_matrix"] = up
    shadow._gfx_matrix_buffer[2].update_full()


class _WithoutCutoff:
    """The light as ``PointLightShadow._update_matrix`` reads it, with ``distance = 0``:
    pygfx then keeps the camera's depth range instead of ``(distance / 1e5, 10 distance)``."""

    distance = 0.0

    def __init__(self, light: Any) -> None:
        self._light = light

    def __getattr__(self, name: str) -> Any:
        return getattr(self._light, name)
