"""shadowmath: shadow matrices for NumPy and JAX.

Blinn's planar-projection shadows and Gabor Nagy's adaptive projective shadow
textures ("Real-Time Shadows on Complex Objects"), derived and tested against
geometry rather than copied from print. The full text of these conventions,
with figures, is ``docs/conventions.md``.

CONVENTIONS
-----------
* **Column vectors.** A transformed point is ``M @ p``; matrices compose right
  to left (``blocker_to_clip = P @ W @ B``). The articles print row-vector
  matrices: ours are their transposes.
* **Memory layout is separate.** NumPy stores ``M[row, col]`` row-major;
  OpenGL's ``mat4`` wants columns first. :func:`column_major_bytes` gives the
  float32 bytes for a uniform; nothing else in the package changes layout.
* **Planes** are ``(a, b, c, d)`` for ``a x + b y + c z + d = 0``.
* **Lights** are homogeneous ``(x, y, z, w)``: ``w = 1`` a point light at
  ``(x, y, z)``, ``w = 0`` a directional light whose ``(x, y, z)`` points from
  the scene *toward* the light. Functions of Nagy's method take a point
  light's position ``(x, y, z)``.
* **Light coordinates** (Nagy): origin at the light, ``+Z`` toward the
  blocker, ``X = normalize(Z x V)`` with ``V`` the helper axis, ``Y = X x Z``.
  Since ``X x Y = -Z`` the frame is *left-handed*. An OpenGL right-handed
  look-at camera placed at the light with the same ``X`` and ``Y`` looks down
  its ``-z``: its view coordinates are ours with ``z`` negated.
* **Clip space and depth**: OpenGL's, ``w_clip = +z_light > 0`` in front of
  the light, NDC depth ``-1`` at near and ``+1`` at far; texture coordinates
  ``(s, t, r)`` in ``[0, 1]`` with ``t = 0`` at the map's first row.
* **Batches**: every argument takes leading batch dimensions, ``(*batch, 3)``
  points, ``(*batch, N, 3)`` vertex sets, ``(*batch, 4, 4)`` matrices, that
  broadcast NumPy-style.
* **Backends**: NumPy in gives NumPy out, JAX in gives JAX out (a mix gives
  JAX); float32 stays float32, float64 stays float64, integers become float64
  (float16 becomes float32, with a :class:`ShadowFitWarning`). ``import shadowmath``
  does not import JAX.
* **Errors**: bad shapes always raise ``ValueError``. Bad values raise
  ``ValueError`` naming the argument and the problem for NumPy and concrete
  JAX inputs; inside JAX transformations (``jit``, ``vmap``, ``grad``), where
  raising is impossible, the affected outputs are NaN instead, never a finite
  wrong matrix.
"""

