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
        ("--depth-bias", "(default: 2.5+2K 4, K the --pcf radius; pcss: 0 1)"),
        ("--area-light", "(default: 1 1 with those methods)"),
        ("--samples", "(default: 16)"),
        ("--seed", "(default: 0)"),
        ("--api", "(default: opengl)"),
        ("--directional", "(default: the point light)"),
        ("--cascade-colors", "(default: not written)"),
        ("--light-size", "(default: 0.25, a sun 1 degree; cascades: 0, hard shadows)"),
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
        (["--method", "soft", "--light-size", "1"], "--light-size 1: --method soft does not"),
        (["--light-size", "1"], "--light-size 1: --method texture does not read it"),
        (
            ["--method", "cascades", "--light-size", "95"],
            "--light-size 95: a sun's angular radius in degrees must be below 90",
        ),
        (["--method", "pcss", "--light-size", "-1"], "argument --light-size: expected a number"),
        (
            ["--method", "pcss", "--directional", "1", "1", "1", "--light-size", "90"],
            "--light-size 90: a sun's angular radius in degrees must be below 90",
        ),
        (["--method", "pcss", "--pcf", "1"], "--pcf 1: --method pcss compares no depths"),
        (["--method", "depth", "--seed", "3"], "--seed 3: --method depth"),
        (
            ["--method", "soft", "--area-light", "0", "1"],
            "argument --area-light: expected a number > 0",
        ),
        (
            ["--method", "soft", "--samples", "0"],
            "argument --samples: expected an integer from 1 to 65536",
        ),
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


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (
            ["--method", "depth", "--pcf", "50", "--map-size", "64"],
            "--pcf 50 with --map-size 64: a PCF radius of 50 keeps 50 empty texels on each "
            "side of the depth map (max(1, K), so that no 101x101 kernel reads past the "
            "silhouette), which leaves no texel inside a 64x64 map; use --map-size 101 or "
            "more, or --pcf 31 or less",
        ),
        (
            ["--method", "depth", "--pcf", "2", "--map-size", "4"],
            "--pcf 2 with --map-size 4: a PCF radius of 2 keeps 2 empty texels on each side "
            "of the depth map (max(1, K), so that no 5x5 kernel reads past the silhouette), "
            "which leaves no texel inside a 4x4 map; use --map-size 5 or more, or --pcf 1 or "
            "less",
        ),
        (
            ["--method", "soft", "--pcf", "4", "--map-size", "8x64"],
            "--pcf 4 with --map-size 8x64: a PCF radius of 4 keeps 4 empty texels",
        ),
        (
            ["--method", "depth", "--pcf", "128"],
            "--pcf 128 with --map-size 256 (the default): a PCF radius of 128 keeps 128",
        ),
        (
            [
                "--method",
                "depth",
                "--directional",
                "0",
                "1",
                "1",
                "--pcf",
                "10",
                "--map-size",
                "20",
            ],
            "--pcf 10 with --map-size 20:",
        ),
        (
            ["--method", "depth", "--api", "webgpu", "--pcf", "10", "--map-size", "20"],
            "--pcf 10 with --map-size 20:",
        ),
    ],
)
def test_map_too_small_for_the_pcf_border_names_both_options(capsys, tmp_path, args, message):
    # The renderer's depth map keeps max(1, K) empty texels on each side (pcf_border_texels):
    # K >= 1 needs 2 K + 1 texels.
    out = tmp_path / "x.png"
    err = _error(capsys, [*SMALL, *args, "--output", str(out)])
    assert err.split(": error: ")[1].startswith(message)
    assert not out.exists()


@pytest.mark.usefixtures("gl")
def test_the_smallest_map_for_a_pcf_radius_renders(capsys, tmp_path):
    """The demo's PCF border rule is the renderer's, not a stricter one: 2 K + 1 texels draw."""
    out = tmp_path / "x.png"
    # A directional light: a point light's frustum through a 1-texel centre is very wide.
    sun = ["--method", "depth", "--directional", "-1", "2", "1.5"]
    assert main([*SMALL, *sun, "--pcf", "2", "--map-size", "5", "--output", str(out)]) == 0
    assert "PCF radius 2" in capsys.readouterr().out


