"""The renderer guide's code runs as printed (docs/renderers.md).

The complete moderngl program is taken from the guide's Markdown and run in a
process of its own (it creates its own EGL context, which must not become the
test process's current one); its shadow must match a ray cast from every pixel
to the light, and the guide's statements about wrapping (repeat ghosts,
clamp-to-border through a sampler) and its per-frame snippets are checked on
the same program.
"""

from __future__ import annotations

import re
import subprocess
import sys
import textwrap
from pathlib import Path

import numpy as np
import pytest

GUIDE = Path(__file__).resolve().parents[2] / "docs" / "renderers.md"
CLAMP_TO_EDGE = "shadow_map.repeat_x = shadow_map.repeat_y = False"
BIND = "shadow_map.use(location=0)"
SCENE = {
    "IMAGE": "IMAGE",
    "MAP": "MAP",
    "B": "blocker_to_world",
    "vertices": "blocker.vertices",
    "light": "light",
    "image": "image",
    "shadowed": "shadowed",
}


def block(title: str) -> str:
    """The fenced code block with ``title="..."`` in the guide, dedented."""
    match = re.search(
        rf'^( *)```\w+ title="{re.escape(title)}"\n(.*?)^\1```$',
        GUIDE.read_text(encoding="utf-8"),
        flags=re.MULTILINE | re.DOTALL,
    )
    assert match, f"no block titled {title} in {GUIDE.name}"
    return textwrap.dedent(match.group(2))


def run(source: str, tmp_path: Path, **values: str) -> tuple[dict[str, np.ndarray], str]:
    """Run ``source`` as a script; return the named expressions' values and what it printed."""
    out = tmp_path / "values.npz"
    dump = ", ".join(f"{name}=_np.asarray({expr})" for name, expr in {**SCENE, **values}.items())
    script = f"{source}\n\nimport numpy as _np\n_np.savez({str(out)!r}, {dump})\n"
    result = subprocess.run(
        [sys.executable, "-c", script],
        capture_output=True,
        text=True,
        cwd=tmp_path,
        timeout=300,
        check=False,
    )
    assert result.returncode == 0, result.stderr
    with np.load(out) as data:
        return dict(data), result.stdout


def ray_cast(ns: dict[str, np.ndarray]) -> np.ndarray:
    """Pixel (i, j) of the floor (row 0 at y = -4): is the box between it and the light?"""
    size = int(ns["IMAGE"])
    centres = -4 + 8 * (np.arange(size) + 0.5) / size
    y, x = np.meshgrid(centres, centres, indexing="ij")
    p = np.stack([x, y, np.zeros_like(x)], axis=-1)
    B = ns["B"]
    assert np.allclose(B[:3, :3], np.eye(3))  # an axis-aligned box: the slab test below
    world = ns["vertices"] + B[:3, 3]
    lo, hi = world.min(axis=0), world.max(axis=0)
    d = ns["light"] - p
    with np.errstate(divide="ignore", invalid="ignore"):
        t0, t1 = (lo - p) / d, (hi - p) / d
    enter = np.minimum(t0, t1).max(axis=-1)
    leave = np.maximum(t0, t1).min(axis=-1)
    return (enter <= leave) & (leave > 0) & (enter < 1)


def test_complete_program_matches_a_ray_cast(gl, tmp_path):
    ns, printed = run(block("shadow_program.py"), tmp_path)
    shadowed, truth = ns["shadowed"], ray_cast(ns)
    assert 0.02 < truth.mean() < 0.2
    # Mismatches only on the shadow's outline, where a pixel's 3x3 neighbourhood is mixed.
    padded = np.pad(truth, 1, mode="edge")
    windows = np.lib.stride_tricks.sliding_window_view(padded, (3, 3))
    mixed = windows.min(axis=(-1, -2)) != windows.max(axis=(-1, -2))
    wrong = shadowed != truth
    assert not np.any(wrong & ~mixed)
    assert wrong.sum() < 0.25 * mixed.sum()  # texels and pixels sample the edge apart
    # Lit where no ray meets the box, in particular everywhere outside the light's frustum.
    assert np.all(ns["image"][~mixed & ~truth] == 255)
    # The guide quotes what the program prints.
    assert printed.strip() in GUIDE.read_text(encoding="utf-8")


