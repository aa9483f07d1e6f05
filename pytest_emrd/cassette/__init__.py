"""Cassettes: one redacted vcrpy cassette per episode, compressed with xz (see :mod:`._file`);
``Tape(spec, ...)`` is the entry point: the episode runs in each of its takes."""

from pytest_emrd.cassette._episode import (
    EpisodeRun,
    FrameDriftWarning,
    Take,
    Tape,
    is_live,
    network_blocked,
)
from pytest_emrd.cassette._file import SUFFIX, CassetteData, FormatError, decode, decompress, encode
from pytest_emrd.cassette._paths import (
    SCRATCH,
    Invocation,
    cassette_path,
    found_cassette,
    missing_summary,
    record_command,
)
from pytest_emrd.cassette._persister import (
    EpisodePersister,
    UnsavedCassette,
    read_cassette,
    writer_lock,
)
from pytest_emrd.cassette._redact import (
    DIGEST,
    canonical_body,
    canonical_json,
    match_keys,
    redact_body,
)
from pytest_emrd.cassette._use import LATENCY, clear_caches, episode_cassette

__all__ = [
    "DIGEST",
    "LATENCY",
    "SCRATCH",
    "SUFFIX",
    "CassetteData",
    "EpisodePersister",
    "EpisodeRun",
    "FormatError",
    "FrameDriftWarning",
    "Invocation",
    "Take",
    "Tape",
    "UnsavedCassette",
    "canonical_body",
    "canonical_json",
    "cassette_path",
    "clear_caches",
    "decode",
    "decompress",
    "encode",
    "episode_cassette",
    "found_cassette",
    "is_live",
    "match_keys",
    "missing_summary",
    "network_blocked",
    "read_cassette",
    "record_command",
    "redact_body",
    "writer_lock",
]