def _too_far(capsys, tmp_path, args):
    return _error(capsys, [*args, "--output", str(tmp_path / "x.png")]).split(": error: ")[1]


@pytest.mark.parametrize("method", ["texture", "depth"])
def test_a_point_light_too_far_for_the_blocker_silhouette(capsys, tmp_path, method):
    err = _too_far(capsys, tmp_path, ["--method", method, "--light", "1e17", "1", "1"])
    assert err.startswith(
        "--light 1e+17 1 1: too far for a point light of this scene: this light is 1e+17 from "
        "the blocker's centre (0.00, 1.60, 2.20), beyond about "
    )
    assert (
        "where the blocker's silhouette (bounding radius 1.35, 1.4e-17 of the distance) falls "
        f"below rounding and --method {method} cannot fit a shadow map to it; bring the light "
        "within "
    ) in err
    assert err.endswith(
        "of the blocker, or for a light that far use a directional one (--directional X Y Z, "
        "the direction toward the light, with --method planar or depth)"
    )
    assert "among the blocker's vertices" not in err


def test_the_silhouette_limit_is_where_the_fit_stops():
    """The limit the message gives is the library's: a map fits just inside it, not beyond."""
    import shadowmath as sm
    from shadowmath.cli._build import blocker_sphere, check_light_and_mesh, farthest_fit
    from shadowmath.cli._options import build_parser, resolve_options

    options = resolve_options(build_parser().parse_args(["--light", "1e17", "1", "1"]))
    geometry = check_light_and_mesh(options)
    limit = farthest_fit(geometry, options.light, options.map_size)
    assert limit is not None
    assert 1e13 < limit < 1e14
    centre, _ = blocker_sphere(geometry)
    aim = (options.light - centre) / np.linalg.norm(options.light - centre)
    vertices, placed = geometry.mesh.vertices, geometry.to_world
    sm.fit_shadow(centre + 0.99 * limit * aim, vertices, 256, blocker_to_world=placed)
    with pytest.raises(ValueError, match="silhouette"):
        sm.fit_shadow(centre + 1.01 * limit * aim, vertices, 256, blocker_to_world=placed)


def test_an_area_light_too_far_for_soft_shadows(capsys, tmp_path):
    err = _too_far(capsys, tmp_path, ["--method", "soft", "--light", "1e17", "1", "1"])
    assert err.startswith(
        "--light 1e+17 1 1: too far for an area light of this scene: the light sample at "
        "(1e+17, 0.57, 1.34) (around --light 1e+17 1 1) is 1e+17 from the blocker's centre"
    )
    assert "--directional X Y Z" in err


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (
            ["--method", "planar", "--light", "1e20", "1", "1"],
            "--light 1e+20 1 1: too far for a point light of this scene: 1e+20 from the "
            "origin, beyond 2.81e+14, where its height above the wall (z = 1) falls below the "
            "rounding of its coordinates (3.6e-15 of the distance) and Blinn's projection onto "
            "the wall (drawn by --method planar, printed by every method) cannot tell the "
            "light from the wall's plane; bring the light within 2.81e+14 of the origin, or "
            "for a light that far use a directional one (--directional X Y Z, the direction "
            "toward the light, with --method planar or depth)",
        ),
        (
            ["--method", "omni", "--light", "1e17", "3", "1"],
            "--light 1e+17 3 1: too far for a point light of this scene: 1e+17 from the "
            "origin, beyond 2.81e+14, where its height above the wall (z = 1)",
        ),
        (
            ["--method", "texture", "--light", "1e12", "1e-3", "1"],
            "--light 1e+12 0.001 1: too far for a point light of this scene: 1e+12 from the "
            "origin, beyond 2.81e+11, where its height above the floor (y = 0.001)",
        ),
        (
            ["--method", "planar", "--light", "1", "1e-300", "1"],
            "--light 1 1e-300 1: y = 1e-300 puts the light within rounding of the floor (the "
            "plane y = 0): 1.41 from the origin, its height must exceed 5.02e-15 (3.6e-15 of "
            "the distance) for Blinn's projection onto the floor (drawn by --method planar, "
            "printed by every method); move the light away from the floor",
        ),
    ],
)
def test_a_point_light_too_far_or_too_close_for_blinns_projection(capsys, tmp_path, args, message):
    assert _too_far(capsys, tmp_path, args).startswith(message)


