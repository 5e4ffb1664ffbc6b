"""The two passes over a blocker's vertices, on whole arrays (NumPy or JAX).

Nagy's algorithm reads the vertices twice: once for the viewing direction
(the mean direction vector, or the bounding box's centre) and the scene's
scale, once in light coordinates for the projection ratios and the depth range.
Here each pass is one expression over the ``(*batch, N, 3)`` array: under
``jax.jit`` XLA fuses it into one loop; with NumPy the intermediate arrays are
allocated, which is why large NumPy blockers go through the compiled loop of
:mod:`._kernels` when Numba is installed. Trusted inputs only.
"""

from __future__ import annotations

from types import ModuleType
from typing import NamedTuple

from shadowmath._boundary._shapes import Float
from shadowmath._boundary._validate import Array


class Spread(NamedTuple):
    """Pass 1: where the blocker lies from the light, and the scales of the thresholds."""

    direction: Array  # (*batch, 3) the MDV (mean of V - L) or the bounding box's centre - L
    coords: Array  # (*batch,) max |coordinate| of the vertices and the light
    reach: Array  # (*batch,) max |V - L| component over the vertices


class Extent(NamedTuple):
    """Pass 2: the blocker in light coordinates."""

    x: Array  # (*batch, N) light coordinates of each vertex
    y: Array
    z: Array
    rx: Array  # (*batch, N) the ratios x / z and y / z (z replaced by 1 where z <= 0)
    ry: Array


def spread(
    xp: ModuleType,
    light: Float[Array, "*#batch 3"],
    verts: Float[Array, "*#batch N 3"],
    *,
    aim: str,
) -> Spread:
    """Pass 1 over ``verts`` ``(*batch, N, 3)`` seen from ``light`` ``(*batch, 3)``."""
    offsets = [verts[..., i] - light[..., None, i] for i in range(3)]  # per component: fused
    if aim == "mean":
        # The differences before the sum: full precision far from the origin.
        direction = xp.stack([xp.mean(o, axis=-1) for o in offsets], axis=-1)
    else:
        direction = xp.stack(
            [0.5 * (xp.max(o, axis=-1) + xp.min(o, axis=-1)) for o in offsets], axis=-1
        )
    coords = xp.max(xp.abs(verts), axis=(-2, -1))
    coords = xp.maximum(coords, xp.max(xp.abs(light), axis=-1))
    reach = xp.max(xp.stack([xp.max(xp.abs(o), axis=-1) for o in offsets]), axis=0)
    return Spread(direction, coords, reach)


def extent(
    xp: ModuleType,
    light: Float[Array, "*#batch 3"],
    verts: Float[Array, "*#batch N 3"],
    axes: tuple[Float[Array, "*#batch 3"], Float[Array, "*#batch 3"], Float[Array, "*#batch 3"]],
) -> Extent:
    """Pass 2: light coordinates and projection ratios of every vertex.

    ``axes = (X, Y, Z)``: the light frame's ``(*batch, 3)`` axes.
    """
    # Written per component (three products and two sums), not as a reduction over
    # the last axis of length 3: XLA fuses the whole pass into one loop this way,
    # while a size-3 reduction per vertex ran 60x slower than a read on the CPU.
    ox, oy, oz = (verts[..., i] - light[..., None, i] for i in range(3))

    def along(axis: Array) -> Array:
        return ox * axis[..., None, 0] + oy * axis[..., None, 1] + oz * axis[..., None, 2]

    x, y, z = along(axes[0]), along(axes[1]), along(axes[2])
    # Divide by a safe z so that invalid entries (z <= 0) never produce inf/NaN
    # derivatives that leak into valid ones; the checks mark them invalid.
    inv_z = 1 / xp.where(z > 0, z, xp.ones_like(z))
    return Extent(x, y, z, x * inv_z, y * inv_z)
