"""The head of a stored episode: what a run needs to know about it without decoding its
trajectory (pure). It is the first line of the episode file (:mod:`pytest_emrd.run._store`),
written with the trajectory in one atomic write: it cannot describe another file."""

from __future__ import annotations

from dataclasses import dataclass, replace
from typing import Any, Final

from pytest_emrd._scrub import scrub
from pytest_emrd._serde import from_versioned_dict, to_dict
from pytest_emrd.trajectory import EpisodeSpec, Trajectory, Usage

HEAD_SCHEMA: Final = 1


@dataclass(frozen=True)
class EpisodeHead:
    """The facts about a stored episode that its store, the terminal summary and the gates'
    bookkeeping read; field names are the episode file's format."""

    spec: EpisodeSpec
    protocol: str
    """World + prompt protocol version the episode ran under."""
    status: str
    """``terminated``, ``budget`` or ``errored``."""
    steps: int
    """Decision cycles recorded."""
    chosen_room: str | None
    final_map_entries: int
    """Entries of the terminal cognitive map (0: the map figure cannot show this episode)."""
    usage: Usage
    """Token usage summed over the steps."""
    error: str | None
    """The stored (scrubbed) error text of an errored episode."""
    session: str
    """Id of the pytest session that computed it."""
    recorded: bool
    """New model traffic was recorded for it (a live episode)."""
    frame_drift: int
    seconds: float
    retries: int
    """Model requests retried while it was computed."""
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
        """Whether this head states what ``trajectory`` holds (the facts about how it was
        obtained, and the error text as scrubbed when it was stored, are the head's own)."""
        facts = {k: getattr(self, k) for k in ("session", "recorded", "frame_drift", "retries")}
        head = EpisodeHead.of(trajectory, seconds=self.seconds, **facts)
        return replace(head, error=self.error) == self

    def to_dict(self) -> dict[str, Any]:
        return to_dict(self)

    @classmethod
    def from_dict(cls, data: dict[str, Any]) -> EpisodeHead:
        return from_versioned_dict(
            cls, data, version=HEAD_SCHEMA, what="episode head", remedy="it is recomputed."
        )
