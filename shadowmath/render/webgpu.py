"""Williams' shadow z-buffer on WebGPU (``wgpu``): the reference render's second API.

Importing this module imports ``wgpu`` (in the ``render`` extra); on a machine
without a GPU it runs on Mesa's software Vulkan driver (Debian:
``mesa-vulkan-drivers``). :func:`render_depth_wgpu` draws the scene of
``render_scene(..., method="depth")`` with WebGPU's conventions
(:func:`shadowmath.api_convention` ``api="webgpu"``), :func:`render_cascades_wgpu` the
cascades of ``render_cascades`` (``shaders/cascades.wgsl``), :func:`render_pcss_wgpu`
one light's ``method="pcss"`` (``shaders/pcss_scene.wgsl``), :func:`render_atlas_wgpu`
many lights through one atlas (``shaders/atlas.wgsl``; PCSS with ``light_size``, a point
light's six face tiles WebGPU's cube maps).
"""

from ._pass_atlas_wgpu import WgpuAtlasFrame as WgpuAtlasFrame
from ._pass_atlas_wgpu import render_atlas_wgpu as render_atlas_wgpu
from ._pass_cascades_wgpu import FLOAT_DEPTH_RESOLUTION as FLOAT_DEPTH_RESOLUTION
from ._pass_cascades_wgpu import WgpuCascadeFrame as WgpuCascadeFrame
from ._pass_cascades_wgpu import render_cascades_wgpu as render_cascades_wgpu
from ._pass_pcss_wgpu import render_pcss_wgpu as render_pcss_wgpu
from ._pass_wgpu import VULKAN_DEBIAN_PACKAGES as VULKAN_DEBIAN_PACKAGES
from ._pass_wgpu import WgpuFrame as WgpuFrame
from ._pass_wgpu import WgpuUnavailableError as WgpuUnavailableError
from ._pass_wgpu import adapter_description as adapter_description
from ._pass_wgpu import render_depth_wgpu as render_depth_wgpu
from ._pass_wgpu import wgpu_device as wgpu_device

__all__ = [
    "FLOAT_DEPTH_RESOLUTION",
    "VULKAN_DEBIAN_PACKAGES",
    "WgpuAtlasFrame",
    "WgpuCascadeFrame",
    "WgpuFrame",
    "WgpuUnavailableError",
    "adapter_description",
    "render_atlas_wgpu",
    "render_cascades_wgpu",
    "render_depth_wgpu",
    "render_pcss_wgpu",
    "wgpu_device",
]
