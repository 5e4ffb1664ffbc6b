"""A Jupyter widget (anywidget) that draws a scene with three.js and the package's fits.

Meshes, one light and a camera; drag the light (TransformControls) or orbit the camera
(OrbitControls): each change of the light comes back to Python, which refits the shadow
(:func:`shadowmath.fit_shadow` or :func:`shadowmath.cube_depth_range`) and sends the
three.js data (:mod:`shadowmath.integrations.threejs`) to the page, where ``shadowmath.js``
applies it. three.js is bundled with the package and sent with the widget's state, so the
widget works offline and in a notebook exported to static HTML with its widget state.
"""

from __future__ import annotations

import html
import json
from typing import Any, NamedTuple

import numpy as np

import shadowmath as sm
from shadowmath.integrations.threejs import (
    MODULE_PATH,
    THREE_PATH,
    JsonValue,
    cascade_shadow_data,
    point_shadow_data,
    shadow_data,
)

try:
    import anywidget
    import traitlets
except ImportError as err:  # pragma: no cover - the extra is part of `dev`
    raise ImportError(
        "shadowmath.integrations.threejs.widget needs anywidget: pip install 'shadowmath[widget]'"
    ) from err

__all__ = ["ShadowWidget", "StaticView", "ViewCamera", "view_camera"]

_ESM = (MODULE_PATH.parent / "widget.js").read_text(encoding="utf-8")

# A page that runs the widget's ESM without Jupyter: a stand-in for anywidget's model holding
# the synced state (changes stay in the page: no Python to refit).
_PAGE = """<!doctype html>
<html><head><meta charset="utf-8"><title>shadowmath ShadowWidget</title></head>
<body style="margin:0"><div id="shadowmath-widget"></div>
<script type="module">
const state = __STATE__;
const esm = __ESM__;
const listeners = {};
const model = {
  get: (name) => state[name],
  set: (name, value) => {
    state[name] = value;
    (listeners["change:" + name] || []).forEach((f) => f());
  },
  on: (event, f) => { (listeners[event] = listeners[event] || []).push(f); },
  save_changes: () => {},
};
window.model = model;
const url = URL.createObjectURL(new Blob([esm], { type: "text/javascript" }));
const widget = (await import(url)).default;
await widget.render({ model, el: document.getElementById("shadowmath-widget") });
window.ready = true;
</script></body></html>
"""


def _script_json(value: object) -> str:
    """JSON that is safe inside a <script> element."""
    return json.dumps(value).replace("</", "<\\/")


def _mesh_json(mesh: Any, color: str) -> dict[str, JsonValue]:
    if isinstance(mesh, sm.Mesh):
        vertices, faces = np.asarray(mesh.vertices), np.asarray(mesh.faces)
    else:
        vertices, faces = (np.asarray(a) for a in mesh)
    if vertices.ndim != 2 or vertices.shape[1] != 3 or faces.ndim != 2 or faces.shape[1] != 3:
        raise ValueError("meshes: each entry is an sm.Mesh or (vertices (N, 3), faces (M, 3))")
    return {
        "positions": [float(v) for v in vertices.reshape(-1)],
        "indices": [int(i) for i in faces.reshape(-1)],
        "color": color,
    }


