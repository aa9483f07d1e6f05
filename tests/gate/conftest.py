"""Small stand-ins for the metric registry and for episodes, to test gates in isolation."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import pytest

from pytest_emrd.trajectory import EpisodeSpec, GroundTruth, Trajectory


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

    def compute(self, trajectories: Sequence[Trajectory], *, rng_seed: int = 0) -> Estimate:
        if not trajectories:
            return Estimate(None, None, None, 0, "no episodes")
        values = [float(len(t.steps)) for t in trajectories]
        mean = sum(values) / len(values)
        return Estimate(mean, values[0], values[-1], len(values))


def make_trajectory(
    spec: EpisodeSpec, *, status: str = "budget", protocol: str = "p1"
) -> Trajectory:
    gt = GroundTruth(objects=(), rooms=(), discoverable_ids=(), spawn_room="Office")
    return Trajectory(
        spec=spec,
        protocol=protocol,
        ground_truth=gt,
        steps=(),
        status=status,
        final_room="Office",
        error="boom" if status == "errored" else None,
    )


@pytest.fixture
def metrics() -> dict[str, StepsMetric]:
    return {"steps": StepsMetric()}
