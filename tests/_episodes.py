"""Episodes run the way tests need them: :func:`run_with_cassette` runs a loop of the test's
own in the product's cassette handling; :func:`agent_runner` is the real loop as such a
``runner(spec, live=...)``, one model client per model and key mode (a replay's without a
key), as the executor keeps them."""

from __future__ import annotations

import json
from collections.abc import Callable
from typing import Any

from perf import run_with_cassette
from pytest_emrd.agent import ChatClient, Registry
from pytest_emrd.cassette import LATENCY, decompress
from pytest_emrd.episode import episode_client, run_episode
from pytest_emrd.trajectory import Trajectory

__all__ = ["AgentRunner", "agent_runner", "run_with_cassette", "traffic"]


class AgentRunner:
    def __init__(self, registry: Registry, run: Callable[..., Trajectory] = run_episode) -> None:
        self.registry, self.run = registry, run
        self.clients: dict[tuple[str, bool], ChatClient] = {}

    def __call__(self, spec: Any, *, live: bool, on_step: Any = None) -> Trajectory:
        key = (spec.model, live)
        if key not in self.clients:
            self.clients[key] = episode_client(self.registry.get(spec.model), live=live)
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


def traffic(blob: bytes) -> tuple[str, list[dict[str, Any]]]:
    """A cassette's protocol and interactions without the latencies a live recording measured
    (which differ between two recordings of the same traffic)."""
    document = json.loads(decompress(blob))
    for interaction in document["interactions"]:
        interaction["response"].pop(LATENCY)
    return document["metadata"]["emrd"]["protocol"], document["interactions"]
