"""``python -m shadowmath``: render the article's Figure 5.8.1 scene and print its matrices.

A torus (or any mesh) between a light and a wall, above a floor, drawn
offscreen with the reference renderer (:mod:`shadowmath.render`, the
``render`` extra) by one of its shadow systems (``--method``) and saved as a
PNG. Every error about the user's options goes through ``argparse``'s
``parser.error`` (exit status 2) and names the option; a missing OpenGL
context, WebGPU adapter or renderer extra exits with status 1.

The layers, each a client of the public API (``import shadowmath as sm``,
:mod:`shadowmath.meshes`, :mod:`shadowmath.render`):

* ``_options``: the parser, the option checks and their messages, :class:`Options`.
* ``_build``: the scene from the options: light checks, blocker mesh, bodies, fits.
* ``_run``: the device and its limits, the render, the files and the printout.
* ``_cascades``: ``--method cascades``, its own large scene under a sun, drawn with
  cascaded shadow maps (``render_cascades``).
* ``_atlas``: ``--method atlas``, a ground with blocks under many lights whose shadow
  maps share one atlas (``render_atlas``).
"""

from __future__ import annotations

import sys
import warnings
from collections.abc import Callable, Sequence
from typing import Any

import shadowmath as sm

from ._atlas import draw_atlas
from ._build import build_scene, check_light_and_mesh, fit_light
from ._cascades import draw_cascades
from ._options import OptionError, Options, build_parser, resolve_options
from ._run import (
    UnavailableError,
    check_limits,
    open_device,
    print_matrices,
    render,
    require_renderer,
    write_outputs,
)

__all__ = ["main"]


def main(argv: Sequence[str] | None = None) -> int:
    """Run the demo with ``argv`` (default ``sys.argv[1:]``); returns the exit status.

    Errors in the options exit through ``SystemExit(2)`` with a message on stderr;
    a missing renderer, OpenGL context or WebGPU adapter through ``SystemExit(1)``.
    """
    parser = build_parser()
    args = parser.parse_args(argv)
    try:
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always", sm.ShadowFitWarning)
            options = resolve_options(args)
            if options.method == "cascades":
                require_renderer()
                printout = draw_cascades(options)
            elif options.method == "atlas":
                require_renderer()
                printout = draw_atlas(options)
            else:
                printout = _draw(options)
    except OptionError as err:
        parser.error(str(err))
    except UnavailableError as err:
        parser.exit(1, f"{parser.prog}: {err}\n")
    _notes(parser.prog, args, caught)
    printout()
    sys.stdout.flush()
    return 0


def _draw(options: Options) -> Callable[[], None]:
    """The article's scene: checked, fitted, drawn and written; returns the printout."""
    geometry = check_light_and_mesh(options)
    require_renderer()
    scene = build_scene(options, geometry)
    fit = fit_light(options, geometry)
    device = open_device(options)
    check_limits(options, device)
    rendered = render(options, scene, fit, device)
    write_outputs(options, rendered)
    return lambda: print_matrices(options, scene, fit, rendered)


def _notes(prog: str, args: Any, caught: list[warnings.WarningMessage]) -> None:
    """The library's soft-limit warnings, once each, as notes naming the option behind them."""
    seen = set()
    for w in caught:
        text = str(w.message)
        if not issubclass(w.category, sm.ShadowFitWarning) or text in seen:
            continue
        seen.add(text)
        if text.startswith("light: ") and args.light is not None:
            text = f"--light {' '.join(f'{v:g}' for v in args.light)}: {text[7:]}"
        elif text.startswith("map_size: "):
            text = f"--map-size with --pcf: {text[10:]}"
        print(f"{prog}: note: {text}", file=sys.stderr)
