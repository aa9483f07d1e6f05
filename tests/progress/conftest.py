"""A flaky OpenAI-compatible endpoint on 127.0.0.1: the reference agents behind HTTP 503s.

The chat requests numbered in ``fail_on`` (1-based) are answered 503 (retried by the
client), every other one by the reference agent named in the request, so an episode
against it records normally with a known number of retries.
"""

from __future__ import annotations

import json
import threading
from collections.abc import Iterator
from dataclasses import dataclass
from http.server import BaseHTTPRequestHandler, ThreadingHTTPServer
from pathlib import Path
from typing import Any

import pytest

from pytest_emrd.agent import load_registry
from pytest_emrd.agent.reference import complete


@dataclass
class Flaky:
    fail_on: frozenset[int] = frozenset({1, 2})
    seen: int = 0
    base_url: str = ""

    def registry_file(self, folder: Path) -> Path:
        """A user registry with model ``flaky``: scout's brain behind this endpoint."""
        path = folder / "flaky-models.yaml"
        entry = {
            "provider": "openai",
            "base_url": self.base_url,
            "model_id": "scout",
            "modality": "both",
            "max_retries": 3,
        }
        path.write_text(json.dumps({"models": {"flaky": entry}}), encoding="utf-8")
        return path


@pytest.fixture
def flaky() -> Iterator[Flaky]:
    state = Flaky()
    registry = load_registry()

    class Handler(BaseHTTPRequestHandler):
        protocol_version = "HTTP/1.1"

        def log_message(self, format: str, *args: Any) -> None:
            """Silent."""

        def _send(self, status: int, payload: dict[str, Any]) -> None:
            data = json.dumps(payload).encode()
            self.send_response(status)
            self.send_header("Content-Type", "application/json")
            self.send_header("Content-Length", str(len(data)))
            self.end_headers()
            self.wfile.write(data)

        def do_GET(self) -> None:
            self._send(200, {"object": "list", "data": [{"id": "scout", "object": "model"}]})

        def do_POST(self) -> None:
            body = json.loads(self.rfile.read(int(self.headers["Content-Length"])))
            state.seen += 1
            if state.seen in state.fail_on:
                self._send(503, {"error": {"message": "overloaded, try again"}})
                return
            self._send(200, complete(body, registry))

    server = ThreadingHTTPServer(("127.0.0.1", 0), Handler)
    server.daemon_threads = True
    thread = threading.Thread(target=server.serve_forever, args=(0.05,), daemon=True)
    thread.start()
    state.base_url = f"http://127.0.0.1:{server.server_address[1]}/v1"
    try:
        yield state
    finally:
        server.shutdown()
        server.server_close()
        thread.join()
