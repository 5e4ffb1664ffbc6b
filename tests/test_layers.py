"""The package's layers, read from every module's imports (lazy ones included).

Bottom to top: ``_boundary`` (argument checks) -> ``_math`` and ``_scene`` (trusted
cores) ->
``_backends`` (the compiled loops) -> ``_geometry`` (the public functions of the geometry,
each at its door, with the public modules ``lights``, ``receivers``, ``meshes``, ``gather``
and ``groundtruth``) -> ``_fits`` (with the public ``scene``) -> ``shadowmath`` (the
re-exports) -> ``render`` and ``integrations`` -> ``cli`` -> ``__main__``. A module
imports its own layer or lower ones, never a higher one; the clients on top import
public names only; the cores take types and constants from the boundary, never its
checks. Inside ``_fits`` each fit is a package of the parts listed in :data:`FITS`, the
shared modules beside them, and the packages have layers of their own
(:data:`FIT_LAYERS`). ``docs/architecture.md`` draws the picture.
"""

from __future__ import annotations

import ast
import re
from pathlib import Path
from typing import NamedTuple

from .test_layout import ROOT, _module

LAYERS: tuple[tuple[str, ...], ...] = (
    ("_boundary",),
    ("_math", "_scene"),
    ("_backends",),
    ("_geometry", "lights", "receivers", "meshes", "gather", "groundtruth"),
    ("_fits", "scene"),
    ("",),  # shadowmath/__init__.py
    ("render", "integrations"),
    ("cli",),
    ("__main__",),
)
CLIENTS = ("render", "integrations", "cli", "__main__")
#: What a core may take from the boundary besides UPPER_CASE constants: types.
#: What a core may take from the boundary: types (the annotation types of
#: _boundary/_shapes.py included: shapes in signatures), and the warning of a renamed
#: field of a public type that a core defines (``Frustum``'s and ``OrthographicBox``'s).
BOUNDARY_TYPES = {"Array", "Context", "ArrayLike", "Bool", "Float", "Int", "IntLike", "Integer"}
BOUNDARY_TYPES |= {"MapSize", "Real", "warn_renamed", "Row", "Scalar", "Truth"}
BOUNDARY_TYPES |= {"Options", "Status", "Vertices"}

#: Each fit's package under ``shadowmath/_fits/``: its modules and what each is.
FITS: dict[str, dict[str, str]] = {
    "shadow": {
        "_door": "fit_shadow's door: the arguments converted and checked once",
        "_driver": "fit_shadow: door -> the driver's form that suits the input -> result",
        "_arrays": "the driver on whole arrays (NumPy, JAX)",
        "_compiled": "the driver through the compiled loop (NumPy with Numba)",
        "_result": "ShadowSetup, what the fit returns",
        "_spot_select": "a spot light's casters, selected at the door",
        "_prepared": "ShadowFitter: the door opened once, the driver every frame",
        "_optimize_frustum": "optimize_frustum, and fit_shadow(method='optimized')",
    },
    "cascades": {
        "_door": "fit_cascades: the arguments read and checked once, the driver's form chosen",
        "_driver": "fit_cascades' driver in its two forms (compiled loop, whole arrays)",
        "_result": "Cascades and CascadeState, what the fit returns",
        "_splits": "cascade_splits",
        "_lispsm": "the LiSPSM warp (warp='lispsm')",
        "_orientation": "the fitted orientation (orientation='fitted')",
    },
    "atlas": {
        "_allocate": "allocate_atlas: the tiles' sizes and places (ShadowAtlas)",
        "_door": "fit_atlas: the lights, casters and options read and checked once",
        "_driver": "fit_atlas' driver: the 2D groups and the cube lights, tiles gathered",
        "_result": "AtlasFit, what the fit returns",
        "_lights": "the atlas's lights read into kinds and rows",
        "_fit_2d": "the 2D lights' driver, one group at a time",
        "_fit_cubes": "the cube lights' driver, six faces each",
        "_report": "what is reported per light; the tiles gathered in order",
        "_viewports": "atlas_viewports, atlas_tile_transforms",
        "_redraw": "atlas_redraw",
    },
    "cube": {
        "_door": "cube_depth_range: the casters and receivers read, converted and checked",
        "_driver": "cube_depth_core on trusted arrays (also the atlas's cube lights)",
        "_result": "CubeDepthRange, what the fit returns",
    },
    "pcss": {
        "_door": "pcss_parameters and pcss_widths: their doors",
        "_driver": "pcss_parameters' driver: Python floats or compiled, and whole arrays",
        "_result": "PcssParameters, PcssWidths: what the functions return",
        "_maps": "each fit's maps as the PCSS formulas read them",
        "_room": "pcss_border_texels, widen_cascades",
    },
    "camera": {"_shadow_camera": "shadow_camera of any fit, camera_to_world"},
}
#: The pieces the fits share, once, beside the packages (top-level modules of ``_fits``).
FITS_SHARED = ("_spec", "_light_kinds", "_backend")
#: Inside ``_fits``, bottom to top: the shared modules, then the fits that build on others.
FIT_LAYERS: tuple[tuple[str, ...], ...] = (
    FITS_SHARED,
    ("shadow",),
    ("cascades", "cube"),
    ("atlas",),
    ("pcss", "camera"),
)


