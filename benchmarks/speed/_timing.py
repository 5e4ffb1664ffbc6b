"""Median timer, result rows and the printed tables shared by the speed benchmarks.

Every figure is a median over ``repeats`` samples; a sample times ``number``
back-to-back calls (calibrated so that a sample of a fast function lasts at
least ``Config.min_time``) and is divided by ``number``. The garbage collector
is off while a sample runs, as in :mod:`timeit`. Functions that return JAX
arrays must block on their result themselves (``jax.block_until_ready``), so
that NumPy timings carry no synchronisation overhead.
"""

from __future__ import annotations

import argparse
import contextlib
import gc
import json
import math
import os
import subprocess
import sys
import time
from collections.abc import Callable, Iterator
from dataclasses import dataclass, field
from typing import Any

BENCH_DIR = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


@dataclass(frozen=True)
class Config:
    """Sizes and repeat counts: the full suite, or ``--tiny`` (everything once, tiny inputs)."""

    tiny: bool = False
    seed: int = 2026

    def size(self, full: int, tiny: int) -> int:
        return tiny if self.tiny else full

    def repeats(self, full: int) -> int:
        return 1 if self.tiny else full

    @property
    def min_time(self) -> float:
        """The shortest sample (seconds) for fast functions; 0 under ``--tiny``."""
        return 0.0 if self.tiny else 0.2


@dataclass(frozen=True)
class Timing:
    """Seconds per call: the median over ``repeats`` samples of ``number`` calls each."""

    median: float
    repeats: int
    number: int = 1

    @property
    def count(self) -> str:
        return f"{self.repeats}" if self.number == 1 else f"{self.repeats}×{self.number}"


def _sample(fn: Callable[[], object], number: int) -> float:
    enabled = gc.isenabled()
    gc.disable()
    try:
        t0 = time.perf_counter()
        for _ in range(number):
            fn()
        return time.perf_counter() - t0
    finally:
        if enabled:
            gc.enable()


def measure(
    fn: Callable[[], object], *, repeats: int, min_time: float = 0.0, warmup: int = 1
) -> Timing:
    """The median time of one call of ``fn``.

    ``warmup`` calls first (not timed); then ``number`` is grown until one
    sample lasts ``min_time`` (1 when ``min_time`` is 0), and ``repeats``
    samples are taken.
    """
    for _ in range(warmup):
        fn()
    number = 1
    if min_time > 0:
        while True:
            t = _sample(fn, number)
            if t >= min_time or number >= 10**7:
                break
            grow = min_time / t * 1.2 if t > 0 else 10.0
            number = max(number + 1, min(int(number * grow), number * 10))
    samples = sorted(_sample(fn, number) / number for _ in range(max(repeats, 1)))
    mid = len(samples) // 2
    median = samples[mid] if len(samples) % 2 else 0.5 * (samples[mid - 1] + samples[mid])
    return Timing(median, len(samples), number)


def synced(fn: Callable[..., object], *args: object) -> Callable[[], object]:
    """``fn(*args)`` waiting for JAX's asynchronous dispatch to finish (``block_until_ready``)."""
    import jax

    def call() -> object:
        return jax.block_until_ready(fn(*args))

    return call


def once(fn: Callable[[], object]) -> Timing:
    """One timed call (a first call, compilation included)."""
    return Timing(_sample(fn, 1), 1, 1)


@contextlib.contextmanager
def numpy_alone() -> Iterator[None]:
    """NumPy input runs the array path within the block, as without the ``fast`` extra."""
    from shadowmath._backends import _kernels

    with _kernels.disabled():
        yield


def fast_extra() -> bool:
    """Whether the ``fast`` extra's compiled loops are there (Numba, not ``SHADOWMATH_NUMBA=0``)."""
    from shadowmath._backends import _kernels

    return _kernels.available()


# ---------------------------------------------------------------------------
# Rows, sections and their tables
# ---------------------------------------------------------------------------


@dataclass
class Row:
    """One line of a table: a workload against its baseline, and the issue's target.

    ``ratio`` is always ``median / baseline`` (below 1: faster than the
    baseline). A target is an upper bound, either on the ratio
    (``limit_on="ratio"``) or on the median in seconds (``limit_on="seconds"``);
    ``target`` is its text as printed. PASS/MISS is informational only.
    """

    workload: str
    timing: Timing
    baseline: str | None = None
    baseline_timing: Timing | None = None
    target: str | None = None
    limit: float | None = None
    limit_on: str = "ratio"
    note: str = ""

    @property
    def ratio(self) -> float | None:
        if self.baseline_timing is None:
            return None
        return self.timing.median / self.baseline_timing.median

    @property
    def status(self) -> str:
        if self.limit is None:
            return ""
        value = self.ratio if self.limit_on == "ratio" else self.timing.median
        if value is None or not math.isfinite(value):
            return "MISS"
        return "PASS" if value <= self.limit else "MISS"

    def to_json(self) -> dict[str, Any]:
        base = self.baseline_timing
        return {
            "workload": self.workload,
            "median_s": self.timing.median,
            "repeats": self.timing.repeats,
            "calls_per_sample": self.timing.number,
            "baseline": self.baseline,
            "baseline_median_s": None if base is None else base.median,
            "baseline_repeats": None if base is None else base.repeats,
            "ratio": self.ratio,
            "target": self.target,
            "status": self.status or None,
            "note": self.note or None,
        }


