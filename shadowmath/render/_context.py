"""The offscreen OpenGL context, shader loading and input checks shared by the passes."""

from __future__ import annotations

from importlib import resources
from typing import Any

import moderngl
import numpy as np
from numpy.typing import NDArray

from shadowmath import check_projection, column_major_bytes

from ._shader_constants import shader_constants

#: Debian packages that provide a headless EGL context (Mesa's llvmpipe without a GPU):
#: the EGL loader, the GL library glcontext opens beside it, and Mesa's drivers.
DEBIAN_PACKAGES = ("libegl1", "libgl1", "libgl1-mesa-dri")

_default: list[moderngl.Context] = []


class GLUnavailableError(RuntimeError):
    """No OpenGL 3.3 context could be created (no EGL library or driver)."""


def standalone_context() -> moderngl.Context:
    """The shared offscreen context: EGL, OpenGL 3.3 core, created on first use.

    Works without a display or GPU through Mesa's llvmpipe. Every function of
    :mod:`shadowmath.render` uses it unless given a ``ctx``.

    Returns:
        a ``moderngl.Context``.

    Raises:
        GLUnavailableError: EGL or a GL driver is missing; the message names the
            Debian packages to install (``libegl1``, ``libgl1``, ``libgl1-mesa-dri``).

    Example:
        >>> ctx = standalone_context()
    """
    if not _default:
        try:
            # Passed as a dict: moderngl's stubs type **settings too narrowly.
            settings: dict[str, Any] = {"require": 330, "backend": "egl"}
            ctx = moderngl.create_standalone_context(**settings)
        except Exception as err:  # glcontext raises bare Exceptions
            raise GLUnavailableError(
                f"no OpenGL 3.3 context through EGL ({err}); on Debian/Ubuntu install "
                f"{', '.join(DEBIAN_PACKAGES)} (apt-get install -y {' '.join(DEBIAN_PACKAGES)})"
            ) from err
        _default.append(ctx)
    return make_current(_default[0])


def make_current(ctx: moderngl.Context) -> moderngl.Context:
    """Make ``ctx`` the thread's current GL context again, and return it.

    Another library's graphics work on this thread can leave its own context current:
    pygfx's offscreen canvas does (wgpu on Mesa), after which every GL call on ours
    fails (moderngl: "cannot create buffer"). moderngl's ``__enter__`` makes the context
    current; its ``__exit__``, which would restore the other one, is not called.
    """
    ctx.__enter__()  # type: ignore[no-untyped-call]
    return ctx


def resolve_context(ctx: moderngl.Context | None) -> moderngl.Context:
    """``ctx``, or the shared :func:`standalone_context`, made current."""
    return standalone_context() if ctx is None else make_current(ctx)


def shader_source(name: str) -> str:
    """A shader file shipped in ``shadowmath/render/shaders``, each line ``#include "x"``
    replaced by the source of file ``x`` there, once (a file included again is left out),
    and ``#include "constants.glsl"`` or ``"constants.wgsl"`` by the shared constants in
    that language (:func:`shader_constants`). GLSL and WGSL have no includes of their
    own: the snippets that several shaders share are files included at load time;
    moderngl would expand such a line itself from ``ctx.includes``, but finds none left.

    Example:
        >>> source = shader_source("depth_scene.wgsl")
        >>> any(line.startswith("#include") for line in source.splitlines())
        False
        >>> "fn record(" in source
        True
        >>> "const PCSS_FILTER_TAPS: i32 = 64;" in shader_source("pcss_scene.wgsl")
        True
    """
    return _expand(name, set())


def _expand(name: str, done: set[str]) -> str:
    """:func:`shader_source` of ``name``, leaving out the files in ``done`` (updated)."""
    done.add(name)
    if name in ("constants.glsl", "constants.wgsl"):
        return shader_constants("glsl" if name.endswith(".glsl") else "wgsl")
    text = (resources.files("shadowmath.render") / "shaders" / name).read_text(encoding="utf-8")
    lines = text.splitlines(keepends=True)
    for i, line in enumerate(lines):
        if line.startswith('#include "'):
            included = line.strip()[len('#include "') : -1]
            lines[i] = "" if included in done else _expand(included, done) + "\n"
    return "".join(lines)


