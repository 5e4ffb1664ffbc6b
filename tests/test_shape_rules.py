"""The shape rules of the package's code (issue 26): short functions, few positional arguments.

Read from the source with ``ast``: a function's length counts the lines of its body after
the docstring; its positional parameters leave out ``self`` and ``cls``.
"""

from __future__ import annotations

import ast
from collections.abc import Iterator
from pathlib import Path

import pytest

PACKAGE = Path(__file__).resolve().parents[1] / "shadowmath"
MAX_LINES = 60
MAX_POSITIONAL = 5


def _functions() -> Iterator[tuple[str, ast.FunctionDef | ast.AsyncFunctionDef]]:
    for path in sorted(PACKAGE.rglob("*.py")):
        tree = ast.parse(path.read_text())
        for node in ast.walk(tree):
            if isinstance(node, ast.FunctionDef | ast.AsyncFunctionDef):
                yield f"{path.relative_to(PACKAGE).as_posix()}:{node.name}", node


def _code_lines(node: ast.FunctionDef | ast.AsyncFunctionDef) -> int:
    body = node.body
    first = body[0]
    docstring = isinstance(first, ast.Expr) and isinstance(first.value, ast.Constant)
    if docstring and isinstance(first.value.value, str):
        if len(body) == 1:
            return 0
        first = body[1]
    end = node.end_lineno or first.lineno
    return end - first.lineno + 1


def _positional(node: ast.FunctionDef | ast.AsyncFunctionDef) -> int:
    names = [a.arg for a in (*node.args.posonlyargs, *node.args.args)]
    return len(names) - (1 if names[:1] in (["self"], ["cls"]) else 0)


def test_no_function_is_longer_than_a_screen() -> None:
    long = {name: n for name, node in _functions() if (n := _code_lines(node)) > MAX_LINES}
    assert long == {}


def test_no_function_takes_more_than_five_positional_arguments() -> None:
    many = {name for name, node in _functions() if _positional(node) > MAX_POSITIONAL}
    assert many == set()


@pytest.mark.parametrize(
    ("source", "lines", "positional"),
    [
        ('def f(a, b):\n    """Doc."""\n    x = 1\n    return x\n', 2, 2),
        ("class C:\n    def m(self, a, b, c, d, e, f):\n        return a\n", 1, 6),
    ],
)
def test_the_rules_read_the_source(source: str, lines: int, positional: int) -> None:
    node = next(n for n in ast.walk(ast.parse(source)) if isinstance(n, ast.FunctionDef))
    assert (_code_lines(node), _positional(node)) == (lines, positional)
