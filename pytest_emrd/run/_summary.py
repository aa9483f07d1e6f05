"""What the terminal reports about episodes: one summary per episode, progress, usage (pure)."""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import dataclass
from typing import Any

from pytest_emrd._serde import from_dict, to_dict
from pytest_emrd.gate._table import UsageRow
from pytest_emrd.run._store import StoredEpisode


@dataclass(frozen=True)
class EpisodeSummary:
    """The few facts about an episode that travel from an xdist worker to the controller."""

    case: str
    model: str
    status: str
    steps: int
    chosen_room: str | None
    prompt_tokens: int
    completion_tokens: int
    cost_usd: float | None
    """Estimated from the registry's prices per million tokens; ``None`` without prices."""
    recorded: bool
    seconds: float
    retries: int = 0
    """Model requests retried while the episode was computed."""

    @classmethod
    def of(
        cls, stored: StoredEpisode, *, price_in: float | None, price_out: float | None
    ) -> EpisodeSummary:
        head, usage = stored.head, stored.head.usage
        cost = None
        if price_in is not None and price_out is not None:
            cost = (usage.prompt_tokens * price_in + usage.completion_tokens * price_out) / 1e6
        return cls(
            case=head.spec.case_id,
            model=head.spec.model,
            status=head.status,
            steps=head.steps,
            chosen_room=head.chosen_room,
            prompt_tokens=usage.prompt_tokens,
            completion_tokens=usage.completion_tokens,
            cost_usd=cost,
            recorded=stored.recorded,
            seconds=stored.seconds,
            retries=stored.retries,
        )

    def progress_line(self, done: int) -> str:
        """``emrd [12] scout-baseline-office-ep03: terminated after 23 steps, ...``."""
        tokens = self.prompt_tokens + self.completion_tokens
        cost = "" if self.cost_usd is None else f", ${self.cost_usd:.3f}"
        retries = f", {self.retries} retr{'y' if self.retries == 1 else 'ies'}" * (self.retries > 0)
        return (
            f"emrd [{done}] {self.case}: {self.status} after {self.steps} steps, chose "
            f"{self.chosen_room or '-'}, {tokens:,} tokens{cost}{retries}, {self.seconds:.1f} s"
        )

    def to_dict(self) -> dict[str, Any]:
        return to_dict(self)

    @classmethod
    def from_dict(cls, data: dict[str, Any]) -> EpisodeSummary:
        return from_dict(cls, data)


def usage_rows(summaries: Iterable[EpisodeSummary]) -> list[UsageRow]:
    """Tokens, cost, retries and errored episodes per model (cost ``None`` as soon as one
    episode has no price)."""
    rows: dict[str, UsageRow] = {}
    for s in summaries:
        row = rows.get(s.model) or UsageRow(s.model, 0, 0, 0, 0.0)
        known = row.cost_usd is not None and s.cost_usd is not None
        rows[s.model] = UsageRow(
            s.model,
            row.episodes + 1,
            row.prompt_tokens + s.prompt_tokens,
            row.completion_tokens + s.completion_tokens,
            (row.cost_usd or 0.0) + (s.cost_usd or 0.0) if known else None,
            retries=row.retries + s.retries,
            errors=row.errors + (s.status == "errored"),
        )
    return [rows[m] for m in sorted(rows)]
