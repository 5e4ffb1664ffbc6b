"""The demo's command line (``python -m shadowmath``): help, option errors, outputs.

Option errors exit with status 2 through ``argparse`` and speak of the options;
the checks that need no OpenGL run everywhere, the others use the GL fixture.
"""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from shadowmath.cli import main
from shadowmath.cli._options import BUILT_IN_MESHES
from tests.render.conftest import gl as gl  # the shared GL fixture (skips or fails)

ROOT = Path(__file__).resolve().parents[1]
SMALL = ["--size", "48", "32"]


def _error(capsys: pytest.CaptureFixture[str], args: list[str]) -> str:
    with pytest.raises(SystemExit) as exc:
        main(args)
    assert exc.value.code == 2
    err = capsys.readouterr().err
    assert err.startswith("usage: python -m shadowmath")
    return err.splitlines()[-1]


def test_help_is_plain_text_with_every_default(capsys):
    with pytest.raises(SystemExit) as exc:
        main(["--help"])
    assert exc.value.code == 0
    text = capsys.readouterr().out
    assert "``" not in text
    assert ":mod:" not in text
    assert ":func:" not in text
    options = text.split("options:\n")[1].split("\n\n")[0]
    entries: dict[str, str] = {}
    for line in options.splitlines():
        if line.startswith("  -"):
            name = line.split()[0].rstrip(",")
            entries[name] = line
        else:
            entries[name] += " " + line.strip()
    for option, default in [
        ("--mesh", "(default: torus)"),
        ("--light", "(default: -2.2 3.6 6.0)"),
        ("--map-size", "(default: 256)"),
        ("--size", "(default: 640 400)"),
        ("--method", "(default: texture)"),
        ("--output", "(default: out/shadow.png)"),
        ("--shadow-map-output", "(default: not written)"),
        ("--pcf", "(default: 0, no filtering)"),
        ("--depth-bias", "(default: 2.5+2K 4, K the --pcf radius)"),
        ("--area-light", "(default: 1 1 with those methods)"),
        ("--samples", "(default: 16)"),
        ("--seed", "(default: 0)"),
        ("--api", "(default: opengl)"),
        ("--directional", "(default: the point light)"),
    ]:
        assert default in " ".join(entries[option].split()), option


def test_unknown_mesh_lists_the_built_in_ones(capsys, tmp_path):
    err = _error(capsys, ["--mesh", "cone", "--output", str(tmp_path / "x.png")])
    assert "--mesh 'cone'" in err
    for name in BUILT_IN_MESHES:
        assert name in err


def test_non_mesh_file_is_refused_with_the_readable_types(capsys, tmp_path):
    err = _error(capsys, ["--mesh", str(ROOT / "README.md"), "--output", str(tmp_path / "x.png")])
    assert "README.md" in err
    assert ".obj" in err
    assert "Error" not in err  # no library exception name leaks through


def test_broken_obj_file_is_an_option_error(capsys, tmp_path):
    obj = tmp_path / "broken.obj"
    obj.write_text("v 0 0 zero\nf 1 2 3\n")
    err = _error(capsys, ["--mesh", str(obj), "--output", str(tmp_path / "x.png")])
    assert err.startswith(f"python -m shadowmath: error: --mesh {obj}: cannot read it as a mesh")


@pytest.mark.parametrize(
    ("light", "where"),
    [(["0", "2", "-1"], "behind the wall"), (["1", "-0.5", "4"], "below the floor")],
)
def test_light_behind_wall_or_below_floor_is_refused(capsys, tmp_path, light, where):
    for method in ("texture", "planar"):
        err = _error(
            capsys, ["--light", *light, "--method", method, "--output", str(tmp_path / "x.png")]
        )
        assert f"--light {' '.join(light)}" in err
        assert where in err


