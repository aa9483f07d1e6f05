"""Start-up and steps never hang: the watchdog and option checks (no ai2thor needed)."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import threading
import time
from collections.abc import Callable
from pathlib import Path
from types import SimpleNamespace
from typing import Any

import pytest

from pytest_emrd.errors import ConfigError, MissingExtraError, TransportError
from pytest_emrd.world import Layout
from pytest_emrd.world.thor import ThorSimulator
from pytest_emrd.world.thor._launch import import_ai2thor

from .conftest import still_running

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


def test_a_step_timeout_kills_unity_and_its_process_group(
    fake_controller: type, layout: Layout, tmp_path: Path
) -> None:
    """The controller's Unity process leads its own group (as :func:`launcher` starts it)
    and has a child; a step that never returns must leave neither running."""
    pids = tmp_path / "pids.txt"
    unity = subprocess.Popen(
        ["sh", "-c", f"sleep 300 & echo $$ $! > {pids}; wait"], start_new_session=True
    )

    class WithUnity(fake_controller):  # type: ignore[misc, valid-type]
        def __init__(self, **init: Any) -> None:
            super().__init__(**init)
            self.server = SimpleNamespace(unity_proc=unity)

    try:
        sim = ThorSimulator(controller_factory=WithUnity, step_timeout=0.5)
        sim.reset(layout, "baseline", "Office", 0)
        while not pids.exists() or len(pids.read_text().split()) < 2:
            time.sleep(0.02)
        started = [int(p) for p in pids.read_text().split()]
        never = threading.Event()
        fake_controller.instances[-1].step = lambda *a, **k: never.wait()
        with pytest.raises(TransportError, match="step_timeout"):
            sim.step("Turn(Left)")
        never.set()
        assert not still_running(started)
    finally:
        if unity.poll() is None:
            os.killpg(unity.pid, signal.SIGKILL)
        unity.wait()


@pytest.mark.parametrize(
    ("option", "value"),
    [("start_timeout", 0), ("step_timeout", -1.0), ("step_timeout", "fast")],
    ids=["zero-start", "negative-step", "text-step"],
)
def test_bad_timeouts_are_rejected(option: str, value: Any) -> None:
    with pytest.raises(ConfigError, match=f"{option}="):
        ThorSimulator(**{option: value})
