"""The speed benchmarks of issue 9 (``make bench``), on shadowmath's public API only.

Each module has ``NAME``, ``TITLE`` and ``run(cfg) -> Section``; ``benchmarks/run.py``
runs them in the order of :data:`SECTIONS`.
"""

from __future__ import annotations

from types import ModuleType

from . import batch, compile, coverage, derivatives, gpu, large, options, single, suns

SECTIONS: dict[str, ModuleType] = {
    m.NAME: m for m in (single, options, batch, suns, large, derivatives, compile, gpu, coverage)
}
