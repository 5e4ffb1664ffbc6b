r"""three.js integration: what a three.js application sets on its lights' shadows.

three.js fits nothing: a ``DirectionalLightShadow`` draws through a fixed
``OrthographicCamera(-5, 5, 5, -5, 0.5, 500)`` placed at the light and aimed at its target,
a ``SpotLightShadow`` rebuilds its ``PerspectiveCamera`` from the cone every frame
(``fov = 2 angle focus``, ``far = distance``) and a point light draws six 90-degree faces
between ``near = 0.5`` and ``far = 500``. The functions here turn the package's fits into
plain JSON-ready data (lists and floats) that the ES module shipped beside this file
(:data:`MODULE_PATH`, ``applyShadow(light, data)``) applies to a three.js light each frame,
without writing the light itself.

**three.js's conventions, from its source (r187).** Cameras look down their local ``-z``
(``Matrix4.lookAt``: ``z = normalize(eye - target)``, ``x = normalize(up x z)``,
``y = z x x``); ``Matrix4.elements`` is column-major (``te[12..14]`` the translation);
``OrthographicCamera`` and ``PerspectiveCamera.updateProjectionMatrix`` call
``makeOrthographic(left, right, top, bottom, near, far)`` and
``makePerspective(left, right, top, bottom, near, far)`` with the window at the near plane:
OpenGL's ``glOrtho`` and ``glFrustum``, depth :math:`[-1, 1]` for ``WebGLRenderer``
(``WebGLCoordinateSystem``) and :math:`[0, 1]` for ``WebGPURenderer``
(``WebGPUCoordinateSystem``). ``LightShadow._updateMatrix`` samples with
``shadow.matrix = B P V`` where ``B`` maps NDC to :math:`[0, 1]` (``x, y`` scaled by
1/2 and moved by 1/2; ``z`` too under WebGL, unchanged under WebGPU): so
``shadow.matrix`` is the fit's ``world_to_texture`` for ``api="opengl"``, and the shader
(``shadowmap_pars_fragment``) compares the map's depth with ``shadowCoord.z + bias``
(``- bias`` with a reversed depth buffer). A point light's faces
(``WebGLShadowMap.js``: ``_cubeDirections``, ``_cubeUps``) are OpenGL's cube-map faces,
the package's :func:`shadowmath.cube_face_views`; its shader compares
``a + b / max(|d_x|, |d_y|, |d_z|) + bias`` with the face's :math:`[0, 1]` depth.

**Bias.** ``depth_bias`` is given in the map's stored depth :math:`[0, 1]`, positive
toward the light (a receiver is lit unless the map's depth is nearer than its own minus
``depth_bias``), the units of :func:`shadowmath.slope_scaled_bias` for ``api="opengl"``;
three.js adds ``shadow.bias`` to the receiver's depth, so ``shadow.bias = -depth_bias``
(the same sign with a reversed depth buffer, where three.js subtracts it).

Every camera's data holds both the numbers (``position``, ``target``, ``up``, the window,
``near``, ``far``) from which three.js builds the fit's matrices, and the matrices
(``matrixWorld``, ``projectionMatrix``, ``worldToClip``: 16 floats, column-major as
``Matrix4.fromArray`` reads them, WebGL's depth range) to check against.
"""

from __future__ import annotations

from pathlib import Path
from typing import Final

import numpy as np
from jaxtyping import Real
from numpy.typing import ArrayLike, NDArray

from shadowmath import (
    AtlasFit,
    Cascades,
    CubeDepthRange,
    ShadowCamera,
    ShadowSetup,
    camera_to_world,
    cube_face_views,
    shadow_camera,
)

__all__ = [
    "LICENSE_PATH",
    "MODULE_PATH",
    "THREE_PATH",
    "THREE_VERSION",
    "JsonValue",
    "atlas_tile_data",
    "cascade_shadow_data",
    "point_shadow_data",
    "shadow_data",
]

