"""Bounded retries with exponential backoff and jitter, honouring ``Retry-After``.

Retried: HTTP 429, the 5xx of :data:`RETRY_STATUSES`, transport errors and 2xx bodies that
are not the JSON the provider promised. Not retried: other 4xx (a bad key or request does
not heal). The request sent again is the same object, byte for byte. Each retry is logged
on ``pytest_emrd.agent.retry`` at WARNING (docs/user-guide/recording.md) with the attribute
:data:`pytest_emrd._logging.RETRY_ATTR`, by which live progress counts retries.
"""

from __future__ import annotations

import contextlib
import email.utils
import logging
import random
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any, Final

import httpx

from pytest_emrd import __version__
from pytest_emrd._logging import RETRY_ATTR
from pytest_emrd.errors import TransportError

RETRY_STATUSES: Final = frozenset({429, 500, 502, 503, 504, 520, 522, 524, 529})
_BODY_EXCERPT: Final = 300
#: Headers of every request besides the provider's (Host and Content-Length come from httpx).
#: Not ``httpx.Client.build_request``, which would add its own defaults and the cookies the
#: server set: a model API needs none of them, and a cookie would carry state between requests.
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
    with contextlib.suppress(ValueError):
        return max(0.0, float(value))
    try:
        when = email.utils.parsedate_to_datetime(value)
    except (TypeError, ValueError):
        return None
    return max(0.0, when.timestamp() - time.time())


def _excerpt(response: httpx.Response) -> str:
    text = response.text
    return text[:_BODY_EXCERPT] + ("..." if len(text) > _BODY_EXCERPT else "")


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


def post_json(
    http: httpx.Client,
    url: httpx.URL,
    shown: str,
    *,
    content: bytes,
    headers: dict[str, str],
    policy: RetryPolicy,
    read: Callable[[Any], Any],
    key: str | None,
) -> Any:
    """POST the JSON ``content`` to ``url`` and return ``read(json)`` (which raises on a garbage
    body), retrying per ``policy``; exhausted retries or a non-retryable status raise
    :class:`TransportError` naming the URL as ``shown`` (logged), the attempts and the last
    cause, with the API ``key`` masked."""
    sent = httpx.Headers(_DEFAULT_HEADERS)
    sent.update(headers)  # a default is dropped where ``headers`` sets it, in any case
    request = httpx.Request(
        "POST", url, content=content, headers=sent, extensions={"timeout": http.timeout.as_dict()}
    )

    def mask(text: str) -> str:
        return text.replace(key, "***") if key else text

    attempts = policy.max_retries + 1
    for attempt in range(1, attempts + 1):
        try:
            return _attempt(http, request, shown, read)
        except _Retryable as failure:
            cause = mask(str(failure))
            if attempt == attempts:
                break
            wait = policy.backoff(attempt - 1, failure.retry_after)
            logger.warning(
                "POST %s attempt %d/%d failed; retrying in %.2f s. Cause: %s",
                shown,
                attempt,
                attempts,
                wait,
                cause,
                extra={RETRY_ATTR: attempt},
            )
            policy.sleep(wait)
        except TransportError as exc:
            raise TransportError(mask(str(exc))) from None
    raise TransportError(f"POST {shown} failed after {attempts} attempt(s); last cause: {cause}")
