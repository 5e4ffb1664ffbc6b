"""A small mutation runner for shadowmath's core formulas.

Each entry of :data:`MUTATIONS` changes one piece of exact source text into a
plausible mistake (a sign, a factor, a rounding mode). For each, the runner copies
the repository's ``shadowmath/`` and ``tests/`` (and ``conftest.py``,
``pyproject.toml``) into a temporary folder, applies the one mutation there, and
runs the entry's test files with ``pytest -x``: a mutation is *killed* when a test
fails, and *SURVIVED* when they all pass, which means the tests do not pin that
piece of the formula down.

The tests run with ``SHADOWMATH_NUMBA=0`` (the array path: no compiled code cached
from the unmutated source can hide a mutation) and ``PYTHONPATH`` set to the
temporary folder (checked: ``shadowmath`` must be imported from there), with a
fixed hypothesis seed (``--seed``, default 0) so that a run can be repeated. First the
listed test files run once unmutated (the baseline): a test that fails without any
mutation would "kill" every mutation, so a failing baseline stops the run.

Usage::

    python tools/mutations.py             # every mutation; exit status 1 if one survived
    python tools/mutations.py --list      # the table, without running anything
    python tools/mutations.py --only b-directional-pad --only stable-floor
    python tools/mutations.py --repo /path/to/checkout

Exit status: 0 every mutation killed, 1 some mutation survived, 2 the run itself
failed (the baseline, a mutation's text not found exactly once, a timeout or a
pytest error other than failing tests).
"""

from __future__ import annotations

import argparse
import os
import shutil
import subprocess
import sys
import tempfile
import time
from collections.abc import Iterable, Sequence
from dataclasses import dataclass
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
COPIED = ("shadowmath", "tests", "conftest.py", "pyproject.toml")
IGNORED = shutil.ignore_patterns("__pycache__", "*.pyc", "*.nbi", "*.nbc", ".hypothesis")
TIMEOUT_S = 1800.0

STABLE = ("tests/test_fit_mutations.py", "tests/test_directional.py")


@dataclass(frozen=True)
class Mutation:
    """One source change and the test files that must kill it."""

    id: str
    file: str  # relative to the repository
    original: str  # exact text, found exactly once in ``file``
    mutated: str
    description: str
    tests: tuple[str, ...]  # test files (or pytest node ids), relative to the repository