from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:  # what mypy and readers see; at run time each name loads on first use
    from ._boundary._messages import ShadowFitWarning as ShadowFitWarning
    from ._fits._spec import ShadowMapSpec as ShadowMapSpec
    from ._fits.atlas._allocate import ShadowAtlas as ShadowAtlas
    from ._fits.atlas._allocate import allocate_atlas as allocate_atlas
    from ._fits.atlas._door import fit_atlas as fit_atlas
    from ._fits.atlas._redraw import atlas_redraw as atlas_redraw
    from ._fits.atlas._result import AtlasFit as AtlasFit
    from ._fits.atlas._viewports import atlas_tile_transforms as atlas_tile_transforms
    from ._fits.atlas._viewports import atlas_viewports as atlas_viewports
    from ._fits.camera._shadow_camera import ShadowCamera as ShadowCamera
    from ._fits.camera._shadow_camera import camera_to_world as camera_to_world
    from ._fits.camera._shadow_camera import shadow_camera as shadow_camera
    from ._fits.cascades._door import fit_cascades as fit_cascades
    from ._fits.cascades._result import Cascades as Cascades
    from ._fits.cascades._result import CascadeState as CascadeState
    from ._fits.cascades._splits import cascade_splits as cascade_splits
    from ._fits.cube._door import cube_depth_range as cube_depth_range
    from ._fits.cube._result import CubeDepthRange as CubeDepthRange
    from ._fits.pcss._door import pcss_parameters as pcss_parameters
    from ._fits.pcss._door import pcss_widths as pcss_widths
    from ._fits.pcss._result import PcssParameters as PcssParameters
    from ._fits.pcss._result import PcssWidths as PcssWidths
    from ._fits.pcss._room import pcss_border_texels as pcss_border_texels
    from ._fits.pcss._room import widen_cascades as widen_cascades
    from ._fits.shadow._driver import fit_shadow as fit_shadow
    from ._fits.shadow._driver import receiver_texture_matrix as receiver_texture_matrix
    from ._fits.shadow._optimize_frustum import FrustumFit as FrustumFit
    from ._fits.shadow._optimize_frustum import optimize_frustum as optimize_frustum
    from ._fits.shadow._prepared import PreparedFit as PreparedFit
    from ._fits.shadow._prepared import ShadowFitter as ShadowFitter
    from ._fits.shadow._result import ShadowSetup as ShadowSetup
    from ._geometry._adaptive_frustum import adaptive_frustum as adaptive_frustum
    from ._geometry._adaptive_frustum import blocker_projection as blocker_projection
    from ._geometry._adaptive_frustum import border_margin as border_margin
    from ._geometry._adaptive_frustum import receiver_projection as receiver_projection
    from ._geometry._api_convention import api_convention as api_convention
    from ._geometry._area_light import area_light_samples as area_light_samples
    from ._geometry._area_light import area_light_samples_jax as area_light_samples_jax
    from ._geometry._area_light import pyramid_to_unit_cube as pyramid_to_unit_cube
    from ._geometry._checks import check_finite as check_finite
    from ._geometry._checks import check_projection as check_projection
    from ._geometry._column_major import column_major_bytes as column_major_bytes
    from ._geometry._cube_faces import cube_face as cube_face
    from ._geometry._cube_faces import cube_face_depth as cube_face_depth
    from ._geometry._cube_faces import cube_face_direction as cube_face_direction
    from ._geometry._cube_faces import cube_face_projection as cube_face_projection
    from ._geometry._cube_faces import cube_face_views as cube_face_views
    from ._geometry._depth_bias import normal_offset as normal_offset
    from ._geometry._depth_bias import slope_scaled_bias as slope_scaled_bias
    from ._geometry._depth_bias import texel_world_size as texel_world_size
    from ._geometry._light_frame import helper_axis as helper_axis
    from ._geometry._light_frame import light_frame as light_frame
    from ._geometry._light_frame import light_frame_from_direction as light_frame_from_direction
    from ._geometry._light_frame import light_to_world as light_to_world
    from ._geometry._light_frame import mean_direction_vector as mean_direction_vector
    from ._geometry._light_frame import world_to_light as world_to_light
    from ._geometry._pcf_lookup import pcf as pcf
    from ._geometry._pcf_lookup import pcf_border_texels as pcf_border_texels
    from ._geometry._planar_projection import planar_projection as planar_projection
    from ._geometry._shadow_measures import cross_section_area as cross_section_area
    from ._geometry._shadow_measures import receiver_texel_size as receiver_texel_size
    from ._geometry._shadow_measures import silhouette_coverage as silhouette_coverage
    from ._geometry._smooth_frustum import offcenter_frustum as offcenter_frustum
    from ._geometry._smooth_frustum import rolled_light_frame as rolled_light_frame
    from ._geometry._smooth_frustum import smooth_frustum as smooth_frustum
    from ._geometry._smooth_frustum import smooth_max as smooth_max
    from ._math._conventions import GRAPHICS_APIS as GRAPHICS_APIS
    from ._math._conventions import ApiConvention as ApiConvention
    from ._math._cube import CubeFaceCoords as CubeFaceCoords
    from ._math._cube import CubeFaceDepth as CubeFaceDepth
    from ._math._frame import LightFrame as LightFrame
    from ._math._frustum import NEAR_FAR_SLACK as NEAR_FAR_SLACK
    from ._math._frustum import Frustum as Frustum
    from ._math._frustum import OrthographicBox as OrthographicBox
    from ._scene._summary import GeometrySummary as GeometrySummary
    from .gather import gather_meshes as gather_meshes
    from .lights import DirectionalLight as DirectionalLight
    from .lights import PointLight as PointLight
    from .lights import SpotLight as SpotLight
    from .receivers import Mesh as Mesh
    from .receivers import Triangles as Triangles
    from .scene import LightShadows as LightShadows
    from .scene import SceneAtlas as SceneAtlas
    from .scene import SceneCascades as SceneCascades
    from .scene import SceneSummaries as SceneSummaries
    from .scene import ShadowScene as ShadowScene
    from .scene import SummaryFit as SummaryFit
    from .scene import fit_summaries as fit_summaries
    from .scene import summarize_geometry as summarize_geometry

