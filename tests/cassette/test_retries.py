"""A replay re-enacts only the replies that counted: no retry, no backoff sleep."""

from __future__ import annotations

import json
import logging
import lzma
import random
from dataclasses import dataclass, field
from pathlib import Path

import pytest

from pytest_emrd.agent import ModelConfig, OpenAICompatibleClient, RetryPolicy
from pytest_emrd.cassette import cassette_path
from pytest_emrd.trajectory import EpisodeSpec, Trajectory
from tests._episodes import run_with_cassette

from .conftest import PROTOCOL, FakeServer, trajectory

DEEP = b"[" * 100_000 + b"]" * 100_000


@dataclass
class ClientRunner:
    """Three model requests through the product's client (its retries and backoff)."""

    base_url: str
    sleeps: list[float] = field(default_factory=list)

    def __call__(self, spec: EpisodeSpec, *, live: bool) -> Trajectory:
        config = ModelConfig(
            name="fake", provider="openai", model_id="m", base_url=self.base_url, max_retries=3
        )
        policy = RetryPolicy(max_retries=3, sleep=self.sleeps.append, rng=random.Random(7))
        replies: list[str] = []
        client = OpenAICompatibleClient(
            config, base_url=self.base_url, policy=policy, require_key=False
        )
        try:
            with client:
                for t in range(3):
                    messages = [{"role": "user", "content": f"Step {t + 1} of 3"}]
                    replies.append(client.complete(messages).text)
        except Exception as exc:
            return trajectory(spec, replies, error=f"{type(exc).__name__}: {exc}")
        return trajectory(spec, replies)


def _run(spec: EpisodeSpec, runner: ClientRunner, root: Path, mode: str):
    return run_with_cassette(spec, runner, cassettes=root, protocol=PROTOCOL, record_mode=mode)


@pytest.mark.parametrize(
    "unreadable",
    [[b""], [b"{not json"], [DEEP], [b'{"choices": []}'], [b"", b"{not json"]],
    ids=["empty", "invalid-json", "nested-100000-deep", "wrong-shape", "twice"],
)
def test_a_retried_unreadable_reply_is_not_stored_and_not_replayed(
    server: FakeServer, spec: EpisodeSpec, tmp_path: Path, caplog, unreadable: list[bytes]
) -> None:
    server.unreadable_next = list(unreadable)
    live = ClientRunner(f"{server.url}/v1")
    recorded = _run(spec, live, tmp_path, "once")
    assert recorded.trajectory.status == "budget" and recorded.recorded
    assert len(live.sleeps) == len(unreadable)  # retried (and slept) while recording
    document = json.loads(lzma.decompress(cassette_path(tmp_path, spec).read_bytes()))
    bodies = [i["response"]["body"]["string"] for i in document["interactions"]]
    assert len(bodies) == 3 and all(json.loads(b)["choices"] for b in bodies)

    caplog.clear()
    replay = ClientRunner(f"{server.url}/v1")
    with caplog.at_level(logging.WARNING, logger="pytest_emrd.agent.retry"):
        again = _run(spec, replay, tmp_path, "none")
    assert again.trajectory == recorded.trajectory and not again.recorded
    assert replay.sleeps == [] and not caplog.records
