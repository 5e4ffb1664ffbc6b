"""The compiled loops never run stale formulas: their disk cache is keyed on every source.

Numba keys a cached function to its own source file, while the loops of
``shadowmath._math._loops`` inline formulas from other files. A copy of the package is
fitted in a fresh process (which compiles and caches the loops), one formula is
changed in a file that is not ``_loops.py``, and a second fresh process must run
the changed formula: its compiled result equals the array path's new result.
"""

from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
from pathlib import Path

import numpy as np

import shadowmath

SCRIPT = """
import json, numpy as np, shadowmath as sm
from shadowmath._backends import _kernels
box = np.array([[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (4, 6)], float)
sun = np.array([0.3, 1.0, -0.2, 0.0])
assert _kernels.available()
fast = sm.fit_shadow(sun, box, 64).blocker_to_clip
with _kernels.array_path():
    ref = sm.fit_shadow(sun, box, 64).blocker_to_clip
print(json.dumps([fast.tolist(), ref.tolist(), sm.__file__]))
"""


def _fit(root: Path) -> tuple[np.ndarray, np.ndarray]:
    env = {k: v for k, v in os.environ.items() if k != "NUMBA_CACHE_DIR"}
    env["PYTHONPATH"] = str(root)
    # LLVM's optimizations off: each process compiles the loops afresh (the test's point),
    # and what they compute does not depend on the level (no fast-math); 14 % less CPU.
    env["NUMBA_OPT"] = "0"
    out = subprocess.run(
        [sys.executable, "-c", SCRIPT], env=env, cwd=root, capture_output=True, text=True
    )
    assert out.returncode == 0, out.stderr
    fast, ref, where = json.loads(out.stdout.splitlines()[-1])
    assert Path(where).is_relative_to(root)  # the copy ran, not the installed package
    return np.array(fast), np.array(ref)


def test_a_changed_formula_reaches_the_compiled_loop_of_a_fresh_process(tmp_path: Path) -> None:
    package = tmp_path / "shadowmath"
    source = Path(shadowmath.__file__).parent
    shutil.copytree(source, package, ignore=shutil.ignore_patterns("__pycache__"))
    fast, ref = _fit(tmp_path)
    np.testing.assert_allclose(fast, ref, rtol=1e-12, atol=1e-12)
    # An orthographic depth scale of 4 / (f - n) instead of 2 / (f - n): depth row doubled.
    formulas = package / "_math" / "_fit_formulas.py"
    text = formulas.read_text()
    assert text.count("2.0 * inv, -(far + near) * inv") == 1
    formulas.write_text(
        text.replace("2.0 * inv, -(far + near) * inv", "4.0 * inv, -(far + near) * inv")
    )
    fast2, ref2 = _fit(tmp_path)
    np.testing.assert_allclose(fast2, ref2, rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(fast2[2, :3], 2 * fast[2, :3], rtol=1e-12)  # the new formula ran
    np.testing.assert_array_equal(fast2[:2], fast[:2])
    # Both processes cached their loops, each in a folder of its own sources' key.
    assert len(list((package / "__pycache__").glob("shadowmath-*"))) == 2
