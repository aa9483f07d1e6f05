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
from pytest_emrd.cassette._paths import Invocation, ModalityOf, cassette_path, record_command
from pytest_emrd.cassette._persister import LOCK_TIMEOUT_S, UnsavedCassette, writer_lock
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
    unsaved: UnsavedCassette | None = None
    """The recording, when its cassette file could not be written (the episode is still
    good: keep the recording elsewhere, or it is lost); None otherwise."""


class FrameDriftWarning(UserWarning):
    """Lenient matching replayed requests whose frames differ from the recording."""


class _Discard(Exception):
    """Raised inside the cassette block so vcrpy does not save a failed episode."""


#: Runs one episode; ``live`` says whether the model may really be called (an API key is
#: needed) or every request will be replayed (frames then travel as their pixel digests).
EpisodeRunner = Callable[..., Trajectory]


def is_live(
    spec: EpisodeSpec, *, cassettes: Path, record_mode: str, modality_of: ModalityOf | None = None
) -> bool:
    """Whether running ``spec`` calls the model (records), rather than replaying only
    (``modality_of``: the models' default modalities, see :func:`~._paths.cassette_path`)."""
    if record_mode in ("all", "new_episodes"):
        return True
    path = cassette_path(cassettes, spec, modality_of=modality_of)
    return record_mode == "once" and not path.is_file()


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
    modality_of: ModalityOf | None = None,
    keep_unsaved: bool = False,
) -> EpisodeRun:
    """Run ``run(spec, live=...)`` with the model traffic recorded to / replayed from its cassette.

    ``run`` must behave like :func:`pytest_emrd.episode.run_episode`: failures become an
    ``errored`` trajectory, never an exception. An errored episode leaves no cassette behind,
    and its scrubbed ``error`` becomes the cause the cassette explains (missing file in
    ``none`` mode, drift, another modality, an unreadable recorded response) with the command
    that fixes it, built for ``invocation``. A corrupted, edited or stale cassette raises
    :class:`~pytest_emrd.errors.CassetteError`; a cassette that cannot be written raises the
    :class:`OSError`, or with ``keep_unsaved`` is handed back in the run's ``unsaved``.

    Under ``new_episodes`` an episode whose replay drifts is stopped and recorded again whole,
    as under ``all``. An episode that may record holds its cassette's lock
    (:func:`~._persister.writer_lock`): a second run of it waits, then replays what the first
    recorded, or refuses after ``lock_timeout_s`` seconds.
    """
    check_choice("record_mode", record_mode, RECORD_MODES)
    check_choice("matching", matching, MATCHING_MODES)
    where = _Where(cassettes, cassette_path(cassettes, spec, modality_of=modality_of), modality_of)
    modes = _Modes(protocol, record_mode, matching, keep_unsaved)
    if not is_live(spec, cassettes=cassettes, record_mode=record_mode, modality_of=modality_of):
        return _run(spec, run, where, modes, invocation)
    with writer_lock(cassettes, where.path, timeout=lock_timeout_s):
        start = time.perf_counter()
        try:
            return _run(spec, run, where, modes, invocation)
        except _Redo:  # drift under new_episodes: the whole episode again, from scratch
            again = dataclasses.replace(modes, record_mode="all")
            done = _run(spec, run, where, again, invocation)
            return dataclasses.replace(done, seconds=time.perf_counter() - start)


@dataclass(frozen=True)
class _Where:
    """Where an episode's cassette lives: the cassette folder, the file, the defaults."""

    root: Path
    path: Path
    modality_of: ModalityOf | None


@dataclass(frozen=True)
class _Modes:
    """How an episode's cassette is used (see :func:`run_with_cassette`)."""

    protocol: str
    record_mode: str
    matching: str
    keep_unsaved: bool


class _Redo(Exception):
    """The episode drifted under ``new_episodes``: it must be recorded again whole."""


def _run(
    spec: EpisodeSpec,
    run: EpisodeRunner,
    where: _Where,
    modes: _Modes,
    invocation: Invocation | None,
) -> EpisodeRun:
    cassettes, path = where.root, where.path
    record_mode, matching = modes.record_mode, modes.matching
    missing = record_mode == "none" and not path.is_file()
    live = is_live(
        spec, cassettes=cassettes, record_mode=record_mode, modality_of=where.modality_of
    )
    rerecord = record_command(spec, record_mode="all", cassettes=cassettes, invocation=invocation)
    start = time.perf_counter()
    unsaved = None
    try:
        with (
            network_blocked(record_mode == "none"),
            episode_cassette(
                path,
                protocol=modes.protocol,
                record_mode=record_mode,
                matching=matching,
                rerecord_command=rerecord,
                root=cassettes,
                keep_unsaved=modes.keep_unsaved,
            ) as cassette,
        ):
            trajectory = run(spec, live=live)
            recorded, drift = cassette.dirty, cassette.drift
            frame_drift = len(cassette.frame_drift)
            redo = record_mode == "new_episodes" and drift is not None
            if trajectory.status == "errored" or redo:
                raise _Discard
        unsaved = cassette.unsaved  # the cassette was saved (or not) as the block closed
    except _Discard:
        if redo:
            raise _Redo from None
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
                cause = _mismatch(spec, where, modality, rerecord, invocation)
        trajectory = dataclasses.replace(trajectory, error=scrub(cause))
    seconds = time.perf_counter() - start
    return EpisodeRun(trajectory, recorded, frame_drift, seconds, unsaved=unsaved)


def _mismatch(
    spec: EpisodeSpec, where: _Where, recorded: str, rerecord: str, invocation: Invocation | None
) -> str:
    """The modality-mismatch text, whose fix never overwrites the ``recorded`` recording: the
    file is moved to where an episode in ``recorded`` lives, then the asked one is recorded."""
    owner = dataclasses.replace(spec, modality=recorded)
    home = cassette_path(where.root, owner, modality_of=where.modality_of)
    record = record_command(spec, record_mode="once", cassettes=where.root, invocation=invocation)
    return modality_message(
        cassette=where.path,
        recorded=recorded,
        asked=spec.modality,
        home=home,
        record=record,
        rerecord=rerecord,
    )
