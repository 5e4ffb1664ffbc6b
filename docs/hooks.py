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

The notebooks of ``notebooks/`` are pages too, executed by mkdocs-jupyter on every
build (``execute: true`` in mkdocs.yml): they stay where Jupyter users find them and
join the build as ``notebooks/<name>.ipynb``, so the nav names them by that path.
"""

from __future__ import annotations

import importlib
import importlib.metadata
import importlib.resources
import re
from collections.abc import Callable
from pathlib import Path
from typing import Any

from mkdocs.exceptions import PluginError
from mkdocs.plugins import event_priority

_PACKAGES = ("shadowmath", "shadowmath.render")

ROOT = Path(__file__).resolve().parents[1]
NOTEBOOKS = "notebooks"  # both the folder in the repository and the pages' folder on the site

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


def notebook_files() -> dict[str, Path]:
    """The site paths of the notebooks (``notebooks/<name>.ipynb``) and their sources."""
    return {f"{NOTEBOOKS}/{path.name}": path for path in sorted((ROOT / NOTEBOOKS).glob("*.ipynb"))}


# Before the plugins' on_files (priority 0): mkdocs-jupyter turns the notebooks into pages there.
@event_priority(50)
def on_files(files: Any, *, config: Any) -> Any:
    from mkdocs.structure.files import File

    for uri, path in mathjax_files().items():
        files.append(File.generated(config, uri, abs_src_path=str(path)))
    # Source files read from the repository root rather than docs/ (mkdocs-jupyter needs a
    # file with a source folder; it cannot read a generated one).
    for uri in notebook_files():
        files.append(File(uri, str(ROOT), config.site_dir, config.use_directory_urls))
    return files


def on_serve(server: Any, *, config: Any, builder: Any) -> Any:
    """``mkdocs serve`` rebuilds when a notebook changes, as for a page under docs/."""
    server.watch(str(ROOT / NOTEBOOKS))
    return server


# nbconvert's page head loads MathJax 2 (from an empty URL here) and Mermaid from a CDN: the
# site has its own MathJax and no diagrams, and loads nothing from another host.
_NB_SCRIPT = re.compile(r"<script\b[^>]*>.*?</script>", re.DOTALL)
_NB_MARKDOWN = re.compile(
    r'(<div class="jp-RenderedHTMLCommon jp-RenderedMarkdown jp-MarkdownOutput"[^>]*>)'
    r"(.*?)(</div>)",
    re.DOTALL,
)
_NB_CODE = re.compile(r"(<code>.*?</code>)", re.DOTALL)
# A notebook links a docs page by its path from notebooks/, which Jupyter opens: ../docs/x.md#a
_NB_DOCS_LINK = re.compile(r'href="\.\./docs/([^"#]+\.md)(#[^"]*)?"')


def _foreign_script(script: str) -> bool:
    return 'src=""' in script or "text/x-mathjax-config" in script or "https://" in script


def _arithmatex(html: str) -> str:
    """A markdown cell's ``$...$`` and ``$$...$$`` as the spans pymdownx.arithmatex writes."""
    html = re.sub(
        r"<p>\$\$(.+?)\$\$</p>", r'<div class="arithmatex">\\[\1\\]</div>', html, flags=re.DOTALL
    )
    html = re.sub(
        r"\$\$(.+?)\$\$", r'<span class="arithmatex">\\[\1\\]</span>', html, flags=re.DOTALL
    )
    return re.sub(r"(?<!\\)\$([^$]+?)(?<!\\)\$", r'<span class="arithmatex">\\(\1\\)</span>', html)


def notebook_html(html: str, page_url: Callable[[str], str]) -> str:
    """A notebook page's HTML from mkdocs-jupyter, made a page of this site.

    The site's MathJax typesets the markdown cells' math, nbconvert's CDN scripts are
    dropped, and links to ``../docs/<page>.md`` lead to the page on the site
    (``page_url`` gives its URL relative to the notebook's page).
    """
    html = _NB_SCRIPT.sub(lambda m: "" if _foreign_script(m.group()) else m.group(), html)

    def cell(match: re.Match[str]) -> str:
        head, body, tail = match.groups()
        parts = _NB_CODE.split(body)  # odd items are code spans: their dollars stay
        body = "".join(part if k % 2 else _arithmatex(part) for k, part in enumerate(parts))
        body = _NB_DOCS_LINK.sub(lambda m: f'href="{page_url(m[1])}{m[2] or ""}"', body)
        return head + body + tail

    return _NB_MARKDOWN.sub(cell, html)


def on_page_content(html: str, *, page: Any, files: Any, **kwargs: Any) -> str:
    if page.file.src_uri not in notebook_files():
        return html

    def page_url(src_uri: str) -> str:
        target = files.get_file_from_path(src_uri)
        if target is None or not target.is_documentation_page():
            raise PluginError(f"{page.file.src_uri} links to docs/{src_uri}: no such page")
        return str(target.url_relative_to(page.file))

    return notebook_html(html, page_url)


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
