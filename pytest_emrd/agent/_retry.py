"""Bounded retries with exponential backoff and jitter, honouring ``Retry-After``.

Retried: HTTP 429, any 5xx, transport errors (connection refused or reset, timeouts) and
2xx bodies that are not the JSON the provider promised. Not retried: other 4xx (a bad
key or a bad request does not heal). Jitter only changes how long we sleep; the request
sent again is the same object, byte for byte.
"""

from __future__ import annotations

import email.utils
import random
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any, Final

import httpx

from pytest_emrd.errors import TransportError

RETRY_STATUSES: Final = frozenset({429, 500, 502, 503, 504, 520, 522, 524, 529})
_BODY_EXCERPT: Final = 300


class _Malformed(Exception):
    """A 2xx response whose body is not what the provider promised (retried)."""


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


def _excerpt(response: httpx.Response) -> str:
    text = response.text
    return text[:_BODY_EXCERPT] + ("..." if len(text) > _BODY_EXCERPT else "")


def post_json(
    http: httpx.Client,
    url: str,
    *,
    body: dict[str, Any],
    headers: dict[str, str],
    policy: RetryPolicy,
    read: Callable[[Any], Any],
) -> Any:
    """POST ``body`` and return ``read(json)``, retrying per ``policy``.

    ``read`` turns the decoded JSON into the caller's result and raises ``KeyError``,
    ``TypeError`` or ``ValueError`` when the shape is wrong (treated as a garbage body).
    Exhausted retries or a non-retryable status raise :class:`TransportError` naming the
    URL, the attempts and the last cause.
    """
    request = http.build_request("POST", url, json=body, headers=headers)
    cause = ""
    for attempt in range(policy.max_retries + 1):
        retry_after = None
        try:
            response = http.send(request)
            if response.status_code in RETRY_STATUSES:
                retry_after = retry_after_seconds(response.headers.get("retry-after"))
                cause = f"HTTP {response.status_code}: {_excerpt(response)}"
            elif response.is_error:
                raise TransportError(
                    f"POST {url} failed with HTTP {response.status_code} (not retried): "
                    f"{_excerpt(response)}"
                )
            else:
                try:
                    return read(response.json())
                except (ValueError, KeyError, TypeError, IndexError) as exc:
                    raise _Malformed(
                        f"HTTP {response.status_code} with an unreadable body "
                        f"({type(exc).__name__}: {exc}): {_excerpt(response)}"
                    ) from exc
        except httpx.TransportError as exc:
            cause = f"{type(exc).__name__}: {exc}"
        except _Malformed as exc:
            cause = str(exc)
        if attempt < policy.max_retries:
            policy.sleep(policy.backoff(attempt, retry_after))
    raise TransportError(
        f"POST {url} failed after {policy.max_retries + 1} attempt(s); last cause: {cause}"
    )