class Import(NamedTuple):
    importer: str  # "shadowmath._math._frame"
    module: str  # "shadowmath._boundary._validate"
    names: tuple[str, ...]  # ("Array",); () for ``import module``


def _part(module: str) -> str:
    """The package's top part a module belongs to: ``"_math"``, ``"render"``, ``""``."""
    parts = module.split(".")
    return parts[1] if len(parts) > 1 else ""


def layer(module: str) -> int:
    part = _part(module)
    return next(i for i, parts in enumerate(LAYERS) if part in parts)


def _imports(path: Path, name: str) -> list[Import]:
    package = name if path.name == "__init__.py" else name.rpartition(".")[0]
    found: list[Import] = []
    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
        if isinstance(node, ast.ImportFrom):
            base = node.module or ""
            if node.level:
                parts = package.split(".")[: len(package.split(".")) - node.level + 1]
                base = ".".join([*parts, base] if base else parts)
            found.append(Import(name, base, tuple(a.name for a in node.names)))
        elif isinstance(node, ast.Import):
            found += [Import(name, a.name, ()) for a in node.names]
    return [i for i in found if i.module.split(".")[0] == "shadowmath"]


def package_imports() -> list[Import]:
    return [i for p in sorted(ROOT.rglob("*.py")) for i in _imports(p, _module(p))]


def upward(imports: list[Import]) -> list[Import]:
    """Imports of a module from a higher layer than the importer's."""
    return [i for i in imports if layer(i.module) > layer(i.importer)]


def private_to_clients(imports: list[Import]) -> list[Import]:
    """A client's imports of another part's private module or name (leading underscore)."""
    return [
        i
        for i in imports
        if _part(i.importer) in CLIENTS
        and _part(i.module) != _part(i.importer)
        and any(p.startswith("_") for p in (*i.module.split(".")[1:], *i.names))
    ]


def checks_in_cores(imports: list[Import]) -> list[Import]:
    """A core's imports from the boundary of anything but its types and constants."""
    return [
        i
        for i in imports
        if _part(i.importer) == "_math"
        and _part(i.module) == "_boundary"
        and any(n not in BOUNDARY_TYPES and not n.isupper() for n in i.names or ("*",))
    ]


def test_every_module_has_a_layer_and_the_imports_are_read() -> None:
    imports = package_imports()
    for module in {i.importer for i in imports} | {i.module for i in imports}:
        layer(module)  # StopIteration: a new top-level part needs its place in LAYERS
    assert Import(
        "shadowmath._geometry._planar_projection", "shadowmath._backends", ("_kernels",)
    ) in imports  # fmt: skip


def test_no_layer_imports_a_higher_one() -> None:
    assert upward(package_imports()) == []


def fit_layer(module: str) -> int:
    """The layer inside ``_fits`` of ``shadowmath._fits.NAME...``."""
    part = module.split(".")[2]
    return next(i for i, parts in enumerate(FIT_LAYERS) if part in parts)


