"""The main job (python -m shadowmath), render_scene's argument checks, and import isolation."""

from __future__ import annotations

import subprocess
import sys

import numpy as np
import pytest

from shadowmath.__main__ import main
from shadowmath.cli._options import DEFAULT_PCSS_BIAS
from shadowmath.meshes import box, grid
from shadowmath.render import PCSS_POLYGON_OFFSET, Body, Light, render_scene


def _png(path) -> np.ndarray:
    from PIL import Image

    return np.asarray(Image.open(path))


def test_demo_writes_the_picture_and_the_shadow_map(gl, tmp_path, capsys):
    out, smap = tmp_path / "shadow.png", tmp_path / "map.png"
    args = ["--size", "96", "64", "--map-size", "40x24", "--output", str(out)]
    assert main([*args, "--shadow-map-output", str(smap)]) == 0
    printed = capsys.readouterr().out
    assert f"wrote {out}" in printed
    for name in ("blocker_to_clip", "world_to_texture", "planar_projection onto the wall"):
        assert name in printed
    image = _png(out)
    assert image.shape == (64, 96, 3)
    mask = _png(smap)
    assert mask.shape == (24, 40)
    assert mask[1:-1, 1:-1].max() == 255
    assert mask[0].max() == mask[-1].max() == mask[:, 0].max() == mask[:, -1].max() == 0
    # The torus's shadow darkens part of the wall: the picture has both lit and shadowed wall.
    wall = image.reshape(-1, 3)[:, 0]
    assert wall.max() > 180
    assert (wall < 60).sum() > 50


def test_demo_reads_an_obj_file_and_planar_method(gl, tmp_path, capsys):
    obj = tmp_path / "tet.obj"
    obj.write_text("v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n")
    out = tmp_path / "tet.png"
    assert (
        main(["--mesh", str(obj), "--method", "planar", "--size", "64", "48", "--output", str(out)])
        == 0
    )
    assert _png(out).shape == (48, 64, 3)


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (["--mesh", "missing.obj"], "--mesh"),
        (["--light", "0", "1.6", "2.2"], "light"),  # at the torus's centre
        (["--map-size", "2"], "--map-size"),
    ],
)
def test_demo_errors_exit_with_a_message(gl, tmp_path, capsys, args, message):
    with pytest.raises(SystemExit) as exc:
        main([*args, "--output", str(tmp_path / "x.png")])
    assert exc.value.code == 2
    assert message in capsys.readouterr().err
    assert not (tmp_path / "x.png").exists()


FLOOR = Body(*grid((4.0, 4.0)), plane=(0, 0, 1, 0))
BLOCKER = Body(
    *box(), to_world=np.array([[1, 0, 0, 0], [0, 1, 0, 0], [0, 0, 1, 2.0], [0, 0, 0, 1]])
)
CAMERA = np.eye(4)


@pytest.mark.parametrize(
    ("change", "match"),
    [
        ({"method": "stencil"}, "method"),
        ({"lights": []}, "lights"),
        ({"lights": [Light((0, 0, 5))] * 9}, "lights"),
        ({"lights": [Light((0, 0, np.inf))]}, r"lights\[0\]\.position"),
        ({"lights": [Light((0, 0, 5), (1, 1))]}, r"lights\[0\]\.color"),
        ({"receivers": [FLOOR._replace(plane=None)], "method": "planar"}, r"receivers\[0\]\.plane"),
        ({"receivers": [FLOOR._replace(color=(1, 0))]}, r"receivers\[0\]\.color"),
        ({"blockers": [BLOCKER._replace(to_world=np.eye(3))]}, r"blockers\[0\]\.to_world"),
        ({"blockers": [BLOCKER._replace(triangles=[[0, 1, 99]])]}, r"blockers\[0\] triangles"),
        ({"world_to_clip": np.full((4, 4), np.nan)}, "world_to_clip"),
        ({"image_size": (0, 10)}, "image_size"),
        ({"map_size": 1.5}, "map_size"),
        ({"ambient": -1.0}, "ambient"),
        ({"setups": [[]]}, "setups"),
        ({"lights": [Light((0, 0, 2.0))]}, "light"),  # the light inside the blocker
    ],
)
def test_render_scene_bad_input(gl, change, match):
    args = {
        "receivers": [FLOOR],
        "blockers": [BLOCKER],
        "lights": [Light((0, 0, 5))],
        "world_to_clip": CAMERA,
        "image_size": 16,
    }
    args.update(change)
    receivers, blockers, lights, camera = (
        args.pop(k) for k in ("receivers", "blockers", "lights", "world_to_clip")
    )
    with pytest.raises(ValueError, match=match):
        render_scene(receivers, blockers, lights, camera, **args, ctx=gl)


