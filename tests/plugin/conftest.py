"""A throw-away copy of the benchmark suite inside ``pytester``, run as a black box."""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]

GATES = """
scout:
  baseline:
    errored_rate: {max: 0.0}
    aec: {min: 0.05}
"""


@pytest.fixture
def suite(pytester: pytest.Pytester) -> pytest.Pytester:
    """The real benchmarks/test_emrd.py plus a small thresholds.yaml, in a temp rootdir."""
    pytester.makepyfile(test_emrd=(ROOT / "benchmarks" / "test_emrd.py").read_text())
    pytester.makefile(".yaml", thresholds=GATES)
    return pytester


@pytest.fixture
def small() -> Callable[..., list[str]]:
    """Arguments for a small grid: scout, baseline, office, ``episodes`` episodes."""

    def args(*extra: str, episodes: int = 2) -> list[str]:
        return [
            "-p",
            "no:cacheprovider",
            "--emrd-condition=baseline",
            "--emrd-spawn=office",
            f"--emrd-episodes={episodes}",
            *extra,
        ]

    return args


@pytest.fixture(scope="module")
def recorded(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """Cassettes of scout-baseline-office-ep00/ep01, recorded live from the reference server."""
    from pytest_emrd.agent import load_registry
    from pytest_emrd.cassette import agent_runner, run_with_cassette
    from pytest_emrd.episode import protocol_version
    from pytest_emrd.trajectory import EpisodeSpec

    root = tmp_path_factory.mktemp("cassettes")
    runner = agent_runner(load_registry())
    for episode in (0, 1):
        spec = EpisodeSpec("scout", "baseline", "office", episode, modality="both")
        run = run_with_cassette(
            spec, runner, cassettes=root, protocol=protocol_version(), record_mode="once"
        )
        assert run.recorded and run.trajectory.status != "errored", run.trajectory.error
    return root
