"""Fixtures for the agent tests: a fault-injecting local HTTP server."""

from __future__ import annotations

import json
import threading
import time
from collections.abc import Iterator
from dataclasses import dataclass, field
from http.server import BaseHTTPRequestHandler, ThreadingHTTPServer
from typing import Any

import pytest

OK_BODY = {
    "choices": [{"message": {"role": "assistant", "content": "hello"}}],
    "usage": {"prompt_tokens": 11, "completion_tokens": 3},
}
ANTHROPIC_OK = {
    "content": [{"type": "text", "text": "hello"}],
    "usage": {"input_tokens": 11, "output_tokens": 3},
}


@dataclass
class FaultServer:
    """A loopback server answering from a script: one entry per request, then OK forever.

    Script entries: ``("status", code, headers)`` (optionally a 4th item: the body),
    ``("garbage", code)``, ``("stall", s)`` (sleeps ``s`` seconds before answering OK: a
    client timeout), ``("ok",)``.
    """

    script: list[tuple[Any, ...]] = field(default_factory=list)
    ok_body: dict[str, Any] = field(default_factory=lambda: OK_BODY)
    bodies: list[bytes] = field(default_factory=list)
    headers: list[dict[str, str]] = field(default_factory=list)
    paths: list[str] = field(default_factory=list)
    base_url: str = ""


def _handler(state: FaultServer) -> type[BaseHTTPRequestHandler]:
    class Handler(BaseHTTPRequestHandler):
        protocol_version = "HTTP/1.1"

        def log_message(self, format: str, *args: Any) -> None:
            """Quiet."""

        def _reply(self, code: int, body: bytes, headers: dict[str, str] | None = None) -> None:
            self.send_response(code)
            for k, v in (headers or {}).items():
                self.send_header(k, v)
            self.send_header("Content-Length", str(len(body)))
            self.end_headers()
            self.wfile.write(body)

        def do_POST(self) -> None:
            body = self.rfile.read(int(self.headers["Content-Length"]))
            state.bodies.append(body)
            state.headers.append({k.lower(): v for k, v in self.headers.items()})
            state.paths.append(self.path)
            entry = state.script.pop(0) if state.script else ("ok",)
            if entry[0] == "status":
                body = entry[3] if len(entry) > 3 else b'{"error": "injected"}'
                self._reply(entry[1], body, entry[2])
            elif entry[0] == "garbage":
                self._reply(entry[1], b"<html>upstream hiccup</html>")
            else:
                if entry[0] == "stall":
                    time.sleep(entry[1])
                self._reply(200, json.dumps(state.ok_body).encode())

    return Handler


@pytest.fixture
def fault_server() -> Iterator[FaultServer]:
    state = FaultServer()
    server = ThreadingHTTPServer(("127.0.0.1", 0), _handler(state))
    server.daemon_threads = True
    thread = threading.Thread(target=server.serve_forever, args=(0.05,), daemon=True)
    thread.start()
    state.base_url = f"http://127.0.0.1:{server.server_address[1]}"
    yield state
    server.shutdown()
    server.server_close()
    thread.join()
