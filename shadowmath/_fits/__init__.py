"""The fits, a package each, with the pieces they share beside them.

* :mod:`.shadow`: :func:`fit_shadow`: its door, its driver (an array form and a compiled
  form), its result :class:`ShadowSetup`; :class:`ShadowFitter` and :func:`optimize_frustum`.
* :mod:`.cascades`: :func:`fit_cascades`, :func:`cascade_splits`, the warp and the fitted
  orientation.
* :mod:`.atlas`: :func:`allocate_atlas`, :func:`fit_atlas` and its tiles' transforms.
* :mod:`.cube`: :func:`cube_depth_range`.
* :mod:`.pcss`: :func:`pcss_parameters` and the room its kernel needs.
* :mod:`.camera`: :func:`shadow_camera` of any fit.
* shared: :mod:`._spec` (:class:`ShadowMapSpec`, the fits' cache key) and
  :mod:`._light_kinds` (a light's kind, read in one place).
"""
