"""A real local chat-completions server and a small episode runner that talks to it.

The runner behaves like the episode loop as the cassette layer sees it: a growing history
window, one JPEG frame per step registered with its pixel digest, secrets in headers and
query, and failures returned as an ``errored`` trajectory.
"""

from __future__ import annotations

import base64
import hashlib
import io
import json
import threading
from collections.abc import Iterator
from dataclasses import dataclass, field
from http.server import BaseHTTPRequestHandler, ThreadingHTTPServer
from typing import Any

import httpx
import numpy as np
import pytest
from PIL import Image

from pytest_emrd import frames
from pytest_emrd.trajectory import EpisodeSpec, GroundTruth, Pose, Step, Trajectory, Usage

FAKE_KEY = "sk-emrd-fake-0123456789abcdef"
PROTOCOL = "test-protocol-1"


@dataclass
class FakeServer:
    url: str
    seen_headers: list[dict[str, str]] = field(default_factory=list)
    fail_next: int = 0
    unreadable_next: list[bytes] = field(default_factory=list)
    """Bodies sent with status 200 instead of the next replies (garbage a client retries)."""


@pytest.fixture
def server() -> Iterator[FakeServer]:
    state = FakeServer(url="")

    class Handler(BaseHTTPRequestHandler):
        def log_message(self, *args: Any) -> None:
            pass

        def do_POST(self) -> None:
            body = self.rfile.read(int(self.headers["Content-Length"]))
            state.seen_headers.append(dict(self.headers))
            if state.fail_next:
                state.fail_next -= 1
                self.send_response(500)
                self.end_headers()
                return
            if state.unreadable_next:
                self._send(state.unreadable_next.pop(0))
                return
            messages = json.loads(body)["messages"]
            reply = f"reply {len(messages)} {hashlib.sha256(body).hexdigest()[:8]}"
            payload = json.dumps(
                {
                    "choices": [{"message": {"role": "assistant", "content": reply}}],
                    "usage": {"prompt_tokens": len(body) // 4, "completion_tokens": 7},
                }
            ).encode()
            self._send(payload)

        def _send(self, payload: bytes) -> None:
            self.send_response(200)
            self.send_header("Content-Type", "application/json")
            self.send_header("Content-Length", str(len(payload)))
            self.end_headers()
            self.wfile.write(payload)

    httpd = ThreadingHTTPServer(("127.0.0.1", 0), Handler)
    state.url = f"http://127.0.0.1:{httpd.server_address[1]}"
    thread = threading.Thread(target=httpd.serve_forever, daemon=True)
    thread.start()
    yield state
    httpd.shutdown()
    httpd.server_close()


def frame(seed: int, t: int) -> np.ndarray:
    rng = np.random.default_rng([seed, t])
    small = rng.integers(0, 256, size=(8, 8, 3), dtype=np.uint8)
    return np.kron(small, np.ones((8, 8, 1), dtype=np.uint8))


def trajectory(spec: EpisodeSpec, steps: list[str], error: str | None = None) -> Trajectory:
    gt = GroundTruth(objects=(), rooms=(), discoverable_ids=(), spawn_room="Office")
    return Trajectory(
        spec=spec,
        protocol=PROTOCOL,
        ground_truth=gt,
        steps=tuple(
            Step(
                index=i + 1,
                pose=Pose(0.0, 0.0, 0.0),
                room="Office",
                visible_ids=(),
                cognitive_map=(),
                action="Turn(Left)",
                success=True,
                feedback="ok",
                raw_reply=reply,
                usage=Usage(10, 7),
            )
            for i, reply in enumerate(steps)
        ),
        status="errored" if error else "budget",
        final_room="Office",
        error=error,
    )


@dataclass
class FakeRunner:
    """``run(spec, live=...)`` against ``base_url``; knobs change what the requests carry."""

    base_url: str
    steps: int = 4
    quality: int = 90
    suffix: str = ""
    pixel_shift: int = 0
    budget: int = 50
    """The total announced in "Step t of <budget>" (independent of ``steps``)."""
    suffix_from: int = 1
    """The first step whose text carries ``suffix`` (a drift in the middle of the episode)."""
    calls: int = 0

    def __call__(self, spec: EpisodeSpec, *, live: bool) -> Trajectory:
        self.calls += 1
        messages: list[dict[str, Any]] = [{"role": "system", "content": "You are a responder."}]
        replies: list[str] = []
        try:
            with httpx.Client(timeout=5) as http:
                for t in range(1, self.steps + 1):
                    pixels = frame(spec.seed, t) + np.uint8(self.pixel_shift)
                    buf = io.BytesIO()
                    Image.fromarray(pixels).save(buf, format="JPEG", quality=self.quality)
                    b64 = base64.b64encode(buf.getvalue()).decode()
                    tail = self.suffix if t >= self.suffix_from else ""
                    frames.register(b64, hashlib.sha256(pixels.tobytes()).hexdigest())
                    content = [
                        {"type": "text", "text": f"Step {t} of {self.budget}{tail}"},
                        {
                            "type": "image_url",
                            "image_url": {"url": f"data:image/jpeg;base64,{b64}"},
                        },
                    ]
                    messages.append({"role": "user", "content": content})
                    response = http.post(
                        f"{self.base_url}/v1/chat/completions",
                        params={"key": FAKE_KEY},
                        json={"model": "fake", "messages": messages[-5:]},
                        headers={"Authorization": f"Bearer {FAKE_KEY}", "x-api-key": FAKE_KEY},
                    )
                    response.raise_for_status()
                    reply = response.json()["choices"][0]["message"]["content"]
                    messages.append({"role": "assistant", "content": reply})
                    replies.append(reply)
        except Exception as exc:
            return trajectory(spec, replies, error=f"{type(exc).__name__}: {exc}")
        return trajectory(spec, replies)


@pytest.fixture
def spec() -> EpisodeSpec:
    return EpisodeSpec(model="fake", condition="baseline", spawn="office", episode=3)
