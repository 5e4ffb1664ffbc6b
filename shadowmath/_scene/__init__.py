"""Scenes that live across frames: per-geometry summaries, per-light culling, draw lists.

``_summary`` computes what the fits need of one geometry (once, shared by its
instances); ``_cull`` holds the culling rules (pure functions on world-space bounding
spheres); ``shadowmath.scene`` is the public door, :class:`shadowmath.ShadowScene`.
"""
