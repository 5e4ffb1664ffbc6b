"""A reference OpenGL renderer for shadowmath's matrices (the ``render`` extra).

Offscreen, through moderngl and EGL (Mesa's llvmpipe on a machine without a
GPU). It follows Gabor Nagy's passes with the matrices of :mod:`shadowmath`
uploaded as they are (:func:`shadowmath.column_major_bytes`), and returns
NumPy arrays. Importing this module imports moderngl; ``import shadowmath``
does not.
"""

from ._context import DEBIAN_PACKAGES as DEBIAN_PACKAGES
from ._context import GLUnavailableError as GLUnavailableError
from ._context import standalone_context as standalone_context
from ._shadow_map import render_shadow_map as render_shadow_map

__all__ = [
    "DEBIAN_PACKAGES",
    "GLUnavailableError",
    "render_shadow_map",
    "standalone_context",
]
