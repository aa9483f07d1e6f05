"""A hostile local provider on 127.0.0.1, fake keys planted everywhere, and a grep for them.

The provider is a real HTTP server. Under ``/ok/`` it forwards to the built-in reference
server (so a whole episode can be recorded through it), under ``/deny/`` it answers 401
and under ``/fail/`` 500, with a body that echoes the key, the ``X-Auth-Token`` header and
the URL (as some providers do), under ``/huge/`` it answers a 200 whose reply is 20 MB. The
user registry written by :func:`leaky_registry` points its models at it with a key in the
query (``?key=${QUERY_ENV}``), a token header (``X-Auth-Token: ${HEADER_ENV}``), a secret in
``extra_body`` (all three declared variables, none named like a credential) and an API key
in an environment variable (sent as ``Authorization: Bearer``). :func:`leaks` and
:func:`text_leaks` look for each planted value as written, URL-encoded and base64-encoded.
"""

from __future__ import annotations

import gzip
import json
import lzma
import threading
from collections.abc import Iterator
from dataclasses import dataclass, field
from http.server import BaseHTTPRequestHandler, ThreadingHTTPServer
from pathlib import Path
from typing import Any

import httpx
import pytest

from pytest_emrd._scrub import encoded_forms
from pytest_emrd.agent import versioned_id
from pytest_emrd.reference import reference_base_url

#: Planted credentials: none of them may reach a file or the terminal.
PLANTED_KEY = "sk-planted-apikey-5f3c9a7e"  # the API key, in the env var of api_key_env
PLANTED_PASSWORD = "planted-password-81d2"  # URL userinfo (refused in a registry)
PLANTED_QUERY = "planted-querykey-44ab"  # ?key=
PLANTED_BODY = "planted body/secret+9c1"  # extra_body client_secret: ${BODY_ENV}
PLANTED_HEADER = "planted-header-token-6e1f"  # X-Auth-Token: ${HEADER_ENV}
PLANTED = (PLANTED_KEY, PLANTED_PASSWORD, PLANTED_QUERY, PLANTED_BODY, PLANTED_HEADER)
KEY_ENV = "EMRD_HARDENING_CRED"  # no credential-like suffix: found only through api_key_env
BODY_ENV = "EMRD_HARDENING_BODY"  # the others are found only because the registry declares them
QUERY_ENV = "EMRD_HARDENING_QUERY"
HEADER_ENV = "EMRD_HARDENING_HEADER"
#: Every planted value in each form a leak could take.
PLANTED_FORMS = tuple(form for secret in PLANTED for form in encoded_forms(secret))
HUGE_CHARS = 20 * 1024 * 1024


@dataclass
class Provider:
    port: int
    seen: list[str] = field(default_factory=list)
    """Authorization header and path of every request (the planted values did travel)."""

    def base_url(self, route: str) -> str:
        """A base URL with a planted key in the query (kept after the endpoint path)."""
        return f"http://127.0.0.1:{self.port}/{route}/v1?key=${{{QUERY_ENV}}}&to="


@pytest.fixture(scope="session")
def provider() -> Iterator[Provider]:
    upstream = reference_base_url()
    seen: list[str] = []

    class Handler(BaseHTTPRequestHandler):
        def log_message(self, *args: Any) -> None:
            pass

        def _send(self, status: int, payload: bytes) -> None:
            self.send_response(status)
            self.send_header("Content-Type", "application/json")
            self.send_header("Content-Length", str(len(payload)))
            self.end_headers()
            self.wfile.write(payload)

        def do_POST(self) -> None:
            body = self.rfile.read(int(self.headers["Content-Length"]))
            seen.append(
                f"{self.headers['Authorization']} {self.headers['X-Auth-Token']} {self.path}"
            )
            if self.path.startswith("/ok/"):
                answer = httpx.post(f"{upstream}/chat/completions", content=body, timeout=30)
                self._send(answer.status_code, answer.content)
            elif self.path.startswith(("/deny/", "/fail/")):
                echo = {
                    "error": {
                        "message": f"Incorrect API key provided: {self.headers['Authorization']}"
                        f" or token {self.headers['X-Auth-Token']} for {self.path}",
                        "type": "invalid_request_error",
                    }
                }
                self._send(401 if "/deny/" in self.path else 500, json.dumps(echo).encode())
            else:
                reply = {"choices": [{"message": {"content": "x" * HUGE_CHARS}}], "usage": {}}
                self._send(200, json.dumps(reply).encode())

    httpd = ThreadingHTTPServer(("127.0.0.1", 0), Handler)
    thread = threading.Thread(target=httpd.serve_forever, daemon=True)
    thread.start()
    yield Provider(httpd.server_address[1], seen)
    httpd.shutdown()
    httpd.server_close()


@pytest.fixture
def planted_env(monkeypatch: pytest.MonkeyPatch) -> str:
    """The planted API key and body secret in the environment variables the registry names."""
    monkeypatch.setenv(KEY_ENV, PLANTED_KEY)
    monkeypatch.setenv(BODY_ENV, PLANTED_BODY)
    monkeypatch.setenv(QUERY_ENV, PLANTED_QUERY)
    monkeypatch.setenv(HEADER_ENV, PLANTED_HEADER)
    return KEY_ENV


def leaky_registry(path: Path, provider: Provider, **routes: str) -> Path:
    """A user registry: ``name=route`` models of the reference agent behind ``provider``."""
    models = {
        name: {
            "provider": "openai",
            "model_id": versioned_id("scout"),
            "base_url": provider.base_url(route),
            "api_key_env": KEY_ENV,
            "extra_body": {"client_secret": "${" + BODY_ENV + "}"},
            "extra_headers": {"X-Auth-Token": "${" + HEADER_ENV + "}"},
            "env": [BODY_ENV, QUERY_ENV, HEADER_ENV],
            "modality": "text",
            "max_retries": 0,
            "timeout_s": 60,
        }
        for name, route in routes.items()
    }
    path.write_text(json.dumps({"models": models}))
    return path


def leaks(root: Path, *, skip: tuple[Path, ...] = ()) -> list[str]:
    """Every file under ``root`` (xz and gzip files decompressed) holding a planted credential."""
    found = []
    for path in sorted(p for p in root.rglob("*") if p.is_file() and p not in skip):
        data = path.read_bytes()
        if path.suffix == ".xz":
            data = lzma.decompress(data)
        elif path.suffix == ".gz":
            data = gzip.decompress(data)
        found += [f"{path}: {s}" for s in PLANTED_FORMS if s.encode() in data]
    return found


def text_leaks(text: str) -> list[str]:
    """The planted credentials present in ``text`` (in any of their forms)."""
    return [s for s in PLANTED_FORMS if s in text]
