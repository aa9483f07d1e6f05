"""Cassettes: one gzip-compressed, redacted, content-addressed vcrpy cassette per episode.

``run_with_cassette`` is the entry point; the rest is exported for tools and tests.
"""

from pytest_emrd._scrub import SECRET_HEADERS
from pytest_emrd.cassette._drift import first_difference
from pytest_emrd.cassette._episode import (
    AgentRunner,
    EpisodeRun,
    EpisodeRunner,
    FrameDriftWarning,
    agent_runner,
    is_live,
    run_with_cassette,
)
from pytest_emrd.cassette._format import CassetteData, FormatError, decode, encode
from pytest_emrd.cassette._network import network_blocked
from pytest_emrd.cassette._paths import (
    Invocation,
    cassette_path,
    missing_cassettes,
    missing_summary,
    record_command,
)
from pytest_emrd.cassette._persister import EpisodePersister
from pytest_emrd.cassette._redact import (
    MatchKeys,
    Redacted,
    canonical_json,
    match_keys,
    redact_body,
)
from pytest_emrd.cassette._routing import routing
from pytest_emrd.cassette._use import (
    EpisodeCassette,
    clear_caches,
    episode_cassette,
    keep_response,
    redact_request,
)

__all__ = [
    "SECRET_HEADERS",
    "AgentRunner",
    "CassetteData",
    "EpisodeCassette",
    "EpisodePersister",
    "EpisodeRun",
    "EpisodeRunner",
    "FormatError",
    "FrameDriftWarning",
    "Invocation",
    "MatchKeys",
    "Redacted",
    "agent_runner",
    "canonical_json",
    "cassette_path",
    "clear_caches",
    "decode",
    "encode",
    "episode_cassette",
    "first_difference",
    "is_live",
    "keep_response",
    "match_keys",
    "missing_cassettes",
    "missing_summary",
    "network_blocked",
    "record_command",
    "redact_body",
    "redact_request",
    "routing",
    "run_with_cassette",
]
