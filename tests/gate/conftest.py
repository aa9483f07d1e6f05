"""Small stand-ins for the metric registry and for episodes, to test gates in isolation."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import pytest

from pytest_emrd.trajectory import Trajectory


@dataclass(frozen=True)
class Estimate:
    value: float | None
    ci_low: float | None
    ci_high: float | None
    n: int
    reason: str | None = None


@dataclass(frozen=True)
class StepsMetric:
    """Mean number of steps, with a crude order-sensitive "CI" to expose ordering bugs."""

    name: str = "steps"
    better: str = "lower"

    def compute(self, trajectories: Sequence[Trajectory], *, rng_seed: int = 0) -> Estimate:
        if not trajectories:
            return Estimate(None, None, None, 0, "no episodes")
        values = [float(len(t.steps)) for t in trajectories]
        mean = sum(values) / len(values)
        return Estimate(mean, values[0], values[-1], len(values))


@pytest.fixture
def metrics() -> dict[str, StepsMetric]:
    return {"steps": StepsMetric()}
