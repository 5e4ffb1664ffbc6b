"""Make the figures of the docs' math pages from shadowmath itself.

Every matrix and axis drawn here comes from the package's public functions; the
figures only plot them. Run from the repository root and commit the PNGs:

    .venv/bin/python docs/figures/make_figures.py

Optionally name figures to make only those: ``... make_figures.py planar frustum``.
"""

from __future__ import annotations

import sys
from collections.abc import Callable
from pathlib import Path

import matplotlib as mpl

mpl.use("Agg")

import matplotlib.pyplot as plt
import numpy as np
from matplotlib.axes import Axes
from matplotlib.figure import Figure
from PIL import Image

import shadowmath as sm

HERE = Path(__file__).resolve().parent
SHADOW = "#444444"
BLOCKER = "#d9822b"
LIGHT = "#f2c500"
RAY = "#9aa5b1"


def torus(
    major: float = 1.0, minor: float = 0.35, n: int = 48, m: int = 24
) -> tuple[np.ndarray, np.ndarray]:
    """Vertices ``(n*m, 3)`` and triangles ``(2*n*m, 3)`` of a torus around ``z``."""
    u = np.linspace(0, 2 * np.pi, n, endpoint=False)[:, None]
    v = np.linspace(0, 2 * np.pi, m, endpoint=False)[None, :]
    ring = major + minor * np.cos(v)
    xyz = np.stack(np.broadcast_arrays(ring * np.cos(u), ring * np.sin(u), minor * np.sin(v)), -1)
    i, j = np.meshgrid(np.arange(n), np.arange(m), indexing="ij")
    a, b = i * m + j, ((i + 1) % n) * m + j
    c, d = ((i + 1) % n) * m + (j + 1) % m, i * m + (j + 1) % m
    tris = np.concatenate([np.stack([a, b, c], -1), np.stack([a, c, d], -1)]).reshape(-1, 3)
    return xyz.reshape(-1, 3), tris


def rotation_x(angle: float) -> np.ndarray:
    c, s = np.cos(angle), np.sin(angle)
    return np.array([[1, 0, 0], [0, c, -s], [0, s, c]])


def homogeneous(points: np.ndarray) -> np.ndarray:
    return np.concatenate([points, np.ones((*points.shape[:-1], 1))], axis=-1)


def apply(M: np.ndarray, points: np.ndarray) -> np.ndarray:
    """``(N, 3)`` points through a 4x4 column-vector matrix, returning ``(N, 4)``."""
    return homogeneous(points) @ M.T


def save(fig: Figure, name: str) -> None:
    path = HERE / f"{name}.png"
    fig.savefig(path, dpi=90)
    plt.close(fig)
    # A palette keeps the committed PNGs a few tens of kB.
    Image.open(path).convert("RGB").quantize(256, method=Image.Quantize.FASTOCTREE).save(
        path, optimize=True
    )
    print(f"{path.relative_to(Path.cwd()) if path.is_relative_to(Path.cwd()) else path}")


