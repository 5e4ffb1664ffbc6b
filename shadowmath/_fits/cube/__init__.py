"""A point light's cube map: :func:`cube_depth_range` (its door :mod:`._door`, driver
:mod:`._driver` and result :mod:`._result`)."""
