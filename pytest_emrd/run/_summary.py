"""What the terminal reports about a stored episode: its summary (the :class:`EpisodeHead`, the
first line of the episode file, and its cost) and the usage table per model."""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import dataclass

from pytest_emrd._serde import JsonRecord
from pytest_emrd.gate import UsageRow
from pytest_emrd.run._store import EpisodeHead, StoredEpisode


@dataclass(frozen=True)
class EpisodeSummary(JsonRecord):
    """What travels from an xdist worker to the controller: an episode's head and cost."""

    head: EpisodeHead
    cost_usd: float | None
    """Estimated from the registry's prices per million tokens; ``None`` without prices."""

    @classmethod
    def of(
        cls, stored: StoredEpisode, *, price_in: float | None, price_out: float | None
    ) -> EpisodeSummary:
        usage, cost = stored.head.usage, None
        if price_in is not None and price_out is not None:
            cost = (usage.prompt_tokens * price_in + usage.completion_tokens * price_out) / 1e6
        return cls(stored.head, cost)

    def progress_line(self, done: int) -> str:
        """``emrd [12] scout-baseline-office-ep03: terminated after 23 steps, ...``."""
        head = self.head
        tokens = head.usage.prompt_tokens + head.usage.completion_tokens
        cost = "" if self.cost_usd is None else f", ${self.cost_usd:.3f}"
        retries = f", {head.retries} retr{'y' if head.retries == 1 else 'ies'}" * (head.retries > 0)
        return (
            f"emrd [{done}] {head.spec.case_id}: {head.status} after {head.steps} steps, chose "
            f"{head.chosen_room or '-'}, {tokens:,} tokens{cost}{retries}, {head.seconds:.1f} s"
        )


def usage_rows(summaries: Iterable[EpisodeSummary]) -> list[UsageRow]:
    """Tokens, cost (``None`` once an episode has no price), retries and errors per model.

    :param summaries: Every episode's :class:`EpisodeSummary`.
    :returns: One :class:`UsageRow` per model, sorted by model.
    """
    rows: dict[str, UsageRow] = {}
    for s in summaries:
        head, model = s.head, s.head.spec.model
        row = rows.get(model) or UsageRow(model, 0, 0, 0, 0.0)
        known = row.cost_usd is not None and s.cost_usd is not None
        rows[model] = UsageRow(
            model,
            row.episodes + 1,
            row.prompt_tokens + head.usage.prompt_tokens,
            row.completion_tokens + head.usage.completion_tokens,
            (row.cost_usd or 0.0) + (s.cost_usd or 0.0) if known else None,
            retries=row.retries + head.retries,
            errors=row.errors + (head.status == "errored"),
        )
    return [rows[m] for m in sorted(rows)]
