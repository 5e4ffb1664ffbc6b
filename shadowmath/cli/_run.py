"""Drawing the demo and writing what it drew: the device, the render, the files, the printout.

:func:`require_renderer` and :func:`open_device` raise :class:`UnavailableError`
(exit status 1) when the ``render`` extra, an OpenGL context or a WebGPU
adapter is missing; :func:`check_limits` refuses sizes beyond the device's
limits; :func:`render` draws the picture with ``shadowmath.render`` (looked up
at each call, so tests may replace ``render_scene``); :func:`write_outputs`
saves the PNGs and prints a line per file; :func:`print_matrices` prints the
matrices the picture was drawn with.
"""

from __future__ import annotations

import importlib
import re
from collections.abc import Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any, NamedTuple

import numpy as np
from numpy.typing import NDArray

import shadowmath as sm

from ._build import FLOOR_PLANE, WALL_PLANE, LightFit, Scene
from ._options import DEPTH_BIAS_METHODS, OptionError, Options, shown

if TYPE_CHECKING:
    import moderngl

    from shadowmath.render import Frame, Light
    from shadowmath.render.webgpu import WgpuFrame

#: The shading of both APIs' pictures (render_scene's defaults, passed explicitly).
AMBIENT = 0.15
BACKGROUND = (0.06, 0.07, 0.09)


class UnavailableError(Exception):
    """The renderer, its OpenGL context or its WebGPU adapter cannot be had (exit status 1).

    The message follows ``python -m shadowmath: `` on stderr.
    """


def require_renderer() -> None:
    """Import moderngl and :mod:`shadowmath.render` (the ``render`` extra).

    Raises:
        UnavailableError: either is missing.
    """
    try:
        importlib.import_module("moderngl")
        importlib.import_module("shadowmath.render")
    except ImportError as err:
        raise UnavailableError(
            f"the demo needs the 'render' extra, pip install 'shadowmath[render]' ({err})"
        ) from None


class Device(NamedTuple):
    """The graphics device and its size limits.

    Attributes:
        ctx: the OpenGL context, or None for WebGPU (``render_depth_wgpu`` opens its own).
        max_texture: the largest texture side (a shadow map's).
        max_image: the largest picture side.
        limit_name: the driver limit behind ``max_texture``, for messages.
    """

    ctx: moderngl.Context | None
    max_texture: int
    max_image: int
    limit_name: str


def open_device(options: Options) -> Device:
    """The OpenGL context (``standalone_context``) or the WebGPU device, with its limits.

    Raises:
        UnavailableError: no context or adapter, or no wgpu for ``--api webgpu``.
    """
    if options.webgpu:
        try:
            from shadowmath.render.webgpu import WgpuUnavailableError, wgpu_device

            device = wgpu_device()
        except ImportError as err:
            raise UnavailableError(f"--api webgpu needs wgpu (the 'render' extra): {err}") from None
        except WgpuUnavailableError as err:
            raise UnavailableError(f"--api webgpu: {err}") from None
        max_texture = int(device.limits["max-texture-dimension-2d"])
        return Device(None, max_texture, max_texture, "max-texture-dimension-2d")
    from shadowmath.render import GLUnavailableError, standalone_context

    try:
        ctx = standalone_context()
    except GLUnavailableError as err:
        raise UnavailableError(str(err)) from None
    max_texture = int(ctx.info["GL_MAX_TEXTURE_SIZE"])
    max_image = min(max_texture, int(ctx.info["GL_MAX_RENDERBUFFER_SIZE"]))
    return Device(ctx, max_texture, max_image, "GL_MAX_TEXTURE_SIZE")