MUTATIONS: tuple[Mutation, ...] = (
    Mutation(
        "a-stable-half-texel",
        "shadowmath/_math/_fit_formulas.py",
        "half_x = radius / (1.0 - 1.0 / (mx * width))\n"
        "    half_y = radius / (1.0 - 1.0 / (my * height))",
        "half_x = radius / (1.0 - 0.5 / (mx * width))\n"
        "    half_y = radius / (1.0 - 0.5 / (my * height))",
        "stable map enlarged by a quarter texel instead of half a texel",
        STABLE,
    ),
    Mutation(
        "b-directional-pad",
        "shadowmath/_math/_fit_formulas.py",
        "pad = (z_hi - z_lo) + where(half_x >= half_y, half_x, half_y)",
        "pad = (z_hi - z_lo)",
        "directional origin padded by the depth range only, not the box size",
        STABLE,
    ),
    Mutation(
        "stable-floor",
        "shadowmath/_math/_fit_formulas.py",
        "cx = rint(ax / safe_tx) * tx - ax\n    cy = rint(ay / safe_ty) * ty - ay",
        "cx = rint(ax / safe_tx - 0.5) * tx - ax\n    cy = rint(ay / safe_ty - 0.5) * ty - ay",
        "stable centre snapped down (a floor) instead of to the nearest texel",
        STABLE,
    ),
    Mutation(
        "welzl-three-levels",
        "shadowmath/_math/_loops.py",
        "                    if _outside(pr, ball):",
        "                    if False:",
        "Welzl's algorithm without its fourth level (spheres of four support points)",
        ("tests/test_stable_sphere.py",),
    ),
    Mutation(
        "receivers-outside-counted",
        "shadowmath/_math/_fit_formulas.py",
        "return inside & ((z > 0) | directional)",
        "return (z > 0) | directional",
        "receiver points outside the map's sides widen the depth range",
        ("tests/test_receivers.py",),
    ),
    Mutation(
        "fit-far-slack",
        "shadowmath/_math/_fit_formulas.py",
        "far = z_hi * (1.0 + slack)",
        "far = z_hi * (1.0 - slack)",
        "fit_shadow's default far plane inside the blocker (slack subtracted)",
        ("tests/test_directional.py",),
    ),
    Mutation(
        "frustum-near-slack",
        "shadowmath/_api/_adaptive_frustum.py",
        "near = z_min * (1 - NEAR_FAR_SLACK) if given_near is None else given_near",
        "near = z_min * (1 + NEAR_FAR_SLACK) if given_near is None else given_near",
        "adaptive_frustum's default near plane behind the nearest vertex (slack added)",
        ("tests/test_setup.py",),
    ),
    Mutation(
        "axes-cross-sign",
        "shadowmath/_math/_formulas.py",
        "normalize3(zy * vz - zz * vy, zz * vx - zx * vz, zx * vy - zy * vx)",
        "normalize3(zy * vz + zz * vy, zz * vx - zx * vz, zx * vy - zy * vx)",
        "axes_from_z: a sign in X = Z x V",
        ("tests/test_frame.py",),
    ),
    Mutation(
        "helper-axis-tie",
        "shadowmath/_math/_formulas.py",
        "pick_x = (ax <= ay) & (ax <= az)",
        "pick_x = (ax < ay) & (ax <= az)",
        "helper_axis3: a tie between |z_x| and |z_y| goes to Y instead of the lowest index",
        ("tests/test_frame.py",),
    ),
    Mutation(
        "light-translation",
        "shadowmath/_math/_formulas.py",
        "ty = -(yx * ox + yy * oy + yz * oz)",
        "ty = -(yx * ox + yy * oy + yz * ox)",
        "light_rows: Y's translation uses the origin's x for its z",
        ("tests/test_frame.py",),
    ),
    Mutation(
        "texture-half",
        "shadowmath/_math/_formulas.py",
        "0.5 * (c[0] + c[12]), 0.5 * (c[1] + c[13])",
        "1.0 * (c[0] + c[12]), 0.5 * (c[1] + c[13])",
        "texture_rows: s's x entry not halved (the 0.5 of (clip + w) / 2)",
        ("tests/test_setup.py",),
    ),
    Mutation(
        "projection-depth",
        "shadowmath/_math/_formulas.py",
        "-2.0 * near * ratio",
        "-1.0 * near * ratio",
        "projection_rows: -n f / (f - n) instead of -2 n f / (f - n) (near off -1)",
        ("tests/test_setup.py",),
    ),
    Mutation(
        "triangle-no-map-edges",
        "shadowmath/_math/_fit_formulas.py",
        "        best = _corner_far((g0, g1, g2), z, k // 2, 2 + k % 2, best, tau)",
        "        best = best",
        "triangle_far: the map's edges piercing a triangle not considered",
        ("tests/test_receivers.py",),
    ),
    Mutation(
        "triangle-no-edge-crossings",
        "shadowmath/_math/_fit_formulas.py",
        "    best = _edge_far(g1, g2, z[1], z[2], best, tau)",
        "    best = best",
        "triangle_far: one edge's crossings of the side planes not considered",
        ("tests/test_receivers.py",),
    ),
    Mutation(
        "receivers-pull-near",
        "shadowmath/_fits/_fit_arrays.py",
        "    return _finish(d, key, a, flags, L, axes, sides, (zb_min, z_hi, zb_min, zb_max))",
        "    return _finish(d, key, a, flags, L, axes, sides,"
        " (0.5 * zb_min, z_hi, zb_min, zb_max))",
        "a point light's near pulled toward the light (as receivers in front used to)",
        ("tests/test_receivers.py",),
    ),
    Mutation(
        "sphere-diameter-as-radius",
        "shadowmath/_math/_fit_formulas.py",
        "    return q[0] + ox, q[1] + oy, q[2] + oz, ox * ox + oy * oy + oz * oz",
        "    return q[0] + ox, q[1] + oy, q[2] + oz, 1.0001 * (ox * ox + oy * oy + oz * oz)",
        "sphere_through: the radius 0.005 % too large (not the minimal sphere)",
        ("tests/test_stable_sphere.py",),
    ),
    Mutation(
        "fov-limit-on-half-width",
        "shadowmath/_math/_fit_formulas.py",
        "    tx = fabs(cx) + half_x / margins[0]",
        "    tx = fabs(cx) + half_x",
        "fov_ok: the map's edge without the margin (a frustum a border too narrow judged)",
        ("tests/test_degenerate.py",),
    ),
)