def test_light_inside_the_blocker_speaks_of_options(capsys, tmp_path):
    err = _error(capsys, ["--light", "0", "1.6", "2.2", "--output", str(tmp_path / "x.png")])
    assert "--light 0 1.6 2.2" in err
    assert "--method planar" in err
    assert "light_frame" not in err  # the library's advice is for library callers
    assert not (tmp_path / "x.png").exists()


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (["--method", "planar", "--map-size", "64"], "--map-size: --method planar"),
        (
            ["--method", "planar", "--shadow-map-output", "m.png"],
            "--shadow-map-output: --method planar",
        ),
        (["--output", "pic.jpg"], "--output pic.jpg: expected a file name ending in .png"),
        (["--size", "0", "10"], "argument --size: expected a positive integer"),
        (["--map-size", "2"], "argument --map-size"),
    ],
)
def test_option_combinations(capsys, args, message):
    assert message in _error(capsys, args)


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (["--method", "shadow-volume"], "argument --method: invalid choice"),
        (["--api", "vulkan"], "argument --api: invalid choice"),
        (["--api", "webgpu"], "--api webgpu: the demo's WebGPU renderer draws --method depth only"),
        (["--api", "webgpu", "--method", "omni"], "not --method omni"),
        (["--method", "texture", "--pcf", "1"], "--pcf 1: --method texture compares no depths"),
        (["--method", "omni", "--pcf", "1"], "--pcf 1: the omni pass samples one cube-map texel"),
        (["--method", "radiance", "--pcf", "1"], "--pcf 1: --method radiance"),
        (["--method", "depth", "--pcf", "-1"], "argument --pcf: expected an integer >= 0"),
        (["--method", "planar", "--depth-bias", "1", "2"], "--depth-bias 1 2: --method planar"),
        (["--method", "radiance", "--depth-bias", "1", "2"], "--depth-bias 1 2: --method radiance"),
        (
            ["--method", "depth", "--depth-bias", "nan", "2"],
            "argument --depth-bias: expected a finite",
        ),
        (
            ["--method", "depth", "--depth-bias", "one", "2"],
            "argument --depth-bias: expected a number",
        ),
        (["--method", "depth", "--area-light", "1", "1"], "--area-light 1 1: --method depth"),
        (["--area-light", "1", "1"], "--area-light 1 1: --method texture lights from a point"),
        (["--method", "omni", "--samples", "4"], "--samples 4: --method omni"),
        (["--method", "depth", "--seed", "3"], "--seed 3: --method depth"),
        (
            ["--method", "soft", "--area-light", "0", "1"],
            "argument --area-light: expected a number > 0",
        ),
        (["--method", "soft", "--samples", "0"], "argument --samples: expected a positive integer"),
        (["--method", "soft", "--seed", "-2"], "argument --seed: expected an integer >= 0"),
        (
            ["--method", "omni", "--map-size", "64x32"],
            "--map-size 64x32: --method omni's cube faces are square",
        ),
        (
            ["--method", "soft", "--shadow-map-output", "m.png"],
            "--shadow-map-output: --method soft",
        ),
        (
            ["--method", "radiance", "--shadow-map-output", "m.png"],
            "--shadow-map-output: --method radiance",
        ),
    ],
)
def test_options_that_do_not_apply_to_the_method_are_refused(capsys, tmp_path, args, message):
    err = _error(capsys, [*args, "--output", str(tmp_path / "x.png")])
    assert message in err
    assert not (tmp_path / "x.png").exists()


def test_area_light_must_stay_above_the_floor_and_before_the_wall(capsys, tmp_path):
    out = ["--output", str(tmp_path / "x.png")]
    # The default light is 3.6 above the floor; a 9-high light facing the torus reaches below.
    err = _error(capsys, ["--method", "soft", "--area-light", "1", "9", *out])
    assert err.split(": error: ")[1].startswith("--area-light 1 9: the light's corner")
    assert "below the floor" in err
    err = _error(
        capsys, ["--method", "radiance", "--light", "0", "3", "1", "--area-light", "1", "4", *out]
    )
    assert "--area-light 1 4" in err
    assert "behind the wall" in err


def test_area_light_edges_face_the_blocker():
    from shadowmath.cli._build import BLOCKER_CENTRE
    from shadowmath.cli._build import area_light_edges as _area_light_edges
    from shadowmath.cli._options import DEFAULT_LIGHT

    light = np.array(DEFAULT_LIGHT)
    edge_u, edge_v = _area_light_edges(light, (1.5, 0.5))
    d = np.array(BLOCKER_CENTRE) - light
    assert np.linalg.norm(edge_u) == pytest.approx(1.5)
    assert np.linalg.norm(edge_v) == pytest.approx(0.5)
    for edge in (edge_u, edge_v):
        assert edge @ d == pytest.approx(0.0, abs=1e-12)  # perpendicular to the light's aim
    assert edge_u[1] == 0.0  # W horizontal
    assert edge_v[1] > 0.0  # H upward
    # Straight above the blocker: W along x, H along -z (still perpendicular to the aim).
    edge_u, edge_v = _area_light_edges(np.array(BLOCKER_CENTRE) + [0, 3, 0], (1.0, 1.0))
    np.testing.assert_allclose(edge_u, [1, 0, 0])
    assert edge_v @ [0, 1, 0] == pytest.approx(0.0)


