"""The inspector's HTTP server: the page, its static files, and a small JSON and Server-Sent-Events API.

==============================  ==============================================================
``GET /``                       the page (static/index.html)
``GET /static/<file>``          the page's scripts, styles and vendored libraries
``GET /api/info``               ``{"mode": "live"|"recorded", "source", "controls": bool}``
``GET /api/states?from=N``      ``{"states": [whole states from position N], "next": M}``
``GET /api/events?from=N``      the same states as Server-Sent Events, one per state, as they come
``GET /api/result``             a recorded run's result.json (``{}`` when there is none)
``POST /api/control/<verb>``    a control request, forwarded to the agent; its JSON reply
==============================  ==============================================================

Standard library only (`http.server` in a thread); it listens on 127.0.0.1 unless told otherwise.
"""

from __future__ import annotations

import json
import threading
from collections.abc import Callable
from http import HTTPStatus
from http.server import BaseHTTPRequestHandler, ThreadingHTTPServer
from pathlib import Path
from typing import Any
from urllib.parse import parse_qs, urlsplit

from agent.app.inspector.history import History
from agent.app.inspector.sources import ControlError

STATIC = Path(__file__).parent / "static"
_TYPES = {".html": "text/html; charset=utf-8", ".js": "text/javascript; charset=utf-8",
          ".css": "text/css; charset=utf-8", ".txt": "text/plain; charset=utf-8"}
#: Forwards one control request (verb, body) and returns the agent's reply.
Controller = Callable[[str, bytes], dict[str, Any]]


class Inspector:
    """The server, running in a thread of its own once started.

    Args:
        history: the states it serves.
        info: what ``/api/info`` says besides ``controls``.
        controller: forwards control requests (None for a recorded run: they are refused).
        result: how the run ended, for ``/api/result``: a recorded run's result.json, or a function
            that says so for a live one (``{}`` while it runs).
        host: the address to listen on.
        port: the port (0: any free one).
    """

    def __init__(self, history: History, info: dict[str, Any], controller: Controller | None = None,
                 result: dict[str, Any] | Callable[[], dict[str, Any]] | None = None, host: str = "127.0.0.1",
                 port: int = 0) -> None:
        fixed = result or {}
        outcome = staticmethod(result if callable(result) else lambda: fixed)
        handler = type("Handler", (_Handler,), {"history": history, "controller": controller,
                                                "info": {**info, "controls": controller is not None},
                                                "outcome": outcome})
        self._server = ThreadingHTTPServer((host, port), handler)
        self._server.daemon_threads = True
        self._thread = threading.Thread(target=self._server.serve_forever, name="inspector", daemon=True)

    @property
    def url(self) -> str:
        """The page's address."""
        host, port = self._server.server_address[:2]
        return f"http://{host}:{port}/"

    def start(self) -> str:
        """Serve in the background.

        Returns:
            The page's address.
        """
        self._thread.start()
        return self.url

    def close(self) -> None:
        """Stop serving and free the port."""
        self._server.shutdown()
        self._server.server_close()


class _Handler(BaseHTTPRequestHandler):
    history: History
    controller: Controller | None
    info: dict[str, Any]
    outcome: Callable[[], dict[str, Any]]
    protocol_version = "HTTP/1.1"

    def log_message(self, format: str, *args: Any) -> None:  # noqa: A002 - the base class's name
        """Requests are not logged (the page polls)."""

    def do_GET(self) -> None:
        """Answer the page, a static file, or an API read."""
        url = urlsplit(self.path)
        start = _position(parse_qs(url.query).get("from", ["0"])[0])
        if url.path == "/":
            self._file(STATIC / "index.html")
        elif url.path.startswith("/static/"):
            self._file(STATIC / url.path.removeprefix("/static/"))
        elif url.path == "/api/info":
            self._json(HTTPStatus.OK, self.info)
        elif url.path == "/api/result":
            self._json(HTTPStatus.OK, self.outcome())
        elif url.path == "/api/states" and start is not None:
            states, after = self.history.since(start)
            self._json(HTTPStatus.OK, {"states": states, "next": after})
        elif url.path == "/api/events" and start is not None:
            resumed = self.headers.get("Last-Event-ID", "")  # a page that reconnects goes on where it was
            self._events(int(resumed) + 1 if resumed.isdigit() else start)
        elif start is None:
            self._json(HTTPStatus.BAD_REQUEST, {"ok": False, "error": "from: expected a whole number ≥ 0"})
        else:
            self._json(HTTPStatus.NOT_FOUND, {"ok": False, "error": f"path: nothing at {url.path}"})

    def do_POST(self) -> None:
        """Forward a control request to the agent."""
        path = urlsplit(self.path).path
        body = self.rfile.read(int(self.headers.get("Content-Length") or 0))
        if not path.startswith("/api/control/"):
            self._json(HTTPStatus.NOT_FOUND, {"ok": False, "error": f"path: nothing at {path}"})
        elif self.controller is None:
            self._json(HTTPStatus.CONFLICT, {"ok": False, "error": "control: a recorded run cannot be controlled"})
        else:
            try:
                self._json(HTTPStatus.OK, self.controller(path.removeprefix("/api/control/"), body))
            except ControlError as error:
                self._json(HTTPStatus.BAD_REQUEST, {"ok": False, "error": str(error)})

    def _events(self, start: int) -> None:
        """Stream the states from ``start`` on, as they come, until the page goes away."""
        self.send_response(HTTPStatus.OK)
        self.send_header("Content-Type", "text/event-stream")
        self.send_header("Cache-Control", "no-cache")
        self.send_header("Connection", "close")
        self.end_headers()
        self.close_connection = True
        position = start
        try:
            while True:
                states, after = self.history.since(position, wait_s=10.0)
                if not states:
                    self.wfile.write(b": still here\n\n")
                for offset, state in enumerate(states):
                    text = json.dumps(state, ensure_ascii=False)
                    self.wfile.write(f"id: {after - len(states) + offset}\ndata: {text}\n\n".encode("utf-8"))
                self.wfile.flush()
                position = after
        except (BrokenPipeError, ConnectionResetError):
            return

    def _file(self, path: Path) -> None:
        path = path.resolve()
        if not path.is_relative_to(STATIC.resolve()) or not path.is_file():
            self._json(HTTPStatus.NOT_FOUND, {"ok": False, "error": f"path: no file {self.path}"})
            return
        self._send(HTTPStatus.OK, path.read_bytes(), _TYPES.get(path.suffix, "application/octet-stream"))

    def _json(self, status: HTTPStatus, data: Any) -> None:
        self._send(status, json.dumps(data, ensure_ascii=False).encode("utf-8"), "application/json")

    def _send(self, status: HTTPStatus, body: bytes, content_type: str) -> None:
        self.send_response(status)
        self.send_header("Content-Type", content_type)
        self.send_header("Content-Length", str(len(body)))
        self.send_header("Cache-Control", "no-store")
        self.end_headers()
        self.wfile.write(body)


def _position(text: str) -> int | None:
    """``from``'s value as a position, or None when it is not one."""
    return int(text) if text.isdigit() else None
