"""Integrations of shadowmath's fits with rendering engines (each an optional extra).

Each integration is a module that imports its engine; import it by name, e.g.
``from shadowmath.integrations.pygfx import set_shadow_camera`` (the ``pygfx`` extra,
``pip install 'shadowmath[pygfx]'``). This package itself imports no engine.
"""
