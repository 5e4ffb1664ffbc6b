"""What ``cube_depth_range`` returns: :class:`CubeDepthRange`."""

from __future__ import annotations

from typing import NamedTuple

from shadowmath._boundary._shapes import Float
from shadowmath._boundary._validate import Array


class CubeDepthRange(NamedTuple):
    """``near`` and ``far`` of a cube shadow map's faces, each ``(*batch,)``: the
    distances along a face's axis to give :func:`cube_face_projection` and
    :func:`cube_face_depth`."""

    near: Float[Array, "*batch"]
    far: Float[Array, "*batch"]