# Each public name and the module that defines it, imported on first use (PEP 562): ``import
# shadowmath`` costs a dictionary, not the package (tests/test_lazy_import.py checks that this
# table and the imports above name the same things).
_MODULES: dict[str, tuple[str, ...]] = {
    "._geometry._adaptive_frustum": (
        "adaptive_frustum",
        "blocker_projection",
        "border_margin",
        "receiver_projection",
    ),
    "._geometry._api_convention": ("api_convention",),
    "._geometry._area_light": (
        "area_light_samples",
        "area_light_samples_jax",
        "pyramid_to_unit_cube",
    ),
    "._geometry._checks": (
        "check_finite",
        "check_projection",
    ),
    "._geometry._column_major": ("column_major_bytes",),
    "._geometry._cube_faces": (
        "cube_face",
        "cube_face_depth",
        "cube_face_direction",
        "cube_face_projection",
        "cube_face_views",
    ),
    "._geometry._depth_bias": (
        "normal_offset",
        "slope_scaled_bias",
        "texel_world_size",
    ),
    "._geometry._light_frame": (
        "helper_axis",
        "light_frame",
        "light_frame_from_direction",
        "light_to_world",
        "mean_direction_vector",
        "world_to_light",
    ),
    "._geometry._pcf_lookup": (
        "pcf",
        "pcf_border_texels",
    ),
    "._geometry._planar_projection": ("planar_projection",),
    "._geometry._shadow_measures": (
        "cross_section_area",
        "receiver_texel_size",
        "silhouette_coverage",
    ),
    "._geometry._smooth_frustum": (
        "offcenter_frustum",
        "rolled_light_frame",
        "smooth_frustum",
        "smooth_max",
    ),
    "._boundary._messages": ("ShadowFitWarning",),
    "._fits.atlas._allocate": ("ShadowAtlas", "allocate_atlas"),
    "._fits.atlas._door": ("fit_atlas",),
    "._fits.atlas._result": ("AtlasFit",),
    "._fits.atlas._redraw": ("atlas_redraw",),
    "._fits.atlas._viewports": ("atlas_tile_transforms", "atlas_viewports"),
    "._fits.cascades._splits": ("cascade_splits",),
    "._fits.cascades._door": ("fit_cascades",),
    "._fits.cascades._result": ("CascadeState", "Cascades"),
    "._fits.cube._door": ("cube_depth_range",),
    "._fits.cube._result": ("CubeDepthRange",),
    "._fits.shadow._optimize_frustum": (
        "FrustumFit",
        "optimize_frustum",
    ),
    "._fits.pcss._door": ("pcss_parameters", "pcss_widths"),
    "._fits.pcss._result": ("PcssParameters", "PcssWidths"),
    "._fits.pcss._room": (
        "pcss_border_texels",
        "widen_cascades",
    ),
    "._fits.shadow._prepared": (
        "PreparedFit",
        "ShadowFitter",
    ),
    "._fits.shadow._driver": (
        "fit_shadow",
        "receiver_texture_matrix",
    ),
    "._fits.camera._shadow_camera": (
        "ShadowCamera",
        "camera_to_world",
        "shadow_camera",
    ),
    "._fits.shadow._result": ("ShadowSetup",),
    "._fits._spec": ("ShadowMapSpec",),
    "._math._conventions": (
        "GRAPHICS_APIS",
        "ApiConvention",
    ),
    "._math._cube": (
        "CubeFaceCoords",
        "CubeFaceDepth",
    ),
    "._math._frame": ("LightFrame",),
    "._math._frustum": (
        "NEAR_FAR_SLACK",
        "Frustum",
        "OrthographicBox",
    ),
    ".gather": ("gather_meshes",),
    ".lights": (
        "DirectionalLight",
        "PointLight",
        "SpotLight",
    ),
    ".receivers": (
        "Mesh",
        "Triangles",
    ),
    "._scene._summary": ("GeometrySummary",),
    ".scene": (
        "LightShadows",
        "SceneAtlas",
        "SceneCascades",
        "SceneSummaries",
        "ShadowScene",
        "SummaryFit",
        "fit_summaries",
        "summarize_geometry",
    ),
}
_WHERE = {name: module for module, names in _MODULES.items() for name in names}