def test_import_shadowmath_does_not_import_moderngl():
    code = (
        "import shadowmath, shadowmath.meshes, shadowmath.groundtruth, sys; "
        "print('moderngl' in sys.modules)"
    )
    result = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, check=True
    )
    assert result.stdout.strip() == "False"


def test_camera_helpers():
    from shadowmath.render import look_at, perspective

    eye, target = np.array([3.0, -2.0, 5.0]), np.array([0.5, 1.0, 0.0])
    V = look_at(eye, target, (0.0, 0.0, 1.0))
    R = V[:3, :3]
    np.testing.assert_allclose(R @ R.T, np.eye(3), atol=1e-12)
    assert np.linalg.det(R) == pytest.approx(1.0)  # right-handed: a rotation
    np.testing.assert_allclose(V @ np.append(eye, 1), [0, 0, 0, 1], atol=1e-12)
    d = np.linalg.norm(target - eye)
    np.testing.assert_allclose(V @ np.append(target, 1), [0, 0, -d, 1], atol=1e-12)
    assert (V @ [0, 0, 10.0, 1])[1] > 0  # world up appears upward
    P = perspective(60.0, 2.0, 0.5, 20.0)
    for z, ndc in ((-0.5, -1.0), (-20.0, 1.0)):
        clip = P @ [0.0, 0.0, z, 1.0]
        assert clip[2] / clip[3] == pytest.approx(ndc)
    top = P @ [0.0, np.tan(np.radians(30.0)), -1.0, 1.0]  # the top of the field of view
    assert top[1] / top[3] == pytest.approx(1.0)
    right = P @ [2 * np.tan(np.radians(30.0)), 0.0, -1.0, 1.0]  # aspect 2: twice as wide
    assert right[0] / right[3] == pytest.approx(1.0)
    with pytest.raises(ValueError, match="up"):
        look_at([0, 0, 0], [0, 0, 1], [0, 0, 2])
    with pytest.raises(ValueError, match="near"):
        perspective(60.0, 1.0, 0.0, 1.0)


# The demo's shadow systems (--method, --pcf, --depth-bias, --area-light, --api): each
# run records the frame the renderer returned, so the checks read its shadow mask.
SMALL = ["--size", "96", "72", "--map-size", "128"]


@pytest.fixture
def demo_frames(gl, tmp_path, monkeypatch, capsys):
    """Run the demo at 96x72 with 128-texel maps; return its frame and printed summary."""
    import shadowmath.render

    frames: list = []
    render = shadowmath.render.render_scene

    def recording(*args, **kwargs):
        frames.append(render(*args, **kwargs))
        return frames[-1]

    monkeypatch.setattr(shadowmath.render, "render_scene", recording)

    def run(*args: str):
        out = tmp_path / "demo.png"
        assert main([*SMALL, "--output", str(out), *args]) == 0
        summary = capsys.readouterr().out.splitlines()[0]
        assert summary.startswith(f"wrote {out}: a 96x72 PNG")
        assert _png(out).shape == (72, 96, 3)
        return frames[-1], summary

    return run


def _receiver_shadow(frame) -> tuple[np.ndarray, np.ndarray]:
    """The shadow mask on the wall and the floor (bodies 0 and 1), and where they are seen."""
    receivers = (frame.body == 0) | (frame.body == 1)
    return frame.shadow[..., 0], receivers


def _shadowed(frame) -> np.ndarray:
    shadow, receivers = _receiver_shadow(frame)
    return (shadow > 0.5) & receivers