def test_the_planar_limit_is_planar_projections():
    """The demo's threshold is planar_projection's: a light just inside it projects."""
    import shadowmath as sm
    from shadowmath.cli._build import PLANAR_ROUNDING

    limit = 1.0 / PLANAR_ROUNDING  # the distance at which a height of 1 is rounding
    sm.planar_projection([0.0, 1.0, 0.0, 0.0], [0.99 * limit, 1.0, 1.0, 1.0])
    with pytest.raises(ValueError, match="light lies in the plane"):
        sm.planar_projection([0.0, 1.0, 0.0, 0.0], [1.01 * limit, 1.0, 1.0, 1.0])


def test_the_radiance_limit_is_pyramid_to_unit_cubes():
    """The demo's threshold is pyramid_to_unit_cube's, for the demo's floor rectangle."""
    import shadowmath as sm
    from shadowmath.cli._build import PYRAMID_ROUNDING, receiver_rectangles

    corner, edge_u, edge_v = receiver_rectangles()[1]  # the floor
    edges = float(np.linalg.norm(edge_u) + np.linalg.norm(edge_v))
    for factor, ok in ((0.99, True), (1.01, False)):
        distance = factor * (1.0 / PYRAMID_ROUNDING - edges)
        apex = corner + [distance, 1.0, 0.0]
        if ok:
            sm.pyramid_to_unit_cube(apex, corner, edge_u, edge_v)
        else:
            with pytest.raises(ValueError, match="apex: lies in the base plane"):
                sm.pyramid_to_unit_cube(apex, corner, edge_u, edge_v)


def test_radiance_light_too_far_or_too_close_to_a_receiver(capsys, tmp_path):
    err = _too_far(capsys, tmp_path, ["--method", "radiance", "--light", "1e17", "1", "1"])
    assert err.startswith(
        "--light 1e+17 1 1: too far for an area light of this scene with --method radiance: "
        "its sample at (1e+17, "
    )
    assert "from the floor's corner (-5.00, 0.00, 0.00), beyond 3.5" in err
    assert "falls below the rounding of the pyramid from the sample to the floor" in err
    assert "--directional X Y Z" in err
    args = ["--method", "radiance", "--light", "1", "1e-13", "3", "--area-light", "1e-14", "1e-14"]
    err = _too_far(capsys, tmp_path, args)
    assert err.startswith(
        "--area-light 1e-14 1e-14: the light's sample at (1.00, 0.00, 3.00) lies within "
        "rounding of the floor (the plane y = 0): its height y = "
    )
    assert err.endswith("make the light smaller or move --light 1 1e-13 3 away from the floor")


@pytest.mark.parametrize(
    ("direction", "message"),
    [
        (
            ["1", "1e-20", "1"],
            "--directional 1 1e-20 1: the light shines parallel to the floor (the plane y = 0) "
            "within rounding: y = 1e-20 is at most 3.6e-15 of the direction's length 1.41, so "
            "Blinn's projection onto the floor (drawn by --method planar, printed with depth) "
            "is undefined; tilt the light away from the floor's plane, y > 5.02e-15",
        ),
        (
            ["1e300", "1e300", "1e300"],
            "--directional 1e+300 1e+300 1e+300: the direction's length 1.73e+300 is too large "
            "for floating point: the library normalizes it, and its square overflows (lengths "
            "from 1.5e-154 to 1.3e+154 work); only the direction matters, e.g. --directional "
            "0.57735 0.57735 0.57735",
        ),
        (
            ["1e-200", "1e-200", "1e-200"],
            "--directional 1e-200 1e-200 1e-200: the direction's length 1.73e-200 is too "
            "small for floating point: the library normalizes it, and its square underflows",
        ),
    ],
)
@pytest.mark.parametrize("method", ["planar", "depth"])
def test_directional_light_parallel_to_a_receiver_or_out_of_range(
    capsys, tmp_path, method, direction, message
):
    err = _too_far(capsys, tmp_path, ["--method", method, "--directional", *direction])
    assert err.startswith(message)


