"""Headless Chromium for the three.js tests: a page served from 127.0.0.1 that draws a
fixed scene with three.js (WebGL, software rendering) through shadowmath's ES module."""

from __future__ import annotations

import http.server
import shutil
import threading
from pathlib import Path
from typing import Any

from shadowmath.integrations import threejs

PAGE = Path(__file__).parent / "threejs" / "page.html"
#: Where Debian's chromium package puts the browser (the /usr/bin/chromium wrapper runs it).
CANDIDATES = ("/usr/lib/chromium/chromium", "chromium", "chromium-browser", "google-chrome")
#: Software WebGL (SwiftShader through ANGLE): the same picture with or without a GPU.
ARGS = ["--use-angle=swiftshader", "--enable-unsafe-swiftshader", "--ignore-gpu-blocklist"]


def browser_path() -> str | None:
    for name in CANDIDATES:
        found = shutil.which(name) or (name if Path(name).is_file() else None)
        if found:
            return found
    return None


def routes(extra: dict[str, tuple[bytes, str]] | None = None) -> dict[str, tuple[bytes, str]]:
    js = "text/javascript"
    served = {
        "/": (PAGE.read_bytes(), "text/html"),
        "/three.js": (threejs.THREE_PATH.read_bytes(), js),
        "/shadowmath.js": (threejs.MODULE_PATH.read_bytes(), js),
    }
    served.update(extra or {})
    return served


def serve(served: dict[str, tuple[bytes, str]]) -> http.server.ThreadingHTTPServer:
    """An HTTP server on 127.0.0.1 (a free port) in a daemon thread, serving ``served``."""

    class Handler(http.server.BaseHTTPRequestHandler):
        def do_GET(self) -> None:
            body, kind = served.get(self.path.split("?")[0], (b"", ""))
            self.send_response(200 if kind else 404)
            self.send_header("Content-Type", kind or "text/plain")
            self.send_header("Content-Length", str(len(body)))
            self.end_headers()
            self.wfile.write(body)

        def log_message(self, *args: Any) -> None:
            pass

    server = http.server.ThreadingHTTPServer(("127.0.0.1", 0), Handler)
    threading.Thread(target=server.serve_forever, daemon=True).start()
    return server