def _penumbra(frame) -> np.ndarray:
    shadow, receivers = _receiver_shadow(frame)
    return (shadow > 0) & (shadow < 1) & receivers


def _agreement(a: np.ndarray, b: np.ndarray) -> float:
    return float((a & b).sum() / (a | b).sum())


def test_depth_and_omni_shadow_the_receivers_where_texture_does(demo_frames):
    texture, said = demo_frames("--method", "texture")
    assert "projective shadow texture from a 128x128 shadow map" in said
    depth, said = demo_frames("--method", "depth")
    assert "Williams' depth shadow map (128x128, PCF radius 0, depth bias 2.5 4)" in said
    assert "OpenGL" in said
    omni, said = demo_frames("--method", "omni")
    assert "omnidirectional cube depth map (six 128x128 faces" in said
    hard = _shadowed(texture)
    assert hard.sum() > 300  # the torus's shadow on the wall and the floor
    assert _agreement(hard, _shadowed(depth)) > 0.97  # measured 1.0 (627 pixels)
    assert _agreement(hard, _shadowed(omni)) > 0.95  # measured 0.97 (17 edge pixels differ)
    for frame in (texture, depth, omni):
        assert not _penumbra(frame).any()  # hard shadows: every pixel 0 or 1


def test_pcf_softens_the_depth_shadow_edge_and_bias_prevents_acne(demo_frames):
    plain, _ = demo_frames("--method", "depth")
    filtered, said = demo_frames("--method", "depth", "--pcf", "2")
    assert "PCF radius 2, depth bias 6.5 4" in said  # the bias's default grows with K
    assert _penumbra(filtered).sum() > 100  # measured 200 fractional pixels
    assert _agreement(_shadowed(plain), _shadowed(filtered)) > 0.95
    acne, said = demo_frames("--method", "depth", "--depth-bias", "0", "0")
    assert "depth bias 0 0" in said
    # Without the polygon offset lit surfaces shadow themselves (measured 855 against 627).
    assert _shadowed(acne).sum() > 1.2 * _shadowed(plain).sum()


def _edge_length(mask: np.ndarray) -> int:
    """Pixels of ``mask`` with a 4-neighbour outside it: the hard shadow's edge, in pixels."""
    padded = np.pad(mask, 1, constant_values=False)
    inner = padded[:-2, 1:-1] & padded[2:, 1:-1] & padded[1:-1, :-2] & padded[1:-1, 2:]
    return int((mask & ~inner).sum())


def test_soft_shadows_have_a_penumbra_wider_than_the_hard_edge(demo_frames):
    hard, _ = demo_frames("--method", "depth")
    soft, said = demo_frames("--method", "soft", "--samples", "16")
    assert "1x1 area light centred at (-2.2, 3.6, 6.0)" in said
    assert "average of 16 samples' depth shadow maps" in said
    assert len(soft.setups[0]) == 16  # one depth map per light sample
    edge = _edge_length(_shadowed(hard))
    penumbra = _penumbra(soft).sum()
    # The penumbra's mean width across the hard edge, in pixels (measured about 3).
    assert penumbra / edge > 2.0
    # The same shadow overall: its darker half lies where the hard shadow is.
    assert _agreement(_shadowed(hard), _shadowed(soft)) > 0.9
    # A larger light widens the penumbra (measured 251, 608, 970 pixels).
    small, said = demo_frames("--method", "soft", "--area-light", "0.4", "0.4")
    assert "0.4x0.4 area light" in said
    big, _ = demo_frames("--method", "soft", "--area-light", "1.6", "1.6")
    assert _penumbra(small).sum() < penumbra < _penumbra(big).sum()


