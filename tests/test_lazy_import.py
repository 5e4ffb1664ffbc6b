"""``import shadowmath`` loads nothing: each public name imports its module on first use.

The speed figure is a benchmark (``benchmarks/speed/single.py``); these tests check the
mechanism: what a fresh process has imported, and that the lazy table in
``shadowmath/__init__.py`` and the imports mypy reads there name the same things.
"""

import ast
import json
import pathlib
import subprocess
import sys

import pytest

import shadowmath

INIT = pathlib.Path(shadowmath.__file__)


def _fresh(code: str) -> dict:
    out = subprocess.run(
        [sys.executable, "-c", code],
        capture_output=True,
        text=True,
        check=True,
        cwd=INIT.parent.parent,
    ).stdout
    return json.loads(out.strip().splitlines()[-1])


def test_import_loads_no_submodule_and_no_numpy():
    seen = _fresh(
        "import json, sys; import shadowmath; "
        "print(json.dumps(sorted(m for m in sys.modules "
        "if m.startswith(('shadowmath', 'numpy', 'jax', 'numba', 'scipy', 'jaxtyping')))))"
    )
    assert seen == ["shadowmath"]


def test_first_use_loads_the_defining_module_only():
    seen = _fresh(
        "import json, sys; import shadowmath; shadowmath.cascade_splits; "
        "print(json.dumps([m in sys.modules for m in "
        "('shadowmath._fits.cascades._splits', 'shadowmath._fits.atlas._door', 'jax', 'numba')]))"
    )
    assert seen == [True, False, False, False]


def _type_checking_imports() -> dict[str, str]:
    """``name: module`` of the ``if TYPE_CHECKING:`` block of ``shadowmath/__init__.py``."""
    tree = ast.parse(INIT.read_text())
    (block,) = (
        node
        for node in tree.body
        if isinstance(node, ast.If) and getattr(node.test, "id", None) == "TYPE_CHECKING"
    )
    names = {}
    for node in block.body:
        assert isinstance(node, ast.ImportFrom)
        for alias in node.names:
            assert alias.asname == alias.name  # `import x as x`: an explicit re-export
            names[alias.name] = "." * node.level + (node.module or "")
    return names


def test_lazy_table_matches_the_imports_mypy_reads():
    assert _type_checking_imports() == shadowmath._WHERE


def test_every_public_name_resolves_to_its_module():
    for name, module in shadowmath._WHERE.items():
        value = getattr(shadowmath, name)
        defined_in = getattr(value, "__module__", None)
        if defined_in is not None and not isinstance(value, (tuple, float, dict)):
            assert defined_in == "shadowmath" + module, name
    assert set(shadowmath.__all__) <= set(shadowmath._WHERE) | {"__version__"}
    assert set(shadowmath._WHERE) <= set(dir(shadowmath))


def test_unknown_name_is_an_attribute_error():
    with pytest.raises(AttributeError, match="has no attribute 'fit_shadows'"):
        shadowmath.fit_shadows  # noqa: B018
    with pytest.raises(ImportError):
        from shadowmath import fit_shadows  # noqa: F401


def test_render_without_moderngl_names_the_extra():
    """A missing moderngl (None in sys.modules: its import fails) is an ImportError that
    says which extra to install, not a bare ModuleNotFoundError from deep inside."""
    seen = _fresh(
        "import json, sys; sys.modules['moderngl'] = None\n"
        "try:\n"
        "    import shadowmath.render\n"
        "except ImportError as err:\n"
        "    print(json.dumps([type(err).__name__, str(err), type(err.__cause__).__name__]))\n"
    )
    kind, message, cause = seen
    assert kind == "ImportError" and cause == "ModuleNotFoundError"
    assert message.startswith("shadowmath.render needs moderngl")
    assert "pip install 'shadowmath[render]'" in message