_HERE = Path(__file__).parent
#: The ES module that applies the data to three.js lights (``applyShadow``).
MODULE_PATH: Final = _HERE / "shadowmath.js"
#: three.js r187 with its OrbitControls and TransformControls, one minified ES module
#: (773 KB), bundled for offline use (``vendor/README.md`` says how it was built).
THREE_PATH: Final = _HERE / "vendor" / "three.bundle.min.js"
#: three.js's MIT licence notice, shipped with it.
LICENSE_PATH: Final = _HERE / "vendor" / "LICENSE"
#: The three.js release bundled and tested (npm ``three``).
THREE_VERSION: Final = "0.187.0"

#: JSON-ready data: what :func:`json.dumps` writes as is.
JsonValue = str | float | int | bool | list["JsonValue"] | dict[str, "JsonValue"]


def _elements(matrix: NDArray[np.float64]) -> list[JsonValue]:
    """A 4 x 4 column-vector matrix as three.js's ``Matrix4.elements`` (column-major)."""
    return [float(v) for v in np.asarray(matrix, dtype=np.float64).T.reshape(16)]


def _float(x: object) -> JsonValue:
    return float(np.asarray(x))


def _vector(v: NDArray[np.float64]) -> list[JsonValue]:
    return [float(x) for x in np.asarray(v, dtype=np.float64).reshape(3)]


def _gl_projection(cam: ShadowCamera) -> NDArray[np.float64]:
    """three.js's ``makeOrthographic`` / ``makePerspective`` (WebGL depth) of the window."""
    near, far = float(cam.near), float(cam.far)
    scale = 1.0 if cam.orthographic else near
    window = [float(w) * scale for w in (cam.left, cam.right, cam.bottom, cam.top)]
    return _window_projection(window, near, far, orthographic=cam.orthographic)


def _window_projection(
    window: list[float], near: float, far: float, *, orthographic: bool
) -> NDArray[np.float64]:
    left, right, bottom, top = window
    m = np.zeros((4, 4))
    if orthographic:
        m[0, 0], m[1, 1], m[2, 2] = 2 / (right - left), 2 / (top - bottom), -2 / (far - near)
        m[0, 3] = -(right + left) / (right - left)
        m[1, 3] = -(top + bottom) / (top - bottom)
        m[2, 3], m[3, 3] = -(far + near) / (far - near), 1.0
    else:
        m[0, 0], m[1, 1] = 2 * near / (right - left), 2 * near / (top - bottom)
        m[0, 2], m[1, 2] = (right + left) / (right - left), (top + bottom) / (top - bottom)
        m[2, 2], m[2, 3] = -(far + near) / (far - near), -2 * far * near / (far - near)
        m[3, 2] = -1.0
    return m


def _check_bias(depth_bias: float) -> float:
    bias = float(depth_bias)
    if not np.isfinite(bias):
        raise ValueError(f"depth_bias: expected a finite number, got {depth_bias!r}")
    return bias


def _camera_data(cam: ShadowCamera, map_size: tuple[int, int], bias: float) -> dict[str, JsonValue]:
    """One (unbatched) shadow camera's data."""
    world = np.asarray(camera_to_world(cam, look="-z"), dtype=np.float64)
    projection = _gl_projection(cam)
    eye, forward = np.asarray(cam.eye, np.float64), np.asarray(cam.forward, np.float64)
    scale = 1.0 if cam.orthographic else float(cam.near)
    data: dict[str, JsonValue] = {
        "type": "orthographic" if cam.orthographic else "perspective",
        "position": _vector(eye),
        "target": _vector(eye + forward),
        "up": _vector(np.asarray(cam.up)),
        "left": float(cam.left) * scale,
        "right": float(cam.right) * scale,
        "top": float(cam.top) * scale,
        "bottom": float(cam.bottom) * scale,
        "near": float(cam.near),
        "far": float(cam.far),
        "mapSize": [int(map_size[0]), int(map_size[1])],
        "bias": -bias,
        "matrixWorld": _elements(world),
        "projectionMatrix": _elements(projection),
        "worldToClip": _elements(projection @ np.linalg.inv(world)),
    }
    if not cam.orthographic:
        data["fov"] = float(np.degrees(cam.fov_y))
        data["aspect"] = float(cam.aspect)
    return data


