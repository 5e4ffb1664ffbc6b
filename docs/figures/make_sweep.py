"""Make the pose sweep's heat map (issue 27): ``benchmarks/bench_sweep.py``'s every pose.

Run from the repository root and commit the PNG (needs Pillow, the ``render`` extra):

    .venv/bin/python docs/figures/make_sweep.py

One row per pose (``scene/h<height>/p<pitch>/y<heading from the sun>/s<sun elevation>``), two
cells per comparison (the gain at the median, then at the 90th percentile: the rival's texel
area per pixel footprint over shadowmath's), coloured by ``log2(gain)`` from red (8× coarser)
through white (equal) to green (8× finer); the last column is the default fit's p90, green
below the aliasing limit (1). The date and the machine are written in the title. Writes
``docs/figures/sweep.png``.
"""

from __future__ import annotations

import datetime
import math
import os
import sys
from pathlib import Path

from PIL import Image, ImageDraw, ImageFont

FIGURES = Path(__file__).resolve().parent
sys.path.insert(0, str(FIGURES.parent.parent / "benchmarks"))

import bench_sweep as sweep  # noqa: E402

LABEL, CELL, ROW, HEAD = 190, 56, 14, 52
GREEN, RED, WHITE = (40, 160, 70), (210, 50, 40), (255, 255, 255)


def colour(gain: float) -> tuple[int, int, int]:
    """White at 1, green toward 8× (and beyond), red toward 1/8."""
    t = max(-1.0, min(1.0, math.log2(gain) / 3))
    end = GREEN if t > 0 else RED
    return tuple(round(w + abs(t) * (e - w)) for w, e in zip(WHITE, end, strict=True))  # type: ignore[return-value]


def machine() -> str:
    with open("/proc/cpuinfo") as f:
        model = next((ln.split(":", 1)[1].strip() for ln in f if ln.startswith("model name")), "")
    return f"{os.cpu_count()}-core {model}".strip()


def main() -> None:
    results, _ = sweep.measure_all(sweep.IMAGE, sweep.VARIANTS)
    columns = len(sweep.COMPARISONS) * 2 + 1
    width, height = LABEL + columns * CELL + 8, HEAD + ROW * len(results) + 8
    image = Image.new("RGB", (width, height), WHITE)
    draw = ImageDraw.Draw(image)
    font = ImageFont.load_default(11)
    w, h = sweep.IMAGE
    title = (
        "Texel area per pixel footprint, rival / shadowmath (green: shadowmath finer); "
        f"{datetime.date.today()}, {w}x{h} image, {machine()}"
    )
    draw.text((6, 4), title, fill=0, font=font)
    for k, c in enumerate(sweep.COMPARISONS):
        x = LABEL + 2 * k * CELL
        draw.text((x + 2, 22), c.label, fill=0, font=font)
        draw.text((x + 2, 36), "median      p90", fill=0, font=font)
    draw.text((LABEL + 2 * len(sweep.COMPARISONS) * CELL + 2, 22), "p90 <= 1?", fill=0, font=font)
    for r, (pose, per) in enumerate(results):
        y = HEAD + r * ROW
        draw.text((6, y), pose.key, fill=0, font=font)
        cells = [
            sweep.gain(per[c.theirs], per[c.ours], s)
            for c in sweep.COMPARISONS
            for s in sweep.STATS
        ]
        p90 = per[sweep.DEFAULT].p90
        for k, g in enumerate([*cells, 1 / p90]):
            x = LABEL + k * CELL
            draw.rectangle((x, y, x + CELL - 1, y + ROW - 1), fill=colour(g), outline=WHITE)
            text = f"{g:.2f}" if k < len(cells) else f"{p90:.2g}"
            draw.text((x + 4, y), text, fill=0, font=font)
    out = FIGURES / "sweep.png"
    image.quantize(colors=64).save(out, optimize=True)  # 64 colours: a fifth of the bytes
    print(f"wrote {out}")


if __name__ == "__main__":
    main()
