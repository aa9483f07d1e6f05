"""Rewrite format-1 cassettes (``.yaml.gz``) in the current format (``.yaml.xz``), verified.

Format-1 cassettes replay as they are; upgrading only makes them smaller (about a third, see
:mod:`._format`). Nothing is re-recorded: each file is decoded, encoded again, and the new
file is written only if it decodes to exactly the same interactions (every method, URI,
header and body byte), after which the old file is removed.
"""

from __future__ import annotations

from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path

from pytest_emrd._atomic import write_bytes_atomic
from pytest_emrd.cassette._format import CassetteData, FormatError, decode, encode
from pytest_emrd.cassette._paths import LEGACY_SUFFIX, current_path
from pytest_emrd.errors import CassetteError


@dataclass(frozen=True)
class Upgraded:
    """One cassette rewritten: where it was and is, and its size before and after."""

    old: Path
    new: Path
    old_bytes: int
    new_bytes: int


def same_traffic(a: CassetteData, b: CassetteData) -> bool:
    """Whether two cassettes read back (:func:`decode`) hold the same protocol and the same
    interactions, byte for byte (``canonical`` is compared too: it is known once read back)."""

    def requests(data: CassetteData) -> list[tuple]:
        return [(r.method, r.uri, r.body, sorted(r.headers.items())) for r in data.requests]

    return (
        a.protocol == b.protocol
        and a.canonical == b.canonical
        and requests(a) == requests(b)
        and list(a.responses) == list(b.responses)
    )


def legacy_files(root: Path) -> list[Path]:
    """The format-1 cassette files under ``root`` (recursively), sorted."""
    return sorted(root.rglob(f"*{LEGACY_SUFFIX}"))


def upgrade(root: Path) -> Iterator[Upgraded]:
    """Upgrade every ``*.yaml.gz`` under ``root``, one file at a time (each one is done or
    not: an interrupted run leaves no half-written file).

    :class:`CassetteError` names a file that is not a readable cassette, or whose ``.yaml.xz``
    twin already exists (which one to keep is the user's call); files before it stay upgraded.
    """
    for old in legacy_files(root):
        new = current_path(old)
        if new.exists():
            raise CassetteError(
                f"cassette={str(old)!r} has a twin {new.name} already, which replays instead; "
                "delete the one you do not want and run the upgrade again"
            )
        blob = old.read_bytes()
        try:
            data = decode(blob)
        except FormatError as exc:
            raise CassetteError(f"cassette={str(old)!r} is not readable: {exc}") from exc
        rewritten = encode(data)
        if not same_traffic(decode(rewritten), data):  # a format bug must never lose traffic
            raise CassetteError(f"cassette={str(old)!r} did not survive re-encoding; kept as is")
        write_bytes_atomic(new, rewritten)
        old.unlink()
        yield Upgraded(old, new, len(blob), len(rewritten))