def check_limits(options: Options, device: Device) -> None:
    """``--map-size`` (unless planar) and ``--size`` within the device's limits.

    Raises:
        OptionError: naming the option, the driver and its limit.
    """
    driver = "WebGPU adapter" if options.webgpu else "OpenGL driver"
    map_w, map_h = options.map_texels
    if options.method != "planar" and max(map_w, map_h) > device.max_texture:
        top = device.max_texture
        raise OptionError(
            f"--map-size {map_w}x{map_h}: larger than this {driver}'s maximum "
            f"texture size, {top}x{top} ({device.limit_name})"
        )
    width, height = options.image_size
    if max(width, height) > device.max_image:
        top = device.max_image
        limits = (
            device.limit_name if options.webgpu else "GL_MAX_TEXTURE_SIZE, GL_MAX_RENDERBUFFER_SIZE"
        )
        raise OptionError(
            f"--size {width} {height}: larger than this {driver}'s maximum image "
            f"size, {top}x{top} ({limits})"
        )


class Rendered(NamedTuple):
    """What was drawn.

    Attributes:
        color: ``(H, W, 3)`` the picture, RGB in ``[0, 1]``.
        setups: the light's setups as the renderer fitted them (one per sample for soft).
        map_picture: the shadow map to save, ``t`` upward (texture, depth, omni), else None.
        adapter: the WebGPU adapter's description, or ``""`` for OpenGL.
    """

    color: NDArray[Any]
    setups: tuple[sm.ShadowSetup, ...]
    map_picture: NDArray[Any] | None
    adapter: str


def render(options: Options, scene: Scene, fit: LightFit, device: Device) -> Rendered:
    """Draw the picture with the device's API.

    Raises:
        UnavailableError: OpenGL failed to draw (e.g. out of memory).
        OptionError: the renderer refused the scene (the checks before should prevent it).
    """
    if options.webgpu:
        try:
            return _render_webgpu(options, scene)
        except ValueError as err:  # the checks before should leave the renderer nothing
            raise renderer_refusal(options, err) from None
    return _render_opengl(options, scene, fit, device.ctx)


def renderer_refusal(options: Options, err: ValueError) -> OptionError:
    """The renderer's ``ValueError`` told as the option that sets the argument it names.

    The checks before drawing should leave the renderer nothing to refuse; this is
    the last resort, keyed on the argument at the start of the renderer's message
    (``map_size: ...``, ``lights[0]: ...``), the light's option when it names none
    the demo sets.
    """
    text = str(err)
    argument = re.split(r"[^a-z_]", text, maxsplit=1)[0]
    map_w, map_h = options.map_texels
    with_pcf = f" with --pcf {options.pcf}" if options.pcf else ""
    area = f"--area-light {shown(options.area_size)} around {options.light_option}"
    option = {
        "map_size": f"--map-size {map_w}x{map_h}{with_pcf}",
        "pcf_radius": f"--pcf {options.pcf}",
        "depth_bias": f"--depth-bias {shown(options.bias)}",
        "samples": f"--samples {options.samples}",
        "image_size": f"--size {shown(options.image_size)}",
        "edge_u": area,
        "edge_v": area,
    }.get(argument, area if options.area and "edge" in text else options.light_option)
    return OptionError(f"{option}: the renderer refused this scene ({text})")


def _render_webgpu(options: Options, scene: Scene) -> Rendered:
    """``render_depth_wgpu``'s depth shadows, shaded in NumPy."""
    from shadowmath.render import Light
    from shadowmath.render import webgpu as wgpu_render

    frame = wgpu_render.render_depth_wgpu(
        scene.receivers,
        [scene.blocker],
        Light(options.light),
        scene.camera,
        image_size=options.image_size,
        map_size=options.map_size,
        pcf_radius=options.pcf,
        depth_bias=options.bias,
    )
    albedo = [body.color for body in (*scene.receivers, scene.blocker)]
    color = webgpu_color(frame, albedo, options.light)
    # WebGPU's first row is t = 0, the top of the light's view: already t upward.
    return Rendered(color, (frame.setup,), depth_picture(frame.depth_map), frame.adapter)