@pytest.mark.parametrize("method", ["depth", "soft"])
def test_light_inside_the_blocker_with_depth_maps(capsys, tmp_path, method):
    args = ["--method", method, "--light", "0", "1.6", "2.2", "--output", str(tmp_path / "x.png")]
    if method == "soft":
        args += ["--area-light", "0.2", "0.2"]
    err = _error(capsys, args)
    option = "--light 0 1.6 2.2" if method == "depth" else "--area-light 0.2 0.2"
    assert err.split(": error: ")[1].startswith(f"{option}: --method {method} needs the whole")
    assert "--method planar or omni" in err


def test_output_folder_must_exist(capsys, tmp_path):
    missing = tmp_path / "no" / "such"
    err = _error(capsys, ["--output", str(missing / "x.png")])
    assert f"the folder {missing} does not exist" in err
    err = _error(
        capsys, ["--output", str(tmp_path / "x.png"), "--shadow-map-output", str(missing / "m.png")]
    )
    assert err.split(": error: ")[1].startswith("--shadow-map-output")
    assert not (tmp_path / "no").exists()


def test_errors_from_a_subprocess_have_no_traceback(tmp_path):
    result = subprocess.run(
        [sys.executable, "-m", "shadowmath", "--mesh", "README.md"],
        cwd=ROOT,
        capture_output=True,
        text=True,
        check=False,
    )
    assert result.returncode == 2
    assert "Traceback" not in result.stderr
    assert "--mesh README.md" in result.stderr


@pytest.mark.usefixtures("gl")
def test_default_output_folder_is_created_and_reported(capsys, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    assert main(SMALL) == 0
    written = tmp_path / "out" / "shadow.png"
    assert written.is_file()
    first = capsys.readouterr().out.splitlines()[0]
    assert first.startswith(f"wrote {written}: a 48x32 PNG")
    assert "256x256 shadow map" in first


@pytest.mark.usefixtures("gl")
def test_planar_needs_no_light_frame_and_no_map(capsys, tmp_path):
    from PIL import Image

    out = tmp_path / "planar.png"
    # A light at the torus's centre: no shadow map can be fitted, Blinn's shadows need none.
    assert (
        main([*SMALL, "--method", "planar", "--light", "0", "1.6", "2.2", "--output", str(out)])
        == 0
    )
    printed = capsys.readouterr().out
    assert f"wrote {out}" in printed
    assert "shadow map" not in printed
    assert "blocker_to_clip" not in printed
    assert "planar_projection onto the wall" in printed
    assert np.asarray(Image.open(out)).shape == (32, 48, 3)


@pytest.mark.usefixtures("gl")
def test_map_size_beyond_the_driver_limit(capsys, tmp_path):
    from shadowmath.render import standalone_context

    limit = int(standalone_context().info["GL_MAX_TEXTURE_SIZE"])
    err = _error(capsys, ["--map-size", f"{limit + 1}x8", "--output", str(tmp_path / "x.png")])
    assert f"--map-size {limit + 1}x8" in err
    assert f"maximum texture size, {limit}x{limit}" in err
    err = _error(capsys, ["--size", str(limit + 1), "8", "--output", str(tmp_path / "x.png")])
    assert f"--size {limit + 1} 8" in err
    assert not (tmp_path / "x.png").exists()


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (["--method", m], f"--directional -1 2 1.5: --method {m} takes a point light")
        for m in ("texture", "omni", "soft", "radiance")
    ]
    + [
        (["--method", "depth", "--light", "1", "2", "3"], "not both"),
        (["--method", "depth", "--api", "webgpu"], "WebGPU renderer takes a point light"),
    ],
)
def test_directional_light_is_refused_where_it_does_not_apply(capsys, tmp_path, args, message):
    err = _error(
        capsys, [*args, "--directional", "-1", "2", "1.5", "--output", str(tmp_path / "x.png")]
    )
    assert message in err
    assert not (tmp_path / "x.png").exists()


