"""Bounded retries with exponential backoff and jitter, honouring ``Retry-After`` (tenacity).

Retried: HTTP 429, any 5xx in :data:`RETRY_STATUSES`, transport errors (connection refused
or reset, timeouts) and 2xx bodies that are not the JSON the provider promised (empty, not
JSON, nested too deep to parse, or of another shape). Not
retried: other 4xx (a bad key or a bad request does not heal). Jitter only changes how long
we sleep; the request sent again is the same object, byte for byte.

The loop is :class:`tenacity.Retrying` (bounded by ``stop_after_attempt``), entered once a
first attempt has failed (a request that succeeds at once pays nothing for it); the wait is
ours, because it must read ``Retry-After`` from the failed response and draw its jitter
from a seedable generator. Each retry is logged on ``pytest_emrd.agent.retry`` at WARNING
with the attempt, the wait and the cause; URLs are logged without userinfo or query and
the API key's literal value is masked wherever it would appear. The record carries the
attribute :data:`pytest_emrd._logging.RETRY_ATTR` (live progress counts retries by it).
"""

from __future__ import annotations

import email.utils
import functools
import logging
import random
import time
from collections.abc import Callable, Iterable
from dataclasses import dataclass, field
from typing import Any, Final

import httpx
import tenacity

from pytest_emrd import __version__
from pytest_emrd._logging import RETRY_ATTR
from pytest_emrd._wire import encode_body
from pytest_emrd.errors import TransportError

RETRY_STATUSES: Final = frozenset({429, 500, 502, 503, 504, 520, 522, 524, 529})
_BODY_EXCERPT: Final = 300
_MASK: Final = "***"
#: Headers of every request besides the provider's (Host and Content-Length come from httpx).
#: The request is built here rather than by ``httpx.Client.build_request``, which would add
#: its own defaults (``Accept: */*``, ``Accept-Encoding``, ``Connection``, its user agent)
#: and the cookies the server set: a model API needs none of them, a cookie would carry state
#: from one request to the next, and every header is copied and scanned several times per
#: request on its way through vcrpy and the redactor.
_DEFAULT_HEADERS: Final = {
    "Accept": "application/json",
    "Content-Type": "application/json",
    "User-Agent": f"pytest-emrd/{__version__}",
}

logger = logging.getLogger("pytest_emrd.agent.retry")


class _Retryable(Exception):
    """One failed attempt that may heal: its cause and the server's ``Retry-After``."""

    def __init__(self, cause: str, retry_after: float | None = None) -> None:
        super().__init__(cause)
        self.retry_after = retry_after


@dataclass(frozen=True)
class RetryPolicy:
    """How often and how long to wait between attempts."""

    max_retries: int = 4
    """Retries after the first attempt."""
    base_delay_s: float = 0.5
    """Backoff before retry ``n`` (0-based) is ``base * 2**n``, scaled by jitter."""
    max_delay_s: float = 30.0
    """Cap on any single wait, ``Retry-After`` included."""
    sleep: Callable[[float], None] = field(default=time.sleep, compare=False)
    rng: random.Random = field(default_factory=random.Random, compare=False)

    def backoff(self, attempt: int, retry_after: float | None) -> float:
        """Seconds to wait before retry ``attempt`` (0-based)."""
        jittered = self.base_delay_s * (2**attempt) * self.rng.uniform(0.5, 1.0)
        wait = max(jittered, retry_after) if retry_after is not None else jittered
        return min(wait, self.max_delay_s)


def retry_after_seconds(value: str | None) -> float | None:
    """``Retry-After`` as seconds: delta-seconds or an HTTP date; None if absent/unreadable."""
    if not value:
        return None
    value = value.strip()
    try:
        return max(0.0, float(value))
    except ValueError:
        pass
    try:
        when = email.utils.parsedate_to_datetime(value)
    except (TypeError, ValueError):
        return None
    return max(0.0, when.timestamp() - time.time())


def _masker(secrets: Iterable[str | None]) -> Callable[[str], str]:
    values = [s for s in secrets if s]

    def mask(text: str) -> str:
        for value in values:
            text = text.replace(value, _MASK)
        return text

    return mask


def _excerpt(response: httpx.Response) -> str:
    text = response.text
    return text[:_BODY_EXCERPT] + ("..." if len(text) > _BODY_EXCERPT else "")


@functools.lru_cache(maxsize=64)
def _parsed_url(url: str) -> httpx.URL:
    """``url`` parsed once (a client posts to one or two URLs; ``httpx.URL`` is immutable)."""
    return httpx.URL(url)


