"""Live progress of running episodes: each step and retry, as it happens (observation only:
what the model is sent, and every trajectory, stay the same).

:class:`EpisodeWatch` logs each step on the ``pytest_emrd.episode`` logger and counts retries;
a live episode publishes its state to a :class:`StatusFile` (replays are too fast to watch and
stay as cheap as they are). On the controller, :class:`LiveBoard` makes one line of them
(``emrd live 3/96 recorded, 2 retries | gw0 <case> step 12/50, retry 2: HTTP 429: ...``) and
:class:`Ticker` prints it from a daemon thread (workers cannot write to the controller's
terminal).
"""

from __future__ import annotations

import json
import logging
import math
import os
import threading
import time
from collections.abc import Callable, Sequence
from dataclasses import KW_ONLY, dataclass, field, replace
from pathlib import Path
from typing import Any, Final

from pytest_emrd._files import write_bytes_atomic
from pytest_emrd._logging import RETRY_ATTR, ROOT_LOGGER
from pytest_emrd._serde import from_dict, to_dict
from pytest_emrd.trajectory import EpisodeSpec, Step, Trajectory

__all__ = [
    "INTERVAL_S",
    "LIVE_FOLDER",
    "POLL_S",
    "EpisodeWatch",
    "LiveBoard",
    "StatusFile",
    "Ticker",
    "WorkerStatus",
    "read_statuses",
    "render_line",
]

LIVE_FOLDER: Final = "live"
#: Seconds between two lines when nothing urgent happened.
INTERVAL_S: Final = 10.0
POLL_S: Final = 0.5
_RETRY_EXCERPT: Final = 90


@dataclass(frozen=True)
class WorkerStatus:
    """One process's live episode, and its totals so far."""

    worker: str
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


class StatusFile:
    """This process's ``<folder>/live/<worker>.json`` (``PYTEST_XDIST_WORKER``, else
    ``main``), rewritten atomically on each change.

    Episodes computed ahead in threads (``--emrd-concurrency``) each get their own file,
    ``<worker>-t<n>.json``: one status per running episode.

    :param folder: The session folder; the files go to its ``live`` subfolder.
    """

    def __init__(self, folder: Path) -> None:
        self.folder = folder / LIVE_FOLDER
        self.name = os.environ.get("PYTEST_XDIST_WORKER", "main")
        self._main = threading.get_ident()
        self._by_thread: dict[int, WorkerStatus] = {}
        self._lock = threading.Lock()

    @property
    def status(self) -> WorkerStatus:
        """The calling thread's status."""
        ident = threading.get_ident()
        with self._lock:
            if ident not in self._by_thread:
                name = self.name if ident == self._main else f"{self.name}-t{len(self._by_thread)}"
                self._by_thread[ident] = WorkerStatus(name, None, 0, 0, 0, None, 0, 0, 0)
            return self._by_thread[ident]

    def update(self, **changes: Any) -> None:
        status = replace(self.status, **changes)
        self._by_thread[threading.get_ident()] = status
        path = self.folder / f"{status.worker}.json"
        write_bytes_atomic(path, json.dumps(to_dict(status)).encode())


def read_statuses(folder: Path) -> list[WorkerStatus]:
    """Every readable status file under ``folder``, by worker name.

    :param folder: The session's live folder.
    :returns: The :class:`WorkerStatus` of each worker; unreadable files skipped.
    """
    statuses = []
    for path in sorted((folder / LIVE_FOLDER).glob("*.json")):
        try:
            statuses.append(from_dict(WorkerStatus, json.loads(path.read_bytes())))
        except (OSError, ValueError, KeyError, TypeError):
            continue  # a file from another version or being replaced: skip this poll
    return statuses


def _retries(statuses: Sequence[WorkerStatus]) -> int:
    return sum(s.retries_total + (s.retries if s.case is not None else 0) for s in statuses)


def render_line(statuses: Sequence[WorkerStatus], total: int) -> str:
    """The live line for ``statuses`` (``total`` live episodes planned in this session).

    :param statuses: Every worker's status.
    :param total: Live episodes planned this session.
    :returns: The one-line summary.
    """
    finished = sum(s.finished for s in statuses)
    errored = sum(s.errored for s in statuses)
    retries = _retries(statuses)
    head = f"emrd live {finished}/{total} recorded"
    if retries:
        head += f", {retries} retr{'y' if retries == 1 else 'ies'}"
    if errored:
        head += f", {errored} errored"
    parts = [head]
    for s in (s for s in statuses if s.case is not None):
        part = f"{s.worker} {s.case} step {s.step}/{s.max_steps}"
        if s.retries:
            part += f", retry {s.retries}: {(s.last_retry or '')[:_RETRY_EXCERPT]}"
        parts.append(part)
    return " | ".join(parts)


