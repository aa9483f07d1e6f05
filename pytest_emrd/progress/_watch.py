"""Watching one episode as it runs: a log line per step, retries counted as they happen.

:class:`EpisodeWatch` is a context manager around one episode. Its :meth:`on_step` is the
episode loop's ``on_step`` callback: it logs ``<case> step k/50: <action> ...`` on the
``pytest_emrd.episode`` logger (INFO for a live episode, DEBUG for a replay). While the
episode runs the watch also listens on the ``pytest_emrd`` logger for retry records
(:data:`~pytest_emrd._logging.RETRY_ATTR`) and counts them. A live episode publishes its
step and retries to a :class:`~pytest_emrd.progress._status.StatusFile` for the live line.
Nothing here changes what the model is sent.
"""

from __future__ import annotations

import dataclasses
import functools
import logging
import threading
from collections.abc import Callable
from pathlib import Path
from types import TracebackType
from typing import TYPE_CHECKING, Any

from pytest_emrd._logging import RETRY_ATTR, ROOT_LOGGER
from pytest_emrd.trajectory import EpisodeSpec, Step, Trajectory

if TYPE_CHECKING:
    from pytest_emrd.cassette import EpisodeRun
    from pytest_emrd.progress._status import StatusFile

log = logging.getLogger(f"{ROOT_LOGGER}.episode")


class EpisodeWatch(logging.Handler):
    """Progress of one episode: step logging, retry counting, optional status publishing."""

    def __init__(self, spec: EpisodeSpec, *, live: bool, status: StatusFile | None = None):
        super().__init__(level=logging.DEBUG)
        self.spec = spec
        self.live = live
        self.status = status if live else None
        self.retries = 0
        self.level_of_steps = logging.INFO if live else logging.DEBUG
        self._step = 0

    def __enter__(self) -> EpisodeWatch:
        vcr = logging.getLogger("vcr")
        if vcr.level == logging.NOTSET:  # it logs whole HTTP bodies at INFO: not progress
            vcr.setLevel(logging.WARNING)
        self._thread = threading.get_ident()
        logging.getLogger(ROOT_LOGGER).addHandler(self)
        how = "recording live" if self.live else "replaying"
        log.log(self.level_of_steps, "%s: %s", self.spec.case_id, how)
        self._publish(case=self.spec.case_id, step=0, retries=0, last_retry=None)
        return self

    def on_step(self, step: Step) -> None:
        """The episode loop's ``on_step``: one log line, and the live status."""
        self._step = step.index
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
        log.log(
            logging.WARNING if trajectory.status == "errored" else self.level_of_steps,
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
                errored=totals.errored + (trajectory.status == "errored"),
                retries_total=totals.retries_total + self.retries,
            )

    def __exit__(
        self, kind: type[BaseException] | None, exc: BaseException | None, tb: TracebackType | None
    ) -> None:
        logging.getLogger(ROOT_LOGGER).removeHandler(self)

    def _publish(self, **changes: object) -> None:
        if self.status is not None:
            self.status.update(max_steps=self.spec.max_steps, **changes)


def watch_episode(
    spec: EpisodeSpec,
    compute: Callable[[Callable[[Step], None]], EpisodeRun],
    *,
    live: bool,
    status: StatusFile | None = None,
) -> EpisodeRun:
    """``compute(on_step)`` under an :class:`EpisodeWatch`; the run with its retries."""
    with EpisodeWatch(spec, live=live, status=status) as watch:
        run = compute(watch.on_step)
        watch.finish(run.trajectory)
    return dataclasses.replace(run, retries=watch.retries)


def run_watched(
    spec: EpisodeSpec,
    runner: Callable[..., Trajectory],
    *,
    status: StatusFile | None,
    cassettes: Path,
    record_mode: str,
    **cassette: Any,
) -> EpisodeRun:
    """:func:`~pytest_emrd.cassette.run_with_cassette` of ``spec`` with ``runner`` (which
    takes ``on_step``), watched: live when the cassette asks for the model."""
    from pytest_emrd.cassette import is_live, run_with_cassette

    def compute(on_step: Callable[[Step], None]) -> EpisodeRun:
        run = functools.partial(runner, on_step=on_step)
        return run_with_cassette(
            spec, run, cassettes=cassettes, record_mode=record_mode, **cassette
        )

    modality_of = cassette.get("modality_of")
    live = is_live(spec, cassettes=cassettes, record_mode=record_mode, modality_of=modality_of)
    return watch_episode(spec, compute, live=live, status=status)