@functools.lru_cache(maxsize=64)
def _public_url(url: str) -> str:
    """``url`` without userinfo or query string (either may carry a credential)."""
    return str(_parsed_url(url).copy_with(userinfo=b"", query=None, fragment=None))


def _request_headers(headers: dict[str, str]) -> dict[str, str]:
    """``headers`` over :data:`_DEFAULT_HEADERS` (names compared case-insensitively)."""
    given = {name.lower() for name in headers}
    return {k: v for k, v in _DEFAULT_HEADERS.items() if k.lower() not in given} | headers


def _attempt(http: httpx.Client, request: httpx.Request, url: str, read: Callable[[Any], Any]):
    """One POST: the read result, :class:`_Retryable`, or a non-retried TransportError."""
    try:
        response = http.send(request)
    except httpx.TransportError as exc:
        raise _Retryable(f"{type(exc).__name__}: {exc}") from exc
    if response.status_code in RETRY_STATUSES:
        retry_after = retry_after_seconds(response.headers.get("retry-after"))
        raise _Retryable(f"HTTP {response.status_code}: {_excerpt(response)}", retry_after)
    if response.is_error:
        raise TransportError(
            f"POST {url} failed with HTTP {response.status_code} (not retried): "
            f"{_excerpt(response)}"
        )
    try:
        return read(response.json())
    except (ValueError, KeyError, TypeError, IndexError, AttributeError, RecursionError) as exc:
        raise _Retryable(
            f"HTTP {response.status_code} with an unreadable body "
            f"({type(exc).__name__}: {exc}): {_excerpt(response)}"
        ) from exc


def _made(failure: _Retryable, attempt: Callable[..., Any]) -> Callable[..., Any]:
    """``attempt`` whose first call raises ``failure``, the outcome of an attempt already
    made: tenacity counts, logs and waits for it as if it had made it."""
    pending = [failure]

    def call(*args: Any) -> Any:
        if pending:
            raise pending.pop()
        return attempt(*args)

    return call


def post_json(
    http: httpx.Client,
    url: str,
    *,
    body: dict[str, Any],
    headers: dict[str, str],
    policy: RetryPolicy,
    read: Callable[[Any], Any],
    secrets: Iterable[str | None] = (),
) -> Any:
    """POST ``body`` and return ``read(json)``, retrying per ``policy``.

    ``read`` turns the decoded JSON into the caller's result and raises ``KeyError``,
    ``TypeError`` or ``ValueError`` when the shape is wrong (treated as a garbage body).
    Exhausted retries or a non-retryable status raise :class:`TransportError` naming the
    URL, the attempts and the last cause. ``secrets`` (the API key) are masked in every
    log line and error message.
    """
    content = encode_body(body)  # what json=body sends, each message encoded once per episode
    request = httpx.Request(
        "POST",
        _parsed_url(url),
        content=content,
        headers=_request_headers(headers),
        extensions={"timeout": http.timeout.as_dict()},
    )
    mask = _masker(secrets)
    shown = _public_url(url)
    attempts = policy.max_retries + 1

    def wait(state: tenacity.RetryCallState) -> float:
        failure = state.outcome.exception() if state.outcome else None
        retry_after = failure.retry_after if isinstance(failure, _Retryable) else None
        return policy.backoff(state.attempt_number - 1, retry_after)

    def log_retry(state: tenacity.RetryCallState) -> None:
        failure = state.outcome.exception() if state.outcome else None
        logger.warning(
            "POST %s attempt %d/%d failed; retrying in %.2f s. Cause: %s",
            shown,
            state.attempt_number,
            attempts,
            state.upcoming_sleep,
            mask(str(failure)),
            extra={RETRY_ATTR: state.attempt_number},
        )

    try:
        try:  # most requests succeed at once: no retry machinery for them
            return _attempt(http, request, shown, read)
        except _Retryable as failure:
            first = failure
        retrying = tenacity.Retrying(
            stop=tenacity.stop_after_attempt(attempts),
            wait=wait,
            retry=tenacity.retry_if_exception_type(_Retryable),
            before_sleep=log_retry,
            sleep=policy.sleep,
        )
        return retrying(_made(first, _attempt), http, request, shown, read)
    except tenacity.RetryError as exc:
        cause = mask(str(exc.last_attempt.exception()))
        raise TransportError(
            f"POST {shown} failed after {attempts} attempt(s); last cause: {cause}"
        ) from None
    except TransportError as exc:
        raise TransportError(mask(str(exc))) from None