@pytest.mark.parametrize(
    ("direction", "message"),
    [
        (["1", "0", "1"], "y = 0 puts the light on or behind the floor"),
        (["1", "1", "-2"], "z = -2 puts the light on or behind the wall"),
        (["1", "nan", "1"], "coordinates must be finite"),
    ],
)
def test_directional_light_must_shine_on_the_wall_and_floor(capsys, tmp_path, direction, message):
    err = _error(
        capsys,
        ["--method", "depth", "--directional", *direction, "--output", str(tmp_path / "x.png")],
    )
    assert err.split(": error: ")[1].startswith(f"--directional {' '.join(direction)}")
    assert message in err


@pytest.mark.usefixtures("gl")
def test_directional_light_with_planar_shadows(capsys, tmp_path):
    from PIL import Image

    out = tmp_path / "planar.png"
    assert (
        main(
            [*SMALL, "--method", "planar", "--directional", "-1", "2", "1.5", "--output", str(out)]
        )
        == 0
    )
    printed = capsys.readouterr().out
    first = printed.splitlines()[0]
    assert "a directional light toward (-1.0, 2.0, 1.5)" in first
    assert "Blinn's planar shadows" in first
    # the flattening matrix takes the homogeneous light (x, y, z, 0)
    from shadowmath import planar_projection

    block = printed.split("planar_projection onto the floor y = 0 =\n")[1].splitlines()[:4]
    printed_matrix = np.array([line.strip(" []").split() for line in block], dtype=float)
    expected = planar_projection((0.0, 1.0, 0.0, 0.0), (-1.0, 2.0, 1.5, 0.0))
    assert np.allclose(printed_matrix, expected)
    assert np.asarray(Image.open(out)).shape == (32, 48, 3)


@pytest.mark.usefixtures("gl")
def test_directional_light_with_a_depth_map(capsys, tmp_path):
    from PIL import Image

    out, depth = tmp_path / "depth.png", tmp_path / "map.png"
    args = ["--method", "depth", "--directional", "-1", "2", "1.5", "--map-size", "64"]
    assert (
        main([*SMALL, *args, "--pcf", "1", "--output", str(out), "--shadow-map-output", str(depth)])
        == 0
    )
    printed = capsys.readouterr().out
    first = printed.splitlines()[0]
    assert "a directional light toward (-1.0, 2.0, 1.5)" in first
    assert "depth shadow map (64x64, orthographic, PCF radius 1" in first
    assert np.asarray(Image.open(out)).shape == (32, 48, 3)
    assert np.asarray(Image.open(depth)).shape[:2] == (64, 64)
    # the light's clip matrix is affine: its last printed row is 0 0 0 1
    block = printed.split("world_to_clip of the light")[1].split("\n\n")[0]
    rows = [line for line in block.splitlines() if line.strip().startswith("[")]
    assert np.allclose(np.array(rows[3].strip(" []").split(), dtype=float), [0, 0, 0, 1])


def test_console_script_runs_the_cli():
    import tomllib

    import shadowmath.__main__
    import shadowmath.cli

    scripts = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]["scripts"]
    module, name = scripts["shadowmath"].split(":")
    assert module == "shadowmath.__main__"
    assert getattr(shadowmath.__main__, name) is shadowmath.cli.main


@pytest.mark.parametrize("text", ["2", "3", "4", "3x2", "2x3", "3x3", "0x10", "-4", "512x256"])
def test_map_size_follows_the_library_border_rule(text):
    """--map-size accepts exactly the sizes border_margin accepts with fit_shadow's border."""
    import argparse

    from shadowmath import border_margin
    from shadowmath.cli._options import MAP_BORDER_TEXELS, map_size_arg

    values = [int(v) for v in text.split("x")]
    size = values[0] if len(values) == 1 else tuple(values)
    try:
        border_margin(size, border_texels=MAP_BORDER_TEXELS)
    except ValueError:
        with pytest.raises(argparse.ArgumentTypeError, match="sizes >= 3"):
            map_size_arg(text)
    else:
        assert map_size_arg(text) == size


@pytest.mark.usefixtures("gl")
def test_map_too_small_for_the_pcf_border_is_an_option_error(capsys, tmp_path):
    # The renderer's depth map keeps 1 + K empty texels on each side: K = 1 needs 5 texels.
    out = tmp_path / "x.png"
    err = _error(
        capsys, [*SMALL, "--method", "depth", "--pcf", "1", "--map-size", "4", "--output", str(out)]
    )
    assert "4x4" in err
    assert not out.exists()
