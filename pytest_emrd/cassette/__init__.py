"""Cassettes: one redacted vcrpy cassette per episode, compressed with xz (see :mod:`._file`).

``run_with_cassette`` is the entry point; the rest is exported for tools and tests.
"""

from pytest_emrd._scrub import SECRET_HEADERS
from pytest_emrd.cassette._drift import first_difference
from pytest_emrd.cassette._episode import (
    EpisodeRun,
    EpisodeRunner,
    FrameDriftWarning,
    is_live,
    run_with_cassette,
)
from pytest_emrd.cassette._file import (
    SUFFIX,
    CassetteData,
    FormatError,
    IntegrityError,
    LegacyFormatError,
    decode,
    decompress,
    encode,
    same_interactions,
)
from pytest_emrd.cassette._network import network_blocked
from pytest_emrd.cassette._paths import (
    SCRATCH,
    Invocation,
    cassette_path,
    found_cassette,
    missing_cassettes,
    missing_summary,
    record_command,
)
from pytest_emrd.cassette._persister import EpisodePersister, writer_lock
from pytest_emrd.cassette._redact import (
    MatchKeys,
    Redacted,
    canonical_json,
    match_keys,
    redact_body,
)
from pytest_emrd.cassette._routing import routing
from pytest_emrd.cassette._upgrade import Upgraded, legacy_files, upgrade
from pytest_emrd.cassette._use import (
    EpisodeCassette,
    clear_caches,
    episode_cassette,
    keep_response,
    redact_request,
)

__all__ = [
    "SCRATCH",
    "SECRET_HEADERS",
    "SUFFIX",
    "CassetteData",
    "EpisodeCassette",
    "EpisodePersister",
    "EpisodeRun",
    "EpisodeRunner",
    "FormatError",
    "FrameDriftWarning",
    "IntegrityError",
    "Invocation",
    "LegacyFormatError",
    "MatchKeys",
    "Redacted",
    "Upgraded",
    "canonical_json",
    "cassette_path",
    "clear_caches",
    "decode",
    "decompress",
    "encode",
    "episode_cassette",
    "first_difference",
    "found_cassette",
    "is_live",
    "keep_response",
    "legacy_files",
    "match_keys",
    "missing_cassettes",
    "missing_summary",
    "network_blocked",
    "record_command",
    "redact_body",
    "redact_request",
    "routing",
    "run_with_cassette",
    "same_interactions",
    "upgrade",
    "writer_lock",
]
