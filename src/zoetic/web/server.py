"""A local HTTP server for one page: ``zoetic view RUN_DIR`` without ``--html``."""

from __future__ import annotations

import os
import sys
import webbrowser
from collections.abc import Callable
from http.server import BaseHTTPRequestHandler, ThreadingHTTPServer

from zoetic.errors import ZoeticError


def make_server(page: str, port: int = 0) -> ThreadingHTTPServer:
    """Return a server on 127.0.0.1:``port`` (0: any free port) that answers ``/`` with ``page``."""
    body = page.encode("utf-8")

    class Handler(BaseHTTPRequestHandler):
        def do_GET(self) -> None:  # noqa: N802 (the http.server API)
            if self.path.split("?")[0] not in ("/", "/index.html"):
                self.send_error(404)
                return
            self.send_response(200)
            self.send_header("Content-Type", "text/html; charset=utf-8")
            self.send_header("Content-Length", str(len(body)))
            self.send_header("Cache-Control", "no-store")
            self.end_headers()
            self.wfile.write(body)

        def log_message(self, *args) -> None:  # quiet
            pass

    try:
        return ThreadingHTTPServer(("127.0.0.1", port), Handler)
    except OSError as exc:
        raise ZoeticError(f"cannot serve on 127.0.0.1:{port} ({exc}); try --port 0") from None


def _has_display() -> bool:
    """Return whether a graphical browser can open here (not a text browser on a server)."""
    if sys.platform in ("darwin", "win32"):
        return True
    return bool(os.environ.get("DISPLAY") or os.environ.get("WAYLAND_DISPLAY"))


def serve(page: str, port: int, open_browser: bool, say: Callable[[str], None] = print) -> None:
    """Serve ``page`` until Ctrl-C; print the URL and open a browser when one is available."""
    server = make_server(page, port)
    url = f"http://127.0.0.1:{server.server_address[1]}/"
    say(f"serving the view at {url} (Ctrl-C to stop)")
    if open_browser and _has_display():
        try:
            webbrowser.open(url)
        except webbrowser.Error:
            pass
    try:
        server.serve_forever()
    except KeyboardInterrupt:
        pass
    finally:
        server.server_close()
