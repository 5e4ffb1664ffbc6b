"""The speed benchmarks (``make bench``) run once at a tiny size so that none can rot.

Nothing here is about time: every benchmark must run and produce finite figures.
The GPU section may be skipped where JAX sees no GPU, the coverage and pygfx sections
where there is no OpenGL context or wgpu adapter (but not under
``SHADOWMATH_REQUIRE_GL=1``, as in CI).
"""

from __future__ import annotations

import json
import math
import os
import subprocess
import sys
from pathlib import Path

import jax

ROOT = Path(__file__).resolve().parent.parent
EXPECTED = [
    "single",
    "options",
    "batch",
    "suns",
    "large",
    "derivatives",
    "compile",
    "gpu",
    "coverage",
    "cascades",
    "sweep",
    "atlas",
    "cube",
    "spot",
    "pygfx",
    "scene",
]


def _has_gpu() -> bool:
    try:
        return bool(jax.devices("gpu"))
    except RuntimeError:
        return False


def _finite(value: object) -> bool:
    return isinstance(value, int | float) and math.isfinite(value)


def test_every_benchmark_runs_tiny(tmp_path: Path) -> None:
    out = tmp_path / "bench.json"
    proc = subprocess.run(
        [sys.executable, str(ROOT / "benchmarks" / "run.py"), "--tiny", "--json", str(out)],
        capture_output=True,
        text=True,
        timeout=900,
        check=False,
    )
    assert proc.returncode == 0, proc.stdout[-4000:] + proc.stderr[-4000:]
    results = json.loads(out.read_text())
    assert results["environment"]["tiny"] is True
    benchmarks = results["benchmarks"]
    assert list(benchmarks) == EXPECTED
    for name, section in benchmarks.items():
        if section["status"] == "skipped":
            may_skip = (name == "gpu" and not _has_gpu()) or (
                name in ("coverage", "pygfx") and os.environ.get("SHADOWMATH_REQUIRE_GL") != "1"
            )
            assert may_skip, f"{name} skipped: {section['skipped']}"
            continue
        assert section["status"] == "ok", section["error"]
        assert section["rows"] or section["figures"], name
        for row in section["rows"]:
            assert _finite(row["median_s"]) and row["median_s"] > 0, (name, row)
            if row["baseline"] is not None:
                assert _finite(row["baseline_median_s"]) and row["baseline_median_s"] > 0
                assert _finite(row["ratio"]), (name, row)
        for key, value in section["figures"].items():
            assert _finite(value), (name, key, value)
