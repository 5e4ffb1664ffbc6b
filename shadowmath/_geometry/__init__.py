"""The public functions of the geometry, each at its door.

Every function here converts and checks its arguments once (with the helpers of
:mod:`shadowmath._boundary`), then calls the trusted cores of :mod:`shadowmath._math`.
``shadowmath/__init__.py`` re-exports them; the fits (:mod:`shadowmath._fits`) build on them.
"""
