"""The requests a model will be sent, built by the episode's own request builder.

A *sweep* is the first :data:`~pytest_emrd.agent.HISTORY_TURNS` steps of a real episode of
the built-in world whose agent turns right every step: real 512x512 frames, real engine
feedback, the real system prompt of the spec's variant and the real sliding window. The
preflight probe is the sweep's last request (a full window: as many images as an episode
ever sends at once); the token estimate replays the sweep over a whole episode.
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass, replace
from typing import Any, Final

from pytest_emrd.agent import HISTORY_TURNS, Conversation, UserTurn, build_system_prompt
from pytest_emrd.episode import build_simulator, start_world, user_turn
from pytest_emrd.trajectory import EpisodeSpec

SWEEP_ACTION: Final = "Turn(Right)"
#: Characters per text token assumed for estimates (English prose and JSON).
CHARS_PER_TOKEN: Final = 4


def sample_reply(action: str = SWEEP_ACTION) -> str:
    """A reply in the protocol the system prompt asks for (the window's assistant turns)."""
    return json.dumps(
        {
            "observation": "A desk and a chair ahead, a doorway on the right wall.",
            "dedup_check": "Desk_1 and Chair_1 are new; Doorway_1 is already mapped.",
            "cognitive_map": {
                "Desk_1": {"type": "Desk", "room": "Office", "x": 1.2, "z": 2.5, "facing": "-z"},
                "Chair_1": {"type": "Chair", "room": "Office", "x": 1.0, "z": 1.9, "facing": "+z"},
                "Doorway_1": {"type": "Doorway", "room": "Office", "x": 3.1, "z": 0.4},
            },
            "action": action,
            "reasoning": "Sweep the room before leaving it.",
        }
    )


@dataclass(frozen=True)
class Sweep:
    """System prompt and user turns of the first steps of a real episode."""

    system: str
    turns: tuple[UserTurn, ...]
    single_image: bool

    def request(self, step: int, reply: str) -> list[dict[str, Any]]:
        """The messages of step ``step`` (1-based) when every earlier reply was ``reply``.

        Steps past the sweep reuse its turns in turn (same sizes, same number of images).
        """
        conversation = Conversation(self.system, single_image=self.single_image)
        for t in range(max(1, step - HISTORY_TURNS + 1), step):
            conversation.record(self._turn(t), reply)
        return conversation.request(self._turn(step))

    def _turn(self, step: int) -> UserTurn:
        return replace(self.turns[(step - 1) % len(self.turns)], step=step)


def sweep(spec: EpisodeSpec, *, single_image: bool, steps: int = HISTORY_TURNS) -> Sweep:
    """The first ``steps`` user turns of ``spec`` on the built-in world, turning right."""
    sim = build_simulator("builtin")
    try:
        layout, obs = start_world(spec, sim)
        turns = []
        for t in range(1, steps + 1):
            turns.append(user_turn(spec, t, obs))
            obs = sim.step(SWEEP_ACTION)
    finally:
        sim.close()
    system = build_system_prompt(
        layout.inventory(), spec.variant, modality=spec.modality, max_steps=spec.max_steps
    )
    return Sweep(system, tuple(turns), single_image)


def count_images(messages: list[dict[str, Any]]) -> int:
    """Image parts in OpenAI-format messages."""
    return sum(
        1
        for m in messages
        if isinstance(m["content"], list)
        for part in m["content"]
        if part.get("type") == "image_url"
    )


def request_tokens(messages: list[dict[str, Any]], *, image_tokens: int) -> int:
    """Estimated prompt tokens: text characters / :data:`CHARS_PER_TOKEN`, plus
    ``image_tokens`` per image (the registry's figure for the provider)."""
    chars = 0
    for m in messages:
        content = m["content"]
        parts = content if isinstance(content, list) else [{"type": "text", "text": content}]
        chars += sum(len(p["text"]) for p in parts if p.get("type") == "text")
    return math.ceil(chars / CHARS_PER_TOKEN) + image_tokens * count_images(messages)
