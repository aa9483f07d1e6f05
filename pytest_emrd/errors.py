"""One error hierarchy for every caller mistake and every failure the product reports.

Messages follow one shape: ``name=value``, what is wrong, and what to do instead.
The ``check_*`` helpers are the only place such messages are built for common checks.
"""

from __future__ import annotations

from collections.abc import Iterable
from typing import Any


class EmrdError(Exception):
    """Root of every error raised by pytest-emrd on purpose."""


class ConfigError(EmrdError):
    """Bad user input: options, thresholds.yaml, model registry, CLI arguments, world config."""


class ProtocolError(EmrdError):
    """A model reply, cassette or stored file that cannot be read as the protocol demands."""


class TransportError(EmrdError):
    """A model endpoint that failed after the bounded retries were spent."""


class CassetteError(EmrdError):
    """A missing, corrupted, stale or divergent cassette."""


class MissingExtraError(EmrdError):
    """An optional dependency is not installed; the message carries the pip command."""


def check_choice(name: str, value: Any, allowed: Iterable[Any], *, hint: str = "") -> None:
    """Raise :class:`ConfigError` unless ``value`` is one of ``allowed``."""
    options = list(allowed)
    if value not in options:
        listed = ", ".join(repr(o) for o in options)
        suffix = f" {hint}" if hint else ""
        raise ConfigError(f"{name}={value!r} is not one of {listed}.{suffix}")


def check_positive_int(name: str, value: Any) -> int:
    """Return ``value`` as an int, raising :class:`ConfigError` unless it is an int >= 1."""
    if isinstance(value, bool) or not isinstance(value, int) or value < 1:
        raise ConfigError(f"{name}={value!r} must be a whole number >= 1.")
    return value


def check_range(name: str, value: float, low: float, high: float) -> float:
    """Raise :class:`ConfigError` unless ``low <= value <= high``."""
    if not low <= value <= high:
        raise ConfigError(f"{name}={value!r} must lie in [{low}, {high}].")
    return value


def missing_extra(module: str, extra: str) -> MissingExtraError:
    """The error for an optional dependency that is not installed."""
    return MissingExtraError(
        f"{module} is not installed; it comes with the {extra!r} extra: "
        f"pip install 'pytest-emrd[{extra}]'"
    )
