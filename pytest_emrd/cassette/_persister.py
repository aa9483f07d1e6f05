"""vcrpy persister for EMRD cassettes: atomic writes, protocol check (file I/O only)."""

from __future__ import annotations

from pathlib import Path
from typing import Any

from vcr.persisters.filesystem import CassetteNotFoundError

from pytest_emrd._atomic import write_bytes_atomic
from pytest_emrd.cassette._format import (
    CassetteData,
    FormatError,
    NewerFormatError,
    decode,
    encode,
)
from pytest_emrd.cassette._paths import current_path
from pytest_emrd.cassette._redact import canonical_keys
from pytest_emrd.errors import CassetteError


class EpisodePersister:
    """Loads and saves one episode's cassette under the current protocol version.

    A missing file is "not found" (vcrpy records it when the mode allows); a file that
    cannot be read is a :class:`CassetteError` naming it; a file recorded under another
    protocol is a :class:`CassetteError` with the command that re-records it; so is a file
    a newer pytest-emrd wrote, which also says to upgrade. In ``all`` mode the old file is
    never read: it is replaced when the episode finishes. A format-1 file (``.yaml.gz``) is
    read as it is; saving over it writes the ``.yaml.xz`` file and removes it.
    """

    def __init__(self, *, protocol: str, fresh: bool, rerecord_command: str) -> None:
        self.protocol = protocol
        self.fresh = fresh
        self.rerecord_command = rerecord_command

    def load_cassette(self, cassette_path: str | Path, serializer: Any = None) -> tuple[list, list]:
        path = Path(cassette_path)
        if self.fresh or not path.is_file():
            raise CassetteNotFoundError(str(path))
        try:
            data = decode(path.read_bytes())
        except NewerFormatError as exc:
            raise CassetteError(
                f"cassette={str(path)!r} cannot be read by this pytest-emrd: {exc}. Upgrade "
                f"pytest-emrd (pip install -U pytest-emrd), or record it again: "
                f"{self.rerecord_command}"
            ) from exc
        except (FormatError, OSError) as exc:
            raise CassetteError(
                f"cassette={str(path)!r} is corrupted: {exc}. Delete it and record it again: "
                f"{self.rerecord_command}"
            ) from exc
        if data.protocol != self.protocol:
            raise CassetteError(
                f"cassette={str(path)!r} was recorded under protocol {data.protocol!r}, but the "
                f"world and prompt are now at {self.protocol!r}; replaying it would compare "
                f"stale traffic. Re-record it: {self.rerecord_command}"
            )
        for request, canonical in zip(data.requests, data.canonical, strict=True):
            if canonical:  # recorded already redacted: keyed as it is, never parsed again
                request.emrd_keys = canonical_keys(request.method, request.path, request.body)
        return list(data.requests), list(data.responses)

    def save_cassette(
        self, cassette_path: str | Path, cassette_dict: dict[str, Any], serializer: Any = None
    ) -> None:
        data = CassetteData(
            protocol=self.protocol,
            requests=tuple(cassette_dict["requests"]),
            responses=tuple(cassette_dict["responses"]),
        )
        path = Path(cassette_path)
        target = current_path(path)
        write_bytes_atomic(target, encode(data))
        if target != path:  # a format-1 file recorded over: its replacement is written
            path.unlink(missing_ok=True)
