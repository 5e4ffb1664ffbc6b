"""A shadow atlas: the tiles' allocation, :func:`fit_atlas` (its door :mod:`._door`, driver
:mod:`._driver` and result :mod:`._result`) with the driver's 2D and cube parts, the lights
read, the report, the viewports and the redraw rule."""