def test_radiance_textures_agree_with_averaged_depth_maps(demo_frames):
    soft, _ = demo_frames("--method", "soft")
    radiance, said = demo_frames("--method", "radiance", "--samples", "16", "--seed", "0")
    assert "Heckbert and Herf's radiance textures (128x128 per receiver)" in said
    assert "16 samples (seed 0)" in said
    assert _penumbra(radiance).sum() > 300
    shadow_s, receivers = _receiver_shadow(soft)
    shadow_r, _ = _receiver_shadow(radiance)
    assert np.abs(shadow_s - shadow_r)[receivers].mean() < 0.01  # measured 0.003
    other, _ = demo_frames("--method", "radiance", "--seed", "7")
    assert not np.array_equal(other.shadow, radiance.shadow)  # the seed moves the jitter


def test_demo_writes_depth_and_cube_maps(demo_frames, tmp_path):
    depth_png = tmp_path / "depth_map.png"
    frame, _ = demo_frames("--method", "depth", "--shadow-map-output", str(depth_png))
    depth = _png(depth_png)
    assert depth.shape == (128, 128)
    # Every texel holds a body here (the wall and floor fill the map): near black, far 0.8.
    # The depth range ends just past the farthest receiver point inside the map, so where
    # the floor meets the wall at a grazing angle the slope-scaled polygon offset can push
    # a texel's depth to 1 (white: lit, as a texel with nothing drawn).
    assert depth.min() == 0 and depth[depth < 255].max() == 204
    assert (depth == 255).sum() <= 4
    # t upward: the saved image is the GL map (row 0 = t = 0) upside down.
    stored = frame.shadow_maps[0][0][::-1].ravel()
    assert np.corrcoef(depth.ravel(), stored)[0, 1] > 0.999
    cube_png = tmp_path / "cube.png"
    demo_frames("--method", "omni", "--map-size", "32", "--shadow-map-output", str(cube_png))
    assert _png(cube_png).shape == (32, 6 * 32)


def test_demo_draws_the_depth_method_with_webgpu(demo_frames, wgpu_device, monkeypatch, tmp_path):
    import shadowmath.render.webgpu

    frames: list = []
    render = shadowmath.render.webgpu.render_depth_wgpu

    def recording(*args, **kwargs):
        frames.append(render(*args, **kwargs))
        return frames[-1]

    monkeypatch.setattr(shadowmath.render.webgpu, "render_depth_wgpu", recording)
    opengl, _ = demo_frames("--method", "depth", "--pcf", "1")
    map_png = tmp_path / "wgpu_map.png"
    _, said = demo_frames(
        "--method", "depth", "--pcf", "1", "--api", "webgpu", "--shadow-map-output", str(map_png)
    )
    assert "drawn with WebGPU on" in said
    (webgpu,) = frames
    # The two APIs shadow the same pixels (measured identical).
    assert (webgpu.body == opengl.body).mean() > 0.99
    assert np.abs(webgpu.shadow - opengl.shadow[..., 0]).mean() < 0.01
    assert _png(map_png).shape == (128, 128)


def test_pcss_penumbra_grows_with_the_light_size(demo_frames):
    """--method pcss: the hard shadow's place (its darker half where the depth method's
    shadow is), a penumbra that widens with --light-size, none at size 0."""
    hard, _ = demo_frames("--method", "depth")
    pcss, said = demo_frames("--method", "pcss")
    assert "percentage-closer soft shadows of radius 0.25" in said and "depth bias 0 1" in said
    assert DEFAULT_PCSS_BIAS == PCSS_POLYGON_OFFSET  # the demo's default is the renderer's
    assert _agreement(_shadowed(hard), _shadowed(pcss)) > 0.85
    none, _ = demo_frames("--method", "pcss", "--light-size", "0")
    small, _ = demo_frames("--method", "pcss", "--light-size", "0.1")
    big, _ = demo_frames("--method", "pcss", "--light-size", "0.6")
    widths = [_penumbra(f).sum() for f in (none, small, pcss, big)]
    assert widths[0] == 0 and widths[1] < widths[2] < widths[3], widths
    sun, said = demo_frames("--method", "pcss", "--directional", "-1", "2", "1.5")
    assert "angular radius 1 degrees" in said and "orthographic" in said
    wide, _ = demo_frames(
        "--method", "pcss", "--directional", "-1", "2", "1.5", "--light-size", "4"
    )
    assert 0 < _penumbra(sun).sum() < _penumbra(wide).sum()