@dataclass
class Section:
    """One benchmark's results: its rows, notes, extra figures, or why it was skipped."""

    name: str
    title: str
    rows: list[Row] = field(default_factory=list)
    notes: list[str] = field(default_factory=list)
    figures: dict[str, float] = field(default_factory=dict)
    text: str = ""  # printed as it is, before the table (a benchmark with its own table)
    skipped: str | None = None
    error: str | None = None

    def to_json(self) -> dict[str, Any]:
        return {
            "title": self.title,
            "status": "error" if self.error else "skipped" if self.skipped else "ok",
            "skipped": self.skipped,
            "error": self.error,
            "rows": [r.to_json() for r in self.rows],
            "figures": self.figures,
            "text": self.text or None,
            "notes": self.notes,
        }


def fmt_time(seconds: float | None) -> str:
    if seconds is None:
        return ""
    if not math.isfinite(seconds):
        return str(seconds)
    if seconds < 1e-3:
        return f"{seconds * 1e6:.3g} µs"
    if seconds < 1:
        return f"{seconds * 1e3:.3g} ms"
    return f"{seconds:.3g} s"


def fmt_ratio(ratio: float | None) -> str:
    return "" if ratio is None else f"{ratio:.3g}"


def table(section: Section) -> str:
    """The section as a Markdown table with its notes (what ``make bench`` prints)."""
    lines = [f"## {section.title}", ""]
    if section.skipped:
        lines.append(f"Skipped: {section.skipped}")
        return "\n".join(lines)
    if section.text:
        lines.extend([section.text.rstrip(), ""])
    if section.rows:
        lines.append(
            "| workload | median | repeats | baseline | baseline median | ratio | target | status |"
        )
        lines.append("|---|---|---|---|---|---|---|---|")
        for r in section.rows:
            base = r.baseline_timing
            workload = r.workload + (f" ({r.note})" if r.note else "")
            cells = [
                workload,
                fmt_time(r.timing.median),
                r.timing.count,
                r.baseline or "",
                "" if base is None else f"{fmt_time(base.median)} ({base.count})",
                fmt_ratio(r.ratio),
                r.target or "",
                r.status,
            ]
            lines.append("| " + " | ".join(cells) + " |")
    if section.notes:
        lines.append("")
        lines.extend(f"* {n}" for n in section.notes)
    if section.error:
        lines.append("")
        lines.append(f"ERROR: {section.error}")
    return "\n".join(lines)


def run_alone(
    run: Callable[[Config], Section], description: str, tiny: str, argv: list[str] | None
) -> int:
    """A section run on its own (``python benchmarks/bench_<name>.py [--tiny]``): its table,
    then its figures; ``tiny`` says what ``--tiny`` shrinks."""
    parser = argparse.ArgumentParser(description=description)
    parser.add_argument("--tiny", action="store_true", help=f"each timing once, {tiny}")
    section = run(Config(tiny=parser.parse_args(argv).tiny))
    print(table(section))
    for name, value in section.figures.items():
        print(f"* {name}: {value:g}")
    return 0


def target_line(section: str, row: Row) -> str:
    """One target on one line: PASS/MISS, the workload, its median, the baseline's, the ratio."""
    base = row.baseline_timing
    against = "" if base is None else f" vs {fmt_time(base.median)} ({row.baseline})"
    ratio = "" if row.ratio is None else f", ratio {fmt_ratio(row.ratio)}"
    on = "ratio" if row.limit_on == "ratio" else "time"
    return (
        f"{row.status or 'MISS'} [{section}] {row.workload}: {fmt_time(row.timing.median)}"
        f"{against}{ratio}; target {on} {row.target}"
    )


def targets(sections: dict[str, Section]) -> list[tuple[str, Row]]:
    """Every row with a target, in order, with its section's name."""
    return [(name, r) for name, s in sections.items() for r in s.rows if r.limit is not None]


# ---------------------------------------------------------------------------
# Fresh processes
# ---------------------------------------------------------------------------


def run_python(code: str, *, env: dict[str, str] | None = None, timeout: float = 900) -> Any:
    """Run ``code`` in a fresh interpreter (this one's) and parse its last stdout line as JSON.

    ``benchmarks/`` is on the child's ``sys.path`` (``from speed import ...``
    works); ``env`` adds to this process's environment.
    """
    prelude = f"import sys; sys.path.insert(0, {BENCH_DIR!r})\n"
    full_env = dict(os.environ)
    if env:
        full_env.update(env)
    proc = subprocess.run(
        [sys.executable, "-c", prelude + code],
        capture_output=True,
        text=True,
        env=full_env,
        timeout=timeout,
        check=False,
    )
    if proc.returncode != 0:
        raise RuntimeError(f"child process failed ({proc.returncode}):\n{proc.stderr[-3000:]}")
    return json.loads(proc.stdout.strip().splitlines()[-1])