@pytest.mark.parametrize("size", [["1e-100", "1e-100"], ["1e-300", "1"], ["1e100", "1e100"]])
def test_area_light_sizes_beyond_floating_point(capsys, tmp_path, size):
    err = _too_far(capsys, tmp_path, ["--method", "soft", "--area-light", *size])
    assert err.startswith(f"--area-light {float(size[0]):g} {float(size[1]):g}: sizes and an area")
    assert (
        "beyond floating point's range: the library squares the edges' lengths and the area, "
        "which must lie from 1.5e-154 to 1.3e+154 for the squares to be told from zero and "
        "infinity; give W, H and W x H in that range"
    ) in err


def test_a_huge_area_light_corner_is_shown_in_three_digits(capsys, tmp_path):
    err = _too_far(capsys, tmp_path, ["--method", "soft", "--area-light", "1e50", "1e50"])
    assert err.startswith(
        "--area-light 1e+50 1e+50: the light's corner (-5.37e+49, -4.55e+49, -7.12e+48) lies "
        "on or behind the wall"
    )


@pytest.mark.parametrize("count", ["0", "65537", "100000000000000000000"])
def test_samples_beyond_the_cap(capsys, tmp_path, count):
    err = _too_far(capsys, tmp_path, ["--method", "soft", "--samples", count])
    assert err == (
        "argument --samples: expected an integer from 1 to 65536 (each sample draws the scene "
        "once more: a depth map with soft, the blocker into each receiver's texture with "
        f"radiance), got '{count}'"
    )


@pytest.mark.parametrize(
    ("args", "attribute", "value"),
    [
        (["--light", "-1e3", "1", "1"], "light", [-1000.0, 1.0, 1.0]),
        (["--directional", "-1E-2", "1", "1"], "directional", [-0.01, 1.0, 1.0]),
        (["--depth-bias", "-1e300", "-.5"], "depth_bias", [-1e300, -0.5]),
    ],
)
def test_negative_numbers_in_exponent_form_are_values(args, attribute, value):
    from shadowmath.cli._options import build_parser

    assert getattr(build_parser().parse_args(args), attribute) == value


def test_negative_infinity_is_a_value_refused_as_not_finite(capsys, tmp_path):
    err = _too_far(capsys, tmp_path, ["--light", "-inf", "1", "1"])
    assert err == "--light -inf 1 1: coordinates must be finite"


def test_a_huge_user_mesh_is_centred_and_scaled_without_overflow(tmp_path):
    from shadowmath.cli._build import blocker_mesh

    obj = tmp_path / "huge.obj"
    obj.write_text("v 1e300 0 0\nv -1e300 0 0\nv 0 1e300 0\nf 1 2 3\n")
    mesh = blocker_mesh(str(obj))
    assert np.isclose(np.linalg.norm(mesh.vertices, axis=1).max(), 1.3)


def test_output_paths_that_cannot_be_written(capsys, tmp_path):
    picture = tmp_path / "x.png"
    err = _too_far(capsys, tmp_path, ["--shadow-map-output", str(picture)])
    assert err == (
        f"--shadow-map-output {picture}: the same file as --output {picture}; the map "
        "would overwrite the picture, give another name"
    )
    (tmp_path / "file").write_text("")
    err = _error(capsys, ["--output", str(tmp_path / "file" / "x.png")])
    assert err.endswith(f"{tmp_path / 'file'} is a file, not a folder")


