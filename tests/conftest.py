"""Shared test configuration: hypothesis profiles, a loopback JSON server.

``ci`` (the default here) is derandomized with no deadline so CI results are
reproducible and immune to a slow shared machine; ``dev`` explores more.
"""

from __future__ import annotations

import importlib
import json
import os
import pkgutil
import threading
from collections.abc import Callable, Iterator
from http.server import BaseHTTPRequestHandler, ThreadingHTTPServer
from typing import Any

import pytest
from hypothesis import HealthCheck, settings

#: ``answer(method, path, json_body_or_None) -> (status, payload)`` of :func:`json_server`.
Answer = Callable[[str, str, Any], tuple[int, Any]]

settings.register_profile(
    "ci",
    derandomize=True,
    deadline=None,
    max_examples=200,
    suppress_health_check=[HealthCheck.too_slow],
    print_blob=True,
)
settings.register_profile("dev", deadline=None, max_examples=500)
settings.load_profile(os.environ.get("HYPOTHESIS_PROFILE", "ci"))

pytest_plugins = ["pytester"]


def _import_the_whole_product() -> None:
    """Import every module of pytest_emrd (and so numpy, scipy, PIL, libyaml, matplotlib) now.

    The ``pytester`` fixture restores ``sys.modules`` when its test ends, dropping whatever was
    first imported during that test. The product imports lazily, so without this a module
    could first load inside a pytester test: a compiled extension dropped that way cannot be
    loaded again in the process ("cannot load module more than once per process"), and a
    dropped module of ours would come back with new classes that ``isinstance`` and
    ``pytest.raises`` no longer recognise. Which test first imports what depends on how xdist
    spreads the tests, so the failures would come and go.
    """
    import pytest_emrd

    for info in pkgutil.walk_packages(pytest_emrd.__path__, "pytest_emrd."):
        if not info.name.endswith("__main__"):
            importlib.import_module(info.name)


_import_the_whole_product()


@pytest.fixture(autouse=True)
def _outside_ci(monkeypatch: pytest.MonkeyPatch) -> None:
    """Tests start from a developer's environment even when CI runs them (``CI=true`` would
    make every recording run of a pytester suite replay-only); a test that is about CI sets
    the variables itself."""
    for name in ("CI", "GITHUB_STEP_SUMMARY", "GITHUB_ACTIONS"):
        monkeypatch.delenv(name, raising=False)


@pytest.fixture
def json_server() -> Iterator[Callable[[Answer], str]]:
    """``json_server(answer)`` starts a loopback HTTP server and returns its ``/v1`` base URL.

    ``answer(method, path, body)`` gives ``(status, payload)`` for each GET or POST (``body``
    is the decoded JSON or None); every server stops when the test ends.
    """
    running: list[tuple[ThreadingHTTPServer, threading.Thread]] = []

    def start(answer: Answer) -> str:
        class Handler(BaseHTTPRequestHandler):
            protocol_version = "HTTP/1.1"

            def log_message(self, format: str, *args: Any) -> None:
                """Silent."""

            def _reply(self, method: str) -> None:
                length = int(self.headers.get("Content-Length") or 0)
                body = json.loads(self.rfile.read(length)) if length else None
                status, payload = answer(method, self.path, body)
                data = json.dumps(payload).encode()
                self.send_response(status)
                self.send_header("Content-Type", "application/json")
                self.send_header("Content-Length", str(len(data)))
                self.end_headers()
                self.wfile.write(data)

            def do_GET(self) -> None:
                self._reply("GET")

            def do_POST(self) -> None:
                self._reply("POST")

        server = ThreadingHTTPServer(("127.0.0.1", 0), Handler)
        server.daemon_threads = True
        thread = threading.Thread(target=server.serve_forever, args=(0.05,), daemon=True)
        thread.start()
        running.append((server, thread))
        return f"http://127.0.0.1:{server.server_address[1]}/v1"

    yield start
    for server, thread in running:
        server.shutdown()
        server.server_close()
        thread.join()
