"""Single-image mode over the Anthropic Messages API: a claude episode against a local
Messages endpoint. Every request holds exactly one image (the current frame) and no
placeholder text; earlier frames travel as the model's own observation of that step."""

from __future__ import annotations

import dataclasses
import json
import threading
from collections.abc import Iterator
from http.server import BaseHTTPRequestHandler, ThreadingHTTPServer
from typing import Any

import pytest

from pytest_emrd.agent import AnthropicClient, load_registry
from pytest_emrd.agent._history import FRAME_SUMMARY
from pytest_emrd.episode import run_episode
from pytest_emrd.trajectory import EpisodeSpec

STEPS = 6


def _reply(step: int) -> str:
    action = "Term(Office)" if step == STEPS else "Turn(Right)"
    return json.dumps(
        {
            "observation": f"View {step}: a desk ahead,  a chair to the left.",
            "dedup_check": "",
            "cognitive_map": {},
            "action": action,
            "reasoning": "done",
        }
    )


class _Messages(BaseHTTPRequestHandler):
    protocol_version = "HTTP/1.1"
    bodies: list[dict[str, Any]]

    def log_message(self, format: str, *args: Any) -> None:
        """Quiet."""

    def do_POST(self) -> None:
        body = json.loads(self.rfile.read(int(self.headers["Content-Length"])))
        self.bodies.append(body)
        answer = {
            "content": [{"type": "text", "text": _reply(len(self.bodies))}],
            "usage": {"input_tokens": 100, "output_tokens": 10},
        }
        data = json.dumps(answer).encode()
        self.send_response(200)
        self.send_header("Content-Length", str(len(data)))
        self.end_headers()
        self.wfile.write(data)


@pytest.fixture
def messages_endpoint() -> Iterator[tuple[str, list[dict[str, Any]]]]:
    bodies: list[dict[str, Any]] = []
    handler = type("Handler", (_Messages,), {"bodies": bodies})
    server = ThreadingHTTPServer(("127.0.0.1", 0), handler)
    server.daemon_threads = True
    thread = threading.Thread(target=server.serve_forever, args=(0.05,), daemon=True)
    thread.start()
    yield f"http://127.0.0.1:{server.server_address[1]}", bodies
    server.shutdown()
    server.server_close()
    thread.join()


def _blocks(body: dict[str, Any]) -> list[dict[str, Any]]:
    return [
        block
        for message in body["messages"]
        for block in (
            message["content"]
            if isinstance(message["content"], list)
            else [{"type": "text", "text": message["content"]}]
        )
    ]


def test_a_claude_episode_sends_one_image_per_request_and_summaries_for_the_rest(
    messages_endpoint: tuple[str, list[dict[str, Any]]], monkeypatch: pytest.MonkeyPatch
) -> None:
    base_url, bodies = messages_endpoint
    config = load_registry().get("claude")
    assert config.single_image and config.provider == "anthropic"
    monkeypatch.setenv(config.api_key_env or "ANTHROPIC_API_KEY", "test-key")
    config = dataclasses.replace(config, base_url=base_url)
    spec = EpisodeSpec("claude", "baseline", "office", 0, modality="vision")
    with AnthropicClient(config, base_url=base_url) as client:
        traj = run_episode(spec, client=client)
    assert traj.status == "terminated" and len(bodies) == STEPS
    for k, body in enumerate(bodies, start=1):
        blocks = _blocks(body)
        assert [b["type"] for b in blocks].count("image") == 1
        assert body["messages"][-1]["content"][-1]["type"] == "image"  # the current frame
        texts = [b["text"] for b in blocks if b["type"] == "text"]
        assert not any("not re-sent" in t or "[Camera" in t for t in texts)
        summaries = [t for t in texts if "as you described it" in t]
        assert len(summaries) == k - 1
        for step, text in enumerate(summaries, start=1):
            observation = f"View {step}: a desk ahead, a chair to the left."
            assert text.endswith(FRAME_SUMMARY.format(step=step, observation=observation))
