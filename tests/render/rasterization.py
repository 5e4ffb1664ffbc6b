"""What the rasterization rules guarantee when one depth map is drawn twice, at two places
in the window (a cascade as its own layer and as an atlas tile): the bound of
docs/accuracy.md ("Accuracy on real GPUs"), from the specifications, not from one
rasterizer's output.

Each texel's depth is the plane of its triangle evaluated at the texel's centre (OpenGL
4.6 section 14.6.1, equation 14.10; Vulkan "Basic Polygon Rasterization"; WebGPU
"Rasterization"). The two draws may differ in

- where the vertices land: window coordinates are snapped to a grid of 2**-SUBPIXEL_BITS
  pixels (OpenGL section 14.5 and Table 23.70, at least 4 bits; Vulkan's
  ``subPixelPrecisionBits``, at least 4), and ``x_w = (w/2) x_d + o_x`` rounds differently
  for another offset ``o_x``, so each vertex may move by one step ``s``; that moves the
  plane at any point inside the triangle by at most ``s (|dz/dx| + |dz/dy|)`` (the moved
  vertex's barycentric weight times its move, summed over the vertices);
- the arithmetic: OpenGL asks of each floating-point result about 1 part in 10**5
  (section 2.3.4.1), and depths are at most 1: ``FLOAT_ACCURACY`` absolute, which also
  covers the 24-bit depth buffer's rounding (2**-24);
- which triangle covers a texel whose centre lies within ``s`` of an edge: there the depth
  may be any of the surfaces meeting within the texel's neighbourhood.

Depths are not required to match bit for bit: the invariance rules (OpenGL Appendix A)
hold for the same state only, and the viewport is state.
"""

from __future__ import annotations

import numpy as np

#: OpenGL 4.6 section 2.3.4.1: "individual results of floating-point operations are
#: accurate to about 1 part in 10**5"; depths lie in [0, 1].
FLOAT_ACCURACY = 1e-5
#: The least GL_SUBPIXEL_BITS (OpenGL 4.6 Table 23.70) and subPixelPrecisionBits (Vulkan
#: required limits) a conformant implementation may have.
MIN_SUBPIXEL_BITS = 4


def neighbourhood(z: np.ndarray, reduce) -> np.ndarray:
    """``reduce`` (np.minimum or np.maximum) over each texel's 3 x 3 neighbourhood (edge
    texels repeat)."""
    p = np.pad(z, 1, mode="edge")
    h, w = z.shape
    out = z.copy()
    for dy in range(3):
        for dx in range(3):
            out = reduce(out, p[dy : dy + h, dx : dx + w])
    return out


def slope_and_creases(z: np.ndarray, tol: float) -> tuple[np.ndarray, np.ndarray]:
    """Per texel: ``|dz/dx| + |dz/dy|`` (the larger one-sided difference on each axis,
    in depth per texel) and whether more than one plane meets around it (a second
    difference above ``tol``: an edge, a crease or a silhouette)."""
    p = np.pad(z, 1, mode="edge")
    slope = np.zeros_like(z)
    crease = np.zeros(z.shape, dtype=bool)
    for before, after in ((p[1:-1, :-2], p[1:-1, 2:]), (p[:-2, 1:-1], p[2:, 1:-1])):
        slope += np.maximum(np.abs(z - before), np.abs(after - z))
        crease |= np.abs(after - 2 * z + before) > tol
    return slope, crease


def same_map_elsewhere(drawn: np.ndarray, reference: np.ndarray, *, subpixel_bits: int) -> None:
    """Assert ``drawn`` is ``reference`` (1 where nothing was drawn) drawn at another place
    in the window, within what the rasterization rules above allow."""
    assert subpixel_bits >= MIN_SUBPIXEL_BITS, subpixel_bits
    drawn = drawn.astype(np.float64)
    reference = reference.astype(np.float64)
    slope, crease = slope_and_creases(reference, 2 * FLOAT_ACCURACY)
    bound = FLOAT_ACCURACY + slope * 2.0**-subpixel_bits
    on_plane = np.abs(drawn - reference) <= bound
    # near an edge, any surface that meets within the texel's neighbourhood
    near_edge = crease & (drawn >= neighbourhood(reference, np.minimum) - bound)
    near_edge &= drawn <= neighbourhood(reference, np.maximum) + bound
    wrong = ~(on_plane | near_edge)
    assert not wrong.any(), (
        f"{wrong.sum()} texels off by more than the rasterization bound, e.g. at "
        f"{np.argwhere(wrong)[:3].tolist()}: {drawn[wrong][:3]} vs {reference[wrong][:3]}"
    )


def same_bodies_but_on_edges(body: np.ndarray, reference: np.ndarray) -> np.ndarray:
    """Assert two pictures of one scene (two APIs, or two places in the window) show the
    same body at each pixel, but where a pixel's centre lies within a sub-pixel step of an
    edge between bodies (there the tie rules and the snap may pick either: pixels whose
    3 x 3 neighbourhood in ``reference`` holds another body). Returns where they agree."""
    edge = neighbourhood(reference, np.minimum) != neighbourhood(reference, np.maximum)
    same = body == reference
    assert np.all(same | edge), f"{int((~same & ~edge).sum())} pixels differ off the edges"
    return same
