"""Percentage-closer soft shadows of every fit: :func:`pcss_parameters` (its door
:mod:`._door`, driver :mod:`._driver` and result :mod:`._result`), the fits' maps read
(:mod:`._maps`) and the room the kernel needs (:mod:`._room`)."""