def _render_opengl(
    options: Options, scene: Scene, fit: LightFit, ctx: moderngl.Context | None
) -> Rendered:
    """``render_scene`` with the chosen method, its failures told as the demo's."""
    import moderngl

    from shadowmath import render as gl_render

    method = options.method
    if method == "cascades" or method == "atlas":  # drawn by _cascades / _atlas, never here
        raise AssertionError(f"--method {method} is drawn by its own module")
    light = _light(options, fit)
    try:
        frame = gl_render.render_scene(
            scene.receivers,
            [scene.blocker],
            [light],
            scene.camera,
            image_size=options.image_size,
            # Planar shadows read no map: the smallest one that fits fit_shadow's border.
            map_size=3 if method == "planar" else options.map_size,
            method=method,
            ambient=AMBIENT,
            background=BACKGROUND,
            setups=[[fit.setup]] if method in ("texture", "planar") else None,
            pcf_radius=options.pcf,
            depth_bias=options.bias if method in DEPTH_BIAS_METHODS else None,
            samples=options.samples,
            seed=options.seed,
            light_size=options.light_size,
            ctx=ctx,
        )
    except moderngl.Error as err:
        map_w, map_h = options.map_texels
        with_map = "" if method == "planar" else f" with {map_w}x{map_h} maps"
        width, height = options.image_size
        raise UnavailableError(
            f"OpenGL failed to render a {width}x{height} picture{with_map}: {err}"
        ) from None
    except ValueError as err:  # the checks before should leave the renderer nothing
        raise renderer_refusal(options, err) from None
    return Rendered(frame.color, frame.setups[0], _gl_map_picture(options, frame), "")


def _light(options: Options, fit: LightFit) -> Light:
    """The renderer's light: directional, a point, or an area light with its edges."""
    from shadowmath.render import Light

    if options.directional:
        return Light(direction=options.light)
    if fit.edges is None:
        return Light(options.light)
    return Light(options.light, edge_u=fit.edges[0], edge_v=fit.edges[1])


def _gl_map_picture(options: Options, frame: Frame) -> NDArray[Any] | None:
    """The shadow map to save, ``t`` upward: a GL map's row 0 is ``t = 0``, its bottom."""
    if options.method == "texture":
        return frame.shadow_maps[0][0][::-1]
    if options.method in ("depth", "pcss"):
        return depth_picture(frame.shadow_maps[0][0][::-1])
    if options.method == "omni":
        faces = np.stack(frame.shadow_maps[0])[:, ::-1]
        return np.concatenate(list(depth_picture(faces)), axis=1)
    return None


def depth_picture(depth: NDArray[Any]) -> NDArray[np.float64]:
    """Window depths as grey: the drawn range stretched from black (near) to light grey
    (far), white where nothing was drawn (depth 1)."""
    d = np.asarray(depth, dtype=np.float64)
    drawn = d < 1.0
    if not drawn.any():
        return np.ones_like(d)
    lo, hi = float(d[drawn].min()), float(d[drawn].max())
    scaled = 0.8 * (d - lo) / (hi - lo if hi > lo else 1.0)
    return np.where(drawn, scaled, 1.0)


def webgpu_color(
    frame: WgpuFrame, albedo: Sequence[Sequence[float]], light: NDArray[np.float64]
) -> NDArray[np.float64]:
    """The picture from a WebGPU frame's record: ``render_scene``'s shading (ambient plus
    Lambert, the diffuse term removed by the shadow mask) with the face normals."""
    body = frame.body
    colors = np.asarray(albedo, dtype=np.float64)[np.clip(body, 0, None)]
    to_light = light - frame.position
    to_light /= np.linalg.norm(to_light, axis=-1, keepdims=True)
    diffuse = np.clip(np.sum(frame.normal * to_light, axis=-1), 0.0, None)
    shade = AMBIENT + diffuse * (1.0 - frame.shadow)
    color = colors * shade[..., None]
    return np.where((body >= 0)[..., None], np.nan_to_num(color), np.asarray(BACKGROUND))


def save_png(option: str, path: Path, image: NDArray[Any]) -> None:
    """``image`` in ``[0, 1]`` (grey or RGB) as an 8-bit PNG.

    Raises:
        OptionError: naming ``option`` and the system's reason (permissions, disk full).
    """
    from PIL import Image

    try:
        Image.fromarray(np.rint(np.clip(image, 0, 1) * 255).astype(np.uint8)).save(path)
    except OSError as err:
        raise OptionError(f"{option} {path}: cannot write it ({err.strerror or err})") from None