@dataclass
class LiveBoard:
    """Decides which live lines to print for one run directory: at once after a new retry or
    error, else at most every ``interval`` seconds when the line changed."""

    run_dir: Path
    _: KW_ONLY
    total: int
    interval: float = INTERVAL_S
    clock: Callable[[], float] = time.monotonic
    _last_line: str = field(default="", init=False)
    _last_time: float = field(default=-math.inf, init=False)
    _urgent_seen: tuple[int, int] = field(default=(0, 0), init=False)

    def poll(self) -> str | None:
        """The line to print now, or ``None``."""
        statuses = read_statuses(self.run_dir)
        if not statuses:
            return None
        line = render_line(statuses, self.total)
        urgent = (_retries(statuses), sum(s.errored for s in statuses))
        now = self.clock()
        due = now - self._last_time >= self.interval and line != self._last_line
        if urgent[0] > self._urgent_seen[0] or urgent[1] > self._urgent_seen[1] or due:
            self._urgent_seen = urgent
            self._last_line, self._last_time = line, now
            return line
        return None


class Ticker:
    """Polls a :class:`LiveBoard` from a daemon thread and hands each line to ``write``.

    :param board: The board to poll (every :data:`POLL_S` seconds).
    :param write: Prints a line on the controller's terminal.
    """

    def __init__(self, board: LiveBoard, write: Callable[[str], None]):
        self.board, self.write = board, write
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._loop, name="emrd-live-line", daemon=True)

    def start(self) -> Ticker:
        self._thread.start()
        return self

    def stop(self) -> None:
        """Stop polling (the end-of-run table has the totals)."""
        self._stop.set()
        self._thread.join()

    def _loop(self) -> None:
        while not self._stop.wait(POLL_S):
            line = self.board.poll()
            if line is not None:
                self.write(line)


log = logging.getLogger(f"{ROOT_LOGGER}.episode")


class EpisodeWatch(logging.Handler):
    """Progress of one episode, started on the calling thread: step logging (its
    :meth:`on_step` is the loop's ``on_step``), retry counting (in a ``with`` block: added to
    the package's logger), optional status publishing.

    :param spec: The episode.
    :param live: Whether it asks the model (steps then log at INFO and the status is published).
    :param status: Where to publish; None for nowhere.
    """

    def __init__(self, spec: EpisodeSpec, *, live: bool, status: StatusFile | None = None):
        super().__init__()
        self.spec = spec
        self.status = status if live else None
        self.retries = 0
        self.level_of_steps = logging.INFO if live else logging.DEBUG
        vcr = logging.getLogger("vcr")
        if vcr.level == logging.NOTSET:  # it logs whole HTTP bodies at INFO: not progress
            vcr.setLevel(logging.WARNING)
        self._thread = threading.get_ident()
        how = "recording live" if live else "replaying"
        log.log(self.level_of_steps, "%s: %s", spec.case_id, how)
        self._publish(
            case=spec.case_id, step=0, max_steps=spec.max_steps, retries=0, last_retry=None
        )

    def __enter__(self) -> EpisodeWatch:
        logging.getLogger(ROOT_LOGGER).addHandler(self)
        return self

    def __exit__(self, *exc: object) -> None:
        logging.getLogger(ROOT_LOGGER).removeHandler(self)

    def on_step(self, step: Step) -> None:
        """The episode loop's ``on_step``: one log line, and the live status."""
        if log.isEnabledFor(self.level_of_steps):
            outcome = "ok" if step.success else "failed"
            unread = f" (reply unreadable: {step.parse_error})" if step.parse_error else ""
            log.log(
                self.level_of_steps,
                "%s step %d/%d: %s %s%s, %s+%s tokens",
                self.spec.case_id,
                step.index,
                self.spec.max_steps,
                step.action or "-",
                outcome,
                unread,
                f"{step.usage.prompt_tokens:,}",
                f"{step.usage.completion_tokens:,}",
            )
        self._publish(step=step.index)

    def emit(self, record: logging.LogRecord) -> None:
        """Count a retry record of this episode's requests."""
        if getattr(record, RETRY_ATTR, None) is None or record.thread != self._thread:
            return  # not a retry, or another episode's (episodes computed ahead in threads)
        self.retries += 1
        cause = record.getMessage().rpartition("Cause: ")[2]  # the status and body, not the URL
        self._publish(retries=self.retries, last_retry=cause)

    def finish(self, trajectory: Trajectory) -> None:
        """Log the outcome and add the episode to this process's live totals."""
        retries = f", {self.retries} retr{'y' if self.retries == 1 else 'ies'}"
        error = f": {trajectory.error}" if trajectory.error else ""
        errored = trajectory.status == "errored"
        level = logging.WARNING if errored else self.level_of_steps
        log.log(
            level,
            "%s: %s after %d steps%s%s",
            self.spec.case_id,
            trajectory.status,
            len(trajectory.steps),
            retries if self.retries else "",
            error,
        )
        if self.status is not None:
            totals = self.status.status
            self.status.update(
                case=None,
                retries=0,
                finished=totals.finished + 1,
                errored=totals.errored + errored,
                retries_total=totals.retries_total + self.retries,
            )

    def _publish(self, **changes: object) -> None:
        if self.status is not None:
            self.status.update(**changes)
