"""mkdocs hooks: keep the API reference complete as the package grows.

Every name in ``shadowmath.__all__`` (and ``shadowmath.render.__all__`` once that
subpackage exists) gets an entry on ``api.md``: names the page does not place in a
section yet are appended under "Not yet sorted", so a new public function is
documented from the moment it is exported.
"""

from __future__ import annotations

import importlib
import re
from typing import Any

_PACKAGES = ("shadowmath", "shadowmath.render")


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
