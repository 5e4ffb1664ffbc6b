"""tools/gpu_check.py (``make gpu-check``): which probe answers name a GPU, and on a machine
without one (CI, this 2-core machine) the check says so and runs nothing."""

from __future__ import annotations

import importlib.util
from pathlib import Path

import pytest

_spec = importlib.util.spec_from_file_location(
    "gpu_check", Path(__file__).parent.parent / "tools" / "gpu_check.py"
)
assert _spec is not None and _spec.loader is not None
gpu_check = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(gpu_check)


@pytest.mark.parametrize(
    ("answer", "gpu"),
    [
        ("NVIDIA H200/PCIe/SSE2 | NVIDIA Corporation | 4.6.0 NVIDIA 580.159.03", True),
        ("llvmpipe (LLVM 15.0.6, 256 bits) | Mesa/X.org | 4.5 (Core Profile) Mesa 22.3.6", False),
        ("NVIDIA H200 | NVIDIA | DiscreteGPU | Vulkan | 580.159.03", True),
        ("llvmpipe (LLVM 15.0.6, 256 bits) | llvmpipe | CPU | Vulkan | Mesa 22.3.6", False),
        ("jax 0.11.2: gpu NVIDIA H200", True),
        ("jax 0.10.2: cpu cpu", False),
        ("NVIDIA H200, 580.159.03, 143771 MiB", True),
        (None, False),
    ],
)
def test_which_answers_name_a_gpu(answer, gpu):
    assert gpu_check.on_gpu(answer) is gpu


def test_with_a_gpu_it_runs_the_render_suite_and_the_gpu_benchmarks(monkeypatch, capsys):
    ran = []
    fake = {"OpenGL (EGL)": "NVIDIA H200/PCIe/SSE2", "WebGPU (wgpu)": "llvmpipe | CPU"}
    monkeypatch.setattr(gpu_check, "PROBES", {k: (lambda v=v: v) for k, v in fake.items()})
    assert gpu_check.main([], run=lambda cmd, env: ran.append((cmd, env)) or 0) == 1
    assert [cmd[-1] for cmd, _ in ran] == ["tests/render", "gpu"]
    assert all(env["SHADOWMATH_REQUIRE_GL"] == "1" for _, env in ran)
    assert "WebGPU (wgpu) drew in software" in capsys.readouterr().out


def test_without_a_gpu_it_says_so_and_runs_nothing(capsys):
    found = gpu_check.describe(gpu_check.PROBES)
    if any(gpu_check.on_gpu(a) for a in found.values()):
        pytest.skip(f"this machine has a GPU: {found}")  # only where make gpu-check runs
    assert gpu_check.main([], run=lambda cmd, env: pytest.fail(f"ran {cmd}")) == 0
    assert "no GPU on this machine" in capsys.readouterr().out
