"""A flaky OpenAI-compatible endpoint on 127.0.0.1: the reference agents behind HTTP 503s.

The chat requests numbered in ``fail_on`` (1-based) are answered 503 (retried by the
client), every other one by the reference agent named in the request, so an episode
against it records normally with a known number of retries.
"""

from __future__ import annotations

import json
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import pytest

from pytest_emrd.agent import load_registry
from pytest_emrd.reference import complete


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
def flaky(json_server) -> Flaky:
    state = Flaky()
    registry = load_registry()

    def answer(method: str, path: str, body: Any) -> tuple[int, dict[str, Any]]:
        if method == "GET":
            return 200, {"object": "list", "data": [{"id": "scout", "object": "model"}]}
        state.seen += 1
        if state.seen in state.fail_on:
            return 503, {"error": {"message": "overloaded, try again"}}
        return 200, complete(body, registry)

    state.base_url = json_server(answer)
    return state