class ShadowWidget(anywidget.AnyWidget):
    """A three.js view of meshes lit by one light whose shadow the package fits.

    Arguments:
        meshes: a list of :class:`~shadowmath.Mesh` or ``(vertices (N, 3), faces (M, 3))``
            pairs in world coordinates; every mesh casts and receives shadows.
        light: ``{"kind": "directional" | "spot" | "point", "position": [x, y, z],
            "target": [x, y, z], "angle": radians (spot)}``; a sun shines from
            ``position`` toward ``target``.
        camera: ``{"position": [...], "target": [...]}`` of the viewer (z up), optionally
            ``"fov"`` (vertical, degrees; 45), ``"near"`` (0.05), ``"far"`` (500) and
            ``"aspect"`` (width / height; the page sends its own back).
        map_size: the shadow map's texels per side.
        cascades: for a sun, ``N > 0`` fits ``N`` cascades (:func:`shadowmath.fit_cascades`)
            to the camera's view and refits each time the camera moves; the page draws them
            as ``N`` directional lights sharing the sun's direction, one per cascade, each
            with ``1 / N`` of the sun's intensity. ``0`` (the default): one fitted camera.

    Traits synced with the page: ``light`` (written back when the light is dragged),
    ``camera`` (written back when an orbit ends), ``shadow`` (the fitted data, refitted on
    each change of ``light`` or ``meshes``, and of ``camera`` in cascades mode),
    ``fit_error`` (why a fit failed, else ""), ``show_frustum`` (the shadow camera's box),
    ``show_map`` (a picture of the shadow map) and ``fitted`` (False: three.js's default
    shadow camera, to compare).

    Example:
        >>> import numpy as np
        >>> box = sm.Mesh(np.array([[x, y, z] for x in (0, 1) for y in (0, 1) for z in (1, 2)],
        ...                        float), np.array([[0, 1, 3], [0, 3, 2], [4, 6, 7]]))
        >>> w = ShadowWidget([box], light={"kind": "directional", "position": [2, 1, 5],
        ...                               "target": [0, 0, 0]})
        >>> w.shadow["type"], w.fit_error
        ('orthographic', '')
    """

    _esm = traitlets.Unicode(_ESM).tag(sync=True)
    three_source = traitlets.Unicode().tag(sync=True)
    module_source = traitlets.Unicode().tag(sync=True)
    meshes: traitlets.List[dict[str, Any]] = traitlets.List().tag(sync=True)
    light = traitlets.Dict().tag(sync=True)
    camera = traitlets.Dict().tag(sync=True)
    shadow = traitlets.Dict().tag(sync=True)
    fit_error = traitlets.Unicode("").tag(sync=True)
    map_size = traitlets.Int(1024).tag(sync=True)
    show_frustum = traitlets.Bool(True).tag(sync=True)
    show_map = traitlets.Bool(False).tag(sync=True)
    fitted = traitlets.Bool(True).tag(sync=True)
    height = traitlets.Int(400).tag(sync=True)
    cascades = traitlets.Int(0).tag(sync=True)

    def __init__(
        self,
        meshes: list[Any],
        *,
        light: dict[str, Any],
        camera: dict[str, Any] | None = None,
        map_size: int = 1024,
        cascades: int = 0,
        **kwargs: Any,
    ) -> None:
        colors = ["#d8d8d8", "#e07a5f", "#3d85c6", "#81b29a", "#f2cc8f"]
        data = [_mesh_json(m, colors[i % len(colors)]) for i, m in enumerate(meshes)]
        view = camera or {"position": [6.0, -8.0, 6.0], "target": [0.0, 0.0, 0.0]}
        super().__init__(
            meshes=data,
            light=dict(light),
            camera=view,
            map_size=map_size,
            cascades=cascades,
            three_source=THREE_PATH.read_text(encoding="utf-8"),
            module_source=MODULE_PATH.read_text(encoding="utf-8"),
            **kwargs,
        )
        self.refit()

    @traitlets.observe("light", "meshes", "map_size", "cascades")
    def _changed(self, change: Any) -> None:
        self.refit()

    @traitlets.observe("camera")
    def _camera_changed(self, change: Any) -> None:
        if self.cascades > 0:  # only cascades follow the viewer
            self.refit()

    def to_html(self) -> str:
        """A standalone HTML page of the widget as it is now (three.js, ``shadowmath.js``,
        the widget's ESM and its state inline): it draws offline, without Jupyter; the light
        and camera can be moved, without refitting (no Python behind it).

        Returns:
            The page's HTML (about 0.85 MB, mostly three.js).
        """
        state = {k: v for k, v in self.get_state().items() if not k.startswith("_")}
        page = _PAGE.replace("__STATE__", _script_json(state))
        return page.replace("__ESM__", _script_json(_ESM))

    def static(self) -> StaticView:
        """The widget as it is now, as an ``<iframe>`` of :meth:`to_html` that any HTML
        output shows (a notebook exported to HTML, the docs site): display it beside or
        instead of the live widget."""
        return StaticView(self.to_html(), self.height + 40)

    def refit(self) -> None:
        """Fit the light's shadow to the meshes and send the three.js data to the page."""
        try:
            if self.cascades < 0:
                raise ValueError(f"cascades: expected 0 or more, got {self.cascades}")
            if self.cascades > 0:
                self.shadow = fit_sun_cascades(
                    self.light, self.meshes, self.camera, self.map_size, self.cascades
                )
            else:
                self.shadow = fit_light(self.light, self.meshes, self.map_size)
            self.fit_error = ""
        except ValueError as err:
            self.shadow, self.fit_error = {}, str(err)


