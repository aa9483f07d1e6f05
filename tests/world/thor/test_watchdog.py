"""The watchdog: a call returns, raises, or is abandoned after its time limit."""

from __future__ import annotations

import threading
import time

import pytest

from pytest_emrd.errors import ConfigError
from pytest_emrd.world.thor._launch import bounded


def _late() -> ConfigError:
    return ConfigError("too late")


def test_value_is_returned() -> None:
    assert bounded(lambda: 42, seconds=5, on_timeout=_late) == 42


def test_exception_of_the_call_propagates() -> None:
    def boom() -> None:
        raise ValueError("no build exists")

    with pytest.raises(ValueError, match="no build exists"):
        bounded(boom, seconds=5, on_timeout=_late)


def test_a_call_that_never_returns_is_abandoned_in_bounded_time() -> None:
    never = threading.Event()
    started = time.monotonic()
    with pytest.raises(ConfigError, match="too late"):
        bounded(never.wait, seconds=0.2, on_timeout=_late)
    assert time.monotonic() - started < 2.0
    never.set()
