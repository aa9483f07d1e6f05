"""The episode loop as tests hand it to ``run_with_cassette``: ``runner(spec, live=...)``, one
model client per model and key mode (a replay's without a key), as the executor keeps them."""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

from pytest_emrd.agent import ChatClient, Registry, make_client
from pytest_emrd.episode import run_episode
from pytest_emrd.trajectory import Trajectory


class AgentRunner:
    def __init__(self, registry: Registry, run: Callable[..., Trajectory] = run_episode) -> None:
        self.registry, self.run = registry, run
        self.clients: dict[tuple[str, bool], ChatClient] = {}

    def __call__(self, spec: Any, *, live: bool, on_step: Any = None) -> Trajectory:
        key = (spec.model, live)
        if key not in self.clients:
            self.clients[key] = make_client(self.registry.get(spec.model), require_key=live)
        client = self.clients[key]
        return self.run(
            spec, registry=self.registry, client=client, on_step=on_step, replay=not live
        )

    def close(self) -> None:
        for client in self.clients.values():
            client.close()
        self.clients.clear()


def agent_runner(
    registry: Registry, *, run: Callable[..., Trajectory] = run_episode
) -> AgentRunner:
    return AgentRunner(registry, run)
