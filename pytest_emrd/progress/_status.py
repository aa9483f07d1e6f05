"""Where a running episode stands, shared between processes through small JSON files.

Each process that runs live episodes (the only one, or each pytest-xdist worker) writes
one file, ``<folder>/live/<worker>.json``, atomically on every step and retry (the plugin's
``folder``: the session's, beside the run directory's locks); the controller reads them all
for the live line. Only live (recording) episodes publish: replays are too
fast to watch and must stay as cheap as they are.
"""

from __future__ import annotations

import json
import os
import threading
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any, Final

from pytest_emrd._atomic import write_bytes_atomic
from pytest_emrd._serde import from_dict, to_dict

LIVE_FOLDER: Final = "live"


@dataclass(frozen=True)
class WorkerStatus:
    """One process's live episode, and its totals so far."""

    worker: str
    """``gw0``... under pytest-xdist, ``main`` otherwise."""
    case: str | None
    """Episode running now (``None`` between episodes)."""
    step: int
    max_steps: int
    retries: int
    """Retries of the running episode so far."""
    last_retry: str | None
    """The last retry's cause (``HTTP 429: ...``), if any."""
    finished: int
    """Live episodes this process finished (errored ones included)."""
    errored: int
    """Of those, how many ended ``errored``."""
    retries_total: int
    """Retries over every live episode of this process."""

    def to_dict(self) -> dict[str, Any]:
        return to_dict(self)

    @classmethod
    def from_dict(cls, data: dict[str, Any]) -> WorkerStatus:
        return from_dict(cls, data)


def worker_name() -> str:
    """This process's name in the live line (``PYTEST_XDIST_WORKER`` or ``main``)."""
    return os.environ.get("PYTEST_XDIST_WORKER", "main")


class StatusFile:
    """This process's ``<folder>/live/<worker>.json``, rewritten atomically on each change.

    Episodes computed ahead in threads (``--emrd-concurrency``) each get their own file,
    ``<worker>-t<n>.json``: one status per running episode.
    """

    def __init__(self, folder: Path, worker: str | None = None) -> None:
        self.folder = folder / LIVE_FOLDER
        self.name = worker or worker_name()
        self._main = threading.get_ident()
        self._by_thread: dict[int, WorkerStatus] = {}
        self._lock = threading.Lock()

    @property
    def status(self) -> WorkerStatus:
        """The calling thread's status."""
        ident = threading.get_ident()
        with self._lock:
            if ident not in self._by_thread:
                n = len(self._by_thread)
                name = self.name if ident == self._main else f"{self.name}-t{n}"
                self._by_thread[ident] = WorkerStatus(name, None, 0, 0, 0, None, 0, 0, 0)
            return self._by_thread[ident]

    def update(self, **changes: Any) -> WorkerStatus:
        status = replace(self.status, **changes)
        self._by_thread[threading.get_ident()] = status
        path = self.folder / f"{status.worker}.json"
        write_bytes_atomic(path, json.dumps(status.to_dict()).encode())
        return status


def read_statuses(folder: Path) -> list[WorkerStatus]:
    """Every readable status file under ``folder``, by worker name."""
    statuses = []
    for path in sorted((folder / LIVE_FOLDER).glob("*.json")):
        try:
            statuses.append(WorkerStatus.from_dict(json.loads(path.read_bytes())))
        except (OSError, ValueError, KeyError, TypeError):
            continue  # a file from another version or being replaced: skip this poll
    return statuses