def __getattr__(name: str) -> Any:
    module = _WHERE.get(name)
    if module is None:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    import importlib
    import types

    from ._boundary._shapes import shapes_checked

    value = getattr(importlib.import_module(module, __name__), name)
    if isinstance(value, types.FunctionType):
        # Itself, but in the test suite (see its docstring): every public function is checked.
        value = shapes_checked(value)
    globals()[name] = value  # later look-ups are plain module attributes
    return value


def __dir__() -> list[str]:
    return sorted({*globals(), *_WHERE})


__version__ = "0.1.0"

__all__ = [
    "GRAPHICS_APIS",
    "NEAR_FAR_SLACK",
    "ApiConvention",
    "AtlasFit",
    "CascadeState",
    "Cascades",
    "CubeDepthRange",
    "CubeFaceCoords",
    "CubeFaceDepth",
    "DirectionalLight",
    "Frustum",
    "FrustumFit",
    "LightFrame",
    "Mesh",
    "OrthographicBox",
    "PcssParameters",
    "PcssWidths",
    "PointLight",
    "PreparedFit",
    "ShadowAtlas",
    "ShadowCamera",
    "ShadowFitWarning",
    "ShadowFitter",
    "ShadowMapSpec",
    "ShadowSetup",
    "SpotLight",
    "Triangles",
    "adaptive_frustum",
    "allocate_atlas",
    "api_convention",
    "area_light_samples",
    "atlas_redraw",
    "atlas_tile_transforms",
    "atlas_viewports",
    "blocker_projection",
    "border_margin",
    "camera_to_world",
    "cascade_splits",
    "check_finite",
    "check_projection",
    "column_major_bytes",
    "cross_section_area",
    "cube_depth_range",
    "cube_face",
    "cube_face_depth",
    "cube_face_direction",
    "cube_face_projection",
    "cube_face_views",
    "fit_atlas",
    "fit_cascades",
    "fit_shadow",
    "gather_meshes",
    "helper_axis",
    "light_frame",
    "light_frame_from_direction",
    "light_to_world",
    "mean_direction_vector",
    "normal_offset",
    "offcenter_frustum",
    "optimize_frustum",
    "pcf",
    "pcf_border_texels",
    "pcss_border_texels",
    "pcss_parameters",
    "pcss_widths",
    "planar_projection",
    "pyramid_to_unit_cube",
    "receiver_projection",
    "receiver_texel_size",
    "receiver_texture_matrix",
    "rolled_light_frame",
    "shadow_camera",
    "silhouette_coverage",
    "slope_scaled_bias",
    "smooth_frustum",
    "smooth_max",
    "texel_world_size",
    "widen_cascades",
    "world_to_light",
]
