"""The requests a model will be sent, and what a live grid of them will cost.

A *sweep* (:class:`Sweep`) is the first :data:`~pytest_emrd.agent.HISTORY_TURNS` steps of a
real episode of the built-in world whose agent turns right every step: real 512x512 frames,
real feedback, the real system prompt and sliding window. The preflight probe is its last
request (a full window: as many images as an episode ever sends at once).

For each step of an episode that uses its whole budget (an upper bound), the request the
loop would send is built and its prompt tokens estimated as text characters / 4 plus the
registry's ``image_tokens`` per frame; replies are :data:`DEFAULT_COMPLETION_TOKENS` long
until a probe measured one. An answered probe calibrates the estimate: every prompt figure
is scaled by ``measured / estimated`` for the probe request, and its reply gives the
completion tokens per step and the replies in the window. The server's count is not taken
on trust: when it and ours differ by more than :data:`TRUSTED_RATIO` either way, the
estimate keeps ours and says why (:attr:`CostEstimate.warning`). Completion tokens and cost
are given twice: expected, and the bound ``max_tokens`` puts on every reply.
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


def sample_reply() -> str:
    """A reply in the protocol the system prompt asks for (the window's assistant turns).

    :returns: The reply text.
    """
    return json.dumps(
        {
            "observation": "A desk and a chair ahead, a doorway on the right wall.",
            "dedup_check": "Desk_1 and Chair_1 are new; Doorway_1 is already mapped.",
            "cognitive_map": {
                "Desk_1": {"type": "Desk", "room": "Office", "x": 1.2, "z": 2.5, "facing": "-z"},
                "Chair_1": {"type": "Chair", "room": "Office", "x": 1.0, "z": 1.9, "facing": "+z"},
                "Doorway_1": {"type": "Doorway", "room": "Office", "x": 3.1, "z": 0.4},
            },
            "action": SWEEP_ACTION,
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
        """The messages of step ``step`` (1-based) when every earlier reply was ``reply``;
        steps past the sweep reuse its turns in turn (same sizes, same number of images)."""
        conversation = Conversation(self.system, single_image=self.single_image)
        for t in range(max(1, step - HISTORY_TURNS + 1), step):
            conversation.record(self._turn(t), reply)
        return conversation.request(self._turn(step))

    def _turn(self, step: int) -> UserTurn:
        return replace(self.turns[(step - 1) % len(self.turns)], step=step)


def sweep(spec: EpisodeSpec, *, single_image: bool) -> Sweep:
    """The first :data:`~pytest_emrd.agent.HISTORY_TURNS` user turns of ``spec`` on the
    built-in world, turning right.

    :param spec: The episode whose modality, variant and budget apply.
    :param single_image: Whether each request carries only the newest frame.
    :returns: The :class:`Sweep`: system prompt and user turns.
    """
    sim = build_simulator("builtin")
    try:
        layout, obs = start_world(spec, sim)
        turns = []
        for t in range(1, HISTORY_TURNS + 1):
            turns.append(user_turn(spec, t, obs))
            obs = sim.step(SWEEP_ACTION)
    finally:
        sim.close()
    system = build_system_prompt(
        layout.inventory(), spec.variant, modality=spec.modality, max_steps=spec.max_steps
    )
    return Sweep(system, tuple(turns), single_image)


def _parts(message: dict[str, Any]) -> list[dict[str, Any]]:
    content = message["content"]
    return content if isinstance(content, list) else [{"type": "text", "text": content}]


def count_images(messages: list[dict[str, Any]]) -> int:
    """Image parts in OpenAI-format messages.

    :param messages: The chat messages.
    :returns: The number of image parts.
    """
    return sum(part.get("type") == "image_url" for m in messages for part in _parts(m))


def request_tokens(messages: list[dict[str, Any]], *, image_tokens: int) -> int:
    """Estimated prompt tokens: text characters / :data:`CHARS_PER_TOKEN`, plus
    ``image_tokens`` per image (the registry's figure for the provider).

    :param messages: The chat messages of one request.
    :param image_tokens: Tokens charged per image.
    :returns: The estimate.
    """
    chars = sum(len(p["text"]) for m in messages for p in _parts(m) if p.get("type") == "text")
    return math.ceil(chars / CHARS_PER_TOKEN) + image_tokens * count_images(messages)


#: Assumed completion tokens per step before a probe measured one: a 20-object cognitive
#: map (about 75 characters an entry) and a few sentences, without hidden reasoning.
DEFAULT_COMPLETION_TOKENS: Final = 500
#: The server's prompt count calibrates ours only within this factor either way.
TRUSTED_RATIO: Final = 4.0


@dataclass(frozen=True)
class Measured:
    """What one answered probe request showed about the provider's token counts."""

    prompt_tokens: int
    """Prompt tokens the provider billed for the probe request."""
    estimated_prompt_tokens: int
    """Our static estimate for the same request (the calibration's denominator)."""
    completion_tokens: int
    reply: str
    seconds: float
    """Wall time of the probe call."""


@dataclass(frozen=True)
class CostEstimate:
    """Tokens and cost of one model's live episodes, an upper bound (every step used)."""

    model: str
    episodes: int
    steps: int
    """Steps per episode assumed (the action budget)."""
    prompt_tokens: int
    completion_tokens: int
    """Expected completion tokens (the probe's reply length per step, or the default)."""
    peak_request_tokens: int
    """Prompt tokens of the largest request (a full window): what the context must hold."""
    cost_usd: float | None
    """Expected cost; ``None`` when the registry has no prices (self-hosted models)."""
    basis: str
    """``registry`` (static figures) or ``probe`` (calibrated by an answered probe)."""
    model_hours: float | None = None
    """Hours of model calls at the probe's latency, one call at a time (``None`` unprobed)."""
    completion_bound: int = 0
    """Completion tokens if every reply used ``max_tokens``: the most the grid can bill."""
    max_tokens: int = 0
    """The registry's ``max_tokens`` behind :attr:`completion_bound`."""
    cost_bound_usd: float | None = None
    """Cost with :attr:`completion_bound` completion tokens (``None`` without prices)."""
    warning: str | None = None
    """Why the server's token count was not used (it differs from ours by more than
    :data:`TRUSTED_RATIO`), else ``None``."""

    def line(self) -> str:
        """``240 episodes x <= 50 steps: <= 38.1 M prompt + ~6.0 M completion tokens
        (<= 49.2 M at max_tokens 4096), ~$X (<= $Y) ...``."""
        cost = "no price in the registry"
        if self.cost_usd is not None and self.cost_bound_usd is not None:
            cost = f"~${self.cost_usd:,.2f} expected, <= ${self.cost_bound_usd:,.2f}"
        hours = "" if self.model_hours is None else f", <= {_duration(self.model_hours)} of calls"
        return (
            f"{self.episodes} episodes x <= {self.steps} steps: <= {_tokens(self.prompt_tokens)} "
            f"prompt + ~{_tokens(self.completion_tokens)} completion tokens expected (<= "
            f"{_tokens(self.completion_bound)} at max_tokens {self.max_tokens:,}), {cost}{hours} "
            f"({self.basis} estimate; largest request ~{self.peak_request_tokens:,} tokens)"
        )


def _tokens(n: int) -> str:
    return f"{n / 1e6:,.1f} M" if n >= 1_000_000 else f"{n:,}"


def _duration(hours: float) -> str:
    return f"{hours:,.1f} h" if hours >= 1 else f"{max(hours * 60, 1):.0f} min"


def estimate_cost(
    config: Any,
    sweep: Sweep,
    *,
    episodes: int,
    max_steps: int,
    measured: Measured | None = None,
) -> CostEstimate:
    """Estimate ``episodes`` live episodes of ``config`` (a ``ModelConfig``) of ``max_steps``."""
    warning = None
    if measured is None:
        completion = DEFAULT_COMPLETION_TOKENS
        reply = "x" * (DEFAULT_COMPLETION_TOKENS * CHARS_PER_TOKEN)
        scale = 1.0
    else:
        completion, reply = max(measured.completion_tokens, 1), measured.reply
        scale = max(measured.prompt_tokens, 0) / max(measured.estimated_prompt_tokens, 1)
        if not 1 / TRUSTED_RATIO <= scale <= TRUSTED_RATIO:
            ratio = "0x" if scale == 0 else f"{scale:.2g}x ours"
            warning = (
                f"the server reported {measured.prompt_tokens:,} prompt tokens for the probe, "
                f"our count of its text and frames is {measured.estimated_prompt_tokens:,} "
                f"(the server's is {ratio}): more than {TRUSTED_RATIO:g}x apart, so the estimate "
                f"uses our count; check image_tokens for {config.name!r} in the registry, or the "
                "server's usage report"
            )
            scale = 1.0
    completion = min(completion, config.max_tokens)
    per_step = [
        request_tokens(sweep.request(t, reply), image_tokens=config.image_tokens)
        for t in range(1, max_steps + 1)
    ]
    prompt = round(sum(per_step) * scale) * episodes
    completion_total = completion * max_steps * episodes
    bound = config.max_tokens * max_steps * episodes
    cost = cost_bound = None
    if config.price_per_mtok_in is not None and config.price_per_mtok_out is not None:
        price_in, price_out = config.price_per_mtok_in, config.price_per_mtok_out
        cost = (prompt * price_in + completion_total * price_out) / 1e6
        cost_bound = (prompt * price_in + bound * price_out) / 1e6
    return CostEstimate(
        model=config.name,
        episodes=episodes,
        steps=max_steps,
        prompt_tokens=prompt,
        completion_tokens=completion_total,
        peak_request_tokens=round(max(per_step) * scale),
        cost_usd=cost,
        basis="probe" if measured is not None and warning is None else "registry",
        model_hours=None if measured is None else measured.seconds * max_steps * episodes / 3600,
        completion_bound=bound,
        max_tokens=config.max_tokens,
        cost_bound_usd=cost_bound,
        warning=warning,
    )
