"""``compare_runs``: per cell and metric, B - A with a seeded two-sample bootstrap CI."""

from __future__ import annotations

import pytest

from pytest_emrd.metrics import GATE_METRICS
from pytest_emrd.metrics.synthetic import synthetic_grid
from pytest_emrd.report import COMPARED, Comparison, compare_runs, render_comparison
from pytest_emrd.trajectory import Trajectory


@pytest.fixture(scope="module")
def forgetful() -> list[Trajectory]:
    """Same episodes as ``grid`` but a planted mean memory of 3 steps instead of 10."""
    return synthetic_grid(model="syn", episodes=2, max_steps=30, mean_memory=3.0)


def test_every_compared_metric_is_a_gate_metric() -> None:
    assert set(COMPARED) <= set(GATE_METRICS)


def test_a_run_against_itself_changes_nothing(grid: list[Trajectory]) -> None:
    c = compare_runs(grid, grid)
    assert len(c.differences) == 3 * len(COMPARED) and not c.only_a and not c.only_b
    for d in c.differences:
        if d.diff is not None:
            assert d.diff == 0.0
        if d.significant is not None:
            assert d.significant is False and d.ci_low <= 0.0 <= d.ci_high


def test_values_are_the_gate_metrics_and_diff_is_b_minus_a(grid, forgetful) -> None:
    c = compare_runs(grid, forgetful)
    for d in c.differences:
        cell_a = sorted((t for t in grid if t.spec.condition == d.condition),
                        key=lambda t: t.spec.case_id)  # fmt: skip
        assert d.a == GATE_METRICS[d.metric].compute(cell_a)
        if d.diff is not None:
            assert d.diff == pytest.approx(d.b.value - d.a.value)


def test_planted_forgetting_is_a_significant_drop_in_memory_strength(grid, forgetful) -> None:
    c = compare_runs(grid, forgetful)
    strength = [d for d in c.differences if d.metric == "memory_strength"]
    assert len(strength) == 3
    for d in strength:
        assert d.diff is not None and d.diff < 0
        assert d.significant is True and d.ci_high < 0
    for d in c.differences:
        if d.ci_low is not None:
            assert d.ci_low <= d.diff <= d.ci_high, d


def test_seeded_and_reproducible(grid, forgetful) -> None:
    assert compare_runs(grid, forgetful) == compare_runs(grid, forgetful)
    other = compare_runs(grid, forgetful, rng_seed=1)
    assert other.rng_seed == 1


def test_cells_in_one_run_only_are_listed(grid: list[Trajectory]) -> None:
    baseline = [t for t in grid if t.spec.condition == "baseline"]
    c = compare_runs(grid, baseline)
    assert c.only_a == ("syn/default/low_light", "syn/default/texture") and c.only_b == ()
    assert {d.condition for d in c.differences} == {"baseline"}


def test_one_episode_gives_a_diff_without_ci(grid: list[Trajectory]) -> None:
    one = grid[:1]
    aec = next(d for d in compare_runs(one, one).differences if d.metric == "aec")
    assert aec.diff == 0.0 and aec.ci_low is None and aec.significant is None
    assert aec.reason == "fewer than two episodes in a run: no confidence interval"


def test_comparison_renders_and_round_trips(grid, forgetful) -> None:
    c = compare_runs(grid, forgetful, names=("v1", "v2"))
    assert Comparison.from_dict(c.to_dict()) == c
    files = render_comparison(c)
    md = files["compare.md"].decode()
    assert "A = v1, B = v2" in md and "| memory_strength |" in md and "**yes**" in md
    assert set(files) == {"compare.md", "compare.html", "compare.json"}
