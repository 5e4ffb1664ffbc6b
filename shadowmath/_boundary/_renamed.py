"""Renamed public names: the old ones keep working for a while, with a ``DeprecationWarning``.

One idea has one name across the API (``pcf_radius`` and ``pcf_filter`` for the PCF kernel
wherever it appears; ``area_light_samples`` for the area light's samples, with ``seed=`` or
a JAX ``key=``). ``docs/api.md`` lists the old names and what replaced them.
"""

from __future__ import annotations

import functools
import warnings
from collections.abc import Callable
from typing import Any, TypeVar

F = TypeVar("F", bound=Callable[..., Any])


def warn_renamed(old: str, new: str) -> None:
    """The ``DeprecationWarning`` of a renamed name, pointing at the caller's line."""
    warnings.warn(
        f"{old} is deprecated and will be removed: use {new}", DeprecationWarning, stacklevel=3
    )


def renamed_keywords(**new_of_old: str) -> Callable[[F], F]:
    """Accept each old keyword ``old=`` as the new one, with a ``DeprecationWarning``.

    Example:
        >>> @renamed_keywords(radius="pcf_radius")
        ... def border(*, pcf_radius: int = 0) -> int:
        ...     return pcf_radius + 1
        >>> import warnings
        >>> with warnings.catch_warnings(record=True) as caught:
        ...     warnings.simplefilter("always")
        ...     border(radius=2), str(caught[0].message)
        (3, 'border(radius=...) is deprecated and will be removed: use pcf_radius=')
    """

    def decorate(fn: F) -> F:
        @functools.wraps(fn)
        def accepting_old_names(*args: Any, **kwargs: Any) -> Any:
            for old, new in new_of_old.items():
                if old in kwargs:
                    if new in kwargs:
                        raise TypeError(f"{fn.__name__}() got {old}= and {new}=: give {new}=")
                    warn_renamed(f"{fn.__name__}({old}=...)", f"{new}=")
                    kwargs[new] = kwargs.pop(old)
            return fn(*args, **kwargs)

        return accepting_old_names  # type: ignore[return-value]

    return decorate
