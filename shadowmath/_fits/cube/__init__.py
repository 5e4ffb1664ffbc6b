"""A point light's cube map: :func:`cube_depth_range` (:mod:`._depth_range`)."""
