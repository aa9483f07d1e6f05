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
