"""Fixtures for the episode-loop tests: a scripted in-process chat client."""

from __future__ import annotations

import json
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import pytest

from pytest_emrd.agent import ChatResponse
from pytest_emrd.errors import TransportError
from pytest_emrd.trajectory import Usage


@dataclass
class ScriptedClient:
    """Replies from a list (the last one repeats); ``fail_at`` raises TransportError there."""

    replies: list[str]
    fail_at: int | None = None
    requests: list[list[dict[str, Any]]] = field(default_factory=list)
    closed: bool = False

    def complete(self, messages: list[dict[str, Any]]) -> ChatResponse:
        self.requests.append(messages)
        n = len(self.requests)
        if self.fail_at is not None and n >= self.fail_at:
            raise TransportError("POST http://model/v1/chat/completions failed after 5 attempt(s)")
        return ChatResponse(self.replies[min(n, len(self.replies)) - 1], Usage(100, 10))

    def close(self) -> None:
        self.closed = True


def protocol_reply(action: str, cmap: dict[str, Any] | None = None, **extra: Any) -> str:
    """A well-formed reply in the EMRD JSON protocol."""
    return json.dumps(
        {
            "observation": "",
            "dedup_check": "",
            "cognitive_map": cmap or {},
            "action": action,
            **extra,
        }
    )


@pytest.fixture
def scripted() -> Callable[..., ScriptedClient]:
    return ScriptedClient


@pytest.fixture
def reply() -> Callable[..., str]:
    return protocol_reply


@pytest.fixture(scope="session")
def fake_thor() -> Any:
    """The fake THOR controller class of ``tests/world/thor/conftest.py`` (loaded by path)."""
    import importlib.util
    import sys
    from pathlib import Path

    path = Path(__file__).resolve().parents[1] / "world" / "thor" / "conftest.py"
    spec = importlib.util.spec_from_file_location("emrd_episode_thor_fakes", path)
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = module  # dataclasses resolve annotations through sys.modules
    spec.loader.exec_module(module)
    return module.FakeController
