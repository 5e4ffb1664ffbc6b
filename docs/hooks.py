"""mkdocs hooks: the API reference stays complete, and MathJax is served with the site.

Every name in ``shadowmath.__all__`` (and ``shadowmath.render.__all__`` once that
subpackage exists) gets an entry on ``api.md``: names the page does not place in a
section yet are appended under "Not yet sorted", so a new public function is
documented from the moment it is exported.

The formulas are typeset by MathJax 3 from the site itself, so they render
offline: the build copies MathJax's browser files from the pinned
``django-static-mathjax`` package of the ``docs`` extra (it vendors the MathJax
distribution and needs no Django) to ``javascripts/mathjax/``. Nothing of
MathJax is committed, and no page loads anything from another host.
"""

from __future__ import annotations

import importlib
import importlib.metadata
import importlib.resources
import re
from pathlib import Path
from typing import Any

_PACKAGES = ("shadowmath", "shadowmath.render")

MATHJAX_DIST = "django-static-mathjax"
MATHJAX_VERSION = "3.2.2.1"  # as pinned in pyproject.toml's docs extra
MATHJAX_DEST = "javascripts/mathjax"
# What tex-mml-chtml.js loads on demand, relative to it: TeX extensions (autoload),
# the CommonHTML fonts, the menu, the accessibility explorer and its speech rules.
_MATHJAX_PARTS = ("tex-mml-chtml.js", "input", "output/chtml", "ui", "a11y", "sre")


def mathjax_files() -> dict[str, Path]:
    """The site paths of MathJax's files and where the installed package holds them.

    Raises:
        RuntimeError: the package is missing or not the pinned version.
    """
    try:
        version = importlib.metadata.version(MATHJAX_DIST)
    except importlib.metadata.PackageNotFoundError:
        raise RuntimeError(
            f"the docs serve MathJax from the {MATHJAX_DIST} package, which is not "
            "installed: pip install -e '.[docs]'"
        ) from None
    if version != MATHJAX_VERSION:
        raise RuntimeError(
            f"{MATHJAX_DIST} {version} is installed, the docs pin {MATHJAX_VERSION}: "
            "pip install -e '.[docs]'"
        )
    package = Path(str(importlib.resources.files("mathjax"))) / "static" / "mathjax"
    es5 = package / "es5"
    files = {f"{MATHJAX_DEST}/LICENSE": package / "LICENSE"}
    for part in _MATHJAX_PARTS:
        source = es5 / part
        found = [source] if source.is_file() else sorted(source.rglob("*"))
        for path in found:
            if path.is_file():
                files[f"{MATHJAX_DEST}/{path.relative_to(es5).as_posix()}"] = path
    return files


def on_files(files: Any, *, config: Any) -> Any:
    from mkdocs.structure.files import File

    for uri, path in mathjax_files().items():
        files.append(File.generated(config, uri, abs_src_path=str(path)))
    return files


def _exported() -> list[str]:
    names: list[str] = []
    for package in _PACKAGES:
        try:
            module = importlib.import_module(package)
        except ImportError:  # an optional subpackage that is absent or lacks its extra
            continue
        names += [f"{package}.{name}" for name in getattr(module, "__all__", ())]
    return names


def on_page_markdown(markdown: str, *, page: Any, **kwargs: Any) -> str:
    if page.file.src_uri != "api.md":
        return markdown
    placed = set(re.findall(r"^::: ([\w.]+)", markdown, flags=re.MULTILINE))
    missing = [name for name in _exported() if name not in placed]
    if not missing:
        return markdown
    entries = "\n\n".join(f"::: {name}" for name in missing)
    return f"{markdown}\n\n## Not yet sorted\n\n{entries}\n"
