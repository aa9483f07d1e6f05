"""The live line: one concise terminal line about the live episodes of a run.

``emrd live 3/96 recorded, 2 retries | gw0 gemini-baseline-office-ep03 step 12/50 |
gw1 gemini-baseline-office-ep04 step 9/50, retry 2: HTTP 429: {"error": ...``

:class:`LiveBoard` turns the workers' status files into that line and decides when it is
worth printing: at once when a retry or an error appeared since the last line, otherwise
at most every ``interval`` seconds and only when something moved. :class:`Ticker` polls it
from a daemon thread of the controller (workers cannot write to the controller's terminal).
"""

from __future__ import annotations

import threading
import time
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Final

from pytest_emrd.progress._status import WorkerStatus, read_statuses

#: Seconds between two lines when nothing urgent happened.
INTERVAL_S: Final = 10.0
POLL_S: Final = 0.5
_RETRY_EXCERPT: Final = 90


def _retries(statuses: Sequence[WorkerStatus]) -> int:
    return sum(s.retries_total + (s.retries if s.case is not None else 0) for s in statuses)


def render_line(statuses: Sequence[WorkerStatus], total: int) -> str:
    """The live line for ``statuses`` (``total`` live episodes planned in this session)."""
    finished = sum(s.finished for s in statuses)
    errored = sum(s.errored for s in statuses)
    retries = _retries(statuses)
    head = f"emrd live {finished}/{total} recorded"
    if retries:
        head += f", {retries} retr{'y' if retries == 1 else 'ies'}"
    if errored:
        head += f", {errored} errored"
    parts = [head]
    for s in statuses:
        if s.case is None:
            continue
        part = f"{s.worker} {s.case} step {s.step}/{s.max_steps}"
        if s.retries:
            said = (s.last_retry or "")[:_RETRY_EXCERPT]
            part += f", retry {s.retries}: {said}"
        parts.append(part)
    return " | ".join(parts)


class LiveBoard:
    """Decides which live lines to print for one run directory."""

    def __init__(
        self,
        run_dir: Path,
        *,
        total: int,
        interval: float = INTERVAL_S,
        clock: Callable[[], float] = time.monotonic,
    ) -> None:
        self.run_dir = run_dir
        self.total = total
        self.interval = interval
        self.clock = clock
        self._last_line = ""
        self._last_time = -float("inf")
        self._urgent_seen = (0, 0)

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
    """Polls a :class:`LiveBoard` from a daemon thread and hands each line to ``write``."""

    def __init__(self, board: LiveBoard, write: Callable[[str], None], *, poll: float = POLL_S):
        self.board, self.write, self.poll = board, write, poll
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
        while not self._stop.wait(self.poll):
            line = self.board.poll()
            if line is not None:
                self.write(line)
