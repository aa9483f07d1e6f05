"""Running one episode inside its cassette: replay, record, explain failures, and block the
network while replaying (only loopback connections may be opened)."""

from __future__ import annotations

import dataclasses
import ipaddress
import socket
import time
from collections.abc import Callable, Iterator
from contextlib import ExitStack, contextmanager, nullcontext
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


class Tape:
    """One episode's cassette: where its traffic is recorded or replayed, whether running it
    calls the model (:attr:`live`, decided once, here) and how a failure is explained.

    The caller runs the episode in each of :meth:`takes` (``with take: take.trajectory =
    ...``) and keeps the last take's :attr:`Take.result`. A failed episode (an ``errored``
    trajectory) leaves no cassette behind; its scrubbed ``error`` becomes the cause the
    cassette explains (missing file, drift, another modality, an unreadable recorded response)
    with the command that fixes it for ``invocation``. A corrupted, edited or stale cassette
    raises ``CassetteError``; an unwritable one the ``OSError``, unless ``keep_unsaved`` hands
    it back in ``unsaved``. Under ``new_episodes`` a drifting replay is recorded again whole. An
    episode that may record holds its cassette's lock (:func:`~._persister.writer_lock`) up to
    ``lock_timeout_s`` seconds.

    :param spec: The episode.
    :param cassettes: The cassette folder.
    :param protocol: The protocol version recorded and checked.
    :param record_mode: ``none``, ``once``, ``new_episodes`` or ``all``.
    :param matching: ``strict`` or ``lenient`` request matching.
    :param invocation: The pytest invocation the fix commands repeat.
    :param modality_of: Default modality per model (:func:`cassette_path`).
    :param keep_unsaved: Return an unwritable recording in ``unsaved`` instead of raising.
    :param lock_timeout_s: Seconds to wait for another writer of the same cassette.
    """

    def __init__(
        self,
        spec: EpisodeSpec,
        *,
        cassettes: Path,
        protocol: str,
        record_mode: str = "once",
        matching: str = "strict",
        invocation: Invocation | None = None,
        modality_of: ModalityOf | None = None,
        keep_unsaved: bool = False,
        lock_timeout_s: float = LOCK_TIMEOUT_S,
    ) -> None:
        check_choice("record_mode", record_mode, RECORD_MODES)
        check_choice("matching", matching, MATCHING_MODES)
        self.spec, self.root, self.protocol, self.invocation = spec, cassettes, protocol, invocation
        self.record_mode, self.matching, self.modality_of = record_mode, matching, modality_of
        self.keep_unsaved, self.lock_timeout_s = keep_unsaved, lock_timeout_s
        self.path = cassette_path(cassettes, spec, modality_of=modality_of)
        self.live = is_live(
            spec, cassettes=cassettes, record_mode=record_mode, modality_of=modality_of
        )

    def takes(self) -> Iterator[Take]:
        """The attempts at the episode: one, and under ``new_episodes`` after a drifting
        replay a second, recorded whole from scratch (record mode ``all``)."""
        lock = writer_lock(self.root, self.path, timeout=self.lock_timeout_s)
        with lock if self.live else nullcontext():
            start = time.perf_counter()
            take = Take(self, self.record_mode, start)
            yield take
            if take.redo:
                take = Take(self, "all", start)
                yield take

    def command(self, record_mode: str) -> str:
        return record_command(
            self.spec, record_mode=record_mode, cassettes=self.root, invocation=self.invocation
        )


class Take(ExitStack):
    """One attempt at an episode inside its cassette (a ``with`` block, see :class:`Tape`):
    the network blocked when replaying only, the episode's HTTP traffic routed to its
    cassette. Set :attr:`trajectory` in the block; :attr:`result` is there after it.

    :param tape: The episode's :class:`Tape`.
    :param record_mode: This attempt's record mode (``all`` for a redo).
    :param start: ``time.perf_counter()`` when the first attempt began.
    """

    trajectory: Trajectory
    result: EpisodeRun

    def __init__(self, tape: Tape, record_mode: str, start: float) -> None:
        super().__init__()
        self.tape, self.record_mode, self.start, self.redo = tape, record_mode, start, False

    def __enter__(self) -> Take:
        tape = self.tape
        if self.record_mode == "none":
            self.enter_context(network_blocked())
        self.cassette = self.enter_context(
            episode_cassette(
                tape.path,
                protocol=tape.protocol,
                record_mode=self.record_mode,
                matching=tape.matching,
                rerecord_command=tape.command("all"),
                root=tape.root,
                keep_unsaved=tape.keep_unsaved,
            )
        )
        return self

    def __exit__(self, kind: Any, exc: Any, tb: Any) -> bool:
        if kind is not None:
            return super().__exit__(kind, exc, tb)
        tape, cassette, trajectory = self.tape, self.cassette, self.trajectory
        recorded, drift, frame_drift = cassette.dirty, cassette.drift, len(cassette.frame_drift)
        self.redo = self.record_mode == "new_episodes" and drift is not None
        if trajectory.status != "errored" and not self.redo:
            super().__exit__(None, None, None)  # saves the cassette (or keeps it unsaved)
            unsaved = cassette.unsaved
        else:
            super().__exit__(_Discard, _Discard(), None)  # vcrpy saves nothing
            recorded, unsaved, cause = False, None, trajectory.error or ""
            if self.record_mode == "none" and not tape.path.is_file():
                cause = (
                    f"cassette missing: {tape.path} does not exist and record mode 'none' "
                    f"replays only. Record it with: {tape.command('once')}"
                )
            elif drift is not None:
                cause, modality = drift, cassette.recorded_modality
                if not cassette.unreadable and modality not in (None, tape.spec.modality):
                    owner = dataclasses.replace(tape.spec, modality=modality)
                    cause = modality_message(
                        cassette=tape.path,
                        recorded=modality,
                        asked=tape.spec.modality,
                        home=cassette_path(tape.root, owner, modality_of=tape.modality_of),
                        record=tape.command("once"),
                        rerecord=tape.command("all"),
                    )
            trajectory = dataclasses.replace(trajectory, error=scrub(cause))
        seconds = time.perf_counter() - self.start
        self.result = EpisodeRun(trajectory, recorded, frame_drift, seconds, unsaved=unsaved)
        return False


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
