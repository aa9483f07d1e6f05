"""vcrpy persister for EMRD cassettes (file I/O only), and the lock of a cassette's writer."""

from __future__ import annotations

from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from vcr.persisters.filesystem import CassetteNotFoundError

from pytest_emrd._files import check_inside, write_bytes_atomic
from pytest_emrd.cassette._file import (
    CassetteData,
    FormatError,
    IntegrityError,
    LegacyFormatError,
    encode,
    inflated,
    parse,
)
from pytest_emrd.cassette._paths import scratch_path
from pytest_emrd.cassette._redact import canonical_keys
from pytest_emrd.errors import CassetteError


def read_cassette(path: Path, *, root: Path | None = None) -> tuple[CassetteData, str]:
    """The cassette at ``path`` and its text (bounded, schema-checked, digest-checked: see
    :mod:`._file`); ``path`` must lie inside ``root`` (default: its own folder) with no
    symbolic link on the way, else a one-line ConfigError before it is opened.

    :param path: The cassette file.
    :param root: The folder it must lie in; None for its own folder.
    :returns: ``(data, text)``.
    """
    check_inside(path.parent if root is None else root, path, what="cassette")
    with path.open("rb") as handle:
        text, whole = inflated(handle)
    return parse(text, whole), text


@dataclass(frozen=True)
class UnsavedCassette:
    """A recorded cassette that could not be written to its file: where it belonged, why,
    and the bytes of the file (redacted exactly as the cassette holds them), which replay as
    that cassette once written to ``path``."""

    path: Path
    cause: OSError
    blob: bytes


@dataclass(kw_only=True)
class EpisodePersister:
    """Loads and saves one episode's cassette (:mod:`._file`) under the current protocol: a
    missing file is "not found" (in ``all`` mode, ``fresh``, the old one is never read), a file
    that cannot be replayed a one-line :class:`CassetteError` naming it and the fix. A file is
    written to ``<root>/.emrd-tmp`` first and renamed into place; with ``keep_unsaved`` a failed
    write is kept in :attr:`unsaved` instead of raising."""

    protocol: str
    fresh: bool
    rerecord_command: str
    root: Path | None = None
    """The cassette folder; ``None``: temporary files are written beside the file."""
    keep_unsaved: bool = False
    unsaved: UnsavedCassette | None = field(default=None, init=False)
    """The last cassette that could not be written (with ``keep_unsaved``), else None."""

    def load_cassette(self, cassette_path: str | Path, serializer: Any = None) -> tuple[list, list]:
        path = Path(cassette_path)
        if self.fresh or not path.is_file():
            raise CassetteNotFoundError(str(path))
        try:
            data, _ = read_cassette(path, root=self.root)
        except LegacyFormatError as exc:
            raise CassetteError(
                f"cassette={str(path)!r} was written by an older pytest-emrd ({exc}), under an "
                f"earlier protocol than {self.protocol}, and cannot replay with this release; "
                f"delete it and record it again: {self.rerecord_command}"
            ) from None
        except IntegrityError as exc:
            raise CassetteError(
                f"cassette={str(path)!r} was changed after it was recorded: {exc}. A cassette "
                f"is replayed only as recorded; re-record it: {self.rerecord_command}"
            ) from None
        except (FormatError, OSError) as exc:
            raise CassetteError(
                f"cassette={str(path)!r} is corrupted: {exc}. Delete it and record it again: "
                f"{self.rerecord_command}"
            ) from None
        if data.protocol != self.protocol:
            raise CassetteError(
                f"cassette={str(path)!r} was recorded under protocol {data.protocol!r}, but the "
                f"world and prompt are now at {self.protocol!r}; replaying it would compare "
                f"stale traffic. Re-record it: {self.rerecord_command}"
            )
        for index, request in enumerate(data.requests):
            if index not in data.raw:  # recorded redacted: keyed as it is, never parsed again
                request.emrd_keys = canonical_keys(request.method, request.path, request.body)
        return list(data.requests), list(data.responses)

    def save_cassette(
        self, cassette_path: str | Path, cassette_dict: dict[str, Any], serializer: Any = None
    ) -> None:
        requests = tuple(cassette_dict["requests"])
        raw = frozenset(i for i, request in enumerate(requests) if not _canonical(request))
        data = CassetteData(self.protocol, requests, tuple(cassette_dict["responses"]), raw)
        path, blob = Path(cassette_path), encode(data)
        check_inside(path.parent if self.root is None else self.root, path, what="cassette")
        try:
            temp = scratch_path(self.root, path, "") if self.root is not None else None
            write_bytes_atomic(path, blob, temp=temp)
        except OSError as exc:
            if not self.keep_unsaved:
                raise
            self.unsaved = UnsavedCassette(path, exc, blob)


def _canonical(request: Any) -> bool:
    keys = getattr(request, "emrd_keys", None)
    return keys is not None and keys.redacted.parsed


#: How long a run waits for another run that records the same cassette before refusing.
LOCK_TIMEOUT_S = 1800.0


@contextmanager
def writer_lock(root: Path, path: Path, *, timeout: float = LOCK_TIMEOUT_S) -> Iterator[None]:
    """Hold the lock of the cassette ``path`` (one writer per cassette across processes; an OS
    file lock, released when its holder ends), then remove what an earlier writer left
    unfinished. Waiting longer than ``timeout`` seconds is a one-line :class:`CassetteError`.

    :param root: The cassette folder, where the lock files live.
    :param path: The cassette the lock is for.
    :param timeout: Seconds to wait for the lock.
    :returns: A context manager holding the lock.
    """
    from filelock import FileLock, Timeout

    lock_file = scratch_path(root, path, ".lock")
    try:
        lock = FileLock(lock_file, timeout=timeout)
        lock.acquire()
    except Timeout:
        raise CassetteError(
            f"cassette={str(path)!r} is being recorded by another run (lock {lock_file}); "
            f"waited {timeout:g} s. Let that run finish, or give this one its own "
            "--emrd-cassettes folder."
        ) from None
    try:
        for leftover in lock_file.parent.glob(f"{path.name}.*.tmp"):
            leftover.unlink(missing_ok=True)
        yield
    finally:
        lock.release()
