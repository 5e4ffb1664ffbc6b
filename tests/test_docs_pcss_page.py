"""The PCSS page carries the complete programs of docs/examples/ as they are: each file
there appears on docs/pcss.md as a titled code block equal to it (inline, not included:
a code host shows the page raw), so the copy a reader takes is the one
tests/render/test_docs_pcss_programs.py runs."""

from __future__ import annotations

from pathlib import Path

from .test_docs import TITLED

ROOT = Path(__file__).resolve().parents[1]
PAGE = ROOT / "docs" / "pcss.md"
EXAMPLES = ROOT / "docs" / "examples"


def test_the_pcss_page_shows_every_example_file_as_it_is() -> None:
    text = PAGE.read_text(encoding="utf-8")
    copies = {path: body for _, path, body in TITLED.findall(text)}
    files = {
        f"docs/examples/{p.name}": p.read_text(encoding="utf-8")
        for p in sorted(EXAMPLES.iterdir())
        if p.suffix in (".py", ".glsl", ".wgsl")
    }
    assert len(files) == 7
    shown = {path: body for path, body in copies.items() if path.startswith("docs/examples/")}
    assert set(shown) == set(files)
    for path, body in shown.items():
        assert body == files[path], path
    assert "--8<--" not in text


def test_every_example_program_is_run_by_the_render_tests() -> None:
    tests = (ROOT / "tests" / "render" / "test_docs_pcss_programs.py").read_text(encoding="utf-8")
    for program in sorted(EXAMPLES.glob("pcss_*.py")):
        if program.stem != "pcss_scene":
            assert f'example("{program.stem}")' in tests, program.name
