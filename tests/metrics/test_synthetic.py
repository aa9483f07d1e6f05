"""The synthetic trajectory generator: determinism, shape, and the plants it promises."""

from __future__ import annotations

import json

from pytest_emrd.metrics.synthetic import synthetic_grid, synthetic_trajectory
from pytest_emrd.trajectory import EpisodeSpec, Trajectory


def test_deterministic_and_json_round_trip() -> None:
    spec = EpisodeSpec("synthetic", "baseline", "kitchen", 3)
    a = synthetic_trajectory(spec, seed=5)
    assert a == synthetic_trajectory(spec, seed=5)
    assert a != synthetic_trajectory(spec, seed=6)
    assert Trajectory.from_dict(json.loads(json.dumps(a.to_dict()))) == a


def test_grid_shape_and_layout(small_grid: list[Trajectory]) -> None:
    assert len(small_grid) == 36
    first = small_grid[0]
    assert len(first.ground_truth.objects) == 39
    assert {o.room for o in first.ground_truth.objects} == {
        "Office", "Conference Room", "Kitchen", "Entrance"
    }  # fmt: skip
    assert all(len(t.steps) <= 50 for t in small_grid)
    assert {t.status for t in small_grid} == {"terminated", "budget"}


def test_same_office_for_every_condition_of_a_spawn_and_episode() -> None:
    grid = synthetic_grid(episodes=1)
    by_key = {}
    for t in grid:
        by_key.setdefault((t.spec.spawn, t.spec.episode), set()).add(t.ground_truth)
    assert all(len(v) == 1 for v in by_key.values())
