"""Running one episode inside its cassette: replay, record, explain failures, and block the
network while replaying (only loopback connections may be opened)."""

from __future__ import annotations

import dataclasses
import ipaddress
import socket
import time
from collections.abc import Callable, Iterator
from contextlib import contextmanager, nullcontext
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from pytest_emrd._scrub import scrub
from pytest_emrd.cassette._paths import (
    Invocation,
    ModalityOf,
    cassette_path,
    modality_message,
    record_command,
)
from pytest_emrd.cassette._persister import LOCK_TIMEOUT_S, UnsavedCassette, writer_lock
from pytest_emrd.cassette._use import episode_cassette
from pytest_emrd.errors import CassetteError, check_choice
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
    retries: int = 0
    """Model requests retried while it ran (set by whoever watched it)."""
    unsaved: UnsavedCassette | None = None
    """The recording, when its cassette file could not be written (keep it elsewhere)."""


class FrameDriftWarning(UserWarning):
    """Lenient matching replayed requests whose frames differ from the recording."""


class _Discard(Exception):
    """Raised inside the cassette block so vcrpy does not save a failed episode."""


#: Runs one episode; ``live``: the model may really be called (else every request replays).
EpisodeRunner = Callable[..., Trajectory]


def is_live(
    spec: EpisodeSpec, *, cassettes: Path, record_mode: str, modality_of: ModalityOf | None = None
) -> bool:
    """Whether running ``spec`` calls the model (records), rather than replaying only.

    :param spec: The episode.
    :param cassettes: The cassette folder.
    :param record_mode: The run's record mode.
    :param modality_of: Default modality per model (:func:`cassette_path`).
    :returns: True when the episode records.
    """
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

    ``run`` turns failures into an ``errored`` trajectory, which leaves no cassette behind and
    whose scrubbed ``error`` becomes the cause the cassette explains (missing file, drift,
    another modality, an unreadable recorded response) with the command that fixes it for
    ``invocation``. A corrupted, edited or stale cassette raises ``CassetteError``; an
    unwritable one the ``OSError``, unless ``keep_unsaved`` hands it back in ``unsaved``. Under
    ``new_episodes`` a drifting replay is recorded again whole. An episode that may record holds
    its cassette's lock (:func:`~._persister.writer_lock`) up to ``lock_timeout_s`` seconds.

    :param spec: The episode.
    :param run: Runs the episode, live or replayed (``run(spec, live=...)``).
    :param cassettes: The cassette folder.
    :param protocol: The protocol version recorded and checked.
    :param record_mode: ``none``, ``once``, ``new_episodes`` or ``all``.
    :param matching: ``strict`` or ``lenient`` request matching.
    :param invocation: The pytest invocation the fix commands repeat.
    :param lock_timeout_s: Seconds to wait for another writer of the same cassette.
    :param modality_of: Default modality per model (:func:`cassette_path`).
    :param keep_unsaved: Return an unwritable recording in ``unsaved`` instead of raising.
    :returns: The :class:`EpisodeRun`: trajectory, whether live, and what was recorded.
    """
    check_choice("record_mode", record_mode, RECORD_MODES)
    check_choice("matching", matching, MATCHING_MODES)
    path = cassette_path(cassettes, spec, modality_of=modality_of)
    episode = _Episode(
        spec, run, cassettes, path, modality_of, protocol, matching, keep_unsaved, invocation
    )
    if not is_live(spec, cassettes=cassettes, record_mode=record_mode, modality_of=modality_of):
        return episode.run(record_mode)
    with writer_lock(cassettes, path, timeout=lock_timeout_s):
        start = time.perf_counter()
        try:
            return episode.run(record_mode)
        except _Redo:  # drift under new_episodes: the whole episode again, from scratch
            done = episode.run("all")
            return dataclasses.replace(done, seconds=time.perf_counter() - start)


class _Redo(Exception):
    """The episode drifted under ``new_episodes``: it must be recorded again whole."""


@dataclass(frozen=True)
class _Episode:
    spec: EpisodeSpec
    runner: EpisodeRunner
    root: Path
    path: Path
    modality_of: ModalityOf | None
    protocol: str
    matching: str
    keep_unsaved: bool
    invocation: Invocation | None

    def command(self, record_mode: str) -> str:
        return record_command(
            self.spec, record_mode=record_mode, cassettes=self.root, invocation=self.invocation
        )

    def run(self, record_mode: str) -> EpisodeRun:
        spec, path = self.spec, self.path
        missing = record_mode == "none" and not path.is_file()
        live = is_live(
            spec, cassettes=self.root, record_mode=record_mode, modality_of=self.modality_of
        )
        rerecord = self.command("all")
        start = time.perf_counter()
        unsaved = None
        try:
            with (
                network_blocked() if record_mode == "none" else nullcontext(),
                episode_cassette(
                    path,
                    protocol=self.protocol,
                    record_mode=record_mode,
                    matching=self.matching,
                    rerecord_command=rerecord,
                    root=self.root,
                    keep_unsaved=self.keep_unsaved,
                ) as cassette,
            ):
                trajectory = self.runner(spec, live=live)
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
                cause = (
                    f"cassette missing: {path} does not exist and record mode 'none' replays "
                    f"only. Record it with: {self.command('once')}"
                )
            elif drift is not None:
                cause = drift
                modality = cassette.recorded_modality
                if not cassette.unreadable and modality not in (None, spec.modality):
                    cause = self.mismatch(modality, rerecord)
            trajectory = dataclasses.replace(trajectory, error=scrub(cause))
        seconds = time.perf_counter() - start
        return EpisodeRun(trajectory, recorded, frame_drift, seconds, unsaved=unsaved)

    def mismatch(self, recorded: str, rerecord: str) -> str:
        """The modality-mismatch text (:func:`~._paths.modality_message`)."""
        owner = dataclasses.replace(self.spec, modality=recorded)
        return modality_message(
            cassette=self.path,
            recorded=recorded,
            asked=self.spec.modality,
            home=cassette_path(self.root, owner, modality_of=self.modality_of),
            record=self.command("once"),
            rerecord=rerecord,
        )


def _is_loopback(sock: socket.socket, address: Any) -> bool:
    if sock.family not in (socket.AF_INET, socket.AF_INET6):
        return True
    host = str(address[0])
    if host == "localhost":
        return True
    try:
        return ipaddress.ip_address(host.split("%", 1)[0]).is_loopback
    except ValueError:
        return False


@contextmanager
def network_blocked() -> Iterator[None]:
    """In the block, a connection to anything but loopback raises :class:`CassetteError`.

    :returns: A context manager; sockets are restored on exit.
    """
    connect, connect_ex = socket.socket.connect, socket.socket.connect_ex

    def guarded(original: Callable[..., Any]) -> Callable[..., Any]:
        def guard(sock: socket.socket, address: Any) -> Any:
            if not _is_loopback(sock, address):
                raise CassetteError(
                    f"address={address!r}: the network is blocked in record mode 'none' "
                    "(replay only); only loopback is reachable. Record with "
                    "--emrd-record-mode=once to allow live requests."
                )
            return original(sock, address)

        return guard

    socket.socket.connect = guarded(connect)  # type: ignore[method-assign]
    socket.socket.connect_ex = guarded(connect_ex)  # type: ignore[method-assign]
    try:
        yield
    finally:
        socket.socket.connect = connect  # type: ignore[method-assign]
        socket.socket.connect_ex = connect_ex  # type: ignore[method-assign]
