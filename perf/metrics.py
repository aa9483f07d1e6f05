"""``python -m perf metrics``: every EMRD metric over a 240-episode grid.

The grid is one model x 3 conditions x 4 spawns x 20 episodes of 50 steps, generated once
by :mod:`pytest_emrd.metrics.synthetic` (not timed). Timed: per-episode metrics for every
trajectory, every gate metric with its bootstrap CI, and every report aggregate.
"""

from __future__ import annotations

from perf import Figure, median_seconds
from pytest_emrd.metrics import (
    anova_conditions,
    as_episode_metrics,
    ebbinghaus,
    evaluate_gates,
    focal_distribution,
    fpsg,
    kaplan_meier_anchored,
    miller_curve,
    positional_accuracy,
    serial_position,
    spatial_identity_resolution,
    tbs_curve,
    time_to_forget,
)
from pytest_emrd.metrics.synthetic import synthetic_grid
from pytest_emrd.trajectory import Trajectory

TARGET_GRID_240_S = 2.0


def all_metrics(trajectories: list[Trajectory]) -> dict[str, object]:
    """Every metric the reports and gates ask for, from raw trajectories, by name."""
    ems = as_episode_metrics(trajectories)
    results: dict[str, object] = dict(evaluate_gates(ems))
    for aggregate in (
        positional_accuracy,
        tbs_curve,
        time_to_forget,
        kaplan_meier_anchored,
        ebbinghaus,
        serial_position,
        miller_curve,
        spatial_identity_resolution,
        focal_distribution,
        fpsg,
        anova_conditions,
    ):
        results[aggregate.__name__] = aggregate(ems)
    return results


def run(*, repeat: int, warmup: int) -> list[Figure]:
    grid = synthetic_grid()
    seconds = median_seconds(lambda: all_metrics(grid), repeat=repeat, warmup=warmup)
    return [Figure("metrics.grid_240_s", seconds, "s", TARGET_GRID_240_S, repeat)]
