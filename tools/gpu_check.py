"""The GPU check (``make gpu-check``): the render suite and the GPU benchmarks on this
machine's GPU, after printing what they run on.

It probes OpenGL through EGL (the vendor's driver when its EGL vendor file is installed),
WebGPU (wgpu over Vulkan), JAX's devices and ``nvidia-smi``. Where none of them finds a
GPU (Mesa's llvmpipe and lavapipe are software), it says "no GPU" and exits 0 without
running anything. Otherwise it runs ``pytest tests/render`` with ``SHADOWMATH_REQUIRE_GL=1``
and ``benchmarks/run.py --only gpu``, and exits 1 if either fails or if a GPU is present
but OpenGL or WebGPU draws in software (then the suite would not test the GPU: see
docs/accuracy.md, "Accuracy on real GPUs", for the EGL and Vulkan loader files). Needs no
package registry: run it from a copy of the tree with the wheels installed.
"""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
from collections.abc import Callable, Sequence

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
#: Software rasterizers (Mesa's llvmpipe for OpenGL, lavapipe for Vulkan) and CPU devices.
SOFTWARE = ("llvmpipe", "lavapipe", "softpipe", "swrast", "swiftshader", "cpu")


def probe_gl() -> str:
    from shadowmath.render import standalone_context

    info = standalone_context().info
    return " | ".join(str(info[k]) for k in ("GL_RENDERER", "GL_VENDOR", "GL_VERSION"))


def probe_wgpu() -> str:
    from shadowmath.render._pass_wgpu import _devices, wgpu_device

    wgpu_device()
    info = _devices[0][0].info
    keys = ("device", "vendor", "adapter_type", "backend_type", "description")
    return " | ".join(str(info.get(k, "")) for k in keys)


def probe_jax() -> str:
    import jax

    devices = (f"{d.platform} {d.device_kind}" for d in jax.devices())
    return f"jax {jax.__version__}: " + ", ".join(devices)


def probe_nvidia_smi() -> str:
    if shutil.which("nvidia-smi") is None:
        raise RuntimeError("nvidia-smi not found")
    query = ["nvidia-smi", "--query-gpu=name,driver_version,memory.total", "--format=csv,noheader"]
    out = subprocess.run(query, capture_output=True, text=True, check=True, timeout=60)
    return out.stdout.strip().replace("\n", "; ")


PROBES: dict[str, Callable[[], str]] = {
    "OpenGL (EGL)": probe_gl,
    "WebGPU (wgpu)": probe_wgpu,
    "JAX": probe_jax,
    "nvidia-smi": probe_nvidia_smi,
}


def describe(probes: dict[str, Callable[[], str]]) -> dict[str, str | None]:
    """Each probe's answer, or None where it raised (printed as unavailable)."""
    found: dict[str, str | None] = {}
    for name, probe in probes.items():
        try:
            found[name] = probe() or None
        except Exception as err:  # a missing module, driver or device
            print(f"{name}: unavailable ({type(err).__name__}: {err})")
            found[name] = None
        else:
            print(f"{name}: {found[name]}")
    return found


def on_gpu(answer: str | None) -> bool:
    """Whether a probe's answer names a hardware device (not a software rasterizer)."""
    if not answer:
        return False
    if answer.startswith("jax"):
        return any(f" {p} " in answer.lower() for p in ("gpu", "cuda", "rocm"))
    return not any(s in answer.lower() for s in SOFTWARE)


def main(argv: Sequence[str] = (), run: Callable[..., int] | None = None) -> int:
    run = run or (lambda cmd, env: subprocess.run(cmd, cwd=ROOT, env=env).returncode)
    os.environ.setdefault("XLA_PYTHON_CLIENT_PREALLOCATE", "false")  # a GPU shared by processes
    found = describe(PROBES)
    if not any(on_gpu(a) for a in found.values()):
        print("gpu-check: no GPU on this machine (no probe found a hardware device): nothing run.")
        return 0
    software = [k for k in ("OpenGL (EGL)", "WebGPU (wgpu)") if not on_gpu(found[k])]
    path = os.pathsep.join(filter(None, (ROOT, os.environ.get("PYTHONPATH"))))  # this tree
    env = {**os.environ, "SHADOWMATH_REQUIRE_GL": "1", "PYTHONPATH": path}
    tests = run([sys.executable, "-m", "pytest", "-q", "-p", "no:cacheprovider", *argv,
                 "tests/render"], env)  # fmt: skip
    bench = run([sys.executable, "benchmarks/run.py", "--only", "gpu"], env)
    print(f"gpu-check: tests/render exit {tests}, benchmarks --only gpu exit {bench}")
    if software:
        print(f"gpu-check: a GPU is present but {', '.join(software)} drew in software")
    return int(bool(tests or bench or software))


if __name__ == "__main__":
    sys.path.insert(0, ROOT)
    sys.exit(main(sys.argv[1:]))
