"""The docs read completely as raw Markdown, and list everything they claim to list.

A code host shows ``docs/*.md`` raw: include lines (pymdownx.snippets' ``--8<--``)
show as themselves there, so the renderer guide and the cascades page carry the
shaders' text inline, and this test keeps each copy equal to its file.
"""

from __future__ import annotations

import base64
import importlib.util
import json
import re
import sys
from pathlib import Path, PurePath

import pytest

ROOT = Path(__file__).resolve().parents[1]
DOCS = ROOT / "docs"
GUIDE = DOCS / "renderers.md"
# ```glsl title="shadowmath/render/shaders/x.vert"  ...  ```
TITLED = re.compile(r'^```(\w+) title="([^"]+)"\n(.*?)^```$', re.MULTILINE | re.DOTALL)


def test_renderer_guide_has_no_include_lines():
    text = GUIDE.read_text(encoding="utf-8")
    assert "--8<--" not in text


def _shader_copies(page: Path) -> dict[str, str]:
    """The page's titled code blocks of shadowmath/render/shaders/ files: path to text."""
    return {
        path: body
        for _, path, body in TITLED.findall(page.read_text(encoding="utf-8"))
        if path.startswith("shadowmath/render/shaders/")
    }


def test_cascades_page_shows_both_tested_shaders_as_they_are():
    """The cascades page carries the complete camera passes that tests/render/
    test_render_cascades.py draws with (GLSL and WGSL), equal to their files."""
    shaders = _shader_copies(DOCS / "cascades.md")
    assert set(shaders) == {
        "shadowmath/render/shaders/cascades.frag",
        "shadowmath/render/shaders/cascades.wgsl",
    }
    for path, body in shaders.items():
        assert body == (ROOT / path).read_text(encoding="utf-8"), path
    assert "--8<--" not in (DOCS / "cascades.md").read_text(encoding="utf-8")


def test_renderer_guide_shaders_equal_the_shader_files():
    shaders = _shader_copies(GUIDE)
    # The shaders of the passes the guide walks through (the lit pass only shades).
    passes = {
        f"shadowmath/render/shaders/{name}"
        for name in (
            "shadow_map.vert", "shadow_map.frag", "surface.vert", "receiver_mask.frag",
            "receiver_subtract.frag", "planar.vert", "planar_mask.frag",
        )
    }  # fmt: skip
    assert passes <= set(shaders)
    for path, body in shaders.items():
        assert body == (ROOT / path).read_text(encoding="utf-8"), path


@pytest.mark.parametrize("page", ["index.md", "getting-started.md"])
def test_pages_list_every_notebook(page):
    text = (DOCS / page).read_text(encoding="utf-8")
    notebooks = sorted(p.name for p in (ROOT / "notebooks").glob("*.ipynb"))
    assert len(notebooks) >= 3
    for name in notebooks:
        assert f"notebooks/{name}" in text, f"{page} does not list {name}"


def test_readme_lists_every_notebook():
    text = (ROOT / "README.md").read_text(encoding="utf-8")
    for path in sorted((ROOT / "notebooks").glob("*.ipynb")):
        assert f"notebooks/{path.name}" in text, path.name


def _hooks():
    spec = importlib.util.spec_from_file_location("docs_hooks", DOCS / "hooks.py")
    assert spec and spec.loader
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_site_loads_no_script_from_another_host():
    text = (ROOT / "mkdocs.yml").read_text(encoding="utf-8")
    scripts = re.search(r"^extra_javascript:\n((?:  - .*\n)+)", text, re.MULTILINE)
    assert scripts
    entries = [line.removeprefix("  - ").strip() for line in scripts.group(1).splitlines()]
    provided = set(_hooks().mathjax_files())
    for entry in entries:
        assert "//" not in entry, entry
        assert (DOCS / entry).is_file() or entry in provided, entry
    assert "javascripts/mathjax/tex-mml-chtml.js" in entries


def test_mathjax_comes_from_the_pinned_package_with_its_fonts():
    files = _hooks().mathjax_files()
    assert files["javascripts/mathjax/tex-mml-chtml.js"].is_file()
    fonts = [
        uri for uri in files if uri.startswith("javascripts/mathjax/output/chtml/fonts/woff-v2/")
    ]
    assert any(uri.endswith("MathJax_Main-Regular.woff") for uri in fonts)
    assert not (DOCS / "javascripts" / "mathjax").exists()  # not committed by hand
    pin = f'"{_hooks().MATHJAX_DIST}=={_hooks().MATHJAX_VERSION}"'
    assert pin in (ROOT / "pyproject.toml").read_text(encoding="utf-8")


def _public_docstring_sections():
    """Every public object's docstring sections, as mkdocstrings gets them for api.md."""
    griffe = pytest.importorskip("griffe")
    sys.path.insert(0, str(DOCS))
    try:
        from griffe_rst import RstToMarkdown
    finally:
        sys.path.remove(str(DOCS))
    extensions = griffe.load_extensions(RstToMarkdown())
    package = griffe.load("shadowmath", extensions=extensions, search_paths=[str(ROOT)])
    import shadowmath
    import shadowmath.render

    names = [*shadowmath.__all__, *(f"render.{n}" for n in shadowmath.render.__all__)]
    for name in names:
        obj = package[name]
        if obj.docstring is not None:
            yield name, obj.docstring.parse("google")