# --------------------------------------------------------------------------- planar
def planar() -> None:
    """Side view of Blinn's projection onto the floor y = 0: point, directional, sign of w."""
    floor = np.array([0.0, 1.0, 0.0, 0.0])
    blocker = np.array([[-0.6, 2.0, 0.0], [0.8, 2.6, 0.0], [0.5, 1.6, 0.0]])
    fig, axes = plt.subplots(1, 3, figsize=(11, 3.9))

    def scene(ax: Axes, light: np.ndarray, title: str) -> None:
        M = sm.planar_projection(floor, light)
        shadow = apply(M, blocker)
        assert np.all(shadow[:, 3] > 0), "points between light and plane must get w > 0"
        flat = shadow[:, :3] / shadow[:, 3:]
        for p, s in zip(blocker, flat, strict=True):
            start = light[:3] if light[3] else p + 3 * light[:3] / np.linalg.norm(light[:3])
            ax.plot([start[0], s[0]], [start[1], s[1]], color=RAY, lw=0.8, zorder=1)
        ax.fill(blocker[:, 0], blocker[:, 1], color=BLOCKER, zorder=2, label="blocker")
        ax.plot(flat[:, 0], flat[:, 1] + 0.02, color=SHADOW, lw=5, zorder=3, label="M p / w")
        ax.axhline(0, color="k", lw=1)
        if light[3]:
            ax.plot(*light[:2], marker="*", ms=16, color=LIGHT, mec="k", zorder=4, label="light")
        ax.set(title=title, xlim=(-3, 3), ylim=(-0.6, 5.2), aspect="equal")
        ax.legend(loc="upper left", fontsize=7)

    scene(axes[0], np.array([0.0, 4.0, 0.0, 1.0]), "point light L = (0, 4, 0, 1)")
    scene(axes[1], np.array([-1.0, 2.0, 0.0, 0.0]), "directional light L = (-1, 2, 0, 0)")

    ax = axes[2]
    light = np.array([0.0, 4.0, 0.0, 1.0])
    x, y = np.meshgrid(np.linspace(-3, 3, 241), np.linspace(-0.6, 5.2, 233))
    grid = np.stack([x, y, np.zeros_like(x)], axis=-1).reshape(-1, 3)
    # The same w whichever sign the plane is given: the matrix is oriented by sign(pi . L).
    w_up = apply(sm.planar_projection(floor, light), grid)[:, 3]
    w_down = apply(sm.planar_projection(-floor, light), grid)[:, 3]
    assert np.allclose(w_up, w_down)
    ax.contourf(x, y, w_up.reshape(x.shape), levels=[-10, 0, 10], colors=["#f4b6b6", "#cfe8cf"])
    beyond = np.array([[0.3, 5.0, 0.0]])
    hb = apply(sm.planar_projection(floor, light), beyond)[0]
    anti = hb[:3] / hb[3]
    ax.plot([beyond[0, 0], anti[0]], [beyond[0, 1], anti[1]], ls="--", color="#b03030", lw=1)
    ax.plot(*beyond[0, :2], "o", color="#b03030")
    ax.plot(anti[0], 0.03, "x", color="#b03030", ms=9, mew=2)
    ax.annotate(f"w = {hb[3]:.1f} < 0\nanti-shadow", (anti[0], 0.1), (0.35, 1.2), fontsize=8)
    ax.plot(*light[:2], marker="*", ms=16, color=LIGHT, mec="k")
    ax.axhline(0, color="k", lw=1)
    ax.text(-2.8, 2.0, "w > 0: shadow kept", fontsize=8)
    ax.text(-2.8, 4.6, "w < 0: clipped", fontsize=8)
    ax.set(title="sign of w (same for plane +pi or -pi)", xlim=(-3, 3), ylim=(-0.6, 5.2))
    ax.set_aspect("equal")
    fig.tight_layout()
    save(fig, "planar")


