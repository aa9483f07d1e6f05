"""Probe: ``timeout_s`` is a deadline, connect to last byte. A loopback server drips its reply
one byte per second (in the headers or in the body); a ``timeout_s: 3`` request ends within
5 s as a retried timeout, then a TransportError naming the deadline."""

from __future__ import annotations

import json
import socket
import threading
import time
from collections.abc import Iterator

import pytest

from pytest_emrd.agent import ModelConfig, RetryPolicy, make_client
from pytest_emrd.errors import TransportError

REPLY = json.dumps({"choices": [{"message": {"content": "hello"}}], "usage": {}}).encode()
HEAD = b"HTTP/1.1 200 OK\r\nContent-Type: application/json\r\nContent-Length: %d\r\n\r\n"


def _drip(conn: socket.socket, part: str, stop: threading.Event) -> None:
    """Read the request, then send the reply, dripping ``part`` one byte a second."""
    conn.settimeout(5)
    data = b""
    while b"\r\n\r\n" not in data:
        data += conn.recv(65536)
    head, _, body = data.partition(b"\r\n\r\n")
    length = int(next(x for x in head.split(b"\r\n") if x.lower().startswith(b"content-length"))
                 .split(b":")[1])  # fmt: skip
    while len(body) < length:
        body += conn.recv(65536)
    header = HEAD % len(REPLY)
    fast, slow = (b"", header + REPLY) if part == "headers" else (header, REPLY)
    try:
        conn.sendall(fast)
        for byte in slow:
            if stop.wait(1.0):
                break
            conn.sendall(bytes([byte]))
    except OSError:
        pass  # the client hung up at its deadline
    finally:
        conn.close()


@pytest.fixture(params=["headers", "body"])
def dripping(request: pytest.FixtureRequest) -> Iterator[str]:
    """The base URL of a server that drips its reply's headers or body a byte a second."""
    server = socket.create_server(("127.0.0.1", 0))
    stop = threading.Event()

    def serve() -> None:
        while not stop.is_set():
            try:
                conn, _ = server.accept()
            except OSError:
                return
            threading.Thread(target=_drip, args=(conn, request.param, stop), daemon=True).start()

    threading.Thread(target=serve, daemon=True).start()
    yield f"http://127.0.0.1:{server.getsockname()[1]}/v1"
    stop.set()
    server.close()


def test_a_dripping_server_cannot_hold_a_request_past_timeout_s(dripping: str) -> None:
    config = ModelConfig(
        name="drip", provider="openai", model_id="m", base_url=dripping, timeout_s=3,
        max_retries=1,
    )  # fmt: skip
    waits: list[float] = []
    client = make_client(config, policy=RetryPolicy(max_retries=0, sleep=waits.append))
    start = time.monotonic()
    with client, pytest.raises(TransportError) as info:
        client.complete([{"role": "user", "content": "hi"}])
    elapsed = time.monotonic() - start
    assert elapsed < 5, f"took {elapsed:.1f} s"
    assert "no complete reply within timeout_s=3 s" in str(info.value)
    assert "\n" not in str(info.value)