def output_path(options: Options) -> Path:
    """``--output``, its default folder created when missing (any other must exist)."""
    output = options.output
    if options.default_output:
        try:
            output.parent.mkdir(parents=True, exist_ok=True)
        except OSError as err:
            raise OptionError(
                f"--output {output}: cannot create its folder ({err.strerror or err})"
            ) from None
    return output


def write_outputs(options: Options, rendered: Rendered) -> None:
    """Save the picture and the shadow map (when asked), printing a line for each file.

    The default output folder is created when missing, any other must exist.

    Raises:
        OptionError: a file (or the default folder) cannot be written, naming its option.
    """
    output = output_path(options)
    save_png("--output", output, rendered.color)
    print(f"wrote {output}: {summary(options, rendered.adapter)}")
    if options.map_output is not None and rendered.map_picture is not None:
        save_png("--shadow-map-output", options.map_output, rendered.map_picture)
        map_w, map_h = options.map_texels
        what = {
            "texture": f"the {map_w}x{map_h} shadow map, t upward",
            "depth": f"the {map_w}x{map_h} depth map, t upward, near dark, far light, "
            "white where nothing was drawn",
            "omni": f"the six {map_w}x{map_h} cube faces +X -X +Y -Y +Z -Z, t upward, "
            "near dark, far light",
            "pcss": f"the {map_w}x{map_h} depth map of the faces turned from the light, "
            "t upward, near dark, far light, white where nothing was drawn",
        }[options.method]
        print(f"wrote {options.map_output}: {what}")


def summary(options: Options, adapter: str) -> str:
    """What the picture shows: its size, the blocker and the light, the shadow system."""
    width, height = options.image_size
    return f"a {width}x{height} PNG, {_lit(options)}, {_drawn(options, adapter)}"


def _lit(options: Options) -> str:
    """The blocker between the light and the wall."""
    where = tuple(float(c) for c in options.light)
    if options.area:
        w, h = options.area_size
        return f"{options.mesh} between a {w:g}x{h:g} area light centred at {where} and a wall"
    if options.directional:
        return f"{options.mesh} between a directional light toward {where} and a wall"
    return f"{options.mesh} between a point light at {where} and a wall"


def _drawn(options: Options, adapter: str) -> str:
    """The shadow system with its map sizes, PCF radius, bias, samples and API."""
    map_w, map_h = options.map_texels
    bias = f"depth bias {options.bias[0]:g} {options.bias[1]:g}"
    pcf, samples, seed = options.pcf, options.samples, options.seed
    api = f"WebGPU on {adapter}, shading composed in NumPy" if options.webgpu else "OpenGL"
    orthographic = ", orthographic" if options.directional else ""
    return {
        "texture": f"Nagy's projective shadow texture from a {map_w}x{map_h} shadow map",
        "planar": "Blinn's planar shadows",
        "depth": f"Williams' depth shadow map ({map_w}x{map_h}{orthographic}, "
        f"PCF radius {pcf}, {bias}) drawn with {api}",
        "omni": f"an omnidirectional cube depth map (six {map_w}x{map_h} faces, {bias})",
        "soft": f"soft shadows, the average of {samples} samples' depth shadow maps "
        f"({map_w}x{map_h}, PCF radius {pcf}, {bias}; seed {seed})",
        "radiance": f"soft shadows, Heckbert and Herf's radiance textures ({map_w}x{map_h} "
        f"per receiver) accumulated over {samples} samples (seed {seed})",
        "pcss": f"percentage-closer soft shadows of {_light_size(options)} from a depth map "
        f"of the faces turned from the light ({map_w}x{map_h}{orthographic}, {bias})",
    }[options.method]


def _light_size(options: Options) -> str:
    """``--light-size`` in words: ``radius 0.25`` or ``angular radius 1 degree``."""
    if options.directional:
        return f"angular radius {np.degrees(options.light_size):g} degrees"
    return f"radius {options.light_size:g}"