# ---------------------------------------------------------------------- helper axis
def helper() -> None:
    """Over all unit Z: which world axis is the helper, and |Z x V| >= sqrt(2/3)."""
    lon, lat = np.meshgrid(np.linspace(-np.pi, np.pi, 361), np.linspace(-np.pi / 2, np.pi / 2, 181))
    z = np.stack([np.cos(lat) * np.cos(lon), np.cos(lat) * np.sin(lon), np.sin(lat)], axis=-1)
    v = sm.helper_axis(z)
    which = np.argmax(v, axis=-1)
    length = np.linalg.norm(np.cross(z, v), axis=-1)
    fig, axes = plt.subplots(1, 2, figsize=(11, 3.4))
    deg = np.degrees
    axes[0].pcolormesh(
        deg(lon),
        deg(lat),
        which,
        cmap=mpl.colors.ListedColormap(["#e41a1c", "#4daf4a", "#377eb8"]),
        shading="auto",
    )
    for color, name in zip(("#e41a1c", "#4daf4a", "#377eb8"), "XYZ", strict=True):
        axes[0].plot([], [], "s", color=color, label=f"V = {name}")
    axes[0].legend(loc="lower left", fontsize=8, ncols=3)
    axes[0].set(
        title="helper_axis(Z): the world axis of Z's smallest |component|",
        xlabel="longitude of Z (deg)",
        ylabel="latitude of Z (deg)",
    )
    im = axes[1].pcolormesh(
        deg(lon), deg(lat), length, cmap="viridis", shading="auto", vmin=np.sqrt(2 / 3), vmax=1
    )
    cbar = fig.colorbar(im, ax=axes[1])
    cbar.set_ticks([np.sqrt(2 / 3), 0.9, 1.0], labels=["√(2/3)", "0.9", "1"])
    k = np.unravel_index(np.argmin(length), length.shape)
    axes[1].plot(deg(lon[k]), deg(lat[k]), "w*", ms=10)
    signs = np.array([[a, b, c] for a in (-1, 1) for b in (-1, 1) for c in (-1, 1)])
    diagonals = signs / np.sqrt(3)
    at_diagonals = np.linalg.norm(np.cross(diagonals, sm.helper_axis(diagonals)), axis=-1)
    assert np.allclose(at_diagonals, np.sqrt(2 / 3))
    assert length.min() >= np.sqrt(2 / 3) - 1e-12
    axes[1].set(
        title="|Z × V| >= √(2/3) = 0.8165, reached at the 8 diagonals (±1,±1,±1)/√3",
        xlabel="longitude of Z (deg)",
    )
    fig.tight_layout()
    save(fig, "helper_axis")


# ------------------------------------------------------------------ frame + frustum
def _scene() -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    verts, tris = torus()
    verts = verts @ rotation_x(0.5).T + np.array([0.3, 1.6, 2.0])
    return np.array([-1.5, 4.5, 7.0]), verts, tris


def frame3d() -> None:
    """The light, its frame axes and the adaptive frustum around a torus, in world space."""
    light, verts, tris = _scene()
    frame = sm.light_frame(light, verts)
    fr = sm.adaptive_frustum(frame, verts, 64)
    L2W = sm.light_to_world(frame)
    fig = plt.figure(figsize=(6.4, 5.4))
    ax = fig.add_subplot(projection="3d")
    ax.plot_trisurf(*verts.T, triangles=tris, color=BLOCKER, alpha=0.55, lw=0)
    ax.scatter(*light, color=LIGHT, s=120, marker="*", edgecolor="k")
    # Frustum corners at near and far: light coords (±rx z, ±ry z, z), to world.
    corners = []
    for z in (float(fr.near), float(fr.far)):
        for sx, sy in ((-1, -1), (1, -1), (1, 1), (-1, 1)):
            corners.append([sx * float(fr.rx_max) * z, sy * float(fr.ry_max) * z, z])
    world = apply(L2W, np.array(corners))[:, :3]
    for ring in (world[:4], world[4:]):
        ax.plot(*np.vstack([ring, ring[:1]]).T, color="k", lw=0.8)
    for k in range(4):
        ax.plot(*np.stack([light, world[4 + k]]).T, color="k", lw=0.6, ls=":")
    for axis, color, name in zip(frame[1:], ("#e41a1c", "#4daf4a", "#377eb8"), "XYZ", strict=True):
        tip = light + 1.6 * axis
        ax.plot(*np.stack([light, tip]).T, color=color, lw=2.5)
        ax.text(*tip, f"{name}_light", color=color, fontsize=9)
    ax.set(xlabel="x", ylabel="y", zlabel="z", title="light frame and adaptive frustum (world)")
    ax.set_box_aspect(np.ptp(np.vstack([verts, light]), axis=0))
    ax.view_init(elev=22, azim=-35)
    ax.locator_params(nbins=4)
    fig.tight_layout()
    save(fig, "light_frame")