class StaticView:
    """A standalone widget page shown in an ``<iframe>`` (``_repr_html_``)."""

    def __init__(self, page: str, height: int) -> None:
        self.page, self.height = page, height

    def _repr_html_(self) -> str:
        return (
            f'<iframe srcdoc="{html.escape(self.page, quote=True)}" '
            f'style="width:100%;height:{self.height}px;border:0"></iframe>'
        )


def _scene(meshes: list[dict[str, Any]]) -> sm.Mesh:
    parts = [
        (sm.Mesh(np.reshape(m["positions"], (-1, 3)), np.reshape(m["indices"], (-1, 3))), np.eye(4))
        for m in meshes
    ]
    return sm.gather_meshes(parts)


class ViewCamera(NamedTuple):
    """The widget's viewer as matrices: ``view`` (world to eye) and ``projection`` (OpenGL)."""

    view: np.ndarray
    projection: np.ndarray


def view_camera(camera: dict[str, Any]) -> ViewCamera:
    r"""The matrices of the widget's camera dict, as three.js builds them.

    ``view`` is ``lookAt`` from ``position`` to ``target`` with ``z`` up (rows: right, up,
    back; :math:`V = [R \mid -R e]`); ``projection`` three.js's ``PerspectiveCamera``
    (``fov`` vertical degrees, ``aspect``, ``near``, ``far``; depth -1..1).

    Raises:
        ValueError: the camera looks straight along ``z`` or ``position`` is ``target``.
    """
    eye = np.asarray(camera["position"], dtype=np.float64)
    forward = np.asarray(camera.get("target", [0.0, 0.0, 0.0]), dtype=np.float64) - eye
    right = np.cross(forward, [0.0, 0.0, 1.0])
    if np.linalg.norm(right) <= 1e-9 * max(float(np.linalg.norm(forward)), 1e-300):
        raise ValueError("camera: position and target must differ and not be along z")
    forward /= np.linalg.norm(forward)
    right /= np.linalg.norm(right)
    view = np.eye(4)
    view[:3, :3] = np.stack([right, np.cross(right, forward), -forward])
    view[:3, 3] = -view[:3, :3] @ eye
    f = 1.0 / np.tan(np.radians(float(camera.get("fov", 45.0))) / 2)
    near, far = float(camera.get("near", 0.05)), float(camera.get("far", 500.0))
    projection = np.zeros((4, 4))
    projection[0, 0], projection[1, 1] = f / float(camera.get("aspect", 1.6)), f
    projection[2, 2:] = -(far + near) / (far - near), -2 * far * near / (far - near)
    projection[3, 2] = -1.0
    return ViewCamera(view, projection)


def fit_sun_cascades(
    light: dict[str, Any],
    meshes: list[dict[str, Any]],
    camera: dict[str, Any],
    map_size: int,
    count: int,
) -> dict[str, JsonValue]:
    """The three.js data of ``count`` cascades of the sun ``light`` over ``meshes``' bounds
    seen by ``camera`` (:func:`shadowmath.fit_cascades`, :func:`view_camera`)."""
    if light.get("kind") != "directional":
        raise ValueError(
            f"cascades: only a directional light has cascades, got {light.get('kind')!r}"
        )
    direction = np.asarray(light["position"], float) - np.asarray(
        light.get("target", [0.0] * 3), float
    )
    vertices = np.asarray(_scene(meshes).vertices)
    bounds = np.stack([vertices.min(axis=0), vertices.max(axis=0)])
    view, projection = view_camera(camera)
    fit = sm.fit_cascades(direction, view, projection, bounds, map_size, count=count)
    return cascade_shadow_data(fit)


def fit_light(
    light: dict[str, Any], meshes: list[dict[str, Any]], map_size: int
) -> dict[str, JsonValue]:
    """The three.js data of ``light``'s fit to ``meshes`` (the widget's JSON forms)."""
    scene = _scene(meshes)
    position = np.asarray(light["position"], dtype=np.float64)
    target = np.asarray(light.get("target", [0.0, 0.0, 0.0]), dtype=np.float64)
    kind = light.get("kind")
    if kind == "point":
        depth = sm.cube_depth_range(position, scene, receivers=scene)
        return point_shadow_data(position, depth, map_size=map_size)
    if kind == "directional":
        fit = sm.fit_shadow(
            sm.DirectionalLight(position - target), scene, map_size, receivers=scene
        )
    elif kind == "spot":
        spot = sm.SpotLight(position, target - position, float(light["angle"]))
        fit = sm.fit_shadow(spot, scene, map_size, receivers=scene)
    else:
        raise ValueError(f"light: kind must be 'directional', 'spot' or 'point', got {kind!r}")
    return shadow_data(fit)