class RunnerError(Exception):
    """The run itself failed (exit status 2): not a verdict on any mutation."""


# A mutated run's pytest outcome, as the table says it.
RESULTS = {"failed": "killed", "passed": "SURVIVED"}


@dataclass(frozen=True)
class Outcome:
    """The result of one pytest run."""

    status: str  # "passed", "failed", or "ERROR ..." (timeout, pytest usage or internal error)
    first_failure: str
    seconds: float


def copy_repo(repo: Path, into: Path) -> None:
    """Copy the package and its tests (no caches) into ``into``."""
    for name in COPIED:
        source = repo / name
        if source.is_dir():
            shutil.copytree(source, into / name, ignore=IGNORED)
        elif source.is_file():
            shutil.copy2(source, into / name)
        else:
            raise RunnerError(f"mutations: {source} is missing")


def mutate(mutation: Mutation, text: str) -> str:
    """``text`` with the mutation applied; its original text must occur exactly once."""
    count = text.count(mutation.original)
    if count != 1:
        raise RunnerError(
            f"mutations: {mutation.id}: the original text occurs {count} times in "
            f"{mutation.file} (expected exactly once):\n{mutation.original}"
        )
    return text.replace(mutation.original, mutation.mutated)


def apply(mutation: Mutation, root: Path) -> None:
    """Apply ``mutation`` to the copy of the repository in ``root``."""
    path = root / mutation.file
    path.write_text(mutate(mutation, path.read_text(encoding="utf-8")), encoding="utf-8")


def environment(root: Path) -> dict[str, str]:
    env = dict(os.environ)
    env["SHADOWMATH_NUMBA"] = "0"
    env["PYTHONPATH"] = str(root)
    env["PYTHONDONTWRITEBYTECODE"] = "1"
    return env


def check_import(root: Path) -> None:
    """Fail unless ``shadowmath`` is imported from ``root`` (not an installed copy)."""
    out = subprocess.run(
        [sys.executable, "-c", "import shadowmath; print(shadowmath.__file__)"],
        cwd=root,
        env=environment(root),
        capture_output=True,
        text=True,
        check=False,
    )
    where = Path(out.stdout.strip() or "?").resolve()
    if out.returncode != 0 or root.resolve() not in where.parents:
        raise RunnerError(
            f"mutations: shadowmath is imported from {where}, not from the copy in {root}:\n"
            f"{out.stderr}"
        )


def first_failure(output: str) -> str:
    """The first ``FAILED``/``ERROR`` node of pytest's short summary, or ``""``."""
    for line in output.splitlines():
        for tag in ("FAILED ", "ERROR "):
            if line.startswith(tag):
                return line[len(tag) :].split(" - ", 1)[0].strip()
    return ""


def run_tests(root: Path, tests: Sequence[str], seed: int) -> Outcome:
    """``pytest -x`` on ``tests`` in the copy at ``root``."""
    command = [sys.executable, "-m", "pytest", "-x", "-q", "-p", "no:cacheprovider"]
    command += [f"--hypothesis-seed={seed}", *tests]
    start = time.perf_counter()
    try:
        out = subprocess.run(
            command,
            cwd=root,
            env=environment(root),
            capture_output=True,
            text=True,
            timeout=TIMEOUT_S,
            check=False,
        )
    except subprocess.TimeoutExpired:
        return Outcome(f"ERROR timeout {TIMEOUT_S:.0f} s", "", time.perf_counter() - start)
    seconds = time.perf_counter() - start
    output = out.stdout + out.stderr
    failed = first_failure(output)
    if out.returncode == 0:
        return Outcome("passed", "", seconds)
    if out.returncode == 1:
        return Outcome("failed", failed, seconds)
    tail = output.strip().splitlines()[-1:] or [""]
    return Outcome(f"ERROR pytest exit {out.returncode}", failed or tail[0], seconds)


