"""``emrd cassettes upgrade``: convert the cassettes older releases wrote, once, verified.

Formats ``emrd-cassette/1`` (``ep<NN>.yaml.gz``) and ``emrd-cassette/2`` (``ep<NN>.yaml.xz``)
become vcrpy cassettes (``ep<NN>.json.xz``, :mod:`._file`). Nothing is re-recorded: each
file is read (:mod:`._legacy`), written in the new format, and the new file is kept only if
it reads back to exactly the same protocol and interactions (every method, URI, header and
body byte); the old file is removed after that.
"""

from __future__ import annotations

from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path

from pytest_emrd._atomic import write_bytes_atomic
from pytest_emrd.cassette._file import SUFFIX, decode, encode, same_interactions
from pytest_emrd.cassette._legacy import LegacyError, read_legacy
from pytest_emrd.cassette._paths import LEGACY_SUFFIXES, SCRATCH, scratch_path
from pytest_emrd.errors import CassetteError


@dataclass(frozen=True)
class Upgraded:
    """One cassette converted: where it was and is, and its size before and after."""

    old: Path
    new: Path
    old_bytes: int
    new_bytes: int


def legacy_files(root: Path) -> list[Path]:
    """The cassette files under ``root`` with an old release's name ending, sorted."""
    found = (p for suffix in LEGACY_SUFFIXES for p in root.rglob(f"*{suffix}"))
    return sorted(p for p in found if SCRATCH not in p.relative_to(root).parts)


def upgrade(root: Path) -> Iterator[Upgraded]:
    """Convert every old cassette under ``root``, one file at a time (each one is done or
    not: an interrupted run leaves no half-written file, and running it again goes on).

    :class:`CassetteError` names a file that is not an old cassette, or whose new twin
    already exists (which one to keep is the user's call); files before it stay converted.
    """
    for old in legacy_files(root):
        new = old.with_name(old.name[: -len(".yaml.gz")] + SUFFIX)
        if new.exists():
            raise CassetteError(
                f"cassette={str(old)!r} has a twin {new.name} already, which replays instead; "
                "delete the one you do not want and run the upgrade again"
            )
        blob = old.read_bytes()
        try:
            data = read_legacy(blob)
        except LegacyError as exc:
            raise CassetteError(f"cassette={str(old)!r} is not an old cassette: {exc}") from None
        rewritten = encode(data)
        if not same_interactions(decode(rewritten), data):  # a bug must never lose traffic
            raise CassetteError(f"cassette={str(old)!r} did not survive conversion; kept as is")
        write_bytes_atomic(new, rewritten, temp=scratch_path(root, new, ""))
        old.unlink()
        yield Upgraded(old, new, len(blob), len(rewritten))