def upward_in_fits(imports: list[Import]) -> list[Import]:
    """Imports inside ``_fits`` of a package or module from a higher fit layer."""
    inside = [
        i for i in imports if all(m.startswith("shadowmath._fits.") for m in (i.importer, i.module))
    ]
    return [i for i in inside if fit_layer(i.module) > fit_layer(i.importer)]


def test_each_fit_is_a_package_of_the_parts_listed() -> None:
    fits = ROOT / "_fits"
    packages = {p.name for p in fits.iterdir() if (p / "__init__.py").is_file()}
    assert packages == set(FITS)
    for name, parts in FITS.items():
        modules = {p.stem for p in (fits / name).glob("*.py") if p.name != "__init__.py"}
        assert modules == set(parts), name
    shared = {p.stem for p in fits.glob("*.py") if p.name != "__init__.py"}
    assert shared == set(FITS_SHARED)
    for fit in ("shadow", "cascades", "atlas", "cube", "pcss"):  # each shows its parts
        assert {"_door", "_driver", "_result"} <= set(FITS[fit]), fit


def test_no_fit_imports_a_higher_one() -> None:
    imports = package_imports()
    for module in {i.importer for i in imports} | {i.module for i in imports}:
        if module.startswith("shadowmath._fits."):
            fit_layer(module)  # StopIteration: a new package or module needs its FIT_LAYERS place
    assert upward_in_fits(imports) == []


def test_render_cli_and_integrations_import_public_names_only() -> None:
    assert private_to_clients(package_imports()) == []


def test_the_cores_take_types_and_constants_from_the_boundary_not_its_checks() -> None:
    assert checks_in_cores(package_imports()) == []


def test_the_rules_find_what_they_forbid() -> None:
    """Each rule flags a planted violation (and leaves its allowed neighbour alone)."""
    core_to_backend = Import("shadowmath._math._planar", "shadowmath._backends", ("_kernels",))
    door_to_backend = Import("shadowmath._geometry._planar_projection", "shadowmath._backends", ())
    boundary_to_core = Import("shadowmath._boundary._x", "shadowmath._math._frame", ("f",))
    assert upward([core_to_backend, door_to_backend, boundary_to_core]) == [
        core_to_backend,
        boundary_to_core,
    ]
    private = Import("shadowmath.render._context", "shadowmath._boundary._projection", ("f",))
    name = Import("shadowmath.cli._run", "shadowmath.render", ("_context",))
    public = Import("shadowmath.cli._run", "shadowmath", ("fit_shadow", "meshes"))
    own = Import("shadowmath.render._pass_lit", "shadowmath.render._context", ("program",))
    assert private_to_clients([private, name, public, own]) == [private, name]
    check = Import(
        "shadowmath._math._frame", "shadowmath._boundary._validate", ("Array", "convert")
    )
    types = Import("shadowmath._math._loops", "shadowmath._boundary._status", ("LIGHT", "Array"))
    module = Import("shadowmath._math._planar", "shadowmath._boundary", ("_status",))
    assert checks_in_cores([check, types, module]) == [check, module]
    shadow_to_atlas = Import("shadowmath._fits.shadow._door", "shadowmath._fits.atlas._door", ())
    atlas_to_shadow = Import("shadowmath._fits.atlas._door", "shadowmath._fits.shadow._door", ())
    spec_to_cube = Import("shadowmath._fits._spec", "shadowmath._fits.cube", ("_driver",))
    assert upward_in_fits([shadow_to_atlas, atlas_to_shadow, spec_to_cube]) == [
        shadow_to_atlas,
        spec_to_cube,
    ]


def test_the_architecture_page_names_only_files_that_exist() -> None:
    """Every ``*.py`` path ``docs/architecture.md`` names (from the package's root or
    shortened to its last parts, e.g. ``cascades/_lispsm.py``) is a module of the package:
    a move or split that leaves the page behind fails here (tests' files count too)."""
    repo = ROOT.parent
    page = (repo / "docs" / "architecture.md").read_text()
    files = ["/" + p.relative_to(repo).as_posix() for d in ("shadowmath", "tests")
             for p in (repo / d).rglob("*.py")]  # fmt: skip
    named = set(re.findall(r"`([\w/]+\.py)\b", page))
    assert named, "the page names no files"
    missing = sorted(n for n in named if not any(f.endswith("/" + n) for f in files))
    assert missing == []