def shadow_data(fit: ShadowSetup, *, depth_bias: float = 0.0) -> dict[str, JsonValue]:
    r"""What a three.js directional or spot light's shadow takes from one fit.

    The fit's camera (:func:`shadowmath.shadow_camera`) in three.js's terms: the shadow
    camera at ``position`` looking at ``target = eye + forward`` with ``up`` (three.js's
    ``Object3D.lookAt``), its window ``left, right, top, bottom`` at the near plane (world
    units for an orthographic fit; ``tan * near`` for a perspective one, which also gets
    ``fov`` in degrees and ``aspect``), ``near``, ``far``, ``mapSize`` (the fit's map) and
    ``bias`` (``-depth_bias``, see the module docstring). With three.js's matrices,

    .. math::

        \mathtt{worldToClip} = P_\mathrm{three}(\mathrm{window}, n, f)\,
        \mathtt{matrixWorld}^{-1} = M_\mathrm{blocker \to clip} B^{-1}

    for the fit's ``api="opengl"`` matrices (``B`` its ``blocker_to_world``), and
    ``shadow.matrix`` (``LightShadow._updateMatrix``) its ``world_to_texture`` (the tests
    check both with three.js's formulas written from its source).

    Arguments:
        fit: one light's :class:`~shadowmath.ShadowSetup` from :func:`shadowmath.fit_shadow`
            (no batch), whose ``map_size`` is set. Its ``api`` does not matter: three.js
            builds its own matrices from the numbers.
        depth_bias: the depth bias in the map's stored depth :math:`[0, 1]`, positive toward
            the light.

    Returns:
        A dict of floats, lists and strings (``json.dumps`` writes it): ``type``
        (``"orthographic"`` or ``"perspective"``), the numbers above, and ``matrixWorld``,
        ``projectionMatrix`` and ``worldToClip`` (16 floats each, column-major, WebGL depth).

    Raises:
        ValueError: a batch of fits, a fit without ``map_size``, a non-finite
            ``depth_bias``; :func:`shadowmath.shadow_camera`'s errors.

    Example:
        >>> import numpy as np, shadowmath as sm
        >>> box = np.array([[x, y, z] for x in (-1, 1) for y in (0, 2) for z in (-1, 1)], float)
        >>> data = shadow_data(sm.fit_shadow(sm.DirectionalLight([1.0, 3.0, 2.0]), box, 1024))
        >>> data["type"], data["mapSize"], data["right"] < 5  # three.js's default: 5
        ('orthographic', [1024, 1024], True)
    """
    if not isinstance(fit, ShadowSetup):
        raise ValueError(f"fit: expected a ShadowSetup from fit_shadow, got {type(fit).__name__}")
    if np.ndim(fit.blocker_to_clip) != 2:
        raise ValueError("fit: expected one light's fit, got a batch (index it first)")
    if fit.map_size is None:
        raise ValueError("fit: has no map_size (use a fit from fit_shadow)")
    bias = _check_bias(depth_bias)
    size = (int(fit.map_size[0]), int(fit.map_size[1]))
    return _camera_data(shadow_camera(fit), size, bias)


