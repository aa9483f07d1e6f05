"""Removing credentials from everything pytest-emrd persists or prints (pure, no I/O).

One scrubber for every exit: cassettes, the results store, reports, the GitHub step summary,
and what pytest prints or writes to ``--junitxml``. It removes the literal value of every
configured API key (the variables named by the registry's ``api_key_env``, :func:`watch_env`,
and any variable named like a credential: ``*_API_KEY``, ``*_TOKEN``, ``*_SECRET``...), also
URL-encoded and base64-encoded (as a value of its own); URL userinfo; credential-like query
parameters; credential-like headers and fields written as text, and bare ``Bearer`` tokens.
Values shorter than :data:`MIN_SECRET_CHARS` are not keys (a variable set to ``1`` must not
blank every digit of a report).

Logs are scrubbed by :class:`ScrubFilter`, which :func:`install_log_scrub` attaches to the
root logger's handlers and to the ``httpx``, ``httpcore``, ``urllib3`` and ``vcr`` loggers:
``pytest --log-cli-level=DEBUG`` prints httpx's request line already scrubbed.
"""

from __future__ import annotations

import base64
import functools
import logging
import os
import re
from collections.abc import Iterable, Mapping
from typing import Any, Final
from urllib.parse import parse_qsl, quote, quote_plus, urlencode, urlsplit, urlunsplit

REDACTED: Final = "<redacted>"
#: Query parameters whose value is a credential (compared case-insensitively).
SECRET_PARAMS: Final = frozenset(
    {
        "key",
        "api_key",
        "apikey",
        "api-key",
        "token",
        "access_token",
        "refresh_token",
        "id_token",
        "auth",
        "sig",
        "signature",
        "secret",
        "client_secret",
        "password",
        "x-goog-api-key",
        "x-amz-signature",
        "x-amz-security-token",
    }
)
#: Header (and JSON field) names whose value is a credential.
SECRET_HEADERS: Final = (
    "authorization",
    "proxy-authorization",
    "x-api-key",
    "api-key",
    "api_key",
    "x-goog-api-key",
    "cookie",
    "set-cookie",
    "access_token",
    "client_secret",
)
#: Environment variable names treated as credentials without being registered.
SECRET_ENV: Final = re.compile(r"(?:^|_)(?:API_KEY|APIKEY|TOKEN|SECRET|SECRET_KEY|ACCESS_KEY)$")
MIN_SECRET_CHARS: Final = 8

_watched: set[str] = set()
_watched_values: set[str] = set()
_cached: list[Any] = [None, ()]

_USERINFO = re.compile(r"(?P<scheme>://)[^/\s@'\"<>`]+@")
_PARAM = re.compile(
    r"(?P<head>[?&;](?:" + "|".join(re.escape(p) for p in sorted(SECRET_PARAMS)) + r")=)"
    r"[^&#\s'\"<>`\\]+",
    re.IGNORECASE,
)
_HEADER = re.compile(
    r"(?P<head>(?<![\w-])(?:"
    + "|".join(re.escape(h) for h in SECRET_HEADERS)
    + r")['\"]?\s*[:=]\s*['\"]?(?:(?:Bearer|Basic|Token)\s+)?)[^\s'\",;}\]\\]+",
    re.IGNORECASE,
)
_BEARER = re.compile(r"(?P<head>\b(?:Bearer|Basic)\s+)[A-Za-z0-9._~+/=-]{8,}")


def watch_env(names: Iterable[str | None]) -> None:
    """Also treat the values of these environment variables as secrets (``api_key_env``)."""
    _watched.update(name for name in names if name)


def watch_value(value: str) -> None:
    """Also treat ``value`` as a secret: the fallback a ``${VAR:-fallback}`` resolved to
    stands where the variable's value would, so a recording made with the variable set and
    a replay made without it redact the same place alike."""
    _watched_values.add(value)


def secret_values(env: Mapping[str, str] | None = None) -> tuple[str, ...]:
    """The configured key values present in ``env`` (default: the process environment, with
    the fallbacks of :func:`watch_value`), longest first so that a key containing another is
    removed whole. For the process environment the answer is cached against a copy of its
    raw bytes, compared without hashing them (decoding ``os.environ`` costs 150 us for 40
    variables, paid on every request otherwise)."""
    if env is not None:
        return _secret_values(env)
    raw = getattr(os.environ, "_data", None)
    if not isinstance(raw, dict):
        return _secret_values(os.environ, _watched_values)
    if _cached[0] != (raw, _watched, _watched_values):
        seen = (dict(raw), set(_watched), set(_watched_values))
        _cached[:] = [seen, _secret_values(os.environ, _watched_values)]
    return _cached[1]


def _secret_values(env: Mapping[str, str], fallbacks: Iterable[str] = ()) -> tuple[str, ...]:
    named = [
        value for name, value in env.items() if name in _watched or SECRET_ENV.search(name.upper())
    ]
    values = {
        form
        for value in (*named, *fallbacks)
        if len(value.strip()) >= MIN_SECRET_CHARS
        for form in encoded_forms(value.strip())
    }
    return tuple(sorted(values, key=lambda v: (-len(v), v)))


def encoded_forms(secret: str) -> tuple[str, ...]:
    """``secret`` as written, URL-encoded (``quote`` and ``quote_plus``) and base64-encoded
    (standard and URL-safe alphabets, with and without padding)."""
    raw = secret.encode()
    b64 = base64.b64encode(raw).decode()
    urlsafe = base64.urlsafe_b64encode(raw).decode()
    forms = (secret, quote(secret, safe=""), quote_plus(secret), b64, b64.rstrip("="), urlsafe)
    return tuple(dict.fromkeys(f for f in (*forms, urlsafe.rstrip("=")) if f))


