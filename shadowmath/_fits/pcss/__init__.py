"""Percentage-closer soft shadows of every fit: :func:`pcss_parameters` (:mod:`._parameters`),
the fits' maps read (:mod:`._maps`) and the room the kernel needs (:mod:`._room`)."""
