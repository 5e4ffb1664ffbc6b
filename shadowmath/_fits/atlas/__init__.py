"""A shadow atlas: the tiles' allocation, :func:`fit_atlas` (:mod:`._fit`) with its 2D and cube
drivers, the lights read, the report, the viewports and the redraw rule."""