def _rasterize(clip: np.ndarray, tris: np.ndarray, size: int) -> np.ndarray:
    """Coverage of texel centres by the triangles' NDC images (a tiny NumPy rasterizer)."""
    ndc = clip[:, :2] / clip[:, 3:]
    centers = (np.arange(size) + 0.5) / size * 2 - 1
    gx, gy = np.meshgrid(centers, centers)
    p = np.stack([gx, gy], -1)[None]
    a, b, c = (ndc[tris[:, k]][:, None, None, :] for k in range(3))

    def edge(u: np.ndarray, v: np.ndarray) -> np.ndarray:
        return (v[..., 0] - u[..., 0]) * (p[..., 1] - u[..., 1]) - (v[..., 1] - u[..., 1]) * (
            p[..., 0] - u[..., 0]
        )

    e0, e1, e2 = edge(a, b), edge(b, c), edge(c, a)
    inside = ((e0 >= 0) & (e1 >= 0) & (e2 >= 0)) | ((e0 <= 0) & (e1 <= 0) & (e2 <= 0))
    return inside.any(axis=0)


def frustum() -> None:
    """Light-space side view with the ratio lines; the map with its border; margins vs size."""
    light, verts, tris = _scene()
    setup = sm.fit_shadow(light, verts, 24)
    p_light = apply(setup.world_to_light, verts)[:, :3]
    fr = setup.frustum
    fig, axes = plt.subplots(1, 3, figsize=(12, 3.9))

    ax = axes[0]
    z = np.linspace(0, float(fr.far) * 1.05, 2)
    ax.scatter(p_light[:, 2], p_light[:, 0], s=2, color=BLOCKER, label="blocker vertices")
    ax.plot(z, float(fr.rx_max) * z, "k-", lw=1, label="x = ±R_x,max z")
    ax.plot(z, -float(fr.rx_max) * z, "k-", lw=1)
    for d, name in ((float(fr.near), "near"), (float(fr.far), "far")):
        ax.axvline(d, color="#377eb8", lw=1, ls="--")
        ax.text(d, float(fr.rx_max) * d * 1.05, name, fontsize=8, color="#377eb8", ha="center")
    ax.plot(0, 0, marker="*", ms=16, color=LIGHT, mec="k")
    ax.set(
        title="light coordinates, seen along -Y",
        xlabel="z_light (toward blocker)",
        ylabel="x_light",
    )
    ax.legend(loc="lower left", fontsize=7)

    ax = axes[1]
    size = 24
    clip = apply(setup.blocker_to_clip, verts)
    cover = _rasterize(clip, tris, size)
    border = np.zeros((size, size), bool)
    border[[0, -1], :] = True
    border[:, [0, -1]] = True
    img = np.where(cover, 0.15, np.where(border, 0.75, 1.0))
    assert not np.any(cover & border), "the blocker must never touch the border texels"
    ax.imshow(img, cmap="gray", vmin=0, vmax=1, origin="lower", extent=(-1, 1, -1, 1))
    m = float(fr.margin_x)
    ax.plot([-m, m, m, -m, -m], [-m, -m, m, m, -m], color="#e41a1c", lw=1)
    ndc = clip[:, :2] / clip[:, 3:]
    ax.scatter(*ndc.T, s=1, color=BLOCKER)
    ax.set(
        title=f"{size}x{size} map: margin {m:.4f} (red), border grey",
        xlabel="x_ndc",
        ylabel="y_ndc (t = 0 at the bottom row)",
    )

    ax = axes[2]
    sizes = np.arange(8, 257)
    derived = np.array([sm.border_margin(int(s))[0] for s in sizes])
    ax.plot(sizes, derived, color="k", label="(size - 2) / size  (1 border texel)")
    ax.axhline(0.98, color="#e41a1c", lw=1, label="the article's 0.98")
    ax.axvspan(8, 50, color="#f4b6b6", alpha=0.6, lw=0)
    ax.axvspan(50, 100, color="#fde0b6", alpha=0.6, lw=0)
    ax.text(12, 0.80, "0.98 covers\nborder-texel\ncentres", fontsize=7)
    ax.text(55, 0.80, "0.98 enters\nthe border", fontsize=7)
    ax.plot([100], [0.98], "ko")
    ax.annotate(
        "100 texels: 0.98", (100, 0.98), (120, 0.9), fontsize=8, arrowprops={"arrowstyle": "->"}
    )
    ax.set(
        title="margin vs map size", xlabel="map size (texels)", ylabel="margin", ylim=(0.7, 1.01)
    )
    ax.legend(loc="lower right", fontsize=7)
    fig.tight_layout()
    save(fig, "frustum")


