"""The suite compiles JAX's programs with XLA's former CPU fusion emitters (``conftest.py``:
they compile the suite's many small programs in a third to half the time). A user's JAX
compiles with the default ones: this test runs representative jitted fits and gradients in
a fresh process with XLA's defaults and holds them to the NumPy values, as the rest of the
suite does under the suite's setting."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import shadowmath as sm

from .cameras import scene

SCRIPT = r"""
import json, sys
import jax
jax.config.update("jax_enable_x64", True)
import jax.numpy as jnp
import numpy as np
import shadowmath as sm
sun, view, proj, box, verts = (np.asarray(a) for a in json.loads(sys.argv[1]))
cascades = jax.jit(lambda L, V: sm.fit_cascades(L, V, proj, box, 512).world_to_texture)
shadow = jax.jit(lambda p, v: sm.fit_shadow(sm.PointLight(p), v, 256).blocker_to_clip)
def loss(L):
    return jnp.sum(sm.fit_cascades(L, view, proj, box, 512).world_to_clip ** 2)
grad = jax.jit(jax.grad(loss))
out = {
    "cascades": np.asarray(cascades(jnp.asarray(sun), jnp.asarray(view))).tolist(),
    "shadow": np.asarray(shadow(jnp.zeros(3), jnp.asarray(verts))).tolist(),
    "grad": np.asarray(grad(jnp.asarray(sun))).tolist(),
}
print(json.dumps(out))
"""


def test_jax_with_xlas_default_compiler_gives_the_suites_values() -> None:
    pytest.importorskip("jax")
    sun, view, proj, box = scene(2)
    verts = np.random.default_rng(5).uniform(-1.0, 1.0, (12, 3)) + [0.4, -0.3, 6.0]
    env = {k: v for k, v in os.environ.items() if k != "XLA_FLAGS"}  # XLA's defaults
    env["JAX_ENABLE_COMPILATION_CACHE"] = "false"
    root = Path(sm.__file__).resolve().parents[1]
    args = json.dumps([np.asarray(a).tolist() for a in (sun, view, proj, box, verts)])
    run = subprocess.run([sys.executable, "-c", SCRIPT, args], env=env, cwd=root,
                         capture_output=True, text=True, timeout=600)  # fmt: skip
    assert run.returncode == 0, run.stderr[-2000:]
    got = json.loads(run.stdout.splitlines()[-1])
    c = sm.fit_cascades(sun, view, proj, box, 512)
    np.testing.assert_allclose(got["cascades"], c.world_to_texture, rtol=1e-10, atol=1e-12)
    s = sm.fit_shadow(sm.PointLight(np.zeros(3)), verts, 256)
    np.testing.assert_allclose(got["shadow"], s.blocker_to_clip, rtol=1e-10, atol=1e-12)

    # The gradient against central differences of the NumPy fit (the loss is smooth here).
    def loss(L: np.ndarray) -> float:
        return float(np.sum(sm.fit_cascades(L, view, proj, box, 512).world_to_clip ** 2))

    h = 1e-6
    fd = [(loss(sun + h * e) - loss(sun - h * e)) / (2 * h) for e in np.eye(3)]
    np.testing.assert_allclose(got["grad"], fd, rtol=1e-5, atol=1e-7 * np.abs(fd).max())