def cascade_shadow_data(cascades: Cascades, *, depth_bias: float = 0.0) -> dict[str, JsonValue]:
    r"""What three.js takes from a directional light's cascades: one camera per cascade.

    three.js draws one orthographic map per ``DirectionalLight``: give cascade ``i`` to a
    light of its own (the ES module's ``applyShadow(lights[i], data.cascades[i])``) and
    light view depths ``[splits[i], splits[i + 1])`` with it, blending into cascade
    ``i + 1`` up to ``bandEnd[i]`` (see :func:`shadowmath.fit_cascades`).

    Arguments:
        cascades: one camera's :class:`~shadowmath.Cascades` (no batch), ``warp=None``.
        depth_bias: as in :func:`shadow_data`.

    Returns:
        ``{"type": "cascades", "splits": [n + 1 floats], "bandEnd": [n floats],
        "cascades": [n camera dicts as shadow_data's]}``, each cascade with the map size
        of its viewport.

    Raises:
        ValueError: a batch of cascades, a non-finite ``depth_bias``;
            :func:`shadowmath.shadow_camera`'s errors (LiSPSM cascades).

    Example:
        >>> import numpy as np, shadowmath as sm
        >>> view = np.eye(4); view[2, 3] = -10.0
        >>> projection = np.array([[1.0, 0, 0, 0], [0, 1, 0, 0], [0, 0, -1.02, -2.02],
        ...                        [0, 0, -1, 0]])
        >>> bounds = np.array([[-8.0, -8, -30], [8, 8, 2]])
        >>> cascades = sm.fit_cascades([0.2, 0.3, 1.0], view, projection, bounds, 512, count=3)
        >>> data = cascade_shadow_data(cascades)
        >>> len(data["cascades"]), len(data["splits"]), data["cascades"][0]["mapSize"]
        (3, 4, [512, 512])
    """
    if not isinstance(cascades, Cascades):
        raise ValueError(f"cascades: expected Cascades, got {type(cascades).__name__}")
    if np.ndim(cascades.splits) != 1:
        raise ValueError("cascades: expected one camera's cascades, got a batch (index it)")
    bias = _check_bias(depth_bias)
    cams = shadow_camera(cascades)
    viewports = np.asarray(cascades.viewports)
    out: list[JsonValue] = []
    for i in range(viewports.shape[0]):
        cam = ShadowCamera._make([np.asarray(f)[i] for f in cams[:9]] + [cams.orthographic])
        size = (int(viewports[i, 2]), int(viewports[i, 3]))
        out.append(_camera_data(cam, size, bias))
    return {
        "type": "cascades",
        "splits": [_float(s) for s in np.asarray(cascades.splits)],
        "bandEnd": [_float(s) for s in np.asarray(cascades.band_end)],
        "cascades": out,
    }


def point_shadow_data(
    light_position: Real[ArrayLike, " 3"],
    depth_range: CubeDepthRange,
    *,
    map_size: int,
    depth_bias: float = 0.0,
) -> dict[str, JsonValue]:
    r"""What a three.js point light's shadow takes: the cube's fitted depth range.

    three.js draws six 90-degree faces at the light (``WebGLShadowMap.js``:
    ``_cubeDirections`` and ``_cubeUps``, OpenGL's cube-map faces, the package's
    :func:`shadowmath.cube_face_views`), through ``shadow.camera``
    (``PerspectiveCamera(90, 1, near, far)``): only ``near`` and ``far`` can be fitted,
    :func:`shadowmath.cube_depth_range`'s. three.js sets ``camera.far = light.distance``
    every frame when that is nonzero; the ES module keeps the fitted ``far`` anyway.

    Arguments:
        light_position: ``(3,)`` the light (for ``worldToClip``; three.js reads its own).
        depth_range: one :class:`~shadowmath.CubeDepthRange` (scalars) fitted at that light.
        map_size: texels per face side (``shadow.mapSize``).
        depth_bias: as in :func:`shadow_data`.

    Returns:
        ``{"type": "cube", "position", "near", "far", "fov": 90, "aspect": 1, "mapSize",
        "bias", "projectionMatrix", "worldToClip": [6 lists of 16 floats, faces +X, -X,
        +Y, -Y, +Z, -Z]}``.

    Raises:
        ValueError: a batch, ``near`` and ``far`` without ``0 < near < far``, a
            ``map_size`` that is not a positive integer, a non-finite ``depth_bias`` or
            light.

    Example:
        >>> import numpy as np, shadowmath as sm
        >>> box = np.array([[x, y, z] for x in (1, 2) for y in (-1, 1) for z in (-1, 1)], float)
        >>> rng = sm.cube_depth_range([0.0, 0.0, 0.0], box)
        >>> data = point_shadow_data([0.0, 0.0, 0.0], rng, map_size=256)
        >>> data["near"], data["far"], data["mapSize"]
        (0.984375, 2.03125, [256, 256])
    """
    light = np.asarray(light_position, dtype=np.float64)
    if light.shape != (3,) or not np.all(np.isfinite(light)):
        raise ValueError(f"light_position: expected 3 finite numbers, got shape {light.shape}")
    if not isinstance(depth_range, CubeDepthRange) or np.ndim(depth_range.near) != 0:
        raise ValueError("depth_range: expected one CubeDepthRange from cube_depth_range")
    near, far = float(depth_range.near), float(depth_range.far)
    if not 0 < near < far < np.inf:
        raise ValueError(f"depth_range: expected 0 < near < far, got ({near}, {far})")
    if isinstance(map_size, bool) or not isinstance(map_size, int) or map_size < 1:
        raise ValueError(f"map_size: expected a positive integer, got {map_size!r}")
    bias = _check_bias(depth_bias)
    projection = _window_projection([-near, near, -near, near], near, far, orthographic=False)
    faces = np.asarray(cube_face_views(light), dtype=np.float64)
    return {
        "type": "cube",
        "position": _vector(light),
        "near": near,
        "far": far,
        "fov": 90.0,
        "aspect": 1.0,
        "mapSize": [map_size, map_size],
        "bias": -bias,
        "projectionMatrix": _elements(projection),
        "worldToClip": [list(_elements(projection @ v)) for v in faces],
    }