def print_matrix(name: str, matrix: Any) -> None:
    """``name =`` and the matrix below it, 5 decimals, rounding noise and ``-0`` shown as 0."""
    # Rounding away the last bits, then + 0.0, prints rounding noise and -0 as 0.
    shown = np.round(np.asarray(matrix, dtype=np.float64), 12) + 0.0
    # Local print options: main() runs in-process in tests and must not change NumPy's.
    with np.printoptions(precision=5, suppress=True):
        print(f"{name} =", shown, sep="\n")


def print_matrices(options: Options, scene: Scene, fit: LightFit, rendered: Rendered) -> None:
    """The blocker's placement, the method's matrices, and Blinn's flattening matrices."""
    print_matrix("blocker_to_world", np.asarray(scene.blocker.to_world))
    method = options.method
    if method == "texture":
        setup = fit.setup
        print_matrix("world_to_light", setup.world_to_light)
        print_matrix("blocker_to_clip (pass 1, the shadow map)", setup.blocker_to_clip)
        print_matrix("world_to_texture (pass 2, the receivers)", setup.world_to_texture)
    elif method == "depth":
        _print_depth_matrices(options, rendered)
    elif method == "pcss":
        _print_depth_matrices(options, rendered)
        _print_pcss_parameters(options, rendered)
    elif method == "omni":
        _print_omni_matrices(options, scene)
    elif fit.points is not None and fit.edges is not None:
        print_matrix("area light edge_u (W, horizontal)", fit.edges[0])
        print_matrix("area light edge_v (H, upward)", fit.edges[1])
        print_matrix(f"area_light_samples (the {options.samples} light samples)", fit.points)
    light_h = np.append(options.light, 0.0 if options.directional else 1.0)
    for name, plane in (("the wall z = 0", WALL_PLANE), ("the floor y = 0", FLOOR_PLANE)):
        print_matrix(f"planar_projection onto {name}", sm.planar_projection(plane, light_h))


def _print_depth_matrices(options: Options, rendered: Rendered) -> None:
    """The depth map's setup, fitted to the blocker's world vertices (its "blocker" is the
    world), and WebGPU's clip conversion when it drew."""
    (setup,) = rendered.setups
    print_matrix("world_to_light", setup.world_to_light)
    print_matrix(
        "world_to_clip of the light (pass 1, every body's depth; OpenGL conventions)",
        setup.blocker_to_clip,
    )
    print_matrix(
        "world_to_texture (pass 2, (s q, t q, r q, q) compared with the map)",
        setup.world_to_texture,
    )
    if options.webgpu:
        print_matrix(
            "gl_clip_to_clip (api_convention(api='webgpu'), applied to both)",
            sm.api_convention(api="webgpu").gl_clip_to_clip,
        )


def _print_pcss_parameters(options: Options, rendered: Rendered) -> None:
    """pcss_parameters of the map: texels per unit of stored depth and the near depth."""
    (setup,) = rendered.setups
    if options.directional:
        p = sm.pcss_parameters(setup, angular_radius=options.light_size, map_size=options.map_size)
    else:
        p = sm.pcss_parameters(setup, light_radius=options.light_size, map_size=options.map_size)
    print_matrix(
        "pcss_parameters: K (texels per unit of depth along s, t), then d_near "
        "(search = K |d_R - d_near|, penumbra = K (d_R - d_B))",
        np.append(np.asarray(p.texels_per_depth), np.asarray(p.near_depth)),
    )


def _print_omni_matrices(options: Options, scene: Scene) -> None:
    """The cube faces' projection, its depth range as the omni pass sets it, and views."""
    light = options.light
    # The pass's depth range: far just beyond the farthest vertex along a face axis.
    far = 1.001 * float(np.abs(scene.world_vertices() - light).max())
    near = 1e-3 * far
    map_w = options.map_texels[0]
    print_matrix(
        f"cube_face_projection(near={near:.5g}, far={far:.5g}, map_size={map_w})",
        sm.cube_face_projection(near, far, map_size=map_w),
    )
    print_matrix("cube_face_views(light), faces +X -X +Y -Y +Z -Z", sm.cube_face_views(light))
