"""Map rows (frame invariance) and the R^2 rows on every grid of evaluation points."""

from __future__ import annotations

import math

import pytest

from pytest_emrd.metrics import R2_POINTS, as_episode_metrics
from pytest_emrd.metrics.synthetic import synthetic_trajectory
from pytest_emrd.trajectory import EpisodeSpec, Trajectory
from pytest_emrd.validate import FRAME_TOLERANCE, frame_checks, r2_points_checks


def _synthetic(mean_memory: float, n: int = 4) -> list[Trajectory]:
    spawns = ("office", "conference", "kitchen", "entrance")
    return [
        synthetic_trajectory(EpisodeSpec("synthetic", "baseline", spawns[i % 4], i),
                             mean_memory=mean_memory)
        for i in range(n)
    ]  # fmt: skip


def test_frame_rows_pass_with_zero_change_on_synthetic_runs() -> None:
    rows = frame_checks({"a": _synthetic(5.0), "b": _synthetic(20.0, 2)})
    assert rows and all(r.section == "Map" and r.verdict == "pass" for r in rows)
    assert {r.name for r in rows} >= {"frame invariance: PA", "frame invariance: SIR"}
    assert all(r.data["max_abs_delta"] <= FRAME_TOLERANCE for r in rows)
    assert all(r.data["episodes"] == 6 for r in rows)


def test_frame_rows_skip_metrics_only_episodes_and_need_a_trajectory() -> None:
    assert frame_checks({"a": as_episode_metrics(_synthetic(5.0, 1))}) == []


def test_r2_rows_one_per_grid_the_default_first() -> None:
    decays = {3.0: _synthetic(3.0), 20.0: _synthetic(20.0)}
    rows = r2_points_checks(decays, {5: _synthetic(5.0)}, _synthetic(8.0))
    assert [r.data["points"] for r in rows] == list(R2_POINTS)
    assert "(default)" in rows[0].name
    assert all(r.verdict in ("pass", "fail", "finding") for r in rows)
    assert all(isinstance(r.data["min_gap"], float) for r in rows)
    assert not math.isnan(rows[0].data["r2_decay_3"] or math.nan)


@pytest.mark.parametrize("points", R2_POINTS)
def test_r2_rows_verdict_follows_the_findings(points: str) -> None:
    decays = {3.0: _synthetic(3.0)}
    (row,) = [
        r for r in r2_points_checks(decays, {}, _synthetic(8.0)) if r.data["points"] == points
    ]
    holds = row.data["r2_decay_3"] is not None and row.data["r2_decay_3"] >= 0.8
    default = points == R2_POINTS[0]
    assert row.verdict == ("pass" if holds else ("fail" if default else "finding"))