def atlas_tile_data(fit: AtlasFit) -> list[dict[str, JsonValue]]:
    r"""Each tile of an atlas (:func:`shadowmath.fit_atlas`) as three.js matrices.

    three.js gives every light its own map, so an atlas shared by many lights is for a
    renderer's own passes (a ``ShaderMaterial`` that samples one depth texture): draw tile
    ``t`` with ``worldToClip`` inside ``viewport`` (texels, from the bottom left, as
    ``WebGLRenderer.setViewport`` with ``setScissorTest``) and sample it with
    ``worldToTexture``. three.js's own viewport convention gives the same sampling matrix:
    ``LightShadow._updateMatrix`` with ``viewport = (x, y, w, h) / tile`` and
    ``frameExtents = atlas / tile`` scales :math:`x, y` by ``w / atlas`` and moves them by
    ``x / atlas`` (the tests check it against ``worldToTexture``).

    Arguments:
        fit: the :class:`~shadowmath.AtlasFit`, fitted with ``api="opengl"`` (three.js's
            ``WebGLRenderer``: clip depth :math:`[-1, 1]`, texture rows from the bottom).

    Returns:
        One dict per tile: ``light``, ``face`` (0 for a 2D map, 0..5 for a cube face),
        ``viewport`` ``[x, y, w, h]`` in texels, ``atlasSize`` ``[W, H]``, ``near``, ``far``,
        ``worldToClip`` and ``worldToTexture`` (16 floats each, column-major).

    Raises:
        ValueError: not an ``AtlasFit``.

    Example:
        >>> import numpy as np, shadowmath as sm
        >>> box = np.array([[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (0, 2)], float)
        >>> lights = [sm.PointLight([0.0, 0.0, 6.0]), sm.DirectionalLight([1.0, 0.0, 2.0])]
        >>> atlas = sm.allocate_atlas([1.0, 1.0], atlas_size=512)
        >>> tiles = atlas_tile_data(sm.fit_atlas(lights, box, atlas))
        >>> [(t["light"], t["face"], t["viewport"][2], t["atlasSize"]) for t in tiles]
        [(0, 0, 256, [512, 512]), (1, 0, 256, [512, 512])]
    """
    if not isinstance(fit, AtlasFit):
        raise ValueError(f"fit: expected an AtlasFit from fit_atlas, got {type(fit).__name__}")
    clip, texture = np.asarray(fit.world_to_clip), np.asarray(fit.world_to_texture)
    viewports = np.asarray(fit.viewports)
    size = [int(fit.texture_size[0]), int(fit.texture_size[1])]
    return [
        {
            "light": int(np.asarray(fit.tile_id)[t]),
            "face": int(np.asarray(fit.tile_face)[t]),
            "viewport": [int(v) for v in viewports[t]],
            "atlasSize": list(size),
            "near": float(np.asarray(fit.near)[t]),
            "far": float(np.asarray(fit.far)[t]),
            "worldToClip": _elements(clip[t]),
            "worldToTexture": _elements(texture[t]),
        }
        for t in range(clip.shape[0])
    ]
