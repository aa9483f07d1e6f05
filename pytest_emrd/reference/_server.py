"""The reference agents behind a real OpenAI-compatible HTTP endpoint on 127.0.0.1.

``POST /v1/chat/completions`` answers with a scripted agent named by ``model``;
``GET /v1/models`` lists them. :func:`reference_base_url` starts one process-wide server on
demand; ``emrd serve`` serves in the foreground.
"""

from __future__ import annotations

import json
import threading
import time
from http import HTTPStatus
from http.server import BaseHTTPRequestHandler, ThreadingHTTPServer
from typing import Any, Final

from pytest_emrd.agent import ModelConfig, Registry, load_registry
from pytest_emrd.errors import ProtocolError, check_range
from pytest_emrd.reference._agents import RequestError, complete, model_list

MAX_BODY_BYTES: Final = 64 * 1024 * 1024
_POLL_S: Final = 0.05


class _Handler(BaseHTTPRequestHandler):
    server: ReferenceServer
    protocol_version = "HTTP/1.1"
    disable_nagle_algorithm = True  # headers and body go out at once: no delayed-ACK stall

    def log_message(self, format: str, *args: Any) -> None:
        """Silent: the test and benchmark output is not the place for an access log."""

    def _send(self, status: int, payload: dict[str, Any]) -> None:
        body = json.dumps(payload, separators=(",", ":")).encode()
        self.send_response(status)
        self.send_header("Content-Type", "application/json")
        self.send_header("Content-Length", str(len(body)))
        self.end_headers()
        self.wfile.write(body)

    def _error(self, status: int, message: str) -> None:
        self._send(status, {"error": {"message": message, "type": "invalid_request_error"}})

    def do_GET(self) -> None:
        if self.path.rstrip("/") in ("/v1/models", "/models"):
            self._send(HTTPStatus.OK, model_list(self.server.registry))
        else:
            self._error(HTTPStatus.NOT_FOUND, f"no route GET {self.path}")

    def do_POST(self) -> None:
        length = int(self.headers.get("Content-Length") or 0)
        try:
            if length > MAX_BODY_BYTES:
                raise RequestError(f"body of {length} bytes", HTTPStatus.REQUEST_ENTITY_TOO_LARGE)
            raw = self.rfile.read(length)
            if self.path.rstrip("/") not in ("/v1/chat/completions", "/chat/completions"):
                raise RequestError(f"no route POST {self.path}", HTTPStatus.NOT_FOUND)
            try:
                body = json.loads(raw)
            except ValueError as exc:
                raise RequestError(f"body is not JSON: {exc}") from None
            payload = complete(body, self.server.registry)
        except ProtocolError as exc:
            self._error(getattr(exc, "status", HTTPStatus.BAD_REQUEST), str(exc))
            return
        time.sleep(self.server.latency_s)
        self._send(HTTPStatus.OK, payload)


class ReferenceServer(ThreadingHTTPServer):
    """The reference endpoint; as a context manager, served from a background thread
    (``emrd serve`` calls :meth:`serve_forever` instead). ``port=0`` binds an ephemeral port;
    ``latency_s`` is added to every completion, like a remote model's."""

    daemon_threads = True
    allow_reuse_address = True

    def __init__(
        self,
        *,
        host: str = "127.0.0.1",
        port: int = 0,
        registry: Registry | None = None,
        latency_s: float = 0.0,
    ) -> None:
        self.registry = registry or load_registry()
        self.latency_s = check_range("latency_s", latency_s, 0, 60)
        super().__init__((host, port), _Handler)
        self._thread = threading.Thread(
            target=self.serve_forever, args=(_POLL_S,), name="emrd-reference-server", daemon=True
        )

    @property
    def base_url(self) -> str:
        host, port = self.server_address[:2]
        return f"http://{host}:{port}/v1"

    def start(self) -> ReferenceServer:
        self._thread.start()
        return self

    def close(self) -> None:
        if self._thread.is_alive():
            self.shutdown()
            self._thread.join()
        self.server_close()

    def __enter__(self) -> ReferenceServer:
        return self.start()

    def __exit__(self, *exc: object) -> None:
        self.close()


_lock = threading.Lock()
_shared: ReferenceServer | None = None


def reference_base_url() -> str:
    """Base URL of the process-wide reference server, started on first use.

    :returns: The server's ``http://127.0.0.1:PORT/v1``.
    """
    global _shared
    with _lock:
        if _shared is None:
            _shared = ReferenceServer().start()
        return _shared.base_url


def base_url_of(config: ModelConfig) -> str:
    """Where ``config``'s requests go: its own ``base_url``, else (a reference agent) the
    process-wide reference server's.

    :param config: The model's registry entry.
    :returns: The base URL its client sends to.
    """
    return config.base_url if config.base_url is not None else reference_base_url()