def test_a_failed_write_names_its_option(tmp_path):
    from shadowmath.cli._options import OptionError
    from shadowmath.cli._run import save_png

    missing = tmp_path / "gone" / "x.png"
    with pytest.raises(OptionError) as info:
        save_png("--output", missing, np.zeros((2, 2)))
    assert str(info.value) == f"--output {missing}: cannot write it (No such file or directory)"


def test_a_renderer_refusal_names_the_option_of_its_argument():
    from shadowmath.cli._options import build_parser, resolve_options
    from shadowmath.cli._run import renderer_refusal

    def refusal(args, text):
        options = resolve_options(build_parser().parse_args([*args, "--output", "x.png"]))
        return str(renderer_refusal(options, ValueError(text)))

    assert refusal(["--method", "depth", "--pcf", "2", "--map-size", "64"], "map_size: no") == (
        "--map-size 64x64 with --pcf 2: the renderer refused this scene (map_size: no)"
    )
    soft = ["--method", "soft", "--area-light", "2", "1"]
    assert refusal(soft, "lights[0]: edge_u and edge_v must be non-zero").startswith(
        "--area-light 2 1 around --light -2.2 3.6 6: the renderer refused this scene"
    )
    assert refusal([], "light: something").startswith("--light -2.2 3.6 6: the renderer refused")


def test_a_fit_that_fails_for_another_reason_names_the_mesh():
    """A flat blocker seen edge-on from outside its reach: not a distance problem."""
    from shadowmath.cli._build import Geometry, fit_in_front, placement
    from shadowmath.cli._options import OptionError, build_parser, resolve_options
    from shadowmath.meshes import Mesh

    flat = Mesh(
        np.array([[-1.0, -1, 0], [1, -1, 0], [1, 1, 0], [-1, 1, 0]]),
        np.array([[0, 1, 2], [0, 2, 3]]),
    )
    geometry = Geometry(flat, placement(np.eye(3), (0.0, 0.0, 0.0)), None)
    options = resolve_options(build_parser().parse_args(["--mesh", "flat.obj"]))
    with pytest.raises(OptionError) as info:
        fit_in_front(
            options, geometry, np.array([5.0, 0.0, 0.0]), option="--light 5 0 0", what="this light"
        )
    assert str(info.value).startswith(
        "--light 5 0 0 with --mesh flat.obj: --method texture cannot fit a shadow map to the "
        "blocker from this light (5.00 from its centre (0.00, 0.00, 0.00), whose bounding "
        "radius is 1.41): "
    )


def test_a_pcf_border_too_wide_for_the_fit_names_pcf_and_map_size(capsys, tmp_path, monkeypatch):
    """A fit refused with the max(1, K) border but made with one texel: the border is the cause."""
    import shadowmath as sm

    real = sm.fit_shadow

    def fit_shadow(*args, border_texels=1, **kwargs):
        if border_texels > 1:  # as the library refuses a frustum wider than it fits
            raise ValueError("light: the fitted frustum would be too wide")
        return real(*args, border_texels=border_texels, **kwargs)

    monkeypatch.setattr(sm, "fit_shadow", fit_shadow)
    for method in ("depth", "soft"):
        err = _too_far(capsys, tmp_path, ["--method", method, "--pcf", "5", "--map-size", "64"])
        assert err.startswith(
            "--pcf 5 with --map-size 64x64: the 5-texel border that a PCF radius of 5 keeps on "
            "each side of the depth map leaves 54x54 texels for the blocker's silhouette, too "
            "few to fit one from "
        )
        assert err.endswith(
            "(a map with a 1-texel border fits); use a larger --map-size or a smaller --pcf"
        )


def test_a_wide_fit_is_a_note_naming_the_light(capsys, tmp_path, gl):
    # The library's ShadowFitWarning (wider than 120 degrees) reaches the user as a note
    # on the option behind it, once, and the demo still runs.
    assert main(["--light", "0", "1.6", "3.4", "--output", str(tmp_path / "x.png")]) == 0
    err = capsys.readouterr().err
    assert err.count("note:") == 1
    assert "note: --light 0 1.6 3.4: the fitted frustum is wider than 120 degrees" in err


