"""A griffe extension: the reST bits of shadowmath's docstrings, as Markdown for the site.

The docstrings are written for ``help()`` and doctests, so they use reST's
``.. math::`` directive and ``:func:`` roles. mkdocstrings renders Markdown; this
turns the directive into an arithmatex ``$$`` block and the roles into links to the
API reference (plain code when the target is not a public name).

Doctest blocks (``>>>`` lines and their output, up to a blank line) become fenced
``pycon`` code: read as Markdown, ``>>>`` opens nested block quotes, in which a
``>>> # comment`` line is a heading that lands in the page's table of contents.
"""

from __future__ import annotations

import re
import textwrap
from typing import Any

import griffe

_ROLE = re.compile(r":(?:func|class|mod|data|attr|meth):`~?([\w.]+)`")
_INLINE_MATH = re.compile(r"^(\s*)\.\. math:: (\S.*)$")
# "margin, near, far: as in ..." documents several arguments at once; griffe's
# Google parser wants one entry per argument.
_GROUPED_ARGS = re.compile(r"^(\s+)(\w+(?:, \w+)+): (.*)$", re.MULTILINE)


def _public_names() -> set[str]:
    import shadowmath

    return set(shadowmath.__all__)


def _math_blocks(text: str) -> str:
    """``.. math::`` + indented block (or same-line formula) -> ``$$ ... $$``."""
    lines = text.split("\n")
    out: list[str] = []
    i = 0
    while i < len(lines):
        line = lines[i]
        inline = _INLINE_MATH.match(line)
        if inline:
            indent, formula = inline.groups()
            out += [f"{indent}$$", f"{indent}{formula}", f"{indent}$$"]
            i += 1
            continue
        if line.strip() == ".. math::":
            indent = line[: len(line) - len(line.lstrip())]
            i += 1
            body: list[str] = []
            while i < len(lines) and (
                not lines[i].strip() or len(lines[i]) - len(lines[i].lstrip()) > len(indent)
            ):
                body.append(lines[i])
                i += 1
            formula = textwrap.dedent("\n".join(body)).strip("\n")
            out += [f"{indent}$$", *(indent + f for f in formula.split("\n")), f"{indent}$$", ""]
            continue
        out.append(line)
        i += 1
    return "\n".join(out)


def _doctest_blocks(text: str) -> str:
    """Each run of doctest lines (from a ``>>>`` line to a blank one) -> a ``pycon`` fence."""
    lines = text.split("\n")
    out: list[str] = []
    i = 0
    while i < len(lines):
        stripped = lines[i].lstrip()
        if stripped != ">>>" and not stripped.startswith(">>> "):
            out.append(lines[i])
            i += 1
            continue
        indent = lines[i][: len(lines[i]) - len(stripped)]
        out.append(f"{indent}```pycon")
        while i < len(lines) and lines[i].strip():
            out.append(indent + lines[i][len(indent) :])
            i += 1
        out.append(f"{indent}```")
    return "\n".join(out)


def _split_grouped_args(text: str) -> str:
    def split(match: re.Match[str]) -> str:
        indent, names, description = match.groups()
        return "\n".join(f"{indent}{name}: {description}" for name in names.split(", "))

    return _GROUPED_ARGS.sub(split, text)


def _roles(text: str, public: set[str]) -> str:
    def link(match: re.Match[str]) -> str:
        name = match.group(1).split(".")[-1]
        if name in public:
            return f"[`{name}`][shadowmath.{name}]"
        return f"`{match.group(1)}`"

    return _ROLE.sub(link, text)


class RstToMarkdown(griffe.Extension):
    """Rewrite every docstring of the loaded package once the tree is complete."""

    def __init__(self) -> None:
        self.public = _public_names()

    def on_object(self, *, obj: griffe.Object, **kwargs: Any) -> None:
        if obj.docstring is not None:
            text = _split_grouped_args(_math_blocks(_doctest_blocks(obj.docstring.value)))
            obj.docstring.value = _roles(text, self.public)