def test_api_examples_are_code_not_headings_or_quotes():
    markdown = pytest.importorskip("markdown")
    examples = 0
    for name, sections in _public_docstring_sections():
        for section in sections:
            if section.kind.value != "admonition":
                continue
            html = markdown.markdown(
                section.value.contents, extensions=["pymdownx.superfences", "toc"]
            )
            examples += ">>>" in section.value.contents
            assert "<blockquote>" not in html, name
            assert not re.search(r"<h[1-6]", html), name
    assert examples > 20


NOTEBOOKS = sorted((ROOT / "notebooks").glob("*.ipynb"))


def _mkdocs_yml():
    yaml = pytest.importorskip("yaml")
    return yaml.safe_load((ROOT / "mkdocs.yml").read_text(encoding="utf-8"))


def _nav_pages(entries):
    for entry in entries:
        value = next(iter(entry.values())) if isinstance(entry, dict) else entry
        if isinstance(value, list):
            yield from _nav_pages(value)
        else:
            yield value


def _jupyter_options():
    (options,) = [p["mkdocs-jupyter"] for p in _mkdocs_yml()["plugins"] if "mkdocs-jupyter" in p]
    return options


def test_every_notebook_is_a_page_of_the_site():
    pages = [page for page in _nav_pages(_mkdocs_yml()["nav"]) if page.endswith(".ipynb")]
    assert len(NOTEBOOKS) >= 3
    assert sorted(pages) == [f"notebooks/{path.name}" for path in NOTEBOOKS]
    # docs/hooks.py brings exactly these files into the build, from notebooks/ itself.
    assert _hooks().notebook_files() == {f"notebooks/{path.name}": path for path in NOTEBOOKS}
    # The build executes them, and a failing cell fails it.
    options = _jupyter_options()
    assert options["execute"] is True
    assert options["allow_errors"] is False
    assert all(PurePath(path).match(options["include"][0]) for path in NOTEBOOKS)


def test_notebooks_are_stored_without_outputs():
    for path in NOTEBOOKS:
        notebook = json.loads(path.read_text(encoding="utf-8"))
        for cell in notebook["cells"]:
            if cell["cell_type"] == "code":
                assert cell["outputs"] == [], path.name
                assert cell["execution_count"] is None, path.name


def test_notebook_html_uses_the_sites_mathjax_and_pages():
    html = (
        '<script src=""> </script><script type="text/x-mathjax-config">init()</script>'
        '<script type="module">await import("https://cdn.example/mermaid.mjs")</script>'
        "<script>copy()</script>"
        '<div class="jp-RenderedHTMLCommon jp-RenderedMarkdown jp-MarkdownOutput" x="1">'
        "<p>$$M = I$$</p><p>with $a &lt; b$, <code>$x$</code> and "
        '<a href="../docs/math/planar.md#top">planar</a></p></div><pre>costs $5, $6</pre>'
    )
    out = _hooks().notebook_html(html, lambda uri: f"../../{uri.removesuffix('.md')}/")
    assert "https://" not in out and "x-mathjax-config" not in out and 'src=""' not in out
    assert "<script>copy()</script>" in out  # the notebook page's own scripts stay
    assert '<div class="arithmatex">\\[M = I\\]</div>' in out
    assert '<span class="arithmatex">\\(a &lt; b\\)</span>' in out
    assert "<code>$x$</code>" in out and "<pre>costs $5, $6</pre>" in out  # no math there
    assert 'href="../../math/planar/#top"' in out


def test_notebook_page_shows_every_figure():
    """The planar notebook's page, as the build makes it: executed, its figures inline PNGs."""
    convert = pytest.importorskip("mkdocs_jupyter.convert")
    options = _jupyter_options()
    path = ROOT / "notebooks" / "planar_shadows.ipynb"
    html = convert.nb2html(
        str(path), execute=options["execute"], allow_errors=options["allow_errors"]
    )
    html = _hooks().notebook_html(html, lambda uri: uri)
    notebook = json.loads(path.read_text(encoding="utf-8"))
    calls = re.compile(r"^\s*show\(fig\)", re.MULTILINE)  # the notebook's figures
    figures = sum(len(calls.findall("".join(c["source"]))) for c in notebook["cells"])
    images = re.findall(r'<img[^>]*src="data:image/png;base64,([^"]+)"', html)
    assert figures == len(images) == 3
    for data in images:
        png = base64.b64decode(data)
        assert png.startswith(b"\x89PNG\r\n\x1a\n") and len(png) > 10_000
    assert "[[ 4.  -1.5  0.   0. ]" in html  # the printed matrix, without -0.
    assert "-0. " not in html


@pytest.mark.parametrize("page", ["index.md", "getting-started.md"])
def test_pages_link_every_notebooks_executed_page(page):
    text = (DOCS / page).read_text(encoding="utf-8")
    assert "executed" in text
    for path in NOTEBOOKS:  # a link mkdocs --strict resolves to the notebook's page
        assert f"](notebooks/{path.name})" in text, f"{page} does not link {path.name}"


def test_readme_says_the_site_shows_the_notebooks_executed():
    text = (ROOT / "README.md").read_text(encoding="utf-8")
    paragraph = text[text.index("Notebooks: `notebooks/") :].split("\n\n")[0]
    assert "docs site" in paragraph and "executed" in paragraph