# ------------------------------------------------------------------------- receiver
def receiver() -> None:
    """A floor textured through world_to_texture: the map, s,t on the floor, the shadow."""
    light, verts, tris = _scene()
    size = 64
    setup = sm.fit_shadow(light, verts, size)
    shadow_map = _rasterize(apply(setup.blocker_to_clip, verts), tris, size)
    x, z = np.meshgrid(np.linspace(-6, 6, 300), np.linspace(-6, 16, 400))
    floor = np.stack([x, np.zeros_like(x), z], -1).reshape(-1, 3)
    stq = apply(setup.world_to_texture, floor)
    q = stq[:, 3]
    s, t = stq[:, 0] / q, stq[:, 1] / q
    inside = (q > 0) & (s >= 0) & (s < 1) & (t >= 0) & (t < 1)
    # Clamp to edge, as the renderer samples: the border texels are empty, so
    # every point outside the map reads "no shadow".
    col = np.clip((s * size).astype(int), 0, size - 1)
    row = np.clip((t * size).astype(int), 0, size - 1)
    shaded = np.where(q > 0, shadow_map[row, col], False)
    fig, axes = plt.subplots(1, 3, figsize=(12, 3.9))
    axes[0].imshow(shadow_map, cmap="gray_r", origin="lower", extent=(0, 1, 0, 1))
    axes[0].set(title=f"{size}x{size} shadow map (t = 0: row 0)", xlabel="s", ylabel="t")
    ext = (-6, 6, -6, 16)
    st = np.where(inside, s, np.nan).reshape(x.shape)
    im = axes[1].imshow(st, origin="lower", extent=ext, cmap="coolwarm", vmin=0, vmax=1)
    axes[1].contour(
        x,
        z,
        np.where(q > 0, t, np.nan).reshape(x.shape),
        levels=[0, 0.5, 1],
        colors="k",
        linewidths=0.7,
    )
    axes[1].contourf(x, z, (q <= 0).reshape(x.shape), levels=[0.5, 1.5], colors=["#bbbbbb"])
    fig.colorbar(im, ax=axes[1], label="s")
    axes[1].set(
        title="floor y=0: s, t = 0, ½, 1;\ngrey q <= 0 (behind the light)", xlabel="x", ylabel="z"
    )
    axes[2].imshow(
        np.where(shaded, 0.3, 1.0).reshape(x.shape),
        cmap="gray",
        vmin=0,
        vmax=1,
        origin="lower",
        extent=ext,
    )
    axes[2].plot(light[0], light[2], marker="*", ms=14, color=LIGHT, mec="k")
    axes[2].set(title="shadow on the floor via world_to_texture", xlabel="x", ylabel="z")
    fig.tight_layout()
    save(fig, "receiver")


FIGURES: dict[str, Callable[[], None]] = {
    "planar": planar,
    "helper_axis": helper,
    "light_frame": frame3d,
    "frustum": frustum,
    "receiver": receiver,
}

if __name__ == "__main__":
    for name in sys.argv[1:] or FIGURES:
        FIGURES[name]()
