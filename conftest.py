"""Doctests see NumPy and the public API, as a user after ``from shadowmath import *`` would."""

from typing import Any

import numpy as np
import pytest

import shadowmath


@pytest.fixture(autouse=True)
def _doctest_names(doctest_namespace: dict[str, Any]) -> None:
    doctest_namespace["np"] = np
    for name in shadowmath.__all__:
        doctest_namespace[name] = getattr(shadowmath, name)
