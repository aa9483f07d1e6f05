"""The head of a stored episode: what a run needs to know about it without decoding its
trajectory (file I/O).

Layout, next to :mod:`pytest_emrd.run._store`'s::

    <run>/heads/<case_id>.json    {"episode_sha256": ..., "code": ..., "head": {...}}

An episode file holds every reply of the model verbatim (150-250 KB of JSON for 50 steps of a
real model); reading one back into a :class:`~pytest_emrd.trajectory.Trajectory` costs about
5 ms, and a second run over a finished run directory (a resume) needs, of most episodes, only
whether they may be reused, their status and their token counts. The head holds those facts,
written beside the episode when the store writes it (or first reads it back).

A head is used only while it describes the very episode file stored now, as the current code
would read it: ``episode_sha256`` is the SHA-256 of the episode file's bytes and ``code`` the
:func:`~pytest_emrd.run.code_fingerprint` of the code that reads episode files
(:data:`HEAD_CODE`). A changed episode file, or a reader that would now read it differently (or
refuse it), sends the store back to the file itself, which is then decoded and validated in
full. Same bytes, same reader: the head states what decoding the file gave when the head was
written. Head files are scrubbed like the episodes (an errored episode's error text).
"""

from __future__ import annotations

import functools
import hashlib
import json
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Final

from pytest_emrd._atomic import write_bytes_atomic
from pytest_emrd._scrub import scrub, scrub_bytes
from pytest_emrd._serde import from_versioned_dict, to_dict
from pytest_emrd.errors import ProtocolError
from pytest_emrd.run._fingerprint import code_fingerprint
from pytest_emrd.trajectory import EpisodeSpec, Trajectory, Usage

HEAD_SCHEMA: Final = 1

#: The code that turns an episode file into a trajectory (fingerprinted, not imported).
HEAD_CODE: Final = (
    "pytest_emrd.trajectory",
    "pytest_emrd._serde",
    "pytest_emrd.run._store",
    "pytest_emrd.run._head",
)


@dataclass(frozen=True)
class EpisodeHead:
    """The facts about a stored episode that its store, the terminal summary and the gates'
    bookkeeping read; field names are the head file's format."""

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

    def to_dict(self) -> dict[str, Any]:
        return to_dict(self)

    @classmethod
    def from_dict(cls, data: dict[str, Any]) -> EpisodeHead:
        return from_versioned_dict(
            cls, data, version=HEAD_SCHEMA, what="episode head", remedy="it is rewritten."
        )


def head_path(run_dir: Path, spec: EpisodeSpec) -> Path:
    """Where a run directory keeps the head of ``spec``'s episode."""
    return run_dir / "heads" / f"{spec.case_id}.json"


def file_digest(episode_file: bytes) -> str:
    """The SHA-256 an episode file's head is valid for."""
    return hashlib.sha256(episode_file).hexdigest()


@functools.cache
def reader_code() -> str:
    """The fingerprint of :data:`HEAD_CODE` in this process."""
    return code_fingerprint(HEAD_CODE)


def read_head(episode_file: Path, *, digest: str) -> EpisodeHead | None:
    """The head saved beside ``episode_file`` (``<run>/episodes/<case_id>.json``) for the bytes
    whose SHA-256 is ``digest``, as this code reads them; None when missing, stale or
    unreadable (the caller reads the episode file itself)."""
    try:
        document = json.loads(
            (episode_file.parent.parent / "heads" / episode_file.name).read_bytes()
        )
        if document["episode_sha256"] != digest or document["code"] != reader_code():
            return None
        head = EpisodeHead.from_dict(document["head"])
    except (OSError, ValueError, KeyError, TypeError, ProtocolError):
        return None
    return head if head.spec.case_id == episode_file.stem else None


def write_head(run_dir: Path, head: EpisodeHead, *, digest: str) -> None:
    """Save ``head`` as the head of the episode file whose SHA-256 is ``digest``."""
    document = {"episode_sha256": digest, "code": reader_code(), "head": head.to_dict()}
    blob = json.dumps(document, separators=(",", ":")).encode()
    write_bytes_atomic(head_path(run_dir, head.spec), scrub_bytes(blob, literal_only=True))
