"""The executor keeps one client per model and key mode, and closes them when it closes."""

from __future__ import annotations

from pathlib import Path

import pytest

import pytest_emrd.episode
from pytest_emrd.agent import load_registry
from pytest_emrd.cassette import canonical_body
from pytest_emrd.episode import Executor


class _Client:
    def __init__(self, name: str, require_key: bool) -> None:
        self.name, self.require_key, self.closed = name, require_key, False

    def close(self) -> None:
        self.closed = True


@pytest.fixture
def built(monkeypatch) -> list[_Client]:
    clients: list[_Client] = []

    def make_client(config, *, base_url=None, require_key=True, deadline=True, encode=None):
        # a replay's client: no key, no deadline, requests in their recorded form
        assert deadline == require_key == (encode is not canonical_body)
        clients.append(_Client(config.name, require_key))
        return clients[-1]

    monkeypatch.setattr(pytest_emrd.episode, "make_client", make_client)
    return clients


def test_one_client_per_model_and_key_mode_serves_every_episode(built):
    runner = Executor(load_registry(), cassettes=Path("cassettes"), protocol="p")
    for _ in range(3):
        runner._client("scout", False)
    runner._client("scout", True)
    assert [(c.name, c.require_key) for c in built] == [("scout", False), ("scout", True)]


def test_clients_close_with_the_executor(built):
    runner = Executor(load_registry(), cassettes=Path("cassettes"), protocol="p")
    runner._client("scout", False)
    runner.close()
    assert [c.closed for c in built] == [True]
