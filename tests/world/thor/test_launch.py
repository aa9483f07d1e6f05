"""Start-up and steps never hang: the watchdog and option checks (no ai2thor needed)."""

from __future__ import annotations

import sys
import threading
import time
from collections.abc import Callable
from typing import Any

import pytest

from pytest_emrd.errors import ConfigError, MissingExtraError, TransportError
from pytest_emrd.world._model import Layout
from pytest_emrd.world.thor import ThorSimulator
from pytest_emrd.world.thor._launch import import_ai2thor

FailedReset = Callable[[ThorSimulator, Layout, float], ConfigError]


def test_missing_ai2thor_names_the_extra(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setitem(sys.modules, "ai2thor", None)
    with pytest.raises(MissingExtraError, match=r"pytest-emrd\[thor\]"):
        import_ai2thor()


def test_controller_that_blocks_forever_is_abandoned(
    failed_reset: FailedReset, layout: Layout
) -> None:
    never = threading.Event()
    sim = ThorSimulator(controller_factory=lambda **_: never.wait(), start_timeout=0.3)
    assert "did not start" in str(failed_reset(sim, layout, 3.0))
    never.set()


def test_a_step_that_never_returns_is_a_transport_error(
    fake_controller: type, layout: Layout
) -> None:
    sim = ThorSimulator(controller_factory=fake_controller, step_timeout=0.3)
    sim.reset(layout, "baseline", "Office", 0)
    never = threading.Event()
    fake_controller.instances[-1].step = lambda *a, **k: never.wait()
    started = time.monotonic()
    with pytest.raises(TransportError, match=r"step_timeout=0\.3"):
        sim.step("Turn(Left)")
    assert time.monotonic() - started < 3.0
    never.set()


@pytest.mark.parametrize(
    ("option", "value"),
    [("start_timeout", 0), ("step_timeout", -1.0), ("step_timeout", "fast")],
    ids=["zero-start", "negative-step", "text-step"],
)
def test_bad_timeouts_are_rejected(option: str, value: Any) -> None:
    with pytest.raises(ConfigError, match=f"{option}="):
        ThorSimulator(**{option: value})