# ---- --method cascades: a sun over a large scene, seen toward the horizon ------------------


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (["--cascade-colors", "c.png"], "--cascade-colors c.png: --method texture has no cascades"),
        (["--method", "cascades", "--light", "1", "2", "3"], "--light 1 2 3: --method cascades"),
        (["--method", "cascades", "--api", "webgpu"], "--api webgpu"),
        (["--method", "cascades", "--shadow-map-output", "m.png"], "--method cascades draws"),
        (["--method", "cascades", "--samples", "4"], "--samples 4: --method cascades"),
        (
            ["--method", "cascades", "--directional", "1", "-1", "1"],
            "y = -1 puts the light on or below the ground",
        ),
    ],
)
def test_cascades_options_that_do_not_apply_are_refused(capsys, tmp_path, args, message):
    err = _error(capsys, [*args, "--output", str(tmp_path / "x.png")])
    assert message in err
    assert not (tmp_path / "x.png").exists()


def test_cascade_colors_must_differ_from_the_output(capsys, tmp_path):
    out = str(tmp_path / "x.png")
    err = _error(capsys, ["--method", "cascades", "--output", out, "--cascade-colors", out])
    assert "the same file as --output" in err


@pytest.mark.usefixtures("gl")
def test_cascades_demo_writes_the_picture_and_its_cascades(capsys, tmp_path):
    from PIL import Image

    out, colored = tmp_path / "c.png", tmp_path / "cc.png"
    args = ["--method", "cascades", "--size", "96", "64", "--map-size", "128", "--pcf", "1"]
    assert main([*args, "--output", str(out), "--cascade-colors", str(colored)]) == 0
    printed = capsys.readouterr().out
    first, second = printed.splitlines()[:2]
    assert "cascaded shadow maps (4 cascades of 128x128, PCF radius 1" in first
    assert str(colored) in second
    picture = np.asarray(Image.open(out)).astype(float)
    tinted = np.asarray(Image.open(colored)).astype(float)
    assert picture.shape == tinted.shape == (64, 96, 3)
    # the tint only multiplies: never brighter, and it changes the picture
    assert np.all(tinted <= picture + 1)
    assert np.abs(tinted - picture).max() > 20
    # the splits are printed, increasing from the camera's near plane to its far one
    block = printed.split("splits (view depths bounding the cascades) =\n")[1].splitlines()[0]
    splits = np.array(block.strip(" []").split(), dtype=float)
    assert len(splits) == 5 and np.all(np.diff(splits) > 0)
    assert splits[0] == pytest.approx(0.5) and splits[-1] == pytest.approx(250.0)
    # each cascade's clip matrix is orthographic: its last printed row is 0 0 0 1
    for i in range(4):
        part = printed.split(f"world_to_clip[{i}] (cascade {i}'s depth map) =\n")[1]
        last = part.splitlines()[3]
        assert np.allclose(np.array(last.strip(" []").split(), dtype=float), [0, 0, 0, 1])


def _recorded_keywords(monkeypatch, name):
    """The keywords the demo passes to ``shadowmath.render.<name>`` (the call still runs)."""
    import shadowmath.render

    seen = {}
    real = getattr(shadowmath.render, name)

    def recording(*args, **kwargs):
        seen.update(kwargs)
        return real(*args, **kwargs)

    monkeypatch.setattr(shadowmath.render, name, recording)
    return seen