def program(ctx: moderngl.Context, vertex: str, fragment: str) -> moderngl.Program:
    """The program linked from two shader files, cached on the context."""
    if not isinstance(ctx.extra, dict):
        ctx.extra = {}
    cache: dict[tuple[str, str], Any] = ctx.extra.setdefault("shadowmath_programs", {})
    key = (vertex, fragment)
    if key not in cache:
        cache[key] = ctx.program(
            vertex_shader=shader_source(vertex), fragment_shader=shader_source(fragment)
        )
    prog: moderngl.Program = cache[key]
    return prog


def uniform(prog: moderngl.Program, name: str) -> moderngl.Uniform:
    """The program's uniform ``name`` (a ``TypeError`` if it is something else)."""
    member = prog[name]
    if not isinstance(member, moderngl.Uniform):
        raise TypeError(f"{name}: not a uniform of the program")
    return member


def bind_block(prog: moderngl.Program, name: str, buffer: moderngl.Buffer) -> None:
    """Bind ``buffer`` to the program's uniform block ``name`` (binding point 0; a
    ``TypeError`` if ``name`` is something else)."""
    block = prog[name]
    if not isinstance(block, moderngl.UniformBlock):
        raise TypeError(f"{name}: not a uniform block of the program")
    block.binding = 0
    buffer.bind_to_uniform_block(0)


def set_uniform(prog: moderngl.Program, name: str, value: Any) -> None:
    uniform(prog, name).value = value


def set_matrix(prog: moderngl.Program, name: str, matrix: Any) -> None:
    """Upload a column-vector matrix to a ``mat4`` uniform (through :func:`column_major_bytes`)."""
    uniform(prog, name).write(column_major_bytes(matrix))


def check_matrix(name: str, matrix: Any) -> NDArray[np.float64]:
    m = np.asarray(matrix, dtype=np.float64)
    if m.shape != (4, 4):
        raise ValueError(f"{name}: expected a (4, 4) matrix, got shape {m.shape}")
    if not np.all(np.isfinite(m)):
        raise ValueError(f"{name}: contains non-finite entries")
    return m


def check_camera_projection(projection: Any) -> NDArray[np.float64]:
    """A viewing camera's ``(4, 4)`` projection, refused unless it is one (the fits' check:
    :func:`shadowmath.check_projection`)."""
    p = check_matrix("projection", projection)
    check_projection(p)
    return p


def check_mesh(
    name: str, vertices: Any, triangles: Any
) -> tuple[NDArray[np.float64], NDArray[np.int64]]:
    """``(N, 3)`` finite vertices and ``(M, 3)`` in-range integer triangles."""
    v = np.asarray(vertices, dtype=np.float64)
    t = np.asarray(triangles)
    if v.ndim != 2 or v.shape[1] != 3 or v.shape[0] == 0:
        raise ValueError(f"{name} vertices: expected a non-empty (N, 3) array, got shape {v.shape}")
    if not np.all(np.isfinite(v)):
        raise ValueError(f"{name} vertices: contain non-finite values")
    if t.ndim != 2 or t.shape[1] != 3 or t.shape[0] == 0:
        raise ValueError(
            f"{name} triangles: expected a non-empty (M, 3) array, got shape {t.shape}"
        )
    if t.dtype.kind not in "iu":
        raise ValueError(f"{name} triangles: expected integer indices, got dtype {t.dtype}")
    if t.min() < 0 or t.max() >= len(v):
        raise ValueError(f"{name} triangles: indices must lie in [0, {len(v)})")
    return v, t.astype(np.int64)


def image_size(name: str, size: Any) -> tuple[int, int]:
    """``size`` or ``(width, height)`` as two positive ints."""
    values = (size, size) if not isinstance(size, tuple | list) else tuple(size)
    if len(values) != 2 or not all(isinstance(s, int | np.integer) for s in values):
        raise ValueError(f"{name}: expected an int or (width, height) of ints, got {size!r}")
    w, h = int(values[0]), int(values[1])
    if w <= 0 or h <= 0:
        raise ValueError(f"{name}: sizes must be positive, got {size!r}")
    return w, h
