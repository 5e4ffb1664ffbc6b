"""Coverage: ``benchmarks/bench_fit.py`` (the optimized fit's silhouette coverage against the
article's MDV set-up, rendered with OpenGL) as one section of the suite.

It runs in a child process: it enables ``jax_enable_x64`` for itself and draws with the
reference renderer. Without an OpenGL context the section is skipped.
"""

from __future__ import annotations

import os
import re
import subprocess
import sys

from ._timing import BENCH_DIR, Config, Section

NAME = "coverage"
TITLE = "Coverage of the optimized fit (benchmarks/bench_fit.py, docs/fitting.md)"

_TARGETS = re.compile(r"targets: median ratio ([\d.]+) .*p10 ratio ([\d.]+)")
_TIMES = re.compile(r"MDV ([\d.]+) ms, optimized ([\d.]+) ms")


def run(cfg: Config) -> Section:
    section = Section(NAME, TITLE)
    args = ["--per-family", "1"] if cfg.tiny else []
    proc = subprocess.run(
        [sys.executable, os.path.join(BENCH_DIR, "bench_fit.py"), *args],
        capture_output=True,
        text=True,
        check=False,
    )
    if proc.returncode != 0:
        if "GLUnavailableError" in proc.stderr:
            section.skipped = "no OpenGL context: " + proc.stderr.strip().splitlines()[-1]
            return section
        raise RuntimeError(f"bench_fit.py failed ({proc.returncode}):\n{proc.stderr[-3000:]}")
    section.text = proc.stdout
    targets, times = _TARGETS.search(proc.stdout), _TIMES.search(proc.stdout)
    if targets is None or times is None:
        raise RuntimeError(f"bench_fit.py printed no targets line:\n{proc.stdout[-2000:]}")
    section.figures["median_coverage_ratio"] = float(targets.group(1))
    section.figures["p10_coverage_ratio"] = float(targets.group(2))
    section.figures["mdv_fit_ms"] = float(times.group(1))
    section.figures["optimized_fit_ms"] = float(times.group(2))
    section.notes.append(
        "Figures: coverage ratios (optimized / MDV, targets ≥ 1.2 median and ≥ 1.5 at the 10th "
        "percentile) and times per fit; `make bench-coverage` runs this benchmark alone, with "
        "its own options (ARGS)."
    )
    return section