@pytest.mark.usefixtures("gl")
def test_cascades_demo_draws_pcss_with_a_light_size(capsys, tmp_path, monkeypatch):
    """--light-size DEGREES with --method cascades: render_cascades' PCSS of that sun."""
    seen = _recorded_keywords(monkeypatch, "render_cascades")
    args = ["--method", "cascades", "--size", "64", "48", "--map-size", "128"]
    assert main([*args, "--light-size", "2", "--output", str(tmp_path / "c.png")]) == 0
    first = capsys.readouterr().out.splitlines()[0]
    assert "percentage-closer soft shadows of angular radius 2 degrees" in first
    assert seen["light_size"] == pytest.approx(np.radians(2.0))
    assert main([*args, "--output", str(tmp_path / "c.png")]) == 0
    assert seen["light_size"] == 0.0 and "percentage-closer" not in capsys.readouterr().out


# ---- --method atlas: many lights sharing one shadow atlas -----------------------------------


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (["--lights", "8"], "--lights 8: --method texture draws one light"),
        (["--method", "atlas", "--light", "1", "2", "3"], "--light 1 2 3: --method atlas places"),
        (
            ["--method", "atlas", "--directional", "1", "2", "3"],
            "--directional 1 2 3: --method atl",
        ),
        (["--method", "atlas", "--map-size", "1000"], "--map-size 1000: --method atlas's map"),
        (["--method", "atlas", "--map-size", "512x256"], "e.g. --map-size 512"),
        (["--method", "atlas", "--api", "webgpu"], "--api webgpu"),
        (["--method", "atlas", "--samples", "4"], "--samples 4: --method atlas"),
        (["--method", "atlas", "--lights", "0"], "expected an integer from 1 to 256"),
        (["--method", "atlas", "--lights", "257"], "expected an integer from 1 to 256"),
        (["--method", "atlas", "--map-size", "64", "--pcf", "20"], "--map-size 64 with --pcf 20"),
    ],
)
def test_atlas_options_that_do_not_apply_are_refused(capsys, tmp_path, args, message, request):
    if "--pcf" in args:  # refused by the renderer's allocation, after the context opens
        request.getfixturevalue("gl")
    err = _error(capsys, [*args, "--output", str(tmp_path / "x.png")])
    assert message in err
    assert not (tmp_path / "x.png").exists()


@pytest.mark.usefixtures("gl")
def test_atlas_demo_writes_the_picture_and_the_atlas(capsys, tmp_path):
    from PIL import Image

    out, atlas = tmp_path / "a.png", tmp_path / "atlas.png"
    args = ["--method", "atlas", "--lights", "18", "--size", "96", "64", "--map-size", "1024"]
    assert main([*args, "--pcf", "1", "--output", str(out), "--shadow-map-output", str(atlas)]) == 0
    printed = capsys.readouterr().out
    first, second = printed.splitlines()[:2]
    assert "under 18 lights (6 point lights with cube maps, 6 spots, 6 suns)" in first
    assert "one 1024x1024 atlas (" in first and "PCF radius 1" in first
    assert "the 1024x1024 atlas" in second
    assert np.asarray(Image.open(out)).shape == (64, 96, 3)
    picture = np.asarray(Image.open(atlas)).astype(float)
    assert picture.shape == (1024, 1024, 3)
    # every light got a tile: one table row each, a point light's six places
    rows = [line for line in printed.splitlines() if line[:5].strip().isdigit()]
    assert len(rows) == 18
    assert all(row.count("(") == (6 if "PointLight" in row else 1) for row in rows)
    # the picture shows drawn depths (dark) inside the tiles and their outlines
    assert (picture.min(axis=-1) < 100).mean() > 0.01
    assert (np.abs(picture[..., 0] - picture[..., 2]) > 100).any()  # orange outlines


@pytest.mark.usefixtures("gl")
def test_omni_demo_draws_the_hard_cube_map_shadow(tmp_path, monkeypatch):
    """--method omni does not read --light-size: render_scene gets light_size 0 (with a
    size it would draw PCSS through the cube map)."""
    seen = _recorded_keywords(monkeypatch, "render_scene")
    args = ["--method", "omni", "--size", "64", "48", "--map-size", "64"]
    assert main([*args, "--output", str(tmp_path / "o.png")]) == 0
    assert seen["method"] == "omni" and seen["light_size"] == 0.0