def test_repeat_wrapping_tiles_ghost_shadows(gl, tmp_path):
    source = block("shadow_program.py")
    assert CLAMP_TO_EDGE in source
    ns, _ = run(source.replace(CLAMP_TO_EDGE, CLAMP_TO_EDGE.replace("False", "True")), tmp_path)
    truth = ray_cast(ns)
    ghosts = ns["shadowed"] & ~truth
    assert ghosts.sum() > 10 * truth.sum()
    # The guide's figure for it.
    assert f"shades {100 * ns['shadowed'].mean():.1f} % of the floor" in " ".join(
        GUIDE.read_text(encoding="utf-8").split()
    )


def test_clamp_to_border_sampler_reads_zero_outside(gl, tmp_path):
    source = block("shadow_program.py")
    reference, _ = run(source, tmp_path)
    snippet = block("clamp_to_border.py")
    # The texture itself repeats: the sampler's border colour must win.
    variant = source.replace(CLAMP_TO_EDGE, CLAMP_TO_EDGE.replace("False", "True")).replace(
        BIND, f"{BIND}\n{snippet}"
    )
    ns, _ = run(variant, tmp_path)
    np.testing.assert_array_equal(ns["image"], reference["image"])


def test_stable_frame_snippet_is_fit_shadow_with_an_up_axis(gl, tmp_path):
    program = block("shadow_program.py")
    stable = block("stable_frame.py")
    matrices = {
        "z_axis": "frame.z_axis",
        "y_axis": "frame.y_axis",
        "UP": "UP",
        "blocker_to_clip": "blocker_to_clip",
        "world_to_texture": "world_to_texture",
        "fit_blocker_to_clip": "setup.blocker_to_clip",
        "fit_world_to_texture": "setup.world_to_texture",
    }
    ns, _ = run(f"{program}\n{stable}", tmp_path, **matrices)
    Z, Y = ns["z_axis"], ns["y_axis"]
    up = ns["UP"] - np.dot(ns["UP"], Z) * Z
    np.testing.assert_allclose(Y, up / np.linalg.norm(up), atol=1e-12)
    vertices = np.c_[ns["vertices"], np.ones(len(ns["vertices"]))]
    clip = ns["blocker_to_clip"] @ vertices.T
    assert np.abs(clip[:2] / clip[3]).max() == pytest.approx(1 - 2 / int(ns["MAP"]))
    # With fit_shadow's own Y as the up axis, the snippet reproduces fit_shadow exactly.
    assert "UP = np.array([0.0, 1.0, 0.0])" in stable
    same = stable.replace("np.array([0.0, 1.0, 0.0])", "setup.frame.y_axis")
    ns, _ = run(f"{program}\n{same}", tmp_path, **matrices)
    np.testing.assert_allclose(ns["blocker_to_clip"], ns["fit_blocker_to_clip"], atol=1e-12)
    np.testing.assert_allclose(ns["world_to_texture"], ns["fit_world_to_texture"], atol=1e-12)


def test_jax_snippet_fits_the_same_matrices(gl, tmp_path):
    pytest.importorskip("jax")
    source = f"{block('shadow_program.py')}\n{block('per_frame_jax.py')}"
    ns, _ = run(source, tmp_path, jax="jax_setup.blocker_to_clip", numpy="setup.blocker_to_clip")
    assert ns["jax"].dtype == np.float32  # JAX's default precision in a user's program
    np.testing.assert_allclose(ns["jax"], ns["numpy"], rtol=1e-5, atol=1e-5)
