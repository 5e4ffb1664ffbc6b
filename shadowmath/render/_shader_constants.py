"""The constants the GLSL and WGSL shaders share, written once and injected as text.

A shader line ``#include "constants.glsl"`` (or ``"constants.wgsl"``) is replaced by
:func:`shader_constants` in that language (:func:`shadowmath.render._context.shader_source`),
so that the two languages' passes use the same array sizes, disk sizes and noise.
"""

from __future__ import annotations

import math
from typing import Literal

#: The most cascades the cascades passes take (their uniform arrays' size).
MAX_CASCADES = 8

#: The taps of the PCSS blocker search and of its filter (Vogel disks, ``pcss.glsl``).
PCSS_SEARCH_TAPS = 32
PCSS_FILTER_TAPS = 64

#: The golden angle ``pi (3 - sqrt 5)``, the angle between a Vogel disk's taps.
GOLDEN_ANGLE = math.pi * (3.0 - math.sqrt(5.0))

#: Jimenez's interleaved gradient noise, ``2 pi fract(c fract(dot(pixel, (a, b))))``: the
#: per-pixel angle that rotates the PCSS disks, its ``(a, b, c)``.
NOISE_X, NOISE_Y, NOISE_SCALE = 0.06711056, 0.00583715, 52.9829189

#: Each shared constant and its type, in the order the shaders receive them.
SHADER_CONSTANTS: dict[str, int | float] = {
    "MAX_CASCADES": MAX_CASCADES,
    "PCSS_SEARCH_TAPS": PCSS_SEARCH_TAPS,
    "PCSS_FILTER_TAPS": PCSS_FILTER_TAPS,
    "GOLDEN_ANGLE": GOLDEN_ANGLE,
    "TWO_PI": 2.0 * math.pi,
    "NOISE_X": NOISE_X,
    "NOISE_Y": NOISE_Y,
    "NOISE_SCALE": NOISE_SCALE,
}


def shader_constants(language: Literal["glsl", "wgsl"]) -> str:
    """:data:`SHADER_CONSTANTS` as ``const`` declarations of ``language`` (an ``int`` stays
    an integer, a ``float`` is written with ``repr``, which reads back to the same double).

    Example:
        >>> shader_constants("wgsl").splitlines()[0]
        'const MAX_CASCADES: i32 = 8;'
        >>> shader_constants("glsl").splitlines()[0]
        'const int MAX_CASCADES = 8;'
    """
    lines = []
    for name, value in SHADER_CONSTANTS.items():
        integer = isinstance(value, int)
        text = str(value) if integer else repr(float(value))
        if language == "glsl":
            lines.append(f"const {'int' if integer else 'float'} {name} = {text};")
        else:
            lines.append(f"const {name}: {'i32' if integer else 'f32'} = {text};")
    return "\n".join(lines) + "\n"
