"""Running one episode inside its cassette: replay, record, and explain failures."""

from __future__ import annotations

import dataclasses
import time
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

from pytest_emrd._scrub import scrub
from pytest_emrd.cassette._drift import modality_message
from pytest_emrd.cassette._network import network_blocked
from pytest_emrd.cassette._paths import Invocation, cassette_path, record_command
from pytest_emrd.cassette._persister import LOCK_TIMEOUT_S, writer_lock
from pytest_emrd.cassette._use import episode_cassette
from pytest_emrd.errors import check_choice
from pytest_emrd.trajectory import MATCHING_MODES, RECORD_MODES, EpisodeSpec, Trajectory


@dataclass(frozen=True)
class EpisodeRun:
    """The outcome of running one episode through its cassette."""

    trajectory: Trajectory
    recorded: bool
    """New traffic was recorded (a live episode), as opposed to a pure replay."""
    frame_drift: int
    """Requests matched leniently whose frames differ from the recording."""
    seconds: float
    """Wall time of the episode."""
    retries: int = 0
    """Model requests retried while it ran (set by whoever watched it)."""


class FrameDriftWarning(UserWarning):
    """Lenient matching replayed requests whose frames differ from the recording."""


class _Discard(Exception):
    """Raised inside the cassette block so vcrpy does not save a failed episode."""


#: Runs one episode; ``live`` says whether the model may really be called (an API key is
#: needed) or every request will be replayed (frames then travel as their pixel digests).
EpisodeRunner = Callable[..., Trajectory]


def is_live(spec: EpisodeSpec, *, cassettes: Path, record_mode: str) -> bool:
    """Whether running ``spec`` calls the model (records), rather than replaying only."""
    if record_mode in ("all", "new_episodes"):
        return True
    return record_mode == "once" and not cassette_path(cassettes, spec).is_file()


def run_with_cassette(
    spec: EpisodeSpec,
    run: EpisodeRunner,
    *,
    cassettes: Path,
    protocol: str,
    record_mode: str = "once",
    matching: str = "strict",
    invocation: Invocation | None = None,
    lock_timeout_s: float = LOCK_TIMEOUT_S,
) -> EpisodeRun:
    """Run ``run(spec, live=...)`` with the model traffic recorded to / replayed from its cassette.

    ``run`` must behave like :func:`pytest_emrd.episode.run_episode`: failures become an
    ``errored`` trajectory, never an exception. An errored episode leaves no cassette behind;
    its ``error`` is replaced by a precise cause when the cassette explains it (missing file
    in ``none`` mode, drift, a modality other than the recorded one, a recorded response the
    client could not read), each with the command that fixes it, built for ``invocation``
    (the test paths and user registry of the run). The error text is scrubbed of secrets. A
    corrupted, edited or stale cassette raises :class:`~pytest_emrd.errors.CassetteError`.

    An episode that may record holds its cassette's lock (:func:`~._persister.writer_lock`)
    while it runs: a second run of the same episode waits, then replays what the first one
    recorded (in ``once`` mode), or refuses after ``lock_timeout_s`` seconds.
    """
    check_choice("record_mode", record_mode, RECORD_MODES)
    check_choice("matching", matching, MATCHING_MODES)
    path = cassette_path(cassettes, spec)
    if not is_live(spec, cassettes=cassettes, record_mode=record_mode):
        return _run(spec, run, path, cassettes, protocol, record_mode, matching, invocation)
    with writer_lock(cassettes, path, timeout=lock_timeout_s):
        return _run(spec, run, path, cassettes, protocol, record_mode, matching, invocation)


def _run(
    spec: EpisodeSpec,
    run: EpisodeRunner,
    path: Path,
    cassettes: Path,
    protocol: str,
    record_mode: str,
    matching: str,
    invocation: Invocation | None,
) -> EpisodeRun:
    missing = record_mode == "none" and not path.is_file()
    live = is_live(spec, cassettes=cassettes, record_mode=record_mode)
    rerecord = record_command(spec, record_mode="all", cassettes=cassettes, invocation=invocation)
    start = time.perf_counter()
    try:
        with (
            network_blocked(record_mode == "none"),
            episode_cassette(
                path,
                protocol=protocol,
                record_mode=record_mode,
                matching=matching,
                rerecord_command=rerecord,
                root=cassettes,
            ) as cassette,
        ):
            trajectory = run(spec, live=live)
            recorded, drift = cassette.dirty, cassette.drift
            frame_drift = len(cassette.frame_drift)
            if trajectory.status == "errored":
                raise _Discard
    except _Discard:
        recorded = False
        cause = trajectory.error or ""
        if missing:
            command = record_command(
                spec, record_mode="once", cassettes=cassettes, invocation=invocation
            )
            cause = (
                f"cassette missing: {path} does not exist and record mode 'none' replays only. "
                f"Record it with: {command}"
            )
        elif drift is not None:
            cause = drift
            modality = cassette.recorded_modality
            if not cassette.unreadable and modality not in (None, spec.modality):
                cause = modality_message(
                    cassette=str(path), recorded=modality, asked=spec.modality, command=rerecord
                )
        trajectory = dataclasses.replace(trajectory, error=scrub(cause))
    return EpisodeRun(trajectory, recorded, frame_drift, time.perf_counter() - start)