def scrub_secrets(text: str, secrets: Iterable[str] | None = None) -> str:
    """``text`` with every literal key value replaced by :data:`REDACTED` (nothing else)."""
    for secret in secret_values() if secrets is None else secrets:
        if secret in text:
            text = text.replace(secret, REDACTED)
    return text


def scrub(text: str, secrets: Iterable[str] | None = None) -> str:
    """``text`` without key values, URL userinfo, secret query parameters or headers (each
    pattern runs only when a cheap substring test says it may match)."""
    text = scrub_secrets(text, secrets)
    if "://" in text and "@" in text:
        text = _USERINFO.sub(rf"\g<scheme>{REDACTED}@", text)
    low = text.lower()
    if "=" in text and any(f"{p}=" in low for p in SECRET_PARAMS):
        text = _PARAM.sub(rf"\g<head>{REDACTED}", text)
    if any(h in low for h in SECRET_HEADERS):
        text = _HEADER.sub(rf"\g<head>{REDACTED}", text)
    if "bearer" in low or "basic" in low:
        text = _BEARER.sub(rf"\g<head>{REDACTED}", text)
    return text


@functools.lru_cache(maxsize=8)
def _heads(secrets: tuple[str, ...]) -> frozenset[bytes]:
    """The first bytes of each of ``secrets``: where none of them is found, no key value is."""
    return frozenset(secret.encode()[:4] for secret in secrets)


def scrub_bytes(
    data: bytes, *, literal_only: bool = False, secrets: Iterable[str] | None = None
) -> bytes:
    """:func:`scrub_secrets` of raw bytes (any encoding), then, unless ``literal_only``, the
    pattern passes of :func:`scrub` when the bytes are UTF-8 text. The key values are looked
    for one by one only where the first bytes of one of them are (a few searches, not one
    per encoded form of each key)."""
    values = secret_values() if secrets is None else tuple(secrets)
    if any(head in data for head in _heads(values)):
        redacted = REDACTED.encode()
        for secret in values:
            data = data.replace(secret.encode(), redacted)
    if literal_only:
        return data
    try:
        text = data.decode()
    except UnicodeDecodeError:
        return data
    clean = scrub(text, ())
    return data if clean == text else clean.encode()


def scrub_uri(uri: str) -> str:
    """``uri`` without userinfo and without secret query parameters (dropped, not masked),
    for files that store URIs as data (cassettes)."""
    parts = urlsplit(uri)
    netloc = parts.netloc.rpartition("@")[2]
    query = parts.query
    if query:
        pairs = parse_qsl(query, keep_blank_values=True)
        query = urlencode([(k, v) for k, v in pairs if k.lower() not in SECRET_PARAMS])
    if netloc == parts.netloc and query == parts.query:
        return scrub_secrets(uri)
    return scrub_secrets(urlunsplit(parts._replace(netloc=netloc, query=query)))


def scrub_report(report: Any) -> None:
    """Scrub a pytest test or collect report in place: its failure text and captured
    sections, which the terminal and ``--junitxml`` print (duck-typed: no pytest import)."""
    longrepr = getattr(report, "longrepr", None)
    if isinstance(longrepr, tuple):  # a skip: (path, line, message)
        report.longrepr = (*longrepr[:-1], scrub(str(longrepr[-1])))
    elif longrepr is not None:
        text = longrepr if isinstance(longrepr, str) else str(longrepr)
        clean = scrub(text)
        if clean != text:
            report.longrepr = clean
    sections = getattr(report, "sections", None)
    if sections:
        report.sections = [(title, scrub(body)) for title, body in sections]


#: Loggers of the libraries that print request lines (URL with its query) and headers.
LIBRARY_LOGGERS: Final = ("httpx", "httpcore", "urllib3", "vcr")


class ScrubFilter(logging.Filter):
    """A logging filter that keeps every record and scrubs it in place: its message (``msg``
    with its ``args`` applied), its formatted traceback and its stack (:func:`scrub`)."""

    def filter(self, record: logging.LogRecord) -> bool:
        if getattr(record, "emrd_scrubbed", False):
            return True
        try:
            message = record.getMessage()
        except Exception:  # a bad format string: the handler reports it, as it would without us
            return True
        clean = scrub(message)
        if clean != message:
            record.msg, record.args = clean, None
        if record.exc_info and not record.exc_text:
            record.exc_text = logging.Formatter().formatException(record.exc_info)
        if record.exc_text:
            record.exc_text = scrub(record.exc_text)
        if record.stack_info:
            record.stack_info = scrub(record.stack_info)
        record.emrd_scrubbed = True
        return True


SCRUB_FILTER: Final = ScrubFilter()


def install_log_scrub() -> None:
    """Attach :data:`SCRUB_FILTER` to every handler of the root logger and to the loggers of
    :data:`LIBRARY_LOGGERS` and their children (idempotent: call it whenever handlers may
    have been added, e.g. at the start of each pytest phase)."""
    for handler in logging.getLogger().handlers:
        handler.addFilter(SCRUB_FILTER)
    prefixes = tuple(f"{name}." for name in LIBRARY_LOGGERS)
    names = [n for n in list(logging.Logger.manager.loggerDict) if n.startswith(prefixes)]
    for name in (*LIBRARY_LOGGERS, *names):
        logging.getLogger(name).addFilter(SCRUB_FILTER)


def remove_log_scrub() -> None:
    """Detach :data:`SCRUB_FILTER` from every logger and root handler it was attached to."""
    for handler in logging.getLogger().handlers:
        handler.removeFilter(SCRUB_FILTER)
    for logger in list(logging.Logger.manager.loggerDict.values()):
        if isinstance(logger, logging.Logger):
            logger.removeFilter(SCRUB_FILTER)
