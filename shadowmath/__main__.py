"""``python -m shadowmath``: the default scene's shadow matrices."""

from __future__ import annotations

import argparse
from collections.abc import Sequence

import numpy as np

from ._planar import planar_projection
from ._setup import fit_shadow


def _torus(major: float = 1.0, minor: float = 0.35, n: int = 32, m: int = 16) -> np.ndarray:
    u = np.linspace(0, 2 * np.pi, n, endpoint=False)[:, None]
    v = np.linspace(0, 2 * np.pi, m, endpoint=False)[None, :]
    x = (major + minor * np.cos(v)) * np.cos(u)
    y = (major + minor * np.cos(v)) * np.sin(u)
    z = minor * np.sin(v) * np.ones_like(u)
    return np.stack([x, y, z], axis=-1).reshape(-1, 3)


def main(argv: Sequence[str] | None = None) -> None:
    parser = argparse.ArgumentParser(prog="shadowmath", description=__doc__)
    parser.add_argument("--light", type=float, nargs=3, default=(0.0, 2.5, 6.0))
    parser.add_argument("--map-size", type=int, default=256)
    args = parser.parse_args(argv)
    np.set_printoptions(precision=4, suppress=True)
    torus = _torus() + np.array([0.0, 1.5, 2.0])
    setup = fit_shadow(np.array(args.light), torus, args.map_size)
    print("light", np.array(args.light), "map", args.map_size)
    print("blocker_to_clip =\n", setup.blocker_to_clip)
    print("world_to_texture =\n", setup.world_to_texture)
    print("planar shadow on the wall z = 0 =\n", planar_projection([0, 0, 1, 0], [*args.light, 1]))


if __name__ == "__main__":
    main()
