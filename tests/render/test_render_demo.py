"""The main job (python -m shadowmath), render_scene's argument checks, and import isolation."""

from __future__ import annotations

import subprocess
import sys

import numpy as np
import pytest

from shadowmath.__main__ import main
from shadowmath.meshes import box, grid
from shadowmath.render import Body, Light, render_scene


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
