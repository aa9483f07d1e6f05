"""TBS curve (carry-forward) and per-episode positional accuracy."""

from __future__ import annotations

import math
from collections.abc import Callable

import pytest

from pytest_emrd.metrics import EpisodeMetrics, episode_metrics, positional_accuracy, tbs_curve
from pytest_emrd.rooms import OFFICE
from pytest_emrd.trajectory import GroundTruthObject, Trajectory

MakeObj = Callable[..., GroundTruthObject]
MakeTraj = Callable[..., Trajectory]


def test_tbs_drift_and_coverage_worked_example(make_obj: MakeObj, make_traj: MakeTraj) -> None:
    truth = [make_obj("Desk_1", x=0, z=0), make_obj("Sink_1", x=6, z=8)]
    steps = [
        (OFFICE, ["Desk_1"], {"d": ("Desk", 0.0, 0.0)}),
        (OFFICE, ["Desk_1"], {"d": ("Desk", 3.0, 4.0)}),  # drifted 5 m from its first position
        (OFFICE, [], {}),
    ]
    m = episode_metrics(make_traj(truth, steps))
    scale = 5.0  # RMS distance of (0, 0) and (6, 8) from their centroid (3, 4)
    assert m.tbs == pytest.approx((0.5, math.exp(-5.0 / scale) * 0.5, 0.0))


def test_tbs_curve_carries_the_last_value_forward(make_obj: MakeObj, make_traj: MakeTraj) -> None:
    truth = [make_obj("Desk_1")]
    short = make_traj(truth, [(OFFICE, ["Desk_1"], {"d": ("Desk", 0.0, 0.0)})])
    long = make_traj(truth, [(OFFICE, [], {})] * 3, status="budget")
    curve = tbs_curve([short, long], t_max=3)
    assert curve.t == (1, 2, 3)
    assert curve.mean == pytest.approx((0.5, 0.5, 0.5))
    assert curve.n == 2


def test_tbs_curve_excludes_unusable_episodes(make_obj: MakeObj, make_traj: MakeTraj) -> None:
    empty = make_traj([make_obj("Desk_1")], [])
    no_base = make_traj([make_obj("Desk_1")], [(OFFICE, [], {})], discoverable=[])
    curve = tbs_curve([empty, no_base])
    assert (curve.t, curve.n, curve.excluded) == ((), 0, 2)


def test_tbs_values_in_unit_interval(small_grid_metrics: list[EpisodeMetrics]) -> None:
    curve = tbs_curve(small_grid_metrics)
    assert len(curve.t) == 50
    assert all(0.0 <= v <= 1.0 for v in curve.mean)


def test_positional_accuracy_per_episode_in_input_order(
    small_grid_metrics: list[EpisodeMetrics],
) -> None:
    values = positional_accuracy(small_grid_metrics)
    assert values == tuple(m.pa for m in small_grid_metrics)
    assert all(v is not None and 0.0 <= v <= 1.0 for v in values)