def run_one(repo: Path, mutation: Mutation | None, tests: Sequence[str], seed: int) -> Outcome:
    """Copy ``repo``, apply ``mutation`` (None: the baseline) and run ``tests`` there."""
    with tempfile.TemporaryDirectory(prefix="shadowmath-mutation-") as folder:
        root = Path(folder)
        copy_repo(repo, root)
        if mutation is not None:
            apply(mutation, root)
        check_import(root)
        return run_tests(root, tests, seed)


def table(rows: Iterable[Sequence[str]], header: Sequence[str]) -> str:
    """A plain-text table, columns padded to their widest cell."""
    cells = [list(header), *(list(r) for r in rows)]
    widths = [max(len(r[i]) for r in cells) for i in range(len(header))]
    lines = ["  ".join(c.ljust(w) for c, w in zip(r, widths, strict=True)).rstrip() for r in cells]
    lines.insert(1, "  ".join("-" * w for w in widths))
    return "\n".join(lines)


def select(only: Sequence[str] | None) -> tuple[Mutation, ...]:
    if not only:
        return MUTATIONS
    known = {m.id for m in MUTATIONS}
    unknown = [i for i in only if i not in known]
    if unknown:
        raise RunnerError(f"mutations: unknown id(s) {unknown}; --list shows them")
    return tuple(m for m in MUTATIONS if m.id in only)


def main(argv: Sequence[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--repo", type=Path, default=ROOT, help="checkout to mutate (copied)")
    parser.add_argument("--only", action="append", metavar="ID", help="run this mutation only")
    parser.add_argument("--list", action="store_true", help="list the mutations and exit")
    parser.add_argument(
        "--no-baseline", action="store_true", help="skip the unmutated run of the tests"
    )
    parser.add_argument("--seed", type=int, default=0, help="hypothesis seed (default 0)")
    args = parser.parse_args(argv)
    try:
        return run(args)
    except RunnerError as err:
        print(err, file=sys.stderr)
        return 2


def run(args: argparse.Namespace) -> int:
    """The run that :func:`main` parsed the options of; the exit status."""
    mutations = select(args.only)
    repo = args.repo.resolve()

    if args.list:
        listed = [(m.id, m.file, m.description, " ".join(m.tests)) for m in mutations]
        print(table(listed, ("id", "file", "description", "tests")))
        return 0

    # Every original text must be found before anything runs (fail loudly and early).
    for m in mutations:
        mutate(m, (repo / m.file).read_text(encoding="utf-8"))

    start = time.perf_counter()
    if not args.no_baseline:
        files = list(dict.fromkeys(t for m in mutations for t in m.tests))
        base = run_one(repo, None, files, args.seed)
        print(
            f"baseline (unmutated, {len(files)} test files): {base.status} in {base.seconds:.0f} s"
        )
        if base.status != "passed":  # the unmutated code must pass its own tests
            print(f"mutations: the baseline fails ({base.first_failure}); nothing to measure")
            return 2

    rows: list[tuple[str, ...]] = []
    results = []
    for m in mutations:
        outcome = run_one(repo, m, m.tests, args.seed)
        result = RESULTS.get(outcome.status, outcome.status)
        results.append(result)
        seconds = f"{outcome.seconds:.0f}"
        rows.append((m.id, m.description, result, outcome.first_failure, seconds))
        print(f"{m.id}: {result} in {seconds} s", flush=True)
    print()
    print(table(rows, ("id", "description", "result", "first failing test", "s")))
    survived = results.count("SURVIVED")
    errors = sum(r.startswith("ERROR") for r in results)
    total = time.perf_counter() - start
    print(
        f"\n{results.count('killed')} killed, {survived} survived, {errors} errors in {total:.0f} s"
    )
    if errors:
        return 2
    return 1 if survived else 0


if __name__ == "__main__":
    sys.exit(main())
