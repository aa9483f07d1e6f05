"""Against the real ai2thor 5.0.0 package (no build, no network, no download).

The build lookup is monkeypatched or starved (HOME is a fresh tmp dir), so a missing
build, a missing Vulkan loader or a Unity process that never answers must fail fast with
a message naming what to install.
"""

from __future__ import annotations

import ctypes.util
from collections.abc import Callable
from pathlib import Path
from typing import Any

import ai2thor.controller
import pytest

from pytest_emrd.errors import ConfigError
from pytest_emrd.world import Layout
from pytest_emrd.world.thor import ThorSimulator
from pytest_emrd.world.thor._launch import import_ai2thor, preflight, releases_dir

from .conftest import still_running

FailedReset = Callable[[ThorSimulator, Layout, float], ConfigError]

thor = import_ai2thor()
pytestmark = pytest.mark.usefixtures("isolated_home")


def test_missing_vulkan_names_libvulkan1(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(ctypes.util, "find_library", lambda name: None)
    with pytest.raises(ConfigError, match="libvulkan1"):
        preflight(thor, {"platform": thor.platform.CloudRendering}, allow_download=False)


@pytest.mark.usefixtures("vulkan")
def test_missing_build_fails_before_any_network_call(
    failed_reset: FailedReset, layout: Layout
) -> None:
    sim = ThorSimulator()
    error = failed_reset(sim, layout, 5.0)
    assert "local_executable_path" in str(error) and releases_dir() in str(error)


@pytest.mark.usefixtures("thor_installed")
def test_a_cached_build_passes_the_preflight() -> None:
    preflight(thor, {"platform": thor.platform.CloudRendering}, allow_download=False)


def test_local_executable_path_must_exist(
    failed_reset: FailedReset, layout: Layout, tmp_path: Path
) -> None:
    sim = ThorSimulator(local_executable_path=str(tmp_path / "thor-Linux64-local"))
    error = failed_reset(sim, layout, 5.0)
    assert "local_executable_path=" in str(error)


@pytest.mark.usefixtures("vulkan")
def test_ai2thor_finding_no_build_is_translated(
    failed_reset: FailedReset, layout: Layout, monkeypatch: pytest.MonkeyPatch
) -> None:
    def no_build(self: Any, *args: Any) -> None:  # ai2thor 5.0.0's own message
        raise Exception(
            "No build exists for arch=Linux platforms=CloudRendering and commits: f0825767"
        )

    monkeypatch.setattr(ai2thor.controller.Controller, "find_build", no_build)
    sim = ThorSimulator(allow_download=True)
    error = failed_reset(sim, layout, 5.0)
    assert "No build exists" in str(error) and "local_executable_path" in str(error)


def test_unity_that_never_answers_is_abandoned(
    failed_reset: FailedReset, layout: Layout, tmp_path: Path
) -> None:
    """A real ai2thor Controller launching a 'Unity' that exits at once: bounded, explained."""
    unity = tmp_path / "thor-Linux64-broken"
    unity.write_text("#!/bin/sh\nexit 1\n")
    unity.chmod(0o755)
    sim = ThorSimulator(local_executable_path=str(unity), x_display=":0", start_timeout=2.0)
    error = failed_reset(sim, layout, 10.0)
    assert "start_timeout=2" in str(error) and "libvulkan1" in str(error)


def _stub_unity(tmp_path: Path, body: str) -> Path:
    """An executable standing in for the Unity player: ai2thor's real start-up code
    launches it; it never answers, so only its side effects are observable."""
    unity = tmp_path / "thor-CloudRendering-stub"
    unity.write_text("#!/bin/sh\n" + body)
    unity.chmod(0o755)
    return unity


def test_local_executable_path_starts_on_a_machine_without_a_display(
    failed_reset: FailedReset, layout: Layout, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """ai2thor wraps a local build as an ExternalBuild (platform Linux64), whose launch
    environment is ``DISPLAY=None`` without an X display: ``Popen`` raised ``TypeError``
    before the build ever ran. Now the build runs (and here, never answers)."""
    monkeypatch.delenv("DISPLAY", raising=False)
    seen = tmp_path / "display.txt"
    unity = _stub_unity(tmp_path, f'echo "$DISPLAY" > {seen}\nexec sleep 30\n')
    sim = ThorSimulator(local_executable_path=str(unity), start_timeout=2.0)
    error = failed_reset(sim, layout, 15.0)
    assert "did not start within start_timeout=2" in str(error), error
    assert seen.read_text().strip() == ":0"


def test_a_start_up_timeout_kills_unity_and_its_process_group(
    failed_reset: FailedReset, layout: Layout, tmp_path: Path
) -> None:
    """The stand-in starts a child of its own, as Unity's crash handler does; after the
    start-up timeout neither may outlive the failed reset."""
    pids = tmp_path / "pids.txt"
    unity = _stub_unity(tmp_path, f"sleep 300 &\necho $$ $! > {pids}\nwait\n")
    sim = ThorSimulator(local_executable_path=str(unity), x_display=":0", start_timeout=2.0)
    failed_reset(sim, layout, 15.0)
    started = [int(p) for p in pids.read_text().split()]
    assert len(started) == 2
    assert not still_running(started)
