"""What a run knows about an episode without decoding its trajectory (pure): its head, the
first line of the episode file (:mod:`pytest_emrd.run._store`, written with the trajectory
in one atomic write: it cannot describe another file), and what the terminal reports."""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import dataclass, replace
from typing import TYPE_CHECKING, Final

from pytest_emrd._scrub import scrub
from pytest_emrd._serde import JsonRecord, Schema
from pytest_emrd.gate._table import UsageRow
from pytest_emrd.trajectory import EpisodeSpec, Trajectory, Usage

if TYPE_CHECKING:
    from pytest_emrd.run._store import StoredEpisode

HEAD_SCHEMA: Final = 1


@dataclass(frozen=True)
class EpisodeHead(JsonRecord):
    """The facts about a stored episode a run reads; field names are the file's format."""

    schema = Schema(HEAD_SCHEMA, "episode head", "it is recomputed.")

    spec: EpisodeSpec
    protocol: str
    """World + prompt protocol version the episode ran under."""
    status: str
    """``terminated``, ``budget`` or ``errored``."""
    steps: int
    chosen_room: str | None
    final_map_entries: int
    """Entries of the terminal cognitive map (0: the map figure cannot show this episode)."""
    usage: Usage
    error: str | None
    """The stored (scrubbed) error text of an errored episode."""
    session: str
    recorded: bool
    """New model traffic was recorded for it (a live episode)."""
    frame_drift: int
    seconds: float
    retries: int
    schema_version: int = HEAD_SCHEMA

    @classmethod
    def of(
        cls,
        trajectory: Trajectory,
        *,
        session: str,
        recorded: bool,
        frame_drift: int,
        seconds: float,
        retries: int = 0,
    ) -> EpisodeHead:
        return cls(
            spec=trajectory.spec,
            protocol=trajectory.protocol,
            status=trajectory.status,
            steps=len(trajectory.steps),
            chosen_room=trajectory.chosen_room,
            final_map_entries=len(trajectory.final_map),
            usage=trajectory.usage,
            error=scrub(trajectory.error) if trajectory.error else trajectory.error,
            session=session,
            recorded=recorded,
            frame_drift=frame_drift,
            seconds=round(seconds, 3),
            retries=retries,
        )

    def describes(self, trajectory: Trajectory) -> bool:
        """Whether this head states what ``trajectory`` holds (how it was obtained aside)."""
        facts = {k: getattr(self, k) for k in ("session", "recorded", "frame_drift", "retries")}
        head = EpisodeHead.of(trajectory, seconds=self.seconds, **facts)
        return replace(head, error=self.error) == self


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
