"""A throw-away copy of the benchmark suite inside ``sandbox``, run as a black box."""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

import pytest

from tests._sandbox import Sandbox

ROOT = Path(__file__).resolve().parents[2]

GATES = """
scout:
  baseline:
    errored_rate: {max: 0.0}
    aec: {min: 0.05}
"""


@pytest.fixture
def suite(sandbox: Sandbox) -> Sandbox:
    """The real benchmarks/test_emrd.py plus a small thresholds.yaml, in a temp rootdir."""
    sandbox.makepyfile(test_emrd=(ROOT / "benchmarks" / "test_emrd.py").read_text())
    sandbox.makefile(".yaml", thresholds=GATES)
    return sandbox


@pytest.fixture
def small() -> Callable[..., list[str]]:
    """Arguments for a small grid: scout, baseline, office, ``episodes`` episodes."""

    def args(*extra: str, episodes: int = 2) -> list[str]:
        return [
            "-p",
            "no:cacheprovider",
            "--emrd-model=scout",
            "--emrd-condition=baseline",
            "--emrd-spawn=office",
            f"--emrd-episodes={episodes}",
            *extra,
        ]

    return args


def _record(root: Path) -> None:
    from pytest_emrd.agent import load_registry
    from pytest_emrd.episode import protocol_version
    from pytest_emrd.trajectory import EpisodeSpec
    from tests._episodes import agent_runner, run_with_cassette

    runner = agent_runner(load_registry())
    for episode in (0, 1):
        spec = EpisodeSpec("scout", "baseline", "office", episode, modality="both")
        run = run_with_cassette(
            spec, runner, cassettes=root, protocol=protocol_version(), record_mode="once"
        )
        assert run.recorded and run.trajectory.status != "errored", run.trajectory.error


@pytest.fixture(scope="session")
def recorded(shared_folder: Callable[..., Path]) -> Path:
    """Cassettes of scout-baseline-office-ep00/ep01, recorded live from the reference server
    once per session (read-only: copy them to change them)."""
    return shared_folder("cassettes", _record)


THOR_CONFTEST = """
import importlib.util
import json
import os
import sys

import ai2thor.controller

_spec = importlib.util.spec_from_file_location("emrd_thor_fakes", {fakes!r})
_fakes = importlib.util.module_from_spec(_spec)
sys.modules[_spec.name] = _fakes
_spec.loader.exec_module(_fakes)


def _log(event, **fields):
    with open({log!r}, "a", encoding="utf-8") as out:
        out.write(json.dumps({{"pid": os.getpid(), "event": event, **fields}}) + "\\n")


class LoggedController(_fakes.FakeController):
    def __init__(self, **init):
        super().__init__(**init)
        _log("start", gpu_device=init.get("gpu_device"), local=init.get("local_executable_path"))

    def stop(self):
        super().stop()
        _log("stop")


ai2thor.controller.Controller = LoggedController
"""


@pytest.fixture
def thor_suite(suite: Sandbox) -> tuple[Sandbox, list[str], Path]:
    """The suite on ``--emrd-backend=ai2thor`` through ai2thor's own start-up path, with the
    fake controller of ``tests/world/thor/conftest.py`` as ``ai2thor.controller.Controller``.

    Returns the sandbox, the backend arguments (a real executable file as
    ``local_executable_path``, ``gpu_device=1``) and the JSON-lines log of controller
    starts and stops (one line per event, with the process id).
    """
    log = suite.path / "controllers.jsonl"
    fakes = ROOT / "tests" / "world" / "thor" / "conftest.py"
    suite.makeconftest(THOR_CONFTEST.format(fakes=str(fakes), log=str(log)))
    build = suite.path / "thor-Linux64-local"
    build.write_text("#!/bin/sh\n")
    build.chmod(0o755)
    args = [
        "--emrd-backend=ai2thor",
        f"--emrd-backend-option=local_executable_path={build}",
        "--emrd-backend-option=gpu_device=1",
    ]
    return suite, args, log
