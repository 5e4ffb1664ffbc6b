"""Every matrix product a fit makes under JAX asks for full float32 precision.

JAX's default matmul precision lets NVIDIA GPUs and TPUs multiply float32 matrices in
TF32 or bfloat16 passes (about 1e-3 relative: several texels of a 4096² map). On this
CPU the precision changes nothing, so the test reads the traced programs instead: every
``dot_general`` in them must carry ``Precision.HIGHEST`` (``_math._vector.matmul``).
"""

from __future__ import annotations

from collections.abc import Callable, Iterator
from typing import Any

import jax
import jax.numpy as jnp
import numpy as np
import pytest

import shadowmath as sm


def _equations(jaxpr: Any) -> Iterator[Any]:
    """Every equation of a program, nested programs (jit, cond, while, scan) included."""
    for eqn in jaxpr.eqns:
        yield eqn
        for value in eqn.params.values():
            for sub in value if isinstance(value, (tuple, list)) else (value,):
                inner = getattr(sub, "jaxpr", sub)
                if hasattr(inner, "eqns"):
                    yield from _equations(inner)


def _products(fn: Callable[..., Any], *args: Any) -> list[Any]:
    closed = jax.make_jaxpr(fn)(*args)
    return [e for e in _equations(closed.jaxpr) if e.primitive.name == "dot_general"]


def _spot() -> Any:
    verts = jnp.array([[-1.0, -1.0, 4.0], [1.0, 1.0, 4.0], [1.0, -1.0, 5.0], [0.0, 0.5, 6.0]])
    B = jnp.eye(4).at[:3, 3].set(jnp.array([0.5, -0.2, 0.1]))

    def fit(p: Any, v: Any, b: Any) -> Any:
        return sm.fit_shadow(sm.SpotLight(p, jnp.array([0.0, 0.0, 1.0]), 0.6), v, 256,
                             blocker_to_world=b)  # fmt: skip

    return fit, (jnp.zeros(3), verts, B)


def _receiver() -> Any:
    verts = jnp.array([[-1.0, -1.0, 4.0], [1.0, 1.0, 4.0], [1.0, -1.0, 5.0]])

    def fit(p: Any, R: Any) -> Any:
        return sm.receiver_texture_matrix(sm.fit_shadow(p, verts, 64), R)

    return fit, (jnp.zeros(3), jnp.eye(4) * 2.0)


def _warped_cascades() -> Any:
    view = np.eye(4)
    view[:3, :3] = [[1, 0, 0], [0, 0.8, -0.6], [0, 0.6, 0.8]]
    view[:3, 3] = [0.0, -2.0, -30.0]
    f, n, far = 1.0, 0.1, 200.0
    a, b = (far + n) / (n - far), 2 * far * n / (n - far)
    proj = np.array([[f, 0, 0, 0], [0, f, 0, 0], [0, 0, a, b], [0, 0, -1, 0]])
    box = jnp.array([[-100.0, -100.0, -1.0], [100.0, 100.0, 10.0]])

    def fit(sun: Any, V: Any) -> Any:
        return sm.fit_cascades(sun, V, jnp.asarray(proj), box, 1024, warp="lispsm")

    return fit, (jnp.array([0.3, 0.1, 0.9]), jnp.asarray(view))


@pytest.mark.parametrize("program", [_spot, _receiver, _warped_cascades],
                         ids=["spot", "receiver", "lispsm"])  # fmt: skip
def test_jax_matrix_products_ask_for_full_precision(program: Callable[[], Any]) -> None:
    fn, args = program()
    products = _products(fn, *args)
    assert products, "the program makes no matrix product: the test would test nothing"
    highest = (jax.lax.Precision.HIGHEST, jax.lax.Precision.HIGHEST)
    assert all(e.params["precision"] == highest for e in products), [
        e.params["precision"] for e in products
    ]
