"""``python -m shadowmath``: the demo's command line, :func:`shadowmath.cli.main`.

``main`` stays importable from here for the ``shadowmath`` console script
(``[project.scripts]``) and for scripts that run the demo in-process.
"""

from __future__ import annotations

import sys

from shadowmath.cli import main

__all__ = ["main"]

if __name__ == "__main__":
    sys.exit(main())
