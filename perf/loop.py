"""``python -m perf loop``: the episode loop's own cost.

* ``loop.step_overhead_ms`` — one decision cycle of the loop with the model and the
  renderer taken out: user text, JPEG data URL, windowed request, frame registration,
  request-body encoding, reply parsing, Term resolution and step bookkeeping. Observations
  and replies are recorded once from a real scout episode on the builtin world, then
  replayed instantly, so the figure is the loop's code and nothing else. Target 5 ms.
* ``loop.episode_s`` — a full episode (50-action budget) of the ``scout`` reference agent
  on the builtin world against the local reference server: world, rendering, HTTP and
  agent included. Target 2 s.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

from perf import Figure, median_seconds
from pytest_emrd import world
from pytest_emrd._wire import encode_body
from pytest_emrd.agent import (
    ChatClient,
    ChatResponse,
    Conversation,
    build_system_prompt,
    load_registry,
)
from pytest_emrd.episode import _Run, run_episode
from pytest_emrd.trajectory import EpisodeSpec
from pytest_emrd.world._model import Observation, WorldPose

SPEC = EpisodeSpec(model="scout", condition="baseline", spawn="office", episode=0, modality="both")


@dataclass
class _Recorder:
    """Wraps a real client and simulator, keeping what they returned."""

    client: ChatClient
    replies: list[ChatResponse] = field(default_factory=list)
    sent: list[list[dict[str, Any]]] = field(default_factory=list)
    """The messages of every request (the loop's own dicts, shared across windows)."""

    def complete(self, messages: list[dict[str, Any]]) -> ChatResponse:
        response = self.client.complete(messages)
        self.sent.append(messages)
        self.replies.append(response)
        return response

    def close(self) -> None:
        self.client.close()


@dataclass
class _Replay:
    """Simulator and client that answer instantly from a recording (no model, no renderer)."""

    observations: list[Observation]
    replies: list[ChatResponse]
    room: str
    visible: tuple[str, ...]
    i: int = 0

    def complete(self, messages: list[dict[str, Any]]) -> ChatResponse:
        encode_body({"model": "bench", "messages": messages})  # the client's body encoding
        return self.replies[self.i % len(self.replies)]

    def step(self, action: str) -> Observation:
        self.i += 1
        return self.observations[self.i % len(self.observations)]

    def current_room(self) -> str:
        return self.room

    def visible_ids(self) -> tuple[str, ...]:
        return self.visible

    def close(self) -> None:
        """Nothing to release."""

    spawn_pose = WorldPose(0.0, 0.0, 0.0)
    agent_pose = spawn_pose


def _record() -> tuple[list[Observation], list[ChatResponse], str]:
    """Observations and replies of one real scout episode (its system prompt too)."""
    from pytest_emrd.agent import make_client
    from pytest_emrd.reference import base_url_of

    episode = world.episode_world(SPEC)
    sim = world.make_simulator("builtin")
    obs = sim.reset(episode.layout, SPEC.condition, episode.spawn_room, episode.seed)
    system = build_system_prompt(episode.layout.inventory(), SPEC.variant, modality=SPEC.modality)
    config = load_registry().get(SPEC.model)
    recorder = _Recorder(make_client(config, base_url=base_url_of(config)))
    run = _Run(SPEC, sim, Conversation(system, single_image=False), replay=False)
    observations = [obs]
    try:
        for t in range(1, SPEC.max_steps + 1):
            _, obs = run.step(t, obs, recorder)
            observations.append(obs)
            if obs.done:
                break
    finally:
        recorder.close()
        sim.close()
    return observations[:-1], recorder.replies, system


def run(*, repeat: int, warmup: int) -> list[Figure]:
    """Both figures; the episode is timed first, so that cold it is a fresh process's first
    episode against the reference server, as a user first meets it."""
    episode_s = median_seconds(lambda: run_episode(SPEC), repeat=repeat, warmup=warmup)
    observations, replies, system = _record()
    steps = len(replies)
    replay = _Replay(observations, replies, room="Office", visible=("Desk_1",))

    def loop_steps() -> None:
        replay.i = 0
        loop = _Run(SPEC, replay, Conversation(system, single_image=False), replay=False)
        obs = observations[0]
        for t in range(1, steps + 1):
            _, obs = loop.step(t, obs, replay)

    per_step_ms = median_seconds(loop_steps, repeat=repeat, warmup=warmup) / steps * 1000.0
    return [
        Figure("loop.step_overhead_ms", round(per_step_ms, 3), "ms", 5.0, repeat),
        Figure("loop.episode_s", round(episode_s, 3), "s", 2.0, repeat),
    ]
