"""What a live grid will cost: tokens from our own requests, dollars from registry prices.

For each step ``t`` of an episode that uses its whole budget (an upper bound: real episodes
often ``Term`` earlier), the request the episode loop would send is built
(:class:`~pytest_emrd.preflight._requests.Sweep`) and its prompt tokens estimated as text
characters / 4 plus the registry's ``image_tokens`` per frame. Replies are assumed to be
:data:`DEFAULT_COMPLETION_TOKENS` long until a probe measured one.

When a probe call was answered, the provider's own count calibrates the estimate: every
prompt figure is scaled by ``measured / estimated`` for the probe request (a full window,
so the mix of text and images matches the steps that dominate the total), and the probe's
reply gives the completion tokens per step and the size of the replies in the window.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Final

from pytest_emrd._serde import to_dict
from pytest_emrd.preflight._requests import CHARS_PER_TOKEN, Sweep, request_tokens

#: Assumed completion tokens per step before a probe measured one: a 20-object cognitive
#: map (about 75 characters an entry) and a few sentences, without hidden reasoning.
DEFAULT_COMPLETION_TOKENS: Final = 500


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
    peak_request_tokens: int
    """Prompt tokens of the largest request (a full window): what the context must hold."""
    cost_usd: float | None
    """``None`` when the registry has no prices (self-hosted models)."""
    basis: str
    """``registry`` (static figures) or ``probe`` (calibrated by an answered probe)."""
    model_hours: float | None = None
    """Hours of model calls at the probe's latency, one call at a time (``None`` unprobed)."""

    def line(self) -> str:
        """``240 episodes x <= 50 steps: <= 38.1 M prompt + 6.0 M completion tokens, ...``."""
        cost = "no price in the registry" if self.cost_usd is None else f"<= ${self.cost_usd:,.2f}"
        hours = "" if self.model_hours is None else f", <= {_duration(self.model_hours)} of calls"
        return (
            f"{self.episodes} episodes x <= {self.steps} steps: <= {_tokens(self.prompt_tokens)} "
            f"prompt + {_tokens(self.completion_tokens)} completion tokens, {cost}{hours} "
            f"({self.basis} estimate; largest request ~{self.peak_request_tokens:,} tokens)"
        )

    def to_dict(self) -> dict[str, Any]:
        return to_dict(self)


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
    if measured is None:
        completion = DEFAULT_COMPLETION_TOKENS
        reply = "x" * (DEFAULT_COMPLETION_TOKENS * CHARS_PER_TOKEN)
        scale = 1.0
    else:
        completion, reply = max(measured.completion_tokens, 1), measured.reply
        scale = measured.prompt_tokens / max(measured.estimated_prompt_tokens, 1)
    per_step = [
        request_tokens(sweep.request(t, reply), image_tokens=config.image_tokens)
        for t in range(1, max_steps + 1)
    ]
    prompt = round(sum(per_step) * scale) * episodes
    completion_total = completion * max_steps * episodes
    cost = None
    if config.price_per_mtok_in is not None and config.price_per_mtok_out is not None:
        cost = (
            prompt * config.price_per_mtok_in + completion_total * config.price_per_mtok_out
        ) / 1e6
    return CostEstimate(
        model=config.name,
        episodes=episodes,
        steps=max_steps,
        prompt_tokens=prompt,
        completion_tokens=completion_total,
        peak_request_tokens=round(max(per_step) * scale),
        cost_usd=cost,
        basis="registry" if measured is None else "probe",
        model_hours=None if measured is None else measured.seconds * max_steps * episodes / 3600,
    )
