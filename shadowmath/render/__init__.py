"""A reference OpenGL renderer for shadowmath's matrices (the ``render`` extra).

Offscreen, through moderngl and EGL (Mesa's llvmpipe on a machine without a
GPU). It follows Gabor Nagy's passes with the matrices of :mod:`shadowmath`
uploaded as they are (:func:`shadowmath.column_major_bytes`), and returns
NumPy arrays. Importing this module imports moderngl; ``import shadowmath``
does not.

* :func:`render_shadow_map`: pass 1 alone, the blocker's flat-colour silhouette
  through ``blocker_to_clip`` (no depth test), as a ``(height, width)`` mask
  whose row 0 is texture ``t = 0``.
* :func:`render_scene`: the whole method from a camera: a lit pass, then per
  light the shadow maps of its blockers applied to the receivers as projective
  textures (or Blinn's flattened blockers, ``method="planar"``), combined into
  one mask per light, and a subtractive pass per light. ``method="depth"`` is
  Williams' shadow z-buffer, ``method="omni"`` a point light's cube depth map
  sampled with ``samplerCubeShadow``; ``method="soft"`` and ``"radiance"`` average
  the hard shadows of an area light's samples (seed 003's depth maps, Heckbert and
  Herf's radiance textures); ``method="pcss"`` is percentage-closer soft shadows of a
  light of ``light_size``, with :func:`shadowmath.pcss_parameters`' quantities
  (``method="omni"`` with ``light_size``: the same through the cube map).
  Lights are points (``Light(position)``), area lights (``edge_u``, ``edge_v``) or,
  for ``method="planar"``, ``"depth"`` and ``"pcss"``, directional (``Light(direction=...)``,
  the homogeneous ``(x, y, z, 0)``: parallel rays, an orthographic depth map).
* :func:`render_cascades`: a sun's cascaded shadow maps fitted to the camera
  (:func:`shadowmath.fit_cascades`), drawn as layers of a texture array or tiles of an
  atlas; the camera-view pass picks the cascade by view depth and blends across the
  bands; optionally a second picture coloured by cascade; with ``light_size`` (the sun's
  angular radius) percentage-closer soft shadows in every cascade.
* :func:`render_atlas`: many point (cube-mapped), spot and directional lights whose
  shadow maps share one atlas (:func:`shadowmath.allocate_atlas`,
  :func:`shadowmath.fit_atlas`), each light's shadow mask and the picture lit by all.
* :func:`radiance_texture`: Heckbert and Herf's radiance texture of one receiver
  parallelogram, as a NumPy array.
* moderngl 5 has no stencil state. Where the articles use the stencil buffer
  (confining planar shadows to their receiver, darkening overlapping shadows
  once) this renderer records each pixel's body id in the lit pass and
  discards mask fragments on other bodies, and blends the masks with ``MAX``.

The shaders are files in ``shadowmath/render/shaders``. No GL context, no
picture: :class:`GLUnavailableError` names the Debian packages to install
(:data:`DEBIAN_PACKAGES`). Without moderngl, importing this module raises an
``ImportError`` that names the extra to install (``pip install 'shadowmath[render]'``).
"""

try:
    import moderngl  # noqa: F401  (the render extra; imported by the passes below)
except ImportError as err:
    raise ImportError(
        "shadowmath.render needs moderngl (the render extra): pip install 'shadowmath[render]'"
    ) from err

from ._context import DEBIAN_PACKAGES as DEBIAN_PACKAGES
from ._context import GLUnavailableError as GLUnavailableError
from ._context import standalone_context as standalone_context
from ._pass_atlas import AtlasFrame as AtlasFrame
from ._pass_atlas import render_atlas as render_atlas
from ._pass_cascades import CASCADE_COLORS as CASCADE_COLORS
from ._pass_cascades import MAX_CASCADES as MAX_CASCADES
from ._pass_cascades import CascadeFrame as CascadeFrame
from ._pass_cascades import render_cascades as render_cascades
from ._pass_lit import MAX_LIGHTS as MAX_LIGHTS
from ._pass_pcss import PCSS_POLYGON_OFFSET as PCSS_POLYGON_OFFSET
from ._pass_planar import PLANAR_POLYGON_OFFSET as PLANAR_POLYGON_OFFSET
from ._pass_soft import radiance_texture as radiance_texture
from ._resources import Body as Body
from ._resources import Light as Light
from ._scene import Frame as Frame
from ._scene import render_scene as render_scene
from ._shadow_map import render_shadow_map as render_shadow_map
from ._viewer_camera import look_at as look_at
from ._viewer_camera import perspective as perspective

__all__ = [
    "CASCADE_COLORS",
    "DEBIAN_PACKAGES",
    "MAX_CASCADES",
    "MAX_LIGHTS",
    "PCSS_POLYGON_OFFSET",
    "PLANAR_POLYGON_OFFSET",
    "AtlasFrame",
    "Body",
    "CascadeFrame",
    "Frame",
    "GLUnavailableError",
    "Light",
    "look_at",
    "perspective",
    "radiance_texture",
    "render_atlas",
    "render_cascades",
    "render_scene",
    "render_shadow_map",
    "standalone_context",
]
